"""train.py's work once its flags are parsed: the config, the experiment directory, new or resumed runs."""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from pathlib import Path
from typing import Callable

from jaxbridge.commands.envs import load_env
from jaxbridge.core import grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.presets import preset_values
from jaxbridge.learn.approaches import APPROACHES
from jaxbridge.utils.cli import UsageError
from jaxbridge.utils.distributed import is_primary
from jaxbridge.utils.stats import cell_text

# train.py flags that set the run's config (flag name = config field); --resume takes the saved config.
CONFIG_FLAGS = ("env", "preset", "env_quirks", "test_protocol", "learner", "num_seeds", "first_seed", "cycles", "episodes_per_cycle",
                "train_steps", "updates_per_cycle", "batch_size", "call_planner_bonus", "checkpoint_every", "seed_block",
                "low_level_budget")


def make_config(flags: dict) -> tuple[TrainConfig, type]:
    """The config of the flags given (None: not given) and its env class; refused in one line where it
    cannot train."""
    given = {field: flags[field] for field in CONFIG_FLAGS if flags.get(field) is not None}
    spec = given.pop("env", TrainConfig.env)
    env_cls = load_env(spec)
    try:
        config = TrainConfig(env=spec, **{**preset_values(given.pop("preset", TrainConfig.preset), env_cls), **given})
    except ValueError as err:  # a value out of its range, e.g. a negative bonus
        raise UsageError(str(err)) from None
    try:
        env_cls.check_quirks(config.env_quirks)
    except ValueError as err:
        raise UsageError(f"--env-quirks: {err}") from None
    if config.test_protocol not in env_cls.test_protocols:
        raise UsageError(f"--test-protocol {config.test_protocol!r}: {env_cls.name} has "
                         f"{', '.join(f'{k} ({v})' for k, v in env_cls.test_protocols.items())}")
    try:
        config.check_buffer_fits()
    except ValueError as err:
        raise UsageError(f"--episodes-per-cycle: {err}") from None
    check_learner_spec(config, env_cls)
    if config.seed_block > config.num_seeds:
        raise UsageError(f"--seed-block {config.seed_block} is larger than the {config.num_seeds} seeds")
    return config, env_cls


def check_learner_spec(config: TrainConfig, env_cls) -> None:
    """Refuse a --learner that does not load or make a learner, and one of your own that breaks the learner
    contract (learn/learner.check_learner: shapes only, nothing is computed)."""
    from jaxbridge.learn.learner import LearnerContractError, check_learner
    from jaxbridge.learn.learners import registered
    from jaxbridge.learn.setup import make_setup
    try:  # making the setup resolves the learner by name (learners.learner_factory) and makes it
        learner = make_setup(dataclasses.replace(config, approach="ours", num_seeds=1), env_cls).learner  # one seed's tasks
        if config.learner not in registered():
            check_learner(learner, config)
    except (ValueError, LearnerContractError) as err:
        raise UsageError(f"--learner: {err}") from None


def check_reachable(config: TrainConfig, env_cls) -> None:
    """Refuse a training horizon too short for some seed's training task ever to reach its goal."""
    needed = {seed: env_cls.train_task(seed).min_steps for seed in config.seeds}
    worst = max(needed, key=needed.get)
    if config.train_steps < needed[worst]:
        raise UsageError(f"--train-steps {config.train_steps} is too small to ever reach the goal: seed {worst}'s "
                         f"training task needs at least {needed[worst]} steps")


def default_approaches(env_cls) -> list[str]:
    """What train.py trains when --approaches is not given: the paper's figure for the env."""
    return list(env_cls.default_approaches or APPROACHES)


# The quick start's measured times (bench.quickstart's record), where the checkout has them.
QUICKSTART_RECORD = Path(__file__).resolve().parents[2] / "docs" / "results" / "quickstart.json"


def start_line(config: TrainConfig, env_cls, approaches: list[str]) -> str:
    """What this run trains, what the default leaves out, and how long the measured default took."""
    from jaxbridge.learn.approaches import get_approach

    line = (f"{env_cls.name}: training {', '.join(get_approach(a).label for a in approaches)} x {config.num_seeds} "
            f"seeds x {config.cycles} cycles")
    if approaches != default_approaches(env_cls):
        return line
    skipped = [a for a in APPROACHES if a not in approaches]
    if skipped:
        line += f"; not {', '.join(get_approach(a).label for a in skipped)} ({env_cls.why_not_all}): --approaches all adds it"
    try:
        measured = json.loads(QUICKSTART_RECORD.read_text())[env_cls.name]
        line += (f"; 8 seeds x 100 cycles took {measured['wall_s'] / 60:.0f} minutes on {measured['machine']['cpu_cores']} "
                 f"CPU cores (docs/PERFORMANCE.md)")
    except (OSError, KeyError, ValueError):  # an installed copy without the records, or an env of your own
        pass
    return line


def sweep_grid(texts: list[str] | None) -> dict[str, tuple]:
    """The hyperparameter grid of the --sweep flags ({} without any), refused in one line if invalid."""
    try:
        return grid.parse_sweeps(texts or [])
    except ValueError as err:
        raise UsageError(str(err)) from None


def new_experiment(flags: dict, approaches: list[str] | None, out: Path, name: str | None, overwrite: bool,
                   progress: bool, workers: int | None, devices: list, max_memory: float | None = None,
                   interrupts=None, tensorboard: bool = False) -> tuple[Path, Callable[[], dict]]:
    """(experiment directory, the training to run) of a new experiment; the directory is locked. A run
    whose memory estimate exceeds `max_memory` GiB (default: what is available) is refused first."""
    from jaxbridge.learn.devices import default_workers
    from jaxbridge.run import memory, rundir

    if name is not None:
        try:
            rundir.check_name(name)
        except rundir.RunDirError as err:
            raise UsageError(str(err)) from None
    config, env_cls = make_config(flags)
    hyper_grid = sweep_grid(flags.get("sweep"))
    approaches = approaches or default_approaches(env_cls)
    settings = len(grid.settings(hyper_grid))  # trained side by side, as more seeds (the worst case)
    try:
        memory.check_training(dataclasses.replace(config, num_seeds=config.num_seeds * settings), env_cls, approaches,
                              workers or default_workers(approaches), None if max_memory is None else int(max_memory * 2**30))
    except memory.TooBig as err:
        raise UsageError(str(err)) from None
    check_reachable(config, env_cls)
    out_dir, replaced, lock = out / (name or env_cls.name), None, None
    try:
        if is_primary():  # the other processes of a multi-process run write nothing (utils/distributed.py)
            replaced = rundir.prepare(out_dir, overwrite)
            lock = rundir.RunLock(out_dir).acquire()
    except rundir.RunDirError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"cannot write experiment directory {out / (name or env_cls.name)}: {err.strerror}") from None
    from jaxbridge.run.experiments import train_approaches  # after the refusals: it loads orbax (~0.2 s)
    if is_primary():  # stdout, as the closing summary: stderr carries progress and the one-line errors
        print(start_line(config, env_cls, approaches), flush=True)
    return out_dir, _releasing(lock, lambda: train_approaches(config, approaches, out_dir, progress, workers=workers,
                                                              devices=devices, replaced=replaced, grid=hyper_grid,
                                                              **_watch(interrupts, tensorboard)))


def check_resume_flags(flags: dict) -> None:
    """--resume takes the saved config: refuse the flags that would set another."""
    clashing = [f"--{flag.replace('_', '-')}" for flag in CONFIG_FLAGS if flags.get(flag) is not None]
    clashing += [f"--{flag}" for flag in ("overwrite", "name", "approaches", "sweep") if flags.get(flag)]
    if clashing:
        raise UsageError(f"--resume continues a run with its saved config; drop {', '.join(clashing)}")


def resumed(run_dir: Path, progress: bool, workers: int | None, devices: list, interrupts=None,
            tensorboard: bool = False) -> Callable[[], dict]:
    """The training that continues the experiment (or one approach's run) in `run_dir`, locked."""
    from jaxbridge.learn.setup import make_setup
    from jaxbridge.run import rundir
    from jaxbridge.run.checkpoint import CheckpointError
    from jaxbridge.run.experiments import check_resumable, is_experiment_dir, load_experiment, runs, train_approaches
    from jaxbridge.run.run_state import load_config
    from jaxbridge.run.runner import train

    try:
        if is_experiment_dir(run_dir):
            config, approaches, hyper_grid = load_experiment(run_dir)
            load_env(config.env)
            check_resumable(run_dir, list(runs(config, approaches, hyper_grid)))
            run = lambda: train_approaches(config, approaches, run_dir, progress, resume=True, workers=workers,
                                           devices=devices, grid=hyper_grid, **_watch(interrupts, tensorboard))
        else:
            config = load_config(run_dir)
            setup = make_setup(config, load_env(config.env))
            run = lambda: {config.approach: train(setup, run_dir, progress, resume=True, devices=devices,
                                                  **_watch(interrupts, tensorboard))}
        return _releasing(rundir.RunLock(run_dir).acquire() if is_primary() else None, run)
    except (ValueError, CheckpointError, rundir.RunDirError) as err:
        raise UsageError(str(err)) from None


def _watch(interrupts, tensorboard: bool = False) -> dict:
    """The stop/trained events of commands.interrupts.Interrupts and --tensorboard, as keyword arguments
    of the runs."""
    events = {"tensorboard": True} if tensorboard else {}
    return events if interrupts is None else {"stop": interrupts.stop, "trained": interrupts.trained, **events}


def _releasing(lock, run: Callable[[], dict]) -> Callable[[], dict]:
    """`run`, releasing `lock` (if any) however it ends."""
    def locked():
        try:
            return run()
        finally:
            if lock is not None:
                lock.release()
    return locked


def report(name: str, info: dict) -> str:
    """One approach's summary line: means over seeds with their 95% intervals."""
    at = info["test_solve_rate_at"]
    last = max((int(c) for c in at), default=None)
    return (f"{name:>25}: mean test solve rate at the last cycle {info['per_cycle']['test_solve_rate']['mean'][-1]:.2f}; "
            f"smooth reward at cycle {info['cycles']}: {cell_text(info['smooth_reward_final'])}"
            + (f"; at cycle {last}: {cell_text(at[str(last)])}" if last else "")
            + f" (95% CIs over seeds {info['seed_range']}; {info['elapsed_s']:.0f} s)")


EXIT_NUMERICAL, EXIT_CANNOT_WRITE = 3, 4


def main(args, devices: list) -> int:
    """train.py after its flags: start or resume, train with Ctrl-C as requests, report; the exit code."""
    from jaxbridge.commands.interrupts import EXIT_INTERRUPTED, Interrupts, run_watched
    from jaxbridge.run.rundir import release_held
    from jaxbridge.utils.files import WriteError

    start, progress = time.perf_counter(), not args.no_progress
    interrupts = Interrupts(on_exit=release_held)
    if args.resume is not None:
        check_resume_flags(vars(args))
        out_dir, run = args.resume, resumed(args.resume, progress, args.workers, devices, interrupts, args.tensorboard)
    else:
        out_dir, run = new_experiment(vars(args), args.approaches, args.out, args.name, args.overwrite, progress,
                                      args.workers, devices, args.max_memory, interrupts, args.tensorboard)
    from jaxbridge.run import checkpoint
    from jaxbridge.run.experiments import is_experiment_dir
    from jaxbridge.run.runner import Interrupted, NumericalFault

    checkpoint.set_quiet(not args.debug)
    try:
        summaries = run_watched(run)
    except checkpoint.CheckpointError as err:
        raise UsageError(str(err)) from None
    except NumericalFault as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_NUMERICAL
    except Interrupted as err:
        print(f"{err}; continue with: python train.py --resume {out_dir}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except WriteError as err:
        if args.debug:
            raise
        print(f"error: {err}; stopped, {last_checkpoints(out_dir)}", file=sys.stderr, flush=True)
        release_held()
        os._exit(EXIT_CANNOT_WRITE)  # at once: orbax's unfinished writes would report at interpreter exit
    finally:
        interrupts.restore()
    if not is_primary():  # process 0 reports for a multi-process run
        return 0
    print(f"done in {time.perf_counter() - start:.0f} s -> {out_dir}/"
          + ("  (figure: curves.png, tables: results.md)" if is_experiment_dir(out_dir) else ""))
    for name, info in summaries.items():
        print(report(name, info))
    return 0


def last_checkpoints(out_dir: Path) -> str:
    """Where a stopped run can resume from, in words."""
    from jaxbridge.run.checkpoint import sealed_steps

    runs = [out_dir] if (out_dir / "checkpoints").is_dir() else sorted(p for p in out_dir.iterdir() if p.is_dir())
    sealed = {run.name: sealed_steps(run / "checkpoints") for run in runs}
    held = ", ".join(f"{name} cycle {steps[-1]}" for name, steps in sealed.items() if steps)
    return (f"the last complete checkpoints are {held}; once it can write, continue with: python train.py --resume "
            f"{out_dir}" if held else "before any checkpoint was complete")
