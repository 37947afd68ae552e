"""Evaluate bridge policies on every seed's test tasks and print a table.

    python eval.py runs/light_switch_door                    # the latest checkpoint of the "ours" run
    python eval.py runs/light_switch_door --approach no_callplanner   # ... of another approach
    python eval.py runs/light_switch_door --cells 40 --doors 8   # ... on larger tasks
    python eval.py --env light_switch_door --bridge oracle --num-seeds 8   # a hand-made bridge
    python eval.py --env doorknobs --bridge oracle --render episode.png      # ... and draw an episode
    python eval.py --env coffee --bridge none --render-task 0 --render plan.png   # pure planning, stuck
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from envs_jax import ENVS
from jaxbridge.approaches import APPROACHES
from jaxbridge import compile_cache
from jaxbridge.cli import UsageError, non_negative_int, positive_int, run_main

BRIDGE_LABELS = {"oracle": "oracle bridge", "random": "random bridge", "none": "pure planning"}
BRIDGE_HELP = ("oracle: the env's hand-written novelty fixer; random: a uniformly random applicable "
               "action whenever stuck; none: pure planning (re-plan whenever stuck)")


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", nargs="?", type=Path, default=None,
                        help="an experiment directory written by train.py (or one approach's run directory in "
                             "it): evaluate the latest checkpoint greedily")
    parser.add_argument("--approach", choices=list(APPROACHES), default=None,
                        help="with an experiment directory: which approach's run to evaluate (default: ours)")
    parser.add_argument("--cells", type=positive_int, default=None,
                        help="with a run: evaluate on tasks of this many cells (Light Switch Door) instead of the test tasks")
    parser.add_argument("--doors", type=non_negative_int, default=None,
                        help="with --cells: doors per task, in distinct cells other than the light's")
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
    parser.add_argument("--render", type=Path, default=None, metavar="PATH.png",
                        help="also draw one evaluated episode to this PNG: the world, the robot's path coloured by "
                             "who was in control (planner, bridge, CallPlanner) and what the bridge fixed (doors it opened; "
                             "Coffee: the jug it twisted, with the arm's height, tilt and wrist over time)")
    parser.add_argument("--render-task", type=non_negative_int, default=None, metavar="K",
                        help="with --render: which episode, an index into all evaluated tasks, seed after seed "
                             "(with 10 tasks per seed, K = 23 is the third seed's task 3); default: the solved task "
                             "of the first seed on which the bridge opened the most doors (the first of those; "
                             "task 0 if none is solved)")
    parser.add_argument("--no-compile-cache", action="store_true", help=compile_cache.HELP)
    return parser.parse_args(argv)


def check_render_args(args) -> None:
    if args.render_task is not None and args.render is None:
        raise UsageError("--render-task picks the episode that --render draws; give --render PATH.png too")
    if args.render is None:
        return
    if args.render.suffix.lower() != ".png":
        raise UsageError(f"--render writes a PNG image: give a path ending in .png, got {args.render}")
    if not args.render.parent.is_dir():
        raise UsageError(f"--render: directory {args.render.parent} does not exist")


def check_render_task(args, num_tasks: int) -> None:
    if args.render_task is not None and args.render_task >= num_tasks:
        raise UsageError(f"--render-task must be below {num_tasks}, the number of evaluated tasks, "
                         f"got {args.render_task}")


def render(args, batch, bridge, bridge_params, controls, result, label: str) -> None:
    """Re-run the chosen evaluated episode with recording on and draw it to args.render."""
    from jaxbridge.artifacts import write_atomic
    from jaxbridge.render import drawer_for, pick_episode, render_episode, trace_episodes

    chosen = [args.render_task] if args.render_task is not None else np.flatnonzero(batch.seeds == batch.seeds[0])
    traces = trace_episodes(batch, bridge, bridge_params, chosen, args.rollout_seed, controls, expected=result)
    trace = traces[0] if args.render_task is not None else pick_episode(traces)
    try:
        write_atomic(args.render, render_episode(batch.env, trace, label))
    except OSError as err:
        raise UsageError(f"cannot write {args.render}: {err.strerror or err}") from None
    summary = drawer_for(batch.env).bridge_summary(trace)
    print(f"drew seed {trace.seed}, task {trace.task} ({'solved' if trace.success else 'not solved'} in "
          f"{trace.steps} steps, {summary}) to {args.render}")


def run_directory(path: Path, approach: str | None) -> Path:
    """The run to evaluate: `path` itself, or its approach's run inside an experiment directory."""
    if (path / "experiment.json").is_file():
        chosen = path / (approach or "ours")
        if not (chosen / "config.json").is_file():
            held = sorted(p.name for p in path.iterdir() if (p / "config.json").is_file())
            raise UsageError(f"{path} holds no {approach or 'ours'} run (it holds: {', '.join(held) or 'none'}); "
                             f"pick one with --approach")
        return chosen
    if approach is not None and (path / "config.json").is_file():
        raise UsageError(f"--approach picks a run inside an experiment directory; {path} is a single run")
    return path


def evaluate_checkpoint(args) -> int:
    from jaxbridge.checkpoint import CheckpointError
    from jaxbridge.evaluate import evaluate_run, format_table, summarise

    args.run = run_directory(args.run, args.approach)
    config_path = args.run / "config.json"
    if not config_path.is_file():
        raise UsageError(f"{args.run} is not a run directory (no config.json); train one with train.py")
    try:
        env = json.loads(config_path.read_text())["env"]
    except (ValueError, KeyError):
        raise UsageError(f"{config_path} is not a valid run config") from None
    if (args.cells is None) != (args.doors is None):
        raise UsageError("--cells and --doors go together")
    sized = None
    if args.cells is not None:
        if env != "light_switch_door":
            raise UsageError(f"--cells/--doors apply to light_switch_door runs only, this run is {env}")
        from envs_jax import light_switch_door as lsd
        if args.doors > args.cells - 1:
            raise UsageError(f"--doors must be at most cells - 1 = {args.cells - 1}, got {args.doors}")
        sized = lambda rng: lsd.sized_task(rng, args.cells, args.doors)
    start = time.perf_counter()
    try:
        config, step, batch, result, policy = evaluate_run(args.run, sized, args.num_tasks, args.rollout_seed)
    except (CheckpointError, ValueError) as err:
        raise UsageError(str(err)) from None
    what = f"{args.num_tasks} tasks of {args.cells} cells, {args.doors} doors per seed" if sized else "test tasks"
    print(f"{args.run}: {config.env}, {config.approach}, checkpoint of cycle {step}, greedy bridge, {what} "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    print(format_table(summarise(batch, result)))
    if args.render is not None:
        check_render_task(args, batch.size)
        render(args, batch, *policy, result,
               f"greedy bridge of {config.approach}, cycle {step}")
    return 0


def main(argv=None) -> int:
    args = parse_args(argv)
    check_render_args(args)
    compile_cache.enable(not args.no_compile_cache)  # before anything compiles
    if args.approach is not None and args.run is None:
        raise UsageError("--approach needs an experiment directory to pick the run from")
    if args.run is not None:
        return evaluate_checkpoint(args)
    from jaxbridge.bridges import make_bridge
    from jaxbridge.evaluate import format_table, run_bridge, summarise
    from jaxbridge.meta_policy import Controls
    from jaxbridge.tasks import evaluation_batch

    env_cls = ENVS[args.env]
    seeds = list(range(args.first_seed, args.first_seed + args.num_seeds))
    start = time.perf_counter()
    batch = evaluation_batch(env_cls, seeds, args.num_tasks)
    check_render_task(args, batch.size)
    bridge = make_bridge(args.bridge, batch.env)
    result = run_bridge(batch, bridge, seed=args.rollout_seed)
    print(f"{args.env}, bridge = {args.bridge}, {batch.size} test tasks "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    print(format_table(summarise(batch, result)))
    if args.render is not None:
        render(args, batch, bridge, None, Controls(), result, BRIDGE_LABELS[args.bridge])
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
