"""Seconds for a greedy evaluation of 8 seeds x 100 test tasks per env, through eval.py's path
(`TrainedPolicy.run`: one jitted, vmapped rollout of every episode): building the tasks on the host,
the first call (compilation included), then the median of 3 calls.

    python -m bench.timings.evaluation [--envs light_switch_door,doorknobs,coffee] [--seeds 0-7] [--tasks 100]
    python -m bench.timings.evaluation --run runs/doorknobs/ours     # a trained run's checkpoint

Without --run each env's networks are freshly initialised: an untrained greedy bridge rarely solves a
task, so its episodes run to the horizon, the slowest case for a rollout.
"""
from __future__ import annotations

import jaxbridge
import os
import statistics
import time
from pathlib import Path

import jax
import numpy as np

from bench.command import CommandParser
from envs_jax import BUILTIN
from jaxbridge.run.evaluate import TrainedPolicy, load_policy
from jaxbridge.learn.setup import make_setup
from jaxbridge.core.tasks import evaluation_batch


def fresh_policy(env: str, seeds: list[int]) -> TrainedPolicy:
    config = jaxbridge.make_config(env, seeds=seeds)
    setup = make_setup(config)
    return TrainedPolicy(setup, 0, setup.init_learners())


def measure(policy: TrainedPolicy, tasks: int) -> dict:
    start = time.perf_counter()
    batch = evaluation_batch(policy.setup.env_cls, policy.config.seeds, tasks, protocol=policy.config.test_protocol)
    build = time.perf_counter() - start

    def timed_run():
        start = time.perf_counter()
        result = jax.block_until_ready(policy.run(batch))
        return time.perf_counter() - start, result

    first, result = timed_run()
    runs = [timed_run()[0] for _ in range(3)]
    steps = int(np.asarray(result.steps).sum())
    return {"env": policy.config.env, "episodes": batch.size, "env_steps": steps, "build_s": build,
            "first_call_s": first, "run_s": statistics.median(runs), "solve_rate": float(np.mean(result.success))}


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, seeds="0-7")
    parser.add_argument("--envs", default=",".join(BUILTIN), help="comma-separated envs (default: %(default)s)")
    parser.add_argument("--tasks", type=int, default=100, help="test tasks per seed (default: %(default)s)")
    parser.add_argument("--run", type=Path, default=None, help="time this run's checkpoint instead")
    args = parser.parse_args()
    policies = ([load_policy(args.run)] if args.run else
                [fresh_policy(env, args.seed_list) for env in args.envs.split(",")])
    print(f"load average {os.getloadavg()[0]:.1f}; {jax.device_count()} device(s)")
    print(f"{'env':<18} {'episodes':>8} {'env steps':>9} {'tasks s':>8} {'1st call s':>10} {'run s':>6} "
          f"{'env steps/s':>11} {'solved':>6}")
    for policy in policies:
        m = measure(policy, args.tasks)
        print(f"{m['env']:<18} {m['episodes']:>8} {m['env_steps']:>9} {m['build_s']:>8.1f} {m['first_call_s']:>10.1f} "
              f"{m['run_s']:>6.2f} {m['env_steps'] / m['run_s']:>11,.0f} {m['solve_rate']:>6.2f}")
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
