"""Evaluate bridge policies: on every seed's test tasks, side by side, on ever larger tasks, in pictures.

    python eval.py runs/light_switch_door                    # the latest checkpoint of the "ours" run
    python eval.py runs/light_switch_door --approach no_callplanner   # ... of another approach
    python eval.py runs/light_switch_door --cells 40 --doors 8   # ... on larger tasks
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

import numpy as np

from envs_jax import ENVS
from jaxbridge.learn.approaches import APPROACHES
from jaxbridge.utils import compile_cache
from jaxbridge.utils.cli import UsageError, non_negative_int, positive_int, run_main

SWEEP_TASKS = 10
BRIDGE_LABELS = {"oracle": "oracle bridge", "random": "random bridge", "none": "pure planning"}
BRIDGE_HELP = ("oracle: the env's hand-written novelty fixer; random: a uniformly random applicable "
               "action whenever stuck; none: pure planning (re-plan whenever stuck)")


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="*", type=Path, metavar="RUN",
                        help="an experiment directory written by train.py (or one approach's run directory in "
                             "it): evaluate the latest checkpoint greedily; two RUNs: side by side")
    parser.add_argument("--approach", choices=list(APPROACHES), default=None,
                        help="with experiment directories: which approach's run to evaluate (default: ours; "
                             "--sweep without it takes every approach of the experiment)")
    parser.add_argument("--sweep", choices=["novelties"], default=None,
                        help="novelties: evaluate on tasks with 1, 2, ... novelty instances (see above) and "
                             "plot solve rate against their number")
    parser.add_argument("--sweep-tasks", type=positive_int, default=None,
                        help=f"with --sweep: tasks per novelty count, met by every seed (default: {SWEEP_TASKS})")
    parser.add_argument("--sweep-seed", type=non_negative_int, default=None,
                        help="with --sweep: seed of the sweep's task draw (default: 0)")
    parser.add_argument("--sweep-out", type=Path, default=None, metavar="DIR",
                        help="with --sweep: where sweep_novelties.png/.md/.csv go (default: the first RUN)")
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
                        help="tasks per seed: of a hand-made bridge's test tasks, or with a RUN of --cells/--doors "
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
    parser.add_argument("--no-compile-cache", action="store_true", help=compile_cache.HELP)
    return parser.parse_args(argv)


def check_render_args(args) -> None:
    if args.render_task is not None and args.render is None and args.gif is None:
        raise UsageError("--render-task picks the episode that --render/--gif draw; give --render PATH.png "
                         "or --gif PATH.gif too")
    for flag, path, suffix in (("--render", args.render, ".png"), ("--gif", args.gif, ".gif")):
        if path is None:
            continue
        if path.suffix.lower() != suffix:
            raise UsageError(f"{flag} writes a {suffix[1:].upper()} image: give a path ending in {suffix}, got {path}")
        if not path.parent.is_dir():
            raise UsageError(f"{flag}: directory {path.parent} does not exist")


def check_render_task(args, num_tasks: int) -> None:
    if args.render_task is not None and args.render_task >= num_tasks:
        raise UsageError(f"--render-task must be below {num_tasks}, the number of evaluated tasks, "
                         f"got {args.render_task}")


def render(args, batch, bridge, bridge_params, controls, result, label: str) -> None:
    """Re-run the chosen evaluated episode with recording on; draw it to args.render, animate it to args.gif."""
    from jaxbridge.viz.animate import render_gif
    from jaxbridge.utils.files import write_atomic
    from jaxbridge.viz.render import drawer_for, pick_episode, render_episode, trace_episodes

    chosen = [args.render_task] if args.render_task is not None else np.flatnonzero(batch.seeds == batch.seeds[0])
    traces = trace_episodes(batch, bridge, bridge_params, chosen, args.rollout_seed, controls, expected=result)
    trace = traces[0] if args.render_task is not None else pick_episode(traces)
    drawn = []
    for path, draw in ((args.render, render_episode), (args.gif, render_gif)):
        if path is None:
            continue
        try:
            write_atomic(path, draw(batch.env, trace, label))
        except OSError as err:
            raise UsageError(f"cannot write {path}: {err.strerror or err}") from None
        drawn.append(str(path))
    summary = drawer_for(batch.env).bridge_summary(trace)
    print(f"drew seed {trace.seed}, task {trace.task} ({'solved' if trace.success else 'not solved'} in "
          f"{trace.steps} steps, {summary}) to {' and '.join(drawn)}")


def run_directory(path: Path, approach: str | None) -> Path:
    """The run to evaluate: `path` itself, or its approach's run inside an experiment directory."""
    if (path / "experiment.json").is_file():
        chosen = path / (approach or "ours")
        if not (chosen / "config.json").is_file():
            raise UsageError(f"{path} holds no {approach or 'ours'} run (it holds: "
                             f"{', '.join(held_runs(path)) or 'none'}); pick one with --approach")
        return chosen
    if approach is not None and (path / "config.json").is_file():
        raise UsageError(f"--approach picks a run inside an experiment directory; {path} is a single run")
    if not (path / "config.json").is_file():
        raise UsageError(f"{path} is not a run directory (no config.json); train one with train.py")
    return path


def held_runs(experiment: Path) -> list[str]:
    return sorted(p.name for p in experiment.iterdir() if (p / "config.json").is_file())


def run_env(run: Path) -> str:
    from jaxbridge.run.runner import load_config

    try:
        return load_config(run).env
    except ValueError as err:
        raise UsageError(str(err)) from None


def sized_tasks(args, env: str):
    """--cells/--doors as a task drawer, or None for each seed's test tasks."""
    if (args.cells is None) != (args.doors is None):
        raise UsageError("--cells and --doors go together")
    if args.cells is None:
        return None
    if env != "light_switch_door":
        raise UsageError(f"--cells/--doors apply to light_switch_door runs only, this run is {env}")
    from envs_jax.light_switch_door import env as lsd
    if args.doors > args.cells - 1:
        raise UsageError(f"--doors must be at most cells - 1 = {args.cells - 1}, got {args.doors}")
    return lambda rng: lsd.sized_task(rng, args.cells, args.doors)


def evaluate(args, run: Path):
    """evaluate_run with its errors as usage errors, and a header line."""
    from jaxbridge.run.checkpoint import CheckpointError
    from jaxbridge.run.evaluate import evaluate_run

    sized = sized_tasks(args, run_env(run))
    start = time.perf_counter()
    try:
        config, step, batch, result, policy = evaluate_run(run, sized, args.num_tasks, args.rollout_seed)
    except (CheckpointError, ValueError) as err:
        raise UsageError(str(err)) from None
    what = f"{args.num_tasks} tasks of {args.cells} cells, {args.doors} doors per seed" if sized else "test tasks"
    print(f"{run}: {config.env}, {config.approach}, checkpoint of cycle {step}, greedy bridge, {what} "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    return config, step, batch, result, policy


def evaluate_checkpoint(args, run: Path) -> int:
    from jaxbridge.run.evaluate import format_table, summarise

    config, step, batch, result, policy = evaluate(args, run)
    print(format_table(summarise(batch, result)))
    if args.render is not None or args.gif is not None:
        check_render_task(args, batch.size)
        render(args, batch, *policy, result, f"greedy bridge of {config.approach}, cycle {step}")
    return 0


def compare_checkpoints(args, runs: list[Path]) -> int:
    """The same evaluation of each run, then side by side."""
    from jaxbridge.run.evaluate import format_comparison, summarise

    envs = {run_env(run) for run in runs}
    if len(envs) > 1:
        raise UsageError(f"side by side needs runs of one env, got {', '.join(sorted(envs))}")
    columns = {}
    for run, given in zip(runs, args.runs):
        _, _, batch, result, _ = evaluate(args, run)
        columns[str(given)] = summarise(batch, result)
    print(format_comparison(columns))
    return 0


def sweep_lines(args) -> dict[str, Path]:
    """The sweep's lines: every approach of a lone experiment directory (unless --approach picks one),
    else one line per RUN."""
    from jaxbridge.learn.approaches import get_approach

    if len(args.runs) == 1 and args.approach is None and (args.runs[0] / "experiment.json").is_file():
        held = held_runs(args.runs[0])
        if not held:
            raise UsageError(f"{args.runs[0]} holds no runs yet")
        order = [a for a in APPROACHES if a in held]
        return {get_approach(a).label: args.runs[0] / a for a in order}
    return {str(given): run_directory(given, args.approach) for given in args.runs}


def sweep(args) -> int:
    from jaxbridge.utils.files import write_atomic
    from jaxbridge.run.checkpoint import CheckpointError
    from jaxbridge.run.evaluate import load_policy
    from jaxbridge.run.sweep import evaluate_sweep, plot_sweep, sweep_csv, sweep_markdown

    args.sweep_tasks = args.sweep_tasks or SWEEP_TASKS
    out = args.sweep_out or args.runs[0]
    if not out.is_dir():
        raise UsageError(f"--sweep-out: directory {out} does not exist")
    lines = sweep_lines(args)
    start = time.perf_counter()
    try:
        policies = {label: load_policy(run) for label, run in lines.items()}
        result = evaluate_sweep(policies, args.sweep_tasks, args.sweep_seed or 0, args.rollout_seed,
                                progress=lambda label: print(f"  {label} ...", flush=True))
    except (CheckpointError, ValueError) as err:
        raise UsageError(str(err)) from None
    cycles = ", ".join(sorted({f"cycle {p.step}" for p in policies.values()}))
    title = (f"{result.env}: greedy bridges ({cycles}) on {args.sweep_tasks} tasks per count, "
             f"{result.counted} 1..{max(result.counts)}")
    print(f"{title} ({time.perf_counter() - start:.1f} s including compilation)")
    table = sweep_markdown(result)
    print(table, end="")
    unseen = [label for label, rate in result.solve_rate.items() if np.isnan(rate).any()]
    note = (f"\nn/a ({', '.join(unseen)}): the full state an approach sees is sized to the largest test task; "
            f"larger tasks do not fit its input.\n" if unseen else "")
    print(note, end="")
    try:
        write_atomic(out / "sweep_novelties.png", plot_sweep(result, title))
        write_atomic(out / "sweep_novelties.md", f"# {title}\n\nTest solve rate, mean [min, max] over seeds.\n\n"
                     + table + note)
        write_atomic(out / "sweep_novelties.csv", sweep_csv(result))
    except OSError as err:
        raise UsageError(f"cannot write to {out}: {err.strerror or err}") from None
    print(f"wrote {out / 'sweep_novelties.png'}, .md and .csv")
    return 0


def main(argv=None) -> int:
    args = parse_args(argv)
    check_render_args(args)
    compile_cache.enable(not args.no_compile_cache)  # before anything compiles
    if args.approach is not None and not args.runs:
        raise UsageError("--approach needs an experiment directory to pick the run from")
    sweep_flags = {"--sweep-out": args.sweep_out, "--sweep-tasks": args.sweep_tasks, "--sweep-seed": args.sweep_seed}
    given = [flag for flag, value in sweep_flags.items() if value is not None]
    if args.sweep is None and given:
        raise UsageError(f"{given[0]} goes with --sweep")
    if args.sweep is not None:
        if not args.runs:
            raise UsageError("--sweep evaluates trained runs: give an experiment or run directory")
        if args.render is not None or args.gif is not None or args.cells is not None:
            raise UsageError("--sweep draws its own tasks; it does not combine with --render/--gif or --cells/--doors")
        return sweep(args)
    if len(args.runs) > 2:
        raise UsageError(f"give one RUN, or two to compare side by side; got {len(args.runs)}")
    if len(args.runs) == 2:
        if args.render is not None or args.gif is not None:
            raise UsageError("--render/--gif draw an episode of one run; give one RUN")
        return compare_checkpoints(args, [run_directory(r, args.approach) for r in args.runs])
    if args.runs:
        return evaluate_checkpoint(args, run_directory(args.runs[0], args.approach))
    from jaxbridge.core.bridges import make_bridge
    from jaxbridge.run.evaluate import format_table, run_bridge, summarise
    from jaxbridge.core.meta_policy import Controls
    from jaxbridge.core.tasks import evaluation_batch

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
    if args.render is not None or args.gif is not None:
        render(args, batch, bridge, None, Controls(), result, BRIDGE_LABELS[args.bridge])
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
