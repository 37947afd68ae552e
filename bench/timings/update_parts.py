"""Where a learning step's time goes, per approach: one seed on one device, the replay buffer filled to
--fill transitions, microseconds per minibatch update for `dqn.learn` as a whole and for each part.

    python -m bench.timings.update_parts [--env light_switch_door] [--approaches ours,no_feature_selection,maple_q]
                                 [--fill 16384] [--updates 1000] [--set NAME=VALUE ...]

The full-state ablations are measured twice, with their task-constant entries split off (the default,
`split_task_state`) and whole. Parts (each jitted alone, over --updates iterations, after a compiling call): the minibatch draws
(`minibatch_indices`, all updates at once), gathering and encoding a minibatch, the forward and backward
pass on a fixed minibatch, clip + Adam, the polyak step; and the per-cycle relabelling of the buffer
(whole, in ms). `dense_fb_us`: the forward and backward pass of a network whose first layer takes only
the minibatch's stored entries and the action (a plain dense layer, no task-constant rows): what the
split's pass would cost if the constant rows' gathers and scatters were free. The parts run on the
weights `learn` fits (without those of the inputs the training tasks never fill: DQN.fit_rows). The
parts do not add up to the whole exactly: XLA fuses across them in `learn`.
"""
from __future__ import annotations

import sys
import time

import jax
import jax.numpy as jnp
import optax

from bench.command import CommandParser
import jaxbridge
from jaxbridge.learn import dqn
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.setup import make_setup
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.q_bridge import SplitInput, at_task, batch_input, input_rows
from jaxbridge.utils.cli import run_main


def _seconds(fn, arg) -> float:
    run = jax.jit(fn)
    jax.block_until_ready(run(arg))
    start = time.perf_counter()
    jax.block_until_ready(run(arg))
    return time.perf_counter() - start


def measure(env_name: str, approach: str, fill: int, updates: int, split: bool = True,
            settings: list[str] | None = None) -> dict:
    config = jaxbridge.make_config(env_name, seeds=1, approach=approach, updates_per_cycle=updates,
                                   split_task_state=split, settings=settings)
    setup = make_setup(config)
    env, learning = setup.train_env, setup.learner
    tasks = setup.train.arrays.tasks  # the seed's training tasks, which a split buffer's `task` indexes
    task = learning.task_part(tasks)
    learner = jax.tree.map(lambda x: x[0], setup.init_learners())
    learner = learner.replace(buffer=learner.buffer.replace(size=jnp.int32(fill)))  # zeros: timing only
    whole = learner  # `learn` takes it whole; its parts run on the weights it fits (DQN.fit_rows)
    learner = learner if learning.fit_rows is None else input_rows(learner, learning.fit_rows)
    net, optimizer = learning.net, learning.optimizer
    _, indices = dqn.minibatch_indices(config, learner)
    batch = jax.tree.map(lambda d: d[indices[0]], learner.buffer.data)
    inputs = batch_input(env, batch.features, batch.skill, batch.param, at_task(task, batch.task))

    def repeat(step):  # `updates` iterations of step(carry) in a scan
        return lambda carry: jax.lax.scan(lambda c, _: (step(c), None), carry, None, length=updates)[0]

    def gather_encode(total):
        def one(total, index):
            b = jax.tree.map(lambda d: d[index], learner.buffer.data)
            encoded = batch_input(env, b.features, b.skill, b.param, at_task(task, b.task))
            return total + sum(x.sum() for x in jax.tree.leaves(encoded)), None
        return jax.lax.scan(one, total, indices)[0]

    def forward_backward(x):  # a step on a fixed minibatch input x, as a function of the parameters
        def step(params):
            grads = jax.grad(lambda p: jnp.mean((net.apply(p, x, members=True) - 1.0) ** 2))(params)
            return jax.tree.map(lambda p, g: p - 1e-3 * g, params, grads)
        return step

    # The stored entries ++ the action as one plain input (ours' input is one already).
    dense = jnp.concatenate([inputs.observation, inputs.action], -1) if isinstance(inputs, SplitInput) else inputs
    dense_params = {"params": net.init(jax.random.key(0), dense[:1])["params"]}

    def adam(state):
        params, opt_state = state
        step, opt_state = optimizer.update(params, opt_state, params, max_norm=config.learner.grad_clip,
                                           learning_rate=config.learner.learning_rate)
        return optax.apply_updates(params, step), opt_state

    per_update = lambda s: 1e6 * s / updates
    return {
        "input": learning.stored_features,
        "learn_us": per_update(_seconds(lambda l: dqn.learn(learning, Hyper.of(config), l, jnp.int32(0), tasks), whole)),
        "relabel_ms": 1e3 * _seconds(lambda l: dqn.relabel(learning, Hyper.of(config), l, l.key, task), learner),
        "draws_us": per_update(_seconds(lambda l: dqn.minibatch_indices(config, l), learner)),
        "gather_encode_us": per_update(_seconds(gather_encode, jnp.float32(0))),
        "forward_backward_us": per_update(_seconds(repeat(forward_backward(inputs)), learner.params)),
        "dense_fb_us": per_update(_seconds(repeat(forward_backward(dense)), dense_params)),
        "adam_us": per_update(_seconds(repeat(adam), (learner.params, learner.opt_state))),
        "polyak_us": per_update(_seconds(repeat(lambda t: optax.incremental_update(learner.params, t, 0.0025)),
                                         learner.target_params)),
    }


def main(argv=None) -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door")
    parser.add_argument("--approaches", default="ours,no_feature_selection,maple_q",
                        help="comma-separated approaches (default: %(default)s)")
    parser.add_argument("--fill", type=int, default=16384, help="stored transitions (default: %(default)s)")
    parser.add_argument("--updates", type=int, default=1000, help="updates per timed call (default: %(default)s)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a setting of the runs measured, as train.py's --set (e.g. feature_noise=0)")
    args = parser.parse_args(argv)
    print(f"jax {jax.__version__}, one {jax.devices()[0].platform} device, {args.env}, buffer filled to {args.fill}, "
          f"us per update" + "".join(f", {s}" for s in args.set))
    columns = ["input", "learn_us", "relabel_ms", "draws_us", "gather_encode_us", "forward_backward_us",
               "dense_fb_us", "adam_us", "polyak_us"]
    print("| approach | " + " | ".join(columns) + " |")
    print("|---" * (len(columns) + 1) + "|")
    for approach in args.approaches.split(","):
        # The full-state ablations twice: their task-constant entries split off (the default), and whole.
        splits = (True, False) if get_approach(approach).controls.observation.whole_state else (True,)
        for split in splits:
            row = measure(args.env, approach, args.fill, args.updates, split, args.set)
            label = approach + ("" if len(splits) == 1 else " (split)" if split else " (whole)")
            print(f"| {label} | " + " | ".join(f"{row[c]:.1f}" if c != "input" else str(row[c]) for c in columns)
                  + " |", flush=True)


if __name__ == "__main__":
    sys.exit(run_main(main))
