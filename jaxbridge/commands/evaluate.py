"""eval.py's work once its flags are parsed: which run, which tasks, the evaluation, side by side, the
generalisation sweep, and drawing an episode."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from jaxbridge.commands.envs import load_env
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.episode import Controls
from jaxbridge.core.presets import default_test_protocol
from jaxbridge.core.tasks import evaluation_specs, make_batch
from jaxbridge.learn.approaches import KNOWN
from jaxbridge.run.checkpoint import CheckpointError
from jaxbridge.run.comparison import run_labels
from jaxbridge.run.memory import TooBig, check_evaluation
from jaxbridge.run.evaluate import evaluate_run, format_comparison, format_table, load_policy, run_bridge, summarise
from jaxbridge.run.run_state import load_config
from jaxbridge.run.sweep import evaluate_sweep, plot_sweep, sweep_csv, sweep_markdown
from jaxbridge.utils.cli import UsageError
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.progress import SlowWork

SWEEP_TASKS = 10
BRIDGE_LABELS = {"oracle": "oracle bridge", "random": "random bridge", "none": "pure planning"}


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
    from jaxbridge.viz.animate import render_gif  # matplotlib and PIL: only when drawing
    from jaxbridge.viz.episodes import pick_episode
    from jaxbridge.viz.render import drawer_for, render_episode, trace_episodes

    try:
        drawer = drawer_for(batch.env)
    except ValueError as err:
        raise UsageError(str(err)) from None
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
    summary = drawer.bridge_summary(trace)
    print(f"drew seed {trace.seed}, task {trace.task} ({'solved' if trace.success else 'not solved'} in "
          f"{trace.steps} steps, {summary}) to {' and '.join(drawn)}")


def run_directory(path: Path, approach: str | None) -> Path:
    """The run to evaluate: `path` itself, or its approach's run (approach@setting in a sweep) inside an
    experiment directory."""
    if approach is not None and (Path(approach).name != approach or approach.startswith(".")):
        raise UsageError(f"--approach {approach!r}: a run name inside the experiment directory, not a path")
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


def run_env(run: Path):
    """The env class of a run directory."""
    try:
        return load_env(load_config(run).env)
    except ValueError as err:
        raise UsageError(str(err)) from None


def task_sizes(text: str) -> dict[str, int]:
    """--task-size NAME=N[,NAME=N...] as a dict (argparse type)."""
    sizes = {}
    for item in filter(None, (part.strip() for part in text.split(","))):
        name, _, value = item.partition("=")
        try:
            sizes[name.strip()] = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected NAME=N[,NAME=N...], got {text!r}") from None
    if not sizes:
        raise argparse.ArgumentTypeError(f"expected NAME=N[,NAME=N...], got {text!r}")
    return sizes


def sized_tasks(sizes: dict[str, int] | None, env_cls):
    """--task-size as a task drawer (the env's `sized_task` hook), or None for each seed's test tasks."""
    if sizes is None:
        return None
    if not env_cls.task_sizes:
        raise UsageError(f"--task-size: env {env_cls.name} builds no tasks of a chosen size")
    unknown = sorted(set(sizes) - set(env_cls.task_sizes))
    if unknown:
        raise UsageError(f"--task-size: {env_cls.name} takes {', '.join(f'{k} ({v})' for k, v in env_cls.task_sizes.items())}; "
                         f"not {', '.join(unknown)}")
    try:
        env_cls.sized_task(np.random.default_rng(0), **sizes)  # refuse bad sizes before anything loads
    except (ValueError, TypeError) as err:
        raise UsageError(f"--task-size: {err}") from None
    return lambda rng: env_cls.sized_task(rng, **sizes)


def protocol_note(env_cls, protocol: str | None) -> str:
    """" (jaxbridge protocol: 1-4 cups per task, ...)" where the test tasks are not the env's default ones."""
    return "" if protocol in (None, default_test_protocol(env_cls)) else f" ({protocol} protocol: {env_cls.test_protocols[protocol]})"


def max_memory_bytes(args) -> int | None:
    return None if args.max_memory is None else int(args.max_memory * 2**30)


def evaluate(args, run: Path):
    """evaluate_run with its errors as usage errors, and a header line."""
    sized = sized_tasks(args.task_size, run_env(run))
    start = time.perf_counter()
    try:
        config, step, batch, result, policy = evaluate_run(run, sized, args.num_tasks, args.rollout_seed,
                                                           max_memory_bytes(args))
    except (CheckpointError, ValueError, TooBig) as err:
        raise UsageError(str(err)) from None
    what = (f"{args.num_tasks} tasks per seed of " + ", ".join(f"{k} {v}" for k, v in args.task_size.items())
            if sized else "test tasks")
    print(f"{run}: {config.env}, {config.approach}, checkpoint of cycle {step}, greedy bridge, {what} "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    return config, step, batch, result, policy


def evaluate_checkpoint(args, run: Path) -> int:
    config, step, batch, result, policy = evaluate(args, run)
    print(format_table(summarise(batch, result)))
    if args.render is not None or args.gif is not None:
        check_render_task(args, batch.size)
        render(args, batch, *policy, result, f"greedy bridge of {config.approach}, cycle {step}")
    return 0


def compare_checkpoints(args, runs: list[Path]) -> int:
    """The same evaluation of each run, then side by side."""
    envs = {run_env(run) for run in runs}
    if len(envs) > 1:
        raise UsageError(f"side by side needs runs of one env, got {', '.join(sorted(e.name for e in envs))}")
    columns = {}
    for run, given in zip(runs, args.runs):
        _, _, batch, result, _ = evaluate(args, run)
        columns[str(given)] = summarise(batch, result)
    print(format_comparison(columns))
    return 0


def sweep_lines(args) -> dict[str, Path]:
    """The sweep's lines: every approach of a lone experiment directory (unless --approach picks one),
    else one line per RUN."""
    if len(args.runs) == 1 and args.approach is None and (args.runs[0] / "experiment.json").is_file():
        held = held_runs(args.runs[0])
        if not held:
            raise UsageError(f"{args.runs[0]} holds no runs yet")
        order = [name for a in KNOWN for name in held if name.partition("@")[0] == a]  # with sweeps' settings
        return {label: args.runs[0] / name for name, label in run_labels(order).items()}
    return {str(given): run_directory(given, args.approach) for given in args.runs}


def sweep(args) -> int:
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
        write_atomic(out / "sweep_novelties.md", f"# {title}\n\nTest solve rate, mean [95% bootstrap CI] over "
                     "seeds (each seed's: the .csv).\n\n" + table + note)
        write_atomic(out / "sweep_novelties.csv", sweep_csv(result))
    except OSError as err:
        raise UsageError(f"cannot write to {out}: {err.strerror or err}") from None
    print(f"wrote {out / 'sweep_novelties.png'}, .md and .csv")
    return 0


def run(args) -> int:
    """Everything eval.py does, from its parsed flags."""
    check_render_args(args)
    if args.approach is not None and not args.runs:
        raise UsageError("--approach needs an experiment directory to pick the run from")
    sweep_flags = {"--sweep-out": args.sweep_out, "--sweep-tasks": args.sweep_tasks, "--sweep-seed": args.sweep_seed}
    given = [flag for flag, value in sweep_flags.items() if value is not None]
    if args.sweep is None and given:
        raise UsageError(f"{given[0]} goes with --sweep")
    if args.sweep is not None:
        if not args.runs:
            raise UsageError("--sweep evaluates trained runs: give an experiment or run directory")
        if args.render is not None or args.gif is not None or args.task_size is not None:
            raise UsageError("--sweep draws its own tasks; it does not combine with --render/--gif or --task-size")
        return sweep(args)
    if len(args.runs) > 2:
        raise UsageError(f"give one RUN, or two to compare side by side; got {len(args.runs)}")
    if len(args.runs) == 2:
        if args.render is not None or args.gif is not None:
            raise UsageError("--render/--gif draw an episode of one run; give one RUN")
        return compare_checkpoints(args, [run_directory(r, args.approach) for r in args.runs])
    if args.runs:
        return evaluate_checkpoint(args, run_directory(args.runs[0], args.approach))
    if args.task_size is not None:
        raise UsageError("--task-size evaluates a trained RUN on larger tasks; give a RUN")
    env_cls = load_env(args.env)
    protocol = args.test_protocol or default_test_protocol(env_cls)
    seeds = list(range(args.first_seed, args.first_seed + args.num_seeds))
    start = time.perf_counter()
    try:
        specs, owners = evaluation_specs(env_cls, seeds, args.num_tasks, protocol)
        check_evaluation(env_cls, specs, max_memory_bytes(args))
    except (ValueError, TooBig) as err:
        raise UsageError(str(err)) from None
    batch = make_batch(env_cls, specs, owners, progress=SlowWork(f"{env_cls.name}: test tasks and plan tables"))
    check_render_task(args, batch.size)
    try:
        bridge = make_bridge(args.bridge, batch.env)
    except ValueError as err:
        raise UsageError(str(err)) from None
    result = run_bridge(batch, bridge, seed=args.rollout_seed)
    print(f"{args.env}, bridge = {args.bridge}, {batch.size} test tasks{protocol_note(env_cls, protocol)} "
          f"({time.perf_counter() - start:.1f} s including compilation)")
    print(format_table(summarise(batch, result)))
    if args.render is not None or args.gif is not None:
        render(args, batch, bridge, None, Controls(), result, BRIDGE_LABELS[args.bridge])
    return 0
