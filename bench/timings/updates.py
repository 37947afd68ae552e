"""Double-DQN minibatch updates per second, every seed at once, on the training layout (seeds over the
devices, each device updating its seeds one after another, as in a cycle).

    python -m bench.timings.updates [--env light_switch_door] [--seeds 0-7] [--updates 1000] [--devices auto|N]

The updates are `jaxbridge.learn.dqn.update_step` (the minibatch slots drawn up front by `minibatch_indices`; Adam step, polyak
step) in a `lax.scan`, as `learn` runs them; the buffer is the one after two training cycles. Not timed:
the target relabelling that precedes them in a cycle.
"""
from __future__ import annotations

import jaxbridge
import statistics
import time

import jax
import jax.numpy as jnp

from bench.command import CommandParser


def measure_updates(setup, seeds, learners, updates: int, repeats: int = 3) -> dict:
    """`updates` minibatch updates of every seed of `learners` (placed on `seeds`), `repeats` timed
    calls after a compiling one. Returns compile seconds (tracing, lowering and XLA of the first call), the median seconds per call
    and updates per second over all seeds."""
    from jaxbridge.utils import compile_cache
    from dataclasses import replace
    from jaxbridge.learn.dqn import minibatch_indices, update_step
    from jaxbridge.learn.hyper import Hyper

    config = replace(setup.config, updates_per_cycle=updates)
    learning = replace(setup.learner, config=config)

    def per_seed(learner, targets):
        key, indices = minibatch_indices(config, learner)
        learner, (losses, _) = jax.lax.scan(
            lambda learner, index: update_step(learning, Hyper.of(config), learner, targets, index), learner, indices)
        return learner.replace(key=key), losses.mean()

    run = jax.jit(seeds.map_seeds(per_seed), out_shardings=seeds.sharding)
    real = seeds.real()
    targets = jax.device_put(jnp.zeros((seeds.padded, config.learner.buffer_capacity), jnp.float32), seeds.sharding)
    with compile_cache.record() as events:
        jax.block_until_ready(run(real, learners, targets))
    compile_s = events.trace_s + events.lower_s + events.compile_s
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(run(real, learners, targets))
        times.append(time.perf_counter() - start)
    median = statistics.median(times)
    return {"updates": updates, "seeds": seeds.num_seeds, "compile_s": compile_s, "median_s": median,
            "updates_per_s": seeds.num_seeds * updates / median}


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door", seeds="0-7")
    parser.add_argument("--updates", type=int, default=None, help="updates per call (default: the env's per cycle)")
    parser.add_argument("--repeats", type=int, default=5, help="timed calls (default: %(default)s)")
    parser.add_argument("--devices", default="auto", help="as train.py (default: auto)")
    args = parser.parse_args()
    from jaxbridge.learn.devices import describe, device_count_arg, select_devices
    devices = select_devices(device_count_arg(args.devices))
    from bench.timings.training import measure_cycles

    config = jaxbridge.make_config(args.env, seeds=args.seed_list)
    run = measure_cycles(config, devices, cycles=2)
    r = measure_updates(run["setup"], run["seeds"], run["learners"], args.updates or config.learner.updates_per_cycle,
                        args.repeats)
    print(f"jax {jax.__version__}, seeds over {describe(devices)} device(s)")
    print(f"{config.env}: {r['seeds']} seeds x {r['updates']} updates (batch {config.learner.batch_size}): compile "
          f"{r['compile_s']:.1f} s, {r['median_s']:.3f} s per call -> {r['updates_per_s']:,.0f} updates/s")


if __name__ == "__main__":
    main()
