"""Evaluate bridge policies: on every seed's test tasks, side by side, on ever larger tasks, in pictures.

    python eval.py runs/light_switch_door                    # the latest checkpoint of the "ours" run
    python eval.py runs/light_switch_door --approach no_callplanner   # ... of another approach
    python eval.py runs/light_switch_door --task-size cells=40,doors=8   # ... on larger tasks
    python eval.py runs/doorknobs --sweep novelties          # every approach on 1..10 doors to the goal
    python eval.py runs/lsd_a runs/lsd_b                     # two runs' checkpoints side by side
    python eval.py runs/coffee --render episode.png --gif episode.gif   # draw and animate an episode
    python eval.py --env light_switch_door --bridge oracle --num-seeds 8   # a hand-made bridge
    python eval.py --env coffee --bridge none --render-task 0 --render plan.png   # pure planning, stuck

The generalisation sweep draws, for each number of novelty instances (Light Switch Door: 1..16 doors in
60 cells; Doorknobs: 1..10 doors between start and goal on 7x7 maps; Coffee: 1..6 cups), --sweep-tasks
tasks, the same for every seed and approach, with horizons scaled by the env's rule, and writes
sweep_novelties.png (solve rate vs count, mean and min-max band over seeds), .md and .csv.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from jaxbridge.commands import evaluate
from jaxbridge.learn.approaches import APPROACHES
from jaxbridge.utils import compile_cache
from jaxbridge.utils.cli import ArgumentParser, non_negative_int, positive_float, positive_int, run_main


def parse_args(argv):
    parser = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="*", type=Path, metavar="RUN",
                        help="an experiment directory written by train.py (or one approach's run directory in "
                             "it): evaluate the latest checkpoint greedily; two RUNs: side by side")
    parser.add_argument("--approach", default=None, metavar="NAME",
                        help=f"with experiment directories: which run to evaluate: an approach ({', '.join(APPROACHES)}) "
                             "or, in a train.py --sweep experiment, approach@setting as its directory is named "
                             "(default: ours; --sweep without it takes every run of the experiment)")
    parser.add_argument("--sweep", choices=["novelties"], default=None,
                        help="novelties: evaluate on tasks with 1, 2, ... novelty instances (see above) and "
                             "plot solve rate against their number")
    parser.add_argument("--sweep-tasks", type=positive_int, default=None,
                        help=f"with --sweep: tasks per novelty count, met by every seed (default: {evaluate.SWEEP_TASKS})")
    parser.add_argument("--sweep-seed", type=non_negative_int, default=None,
                        help="with --sweep: seed of the sweep's task draw (default: 0)")
    parser.add_argument("--sweep-out", type=Path, default=None, metavar="DIR",
                        help="with --sweep: where sweep_novelties.png/.md/.csv go (default: the first RUN)")
    parser.add_argument("--task-size", type=evaluate.task_sizes, default=None, metavar="NAME=N[,NAME=N]",
                        help="with a RUN: evaluate on --num-tasks tasks per seed of these sizes instead of its test "
                             "tasks (the env's sized_task: light_switch_door cells=, doors=; doorknobs map=, doors=; "
                             "coffee cups=)")
    parser.add_argument("--env", default="light_switch_door", metavar="NAME",
                        help="environment of a hand-made bridge: a registered name or package.module:Class "
                             "(default: %(default)s)")
    parser.add_argument("--bridge", default="oracle", choices=["oracle", "random", "none"],
                        help="which bridge acts when the plan is stuck; oracle: the env's hand-written novelty fixer; "
                             "random: a uniformly random applicable action whenever stuck; none: pure planning "
                             "(re-plan whenever stuck) (default: %(default)s)")
    parser.add_argument("--test-protocol", default=None, metavar="NAME",
                        help="with --bridge: which of the env's test-task distributions, e.g. jaxbridge (Coffee: 1-4 "
                             "cups, horizon 110) or authors (Coffee: 4 cups, horizon 100; Light Switch Door: horizon "
                             "30) (default: the one train.py trains on; a RUN's is its own)")
    parser.add_argument("--num-seeds", type=positive_int, default=8,
                        help="evaluate the test tasks of seeds first-seed .. first-seed+N-1 (default: %(default)s)")
    parser.add_argument("--first-seed", type=non_negative_int, default=0, help="first seed (default: %(default)s)")
    parser.add_argument("--num-tasks", type=positive_int, default=10,
                        help="tasks per seed: of a hand-made bridge's test tasks, or with a RUN of --task-size "
                             "tasks (a RUN's test tasks are the ones it trained with) (default: %(default)s, as in the paper)")
    parser.add_argument("--rollout-seed", type=non_negative_int, default=0,
                        help="seed of the rollout's randomness (random bridge, skill parameters) (default: %(default)s)")
    parser.add_argument("--render", type=Path, default=None, metavar="PATH.png",
                        help="also draw one evaluated episode to this PNG: the world, the robot's path coloured by "
                             "who was in control (planner, bridge, CallPlanner) and what the bridge fixed (doors it opened; "
                             "Coffee: the jug it twisted, with the arm's height, tilt and wrist over time)")
    parser.add_argument("--gif", type=Path, default=None, metavar="PATH.gif",
                        help="also animate the episode --render draws (or, without --render, the one it would "
                             "pick) to this GIF: one frame per step (at most 120, keeping every change of "
                             "control), each saying who is in control and which skill runs")
    parser.add_argument("--render-task", type=non_negative_int, default=None, metavar="K",
                        help="with --render/--gif: which episode, an index into all evaluated tasks, seed after seed "
                             "(with 10 tasks per seed, K = 23 is the third seed's task 3); default: the solved task "
                             "of the first seed on which the bridge opened the most doors (the first of those; "
                             "task 0 if none is solved)")
    parser.add_argument("--max-memory", type=positive_float, default=None, metavar="GIB",
                        help="refuse an evaluation whose plan tables are estimated to exceed this many GiB "
                             "(default: the memory available when it starts)")
    parser.add_argument("--no-compile-cache", action="store_true", help=compile_cache.HELP)
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    compile_cache.enable(not args.no_compile_cache)  # before anything compiles
    return evaluate.run(args)


if __name__ == "__main__":
    sys.exit(run_main(main))
