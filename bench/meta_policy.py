"""Env steps per second of the meta-policy (planner + oracle bridge) on Light Switch Door test tasks.

    python -m bench.meta_policy [--repeats 30]

Counts only steps that episodes really take (finished episodes idle until the longest one ends).
Prints compile time and the median over repeats of steady-state throughput.
"""
from __future__ import annotations

import argparse
import statistics
import time

import jax

from envs_jax import light_switch_door as lsd
from envs_jax.light_switch_door import LightSwitchDoor
from jaxbridge.bridges import make_bridge
from jaxbridge.meta_policy import rollout
from jaxbridge.tasks import evaluation_batch, make_batch


def measure(batch, repeats: int) -> dict:
    bridge = make_bridge("oracle", batch.env)

    def once(i):
        result, _ = rollout(batch.env, bridge, None, batch.tasks, batch.tables, batch.horizons,
                            jax.random.split(jax.random.key(i), batch.size), batch.max_steps)
        return jax.block_until_ready(result)

    start = time.perf_counter()
    result = once(0)
    compile_s = time.perf_counter() - start
    times = []
    for i in range(repeats):
        start = time.perf_counter()
        once(i + 1)
        times.append(time.perf_counter() - start)
    steps = int(result.steps.sum())
    median = statistics.median(times)
    return dict(episodes=batch.size, steps=steps, solved=float(result.success.mean()), compile_s=compile_s,
                median_ms=median * 1e3, steps_per_s=steps / median)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=30, help="timed rollouts per case (default: %(default)s)")
    args = parser.parse_args()
    cases = {
        "1 episode (seed 0, task 0)": make_batch(LightSwitchDoor, [lsd.test_tasks(0)[0]], [0]),
        "1 seed x 10 tasks": evaluation_batch(LightSwitchDoor, [0]),
        "8 seeds x 10 tasks": evaluation_batch(LightSwitchDoor, list(range(8))),
    }
    print(f"jax {jax.__version__}, devices: {jax.devices()}")
    print(f"{'case':<28} {'episodes':>8} {'env steps':>9} {'solved':>6} {'compile s':>9} {'ms/rollout':>10} "
          f"{'env steps/s':>12}")
    for name, batch in cases.items():
        r = measure(batch, args.repeats)
        print(f"{name:<28} {r['episodes']:>8} {r['steps']:>9} {r['solved']:>6.2f} {r['compile_s']:>9.2f} "
              f"{r['median_ms']:>10.2f} {r['steps_per_s']:>12,.0f}")


if __name__ == "__main__":
    main()
