"""The learner's optimiser is optax's clip-then-Adam to the bit, and unlike it gives a seed the same
numbers whether its seed block shares a device or not (jaxbridge/learn/optim.py says why). A whole training
run in blocks is checked by `python -m bench.timings.devices --seed-block 2`, too slow for the suite."""
import os
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import optax
from run_helpers import TEST_XLA_FLAGS

from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh
from jaxbridge.learn.optim import clipped_adam

MAX_NORM, LR = 5.0, 1e-3


def fit(optimizer, steps=40):
    """One seed's fitting of a small 2-layer net: (params, opt_state) -> (params, opt_state, losses)."""
    def loss(params, x):
        h = jax.nn.leaky_relu(x @ params["w1"] + params["b1"], 0.01)
        return jnp.mean((h @ params["w2"] - jnp.sin(x.sum(-1, keepdims=True))) ** 2)

    def run(state, xs):
        def step(state, x):
            params, opt_state = state
            value, grads = jax.value_and_grad(loss)(params, x)
            updates, opt_state = optimizer.update(grads, opt_state, params)
            return (optax.apply_updates(params, updates), opt_state), value
        return jax.lax.scan(step, state, xs[:steps])
    return run


def seed_states(optimizer, seeds, scale):
    def one(key):
        k1, k2 = jax.random.split(key)
        params = {"w1": scale * jax.random.normal(k1, (12, 32)), "b1": jnp.zeros(32),
                  "w2": scale * jax.random.normal(k2, (32, 1))}
        return params, optimizer.init(params)
    return jax.vmap(one)(jax.random.split(jax.random.key(0), seeds))


def leaves(tree):
    return [np.asarray(x) for x in jax.tree.leaves(tree)]


def test_clipped_adam_is_optax_clip_then_adam_to_the_bit():
    ours, reference = clipped_adam(MAX_NORM, LR), optax.chain(optax.clip_by_global_norm(MAX_NORM), optax.adam(LR))
    xs = jax.random.normal(jax.random.key(1), (40, 64, 12))
    fit_ours, fit_reference = jax.jit(fit(ours)), jax.jit(fit(reference))  # each compiled once
    for scale in (0.1, 3.0):  # small weights: gradients under the clip norm; large: clipped
        params, _ = jax.tree.map(lambda x: x[0], seed_states(reference, 1, scale))
        a = fit_ours((params, ours.init(params)), xs)
        b = fit_reference((params, reference.init(params)), xs)
        assert jax.tree.structure(a) == jax.tree.structure(b)  # the same state: checkpoints interchange
        assert all(np.array_equal(x, y) for x, y in zip(leaves(a), leaves(b)))
    grads = jax.grad(lambda p: jnp.sum(p["w1"] ** 2))(params)
    assert float(optax.tree.norm(grads)) > MAX_NORM  # the large-weight case did clip


def blocks_on_one_and_two_devices(optimizer) -> bool:
    """4 seeds in blocks of 2 (needs 2 devices): two blocks on one device, or one on each of two.
    Whether every number came out the same."""
    devices = jax.local_devices()
    states = seed_states(optimizer, 4, 3.0)
    xs = jax.random.normal(jax.random.key(2), (4, 40, 64, 12))
    results = []
    for n in (1, 2):
        seeds = SeedMesh(4, tuple(devices[:n]), block=2)
        run = jax.jit(seeds.map_seeds(fit(optimizer)))
        results.append(leaves(run(seeds.real(), seeds.place(states), seeds.place(xs))))
    assert not np.array_equal(results[0][-1][0], results[0][-1][1])  # the seeds do differ
    return all(np.array_equal(x, y) for x, y in zip(*results))


def test_seed_blocks_give_the_same_numbers_on_one_and_two_devices():
    # Its own process: 2 virtual CPU devices must be set before JAX starts. Compiled at XLA's default
    # optimisation level, as users run (not the suite's cheaper one): the rewrite that broke this (a
    # division turned into a reciprocal's product) is an optimisation.
    root = str(Path(__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")])),
           "XLA_FLAGS": os.environ.get("XLA_FLAGS", "").replace(TEST_XLA_FLAGS, "").strip()}
    proc = subprocess.run([sys.executable, __file__], capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["2", "True"]


if __name__ == "__main__":  # the learner's optimiser; --optax: optax's, to see the check fail
    jax.config.update("jax_num_cpu_devices", 2)
    print(len(jax.local_devices()), blocks_on_one_and_two_devices(
        optax.chain(optax.clip_by_global_norm(MAX_NORM), optax.adam(LR)) if "--optax" in sys.argv
        else clipped_adam(TrainConfig().learner.grad_clip, TrainConfig().learner.learning_rate)))
