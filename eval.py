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
import time
from pathlib import Path

import jaxbridge
from jaxbridge.utils import compile_cache
from jaxbridge.utils.cli import ArgumentParser, name_values, non_negative_int, positive_float, positive_int, run_main


def parse_args(argv):
    parser = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="*", type=Path, metavar="RUN",
                        help="an experiment directory written by train.py (or one approach's run directory in "
                             "it): evaluate the latest checkpoint greedily; two RUNs: side by side")
    parser.add_argument("--approach", default=None, metavar="NAME",
                        help=f"with experiment directories: which run to evaluate: an approach ({', '.join(jaxbridge.APPROACHES)}) "
                             "or, in a train.py --sweep experiment, approach@setting as its directory is named "
                             "(default: ours; --sweep without it takes every run of the experiment)")
    parser.add_argument("--sweep", choices=["novelties"], default=None,
                        help="novelties: evaluate on tasks with 1, 2, ... novelty instances (see above) and "
                             "plot solve rate against their number")
    parser.add_argument("--sweep-tasks", type=positive_int, default=None,
                        help=f"with --sweep: tasks per novelty count, met by every seed (default: {jaxbridge.SWEEP_TASKS})")
    parser.add_argument("--sweep-seed", type=non_negative_int, default=None,
                        help="with --sweep: seed of the sweep's task draw (default: 0)")
    parser.add_argument("--sweep-out", type=Path, default=None, metavar="DIR",
                        help="with --sweep: where sweep_novelties.png/.md/.csv go (default: the first RUN)")
    parser.add_argument("--task-size", type=name_values, default=None, metavar="NAME=N[,NAME=N]",
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
                        help="which of the env's test-task distributions to evaluate on, e.g. jaxbridge (Coffee: 1-4 "
                             "cups, horizon 110), authors (Coffee: 4 cups, horizon 100; Light Switch Door: horizon "
                             "30) or held_out (multi_novelty: kinds combined as no training task combines them); "
                             "with a RUN: its seeds' test tasks under it (default: the one train.py trains on; a "
                             "RUN's is its own)")
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
                             "Coffee: the jug it twisted, with the arm's height, tilt and wrist over time); a learned "
                             "selector's rings around the objects it attended to at each decision, as opaque as the weight")
    parser.add_argument("--gif", type=Path, default=None, metavar="PATH.gif",
                        help="also animate the episode --render draws (or, without --render, the one it would "
                             "pick) to this GIF: one frame per step (at most 120, keeping every change of "
                             "control), each saying who is in control and which skill runs")
    parser.add_argument("--render-task", type=non_negative_int, default=None, metavar="K",
                        help="with --render/--gif: which episode, an index into all evaluated tasks, seed after seed "
                             "(with 10 tasks per seed, K = 23 is the third seed's task 3); default: the solved task "
                             "of the first seed on which the bridge opened the most doors (the first of those; "
                             "task 0 if none is solved)")
    parser.add_argument("--attention", action="store_true", help="with a RUN of ours_learned_selection: per seed, how "
                        "often its attention at a bridge decision is on the object the env's fix acts on, and why not")
    parser.add_argument("--planner-alone", action="store_true",
                        help="with a RUN of ours_model_repair: its learned model's planner alone, no bridge (a stall "
                             "is a failure), on the RUN's tasks (its test tasks, --test-protocol's, --task-size's or --sweep's)")
    parser.add_argument("--domain", type=Path, default=None, metavar="FILE.pddl", help="with a RUN of ours_model_repair: "
                        "plan with this PDDL domain (its models/seed<N>.pddl, edited or not) as every seed's model")
    parser.add_argument("--cycle", type=positive_int, default=None, metavar="N",
                        help="with RUNs: evaluate the checkpoint saved after cycle N (a run keeps its latest two and "
                             "those of train.py --keep-cycles) (default: the latest)")
    parser.add_argument("--max-memory", type=positive_float, default=None, metavar="GIB", help="refuse an evaluation "
                        "whose plan tables would exceed this many GiB, or sweep a repair run's seeds in groups within it (default: available)")
    parser.add_argument("--no-compile-cache", action="store_true", help=compile_cache.HELP)
    return parser.parse_args(argv)


def check_flags(args) -> None:
    """Refuse flags that do not go together, before anything loads."""
    given = [flag for flag in ("sweep_out", "sweep_tasks", "sweep_seed") if getattr(args, flag) is not None]
    drawing = args.render is not None or args.gif is not None
    refusals = [(args.render_task is not None and not drawing, "--render-task picks the episode that --render/--gif "
                 "draw; give --render PATH.png or --gif PATH.gif too"),
                (args.approach is not None and not args.runs, "--approach needs an experiment directory to pick the run from"),
                (args.sweep is None and given, f"--{given[0].replace('_', '-')} goes with --sweep" if given else ""),
                (args.sweep is not None and not args.runs, "--sweep evaluates trained runs: give an experiment or run directory"),
                (args.sweep is not None and (drawing or args.task_size is not None),
                 "--sweep draws its own tasks; it does not combine with --render/--gif or --task-size"),
                (args.sweep is None and len(args.runs) > 2, f"give one RUN, or two to compare side by side; got {len(args.runs)}"),
                (len(args.runs) == 2 and drawing, "--render/--gif draw an episode of one run; give one RUN"),
                (not args.runs and args.task_size is not None, "--task-size evaluates a trained RUN on larger tasks; give a RUN"),
                (args.attention and len(args.runs) != 1, "--attention reports on one RUN's evaluation; give one RUN"),
                (args.planner_alone and len(args.runs) != 1 and not args.sweep, "--planner-alone evaluates one RUN (or --sweep's)"),
                (args.test_protocol is not None and args.runs and (args.sweep is not None or args.task_size is not None),
                 "--test-protocol picks a RUN's test tasks; it does not combine with --sweep or --task-size"),
                (args.domain is not None and (len(args.runs) != 1 or args.sweep is not None),
                 "--domain replaces one RUN's learned models; give one RUN (not with --sweep)"),
                (args.cycle is not None and (not args.runs or args.sweep is not None),
                 "--cycle picks a trained RUN's checkpoint to evaluate; give a RUN (not with --sweep)")]
    for path, suffix, flag in ((args.render, ".png", "--render"), (args.gif, ".gif", "--gif")):
        refusals += [(path is not None and path.suffix.lower() != suffix, f"{flag} writes a {suffix[1:].upper()} image: "
                      f"give a path ending in {suffix}, got {path}"),
                     (path is not None and not path.parent.is_dir(), f"{flag}: directory {path and path.parent} does not exist")]
    for refused, message in refusals:
        if refused:
            raise jaxbridge.InputError(message)


def evaluate(args, policy: jaxbridge.Policy) -> jaxbridge.Episodes:
    """A run's latest checkpoint on its test tasks or --task-size tasks, with a header line."""
    start, run = time.perf_counter(), policy.planner_alone if args.planner_alone else policy.evaluate
    episodes = run(task_size=args.task_size, num_tasks=args.num_tasks, rollout_seed=args.rollout_seed,
                   max_memory=args.max_memory, test_protocol=args.test_protocol)
    what = (f"{args.num_tasks} tasks per seed of " + ", ".join(f"{k} {v}" for k, v in args.task_size.items())
            if args.task_size else "test tasks" + (f" ({args.test_protocol} protocol)" if args.test_protocol else ""))
    print(f"{policy.run_dir}: {policy.config.env}, {policy.config.approach}, checkpoint of cycle {policy.cycle}, "
          f"{'learned planner alone' if args.planner_alone else 'greedy bridge'}, {what} "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    return episodes


def sweep(args) -> int:
    out = args.sweep_out or args.runs[0]
    if not out.is_dir():
        raise jaxbridge.InputError(f"--sweep-out: directory {out} does not exist")
    start = time.perf_counter()
    result = jaxbridge.sweep_novelties(jaxbridge.sweep_lines(args.runs, args.approach), args.sweep_tasks or jaxbridge.SWEEP_TASKS,
                                       args.sweep_seed or 0, args.rollout_seed, lambda label: print(f"  {label} ...", flush=True),
                                       args.planner_alone, args.max_memory)
    print(f"{result.title} ({time.perf_counter() - start:.1f} s including compilation)")
    print(result.markdown(), end="")
    result.write(out)
    print(f"wrote {out / 'sweep_novelties.png'}, .md and .csv")
    return 0


def draw(args, bridges: jaxbridge.Bridges, episodes: jaxbridge.Episodes) -> None:
    if args.render is not None or args.gif is not None:
        drawn = bridges.draw(episodes, args.render, args.gif, args.render_task, args.rollout_seed)
        print(f"drew seed {drawn.seed}, task {drawn.task} ({'solved' if drawn.success else 'not solved'} in "
              f"{drawn.steps} steps, {drawn.summary}) to {' and '.join(map(str, drawn.paths))}")


def main(argv=None) -> int:
    args = parse_args(argv)
    compile_cache.enable(not args.no_compile_cache)  # before anything compiles
    check_flags(args)
    if args.sweep is not None:
        return sweep(args)
    policies = {str(run): jaxbridge.load(run, args.approach, args.cycle, args.domain) for run in args.runs}
    envs = {policy.config.env for policy in policies.values()}
    if len(envs) > 1:
        raise jaxbridge.InputError(f"side by side needs runs of one env, got {', '.join(sorted(envs))}")
    if len(policies) == 2:
        print(jaxbridge.side_by_side({run: evaluate(args, policy) for run, policy in policies.items()}))
    elif policies:
        policy = policies[str(args.runs[0])]
        episodes = evaluate(args, policy)
        print(episodes.table())
        if args.attention:
            looked = policy.attention(episodes, args.rollout_seed)
            print(looked.per_seed())
            print(looked.diagnosis())
        draw(args, policy, episodes)
    else:
        start, bridge = time.perf_counter(), jaxbridge.hand_made(args.env, args.bridge, args.test_protocol)
        episodes = bridge.evaluate(range(args.first_seed, args.first_seed + args.num_seeds), args.num_tasks,
                                   args.rollout_seed, args.max_memory)
        print(f"{bridge.describe(len(episodes.seeds))} ({time.perf_counter() - start:.1f} s including compilation)")
        print(episodes.table())
        draw(args, bridge, episodes)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
