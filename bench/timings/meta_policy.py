"""Env steps per second of the meta-policy (planner + oracle bridge) on an env's test tasks.

    python -m bench.timings.meta_policy [--env light_switch_door] [--repeats 30]

Counts only steps that episodes really take (finished episodes idle until the longest one ends).
Prints compile time and the median over repeats of steady-state throughput.
"""
from __future__ import annotations

import statistics
import time

import jax

from bench.command import CommandParser
from envs_jax import env_class
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import evaluation_batch


def measure(batch, repeats: int) -> dict:
    bridge = make_bridge("oracle", batch.env)

    def once(i):
        result, _ = rollout(MetaPolicy(batch.env, bridge), batch.arrays,
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


def cases(env_cls, full: bool = True) -> dict:
    """The batches measured: one episode, (1 seed x 10 tasks,) 8 seeds x 10 tasks."""
    out = {"1 seed x 1 task": evaluation_batch(env_cls, [0], 1)}
    if full:
        out["1 seed x 10 tasks"] = evaluation_batch(env_cls, [0])
    out["8 seeds x 10 tasks"] = evaluation_batch(env_cls, list(range(8)))
    return out


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door")
    parser.add_argument("--repeats", type=int, default=30, help="timed rollouts per case (default: %(default)s)")
    args = parser.parse_args()
    print(f"jax {jax.__version__}, devices: {jax.devices()}")
    print(f"{'case':<28} {'episodes':>8} {'env steps':>9} {'solved':>6} {'compile s':>9} {'ms/rollout':>10} "
          f"{'env steps/s':>12}")
    for name, batch in cases(env_class(args.env)).items():
        r = measure(batch, args.repeats)
        print(f"{name:<28} {r['episodes']:>8} {r['steps']:>9} {r['solved']:>6.2f} {r['compile_s']:>9.2f} "
              f"{r['median_ms']:>10.2f} {r['steps_per_s']:>12,.0f}")


if __name__ == "__main__":
    main()
