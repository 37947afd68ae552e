"""Evaluate a bridge policy on every seed's test tasks and print a table.

    python eval.py --env light_switch_door --bridge oracle --num-seeds 8
"""
from __future__ import annotations

import argparse
import sys
import time

from envs_jax import ENVS
from jaxbridge.cli import non_negative_int, positive_int, run_main

BRIDGE_HELP = ("oracle: the env's hand-written novelty fixer; random: a uniformly random applicable "
               "action whenever stuck; none: pure planning (re-plan whenever stuck)")


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="light_switch_door", choices=sorted(ENVS),
                        help="environment (default: %(default)s)")
    parser.add_argument("--bridge", default="oracle", choices=["oracle", "random", "none"],
                        help=f"which bridge acts when the plan is stuck; {BRIDGE_HELP} (default: %(default)s)")
    parser.add_argument("--num-seeds", type=positive_int, default=8,
                        help="evaluate the test tasks of seeds first-seed .. first-seed+N-1 (default: %(default)s)")
    parser.add_argument("--first-seed", type=non_negative_int, default=0, help="first seed (default: %(default)s)")
    parser.add_argument("--num-tasks", type=positive_int, default=10,
                        help="test tasks per seed (default: %(default)s, as in the paper)")
    parser.add_argument("--rollout-seed", type=non_negative_int, default=0,
                        help="seed of the rollout's randomness (random bridge, skill parameters) (default: %(default)s)")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    from jaxbridge.bridges import make_bridge
    from jaxbridge.evaluate import format_table, run_bridge, summarise
    from jaxbridge.tasks import evaluation_batch

    env_cls = ENVS[args.env]
    seeds = list(range(args.first_seed, args.first_seed + args.num_seeds))
    start = time.perf_counter()
    batch = evaluation_batch(env_cls, seeds, args.num_tasks)
    result = run_bridge(batch, make_bridge(args.bridge, batch.env), seed=args.rollout_seed)
    print(f"{args.env}, bridge = {args.bridge}, {batch.size} test tasks "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    print(format_table(summarise(batch, result)))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
