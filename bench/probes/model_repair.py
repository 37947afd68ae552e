"""The planner's model learned from a seed's exploration, then its planner alone: per seed, record the
meta-policy with the random bridge on the seed's training tasks (what a bridge explores before it has
learned anything), learn the repaired model (jaxbridge.learn_model; with --given over the env's declared
novelty predicates instead of invented ones), and run its plans with no bridge on the seed's test tasks
of each of the env's test protocols (a skill that changes nothing fails) and on tasks of the env's
generalisation sweep at its largest count of novelty instances.

    python -m bench.probes.model_repair --env multi_novelty --seeds 0-7
    python -m bench.probes.model_repair --env multi_novelty --seeds 0-7 --given   # the env's declared predicates

A probe of development seeds: it refuses the test-seed sets (the model-repair study runs those).
"""
from __future__ import annotations

import argparse
import time
from collections import Counter

import numpy as np

import jaxbridge
from bench.command import CommandParser
from jaxbridge.utils.cli import positive_int
from jaxbridge.utils.stats import bootstrap_ci, ci_text


def parse(argv=None) -> argparse.Namespace:
    parser = CommandParser(__spec__.name, __doc__, env="multi_novelty", seeds="0-7")
    parser.add_argument("--episodes", type=positive_int, default=20, help="training tasks per rollout (default: %(default)s)")
    parser.add_argument("--rollouts", type=positive_int, default=3, help="rollouts of them recorded (default: %(default)s)")
    parser.add_argument("--tasks", type=positive_int, default=10, help="test tasks per seed and protocol (default: %(default)s)")
    parser.add_argument("--given", action="store_true",
                        help="learn over the env's declared novelty predicates, not invented ones (the upper bound)")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse(argv)
    env_cls = jaxbridge.load_env(args.env)
    sweep = env_cls.novelty_sweep
    largest = {f"{sweep.counts[-1]} {sweep.counted}": {"novelties": sweep.counts[-1]}} if sweep else {}
    runs = {p: {"protocol": p} for p in env_cls.test_protocols} | largest
    rates: dict[str, list[float]] = {name: [] for name in runs}
    for seed in args.seed_list:
        start = time.perf_counter()
        segments = jaxbridge.record_segments(env_cls, seed, args.episodes, args.rollouts)
        model = jaxbridge.learn_model(env_cls, segments, given=args.given)
        line = [f"seed {seed:>3}: {len(model.learned_operators)} learned operators"]
        for name, which in runs.items():
            run = jaxbridge.plan_alone(model, env_cls, seed, args.tasks, **which)
            rates[name].append(run.solve_rate)
            ended = Counter(e.ended for e in run.episodes)
            line.append(f"{name} {run.solve_rate:.2f} ({', '.join(f'{n} {k}' for k, n in sorted(ended.items()))})")
        print("; ".join(line) + f"; {time.perf_counter() - start:.0f} s", flush=True)
    for name, values in rates.items():
        low, high = bootstrap_ci(np.asarray(values))
        print(f"{args.env} {name}, planner alone{', given predicates' if args.given else ''}, seeds {args.seeds}: "
              f"{ci_text(float(np.mean(values)), (low, high))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
