"""The learner's optimiser is optax's clip-then-Adam to the bit (jaxbridge/optim.py says why it is ours;
tests/test_devices.py checks what it is for: seed blocks identical on 1 and 2 devices)."""

import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxbridge.optim import clipped_adam

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
