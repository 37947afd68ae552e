"""Experiments: several approaches trained on the same env and seeds, one run directory each, then
compared (the paper's figure and tables).

The approaches run concurrently in worker threads (a jitted cycle releases the GIL), which split the
devices between them; one progress bar counts every cycle. Neither changes any number
(docs/DESIGN.md, Host loop; docs/PERFORMANCE.md for the times).
"""
from __future__ import annotations

import dataclasses
import json
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path

from envs_jax import env_class
from jaxbridge.core import grid as hyper_grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import default_workers, split_devices
from jaxbridge.learn.setup import Setup, make_setup
from jaxbridge.run import checkpoint, comparison, rundir
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import Interrupted, train_settings
from jaxbridge.run.scheduling import DevicePool
from jaxbridge.utils import pace
from jaxbridge.utils.distributed import is_primary, multi_process
from jaxbridge.utils.files import WriteError, write_atomic
from jaxbridge.utils.progress import ExperimentProgress

EXPERIMENT_FILE = "experiment.json"
SCHEDULE_FILE = "schedule.json"  # the wall time and each device's busy seconds (run/scheduling.py)
# Seconds per approach in `python -m bench.timings.approaches` (Light Switch Door, 8 seeds, 2 at a time): the
# longest start first, so the workers finish close together. The plan-repair baselines are not measured
# there; they share no CallPlanner's machinery and are ordered as it.
COST = {"maple_q": 200, "no_feature_selection": 172, "no_callplanner": 172, "ours": 111, "random": 20, "pure_planning": 15}
COST.update(plan_progress=COST["no_callplanner"], plan_progress_replan=COST["no_callplanner"])


def is_experiment_dir(path: Path) -> bool:
    return (path / EXPERIMENT_FILE).is_file()


def load_experiment(experiment_dir: Path) -> tuple[TrainConfig, list[str], dict[str, tuple]]:
    """The base config, approach list and hyperparameter grid ({} if none) of an experiment directory."""
    try:
        data = json.loads((experiment_dir / EXPERIMENT_FILE).read_text())
        grid = {key: tuple(tuple(v) if isinstance(v, list) else v for v in values)
                for key, values in data.get("sweep", {}).items()}
        return TrainConfig.from_dict(data["config"]), list(data["approaches"]), grid
    except (OSError, KeyError, TypeError, AttributeError, json.JSONDecodeError) as err:
        raise ValueError(f"{experiment_dir / EXPERIMENT_FILE} is not a valid experiment file: {err}") from None


def runs(config: TrainConfig, approaches: list[str], grid: dict[str, tuple] | None = None) -> dict[str, TrainConfig]:
    """{run directory name: its config}: one run per approach, or per approach and setting of `grid`
    (named approach@setting, e.g. ours@learning_rate=0.0003,gamma=0.9)."""
    named = {}
    for approach in approaches:
        for setting in hyper_grid.settings(grid or {}):
            name = f"{approach}@{hyper_grid.setting_name(setting)}" if setting else approach
            named[name] = dataclasses.replace(config, approach=approach, **setting)
    return named


def check_resumable(experiment_dir: Path, names: list[str]) -> None:
    """Refuse (CheckpointError) to resume an experiment a run of which has results but no checkpoint
    left: resuming would silently train it again from scratch."""
    for name in names:
        run_dir = experiment_dir / name
        if (run_dir / "metrics.csv").is_file() and not checkpoint.sealed_steps(run_dir / "checkpoints"):
            raise checkpoint.CheckpointError(f"{run_dir} has results but no complete checkpoint to resume from; "
                                             f"start the experiment over with --overwrite")


@dataclass(frozen=True)
class Program:
    """Runs that train as one program (they differ only in leaf hyperparameters), with the setup of the
    first, built once: the others' setups differ from it only in their config."""

    names: list[str]
    setup: Setup


@dataclass(frozen=True)
class Plan:
    """An experiment before it trains: its base config, approaches and grid, each run's config by name,
    and the programs they form, each with its setup (what the memory estimate reads too)."""

    config: TrainConfig
    approaches: list[str]
    grid: dict[str, tuple]
    named: dict[str, TrainConfig]
    programs: list[Program]


def program_names(named: dict[str, TrainConfig]) -> list[list[str]]:
    """The runs that train as one program (equal but for leaf hyperparameters), by name, in order."""
    names = list(named)
    return [[names[i] for i in group] for group in hyper_grid.program_groups(list(named.values()))]


def plan(config: TrainConfig, approaches: list[str], grid: dict[str, tuple] | None = None, env_cls=None) -> Plan:
    """The experiment's runs and programs, each program's setup built here, once."""
    named, env_cls = runs(config, approaches, grid), env_cls or env_class(config.env)
    return Plan(config, approaches, grid or {}, named,
                [Program(names, make_setup(named[names[0]], env_cls)) for names in program_names(named)])


def train_approaches(experiment: Plan, experiment_dir: Path, hooks: RunHooks, resume: bool = False,
                     workers: int | None = None, replaced: Path | None = None) -> dict[str, dict]:
    """Train every run of the experiment (run directory `experiment_dir/<approach>`, or with a grid
    `experiment_dir/<approach>@<setting>`), then write the comparison files (figure, results.md,
    results.csv), also after a fault or Ctrl-C for the runs that have files. The programs train
    `workers` at a time. With `resume`, finished runs are kept, started ones continue from their
    checkpoint and the others start. `replaced`: the run this one replaces, moved aside, deleted once
    this one's experiment file is written. Returns each run's summary, in order."""
    config, primary, names = experiment.config, is_primary(), list(experiment.named)  # only process 0 writes files
    if resume:
        check_resumable(experiment_dir, names)
    elif primary:
        write_experiment_file(experiment_dir, config, experiment.approaches, experiment.grid)
        rundir.discard(replaced)
    programs = experiment.programs
    # Across processes the programs take turns, in the same order everywhere: the gathers after each
    # cycle are collective, and two programs' gathers must not cross.
    workers = min(1 if multi_process() else workers or default_workers(programs), len(programs))
    pool = DevicePool(split_devices(hooks.devices, workers), len(programs))
    hooks = dataclasses.replace(hooks, stop=hooks.stop or threading.Event(), display=experiment_display(experiment, hooks, workers))
    order, unwritable = sorted(programs, key=lambda p: -COST.get(p.setup.approach.name, 0) * len(p.names)), False
    try:
        results = run_side_by_side(ProgramRun(experiment.named, experiment_dir, hooks, pool), order, workers, hooks.stop)
        infos = {name: info for p in programs for name, info in zip(p.names, results[p.names[0]])}
        if primary:
            write_atomic(experiment_dir / SCHEDULE_FILE, json.dumps(pool.record(), indent=2) + "\n")
            pace.record(config.env, {experiment.named[n].approach: info["pace"] for n, info in infos.items()
                                     if info and info.get("pace") and not experiment.grid})
        return {name: infos[name] for name in names}
    except WriteError:
        unwritable = True
        raise
    finally:
        hooks.display.close()
        done = [n for n in names if (experiment_dir / n / "metrics.csv").is_file()]
        if done and primary and not unwritable:
            comparison.write_comparison(experiment_dir, config.env, comparison.run_labels(done))


def experiment_display(experiment: Plan, hooks: RunHooks, workers: int) -> ExperimentProgress:
    """One progress display for every program's cycles (on process 0)."""
    config, approaches = experiment.config, experiment.approaches
    what = f"{len(approaches)} approaches" + (f" x {len(experiment.named) // len(approaches)} settings" if experiment.grid else "")
    return ExperimentProgress({p.names[0]: config.cycles for p in experiment.programs},
                              f"{config.env} x{config.num_seeds} seeds, {what}", workers, hooks.progress and is_primary())


def write_experiment_file(experiment_dir: Path, config: TrainConfig, approaches: list[str],
                          grid: dict[str, tuple] | None) -> None:
    """experiment.json: the base config, the approaches and the sweep's grid (what --resume reads)."""
    write_atomic(experiment_dir / EXPERIMENT_FILE, json.dumps(
        {"config": config.to_dict(), "approaches": approaches,
         **({"sweep": {k: list(v) for k, v in grid.items()}} if grid else {})}, indent=2) + "\n")


class ProgramRun:
    """Runs one program of an experiment: brax's low-level runs seed after seed, the others by
    train_settings on a share of the devices, which a worker takes from the pool for the program (with
    any spare shares it takes on the way) and gives back after it."""

    def __init__(self, named: dict[str, TrainConfig], experiment_dir: Path, hooks: RunHooks, pool: DevicePool):
        self.named, self.experiment_dir, self.hooks, self.pool = named, experiment_dir, hooks, pool

    def __call__(self, program: Program) -> list[dict]:
        if self.hooks.stop.is_set():  # interrupted before this program's turn
            raise Interrupted(0)
        held = self.pool.take()
        try:
            hooks = dataclasses.replace(self.hooks, display=self.hooks.display.for_program(program.names[0]))
            if program.setup.approach.low_level:  # brax: seed after seed, one checkpoint, on the default device
                return [self.low_level(dataclasses.replace(program.setup, config=self.named[n]), self.experiment_dir / n,
                                       hooks) for n in program.names]
            return self.train(program, held, hooks)
        finally:
            self.pool.give_back(held)

    def train(self, program: Program, held: list, hooks: RunHooks) -> list[dict]:
        """The program's runs by train_settings on the first share `held`, widened onto spare ones."""
        run_dirs = [self.experiment_dir / name for name in program.names]
        started = all(checkpoint.sealed_steps(d / "checkpoints") for d in run_dirs)
        if not started and is_primary():
            for run_dir in run_dirs:
                rundir.fresh(run_dir)

        def widen(wanted) -> list:
            more = self.pool.spare(wanted)
            held.extend(more)
            return [d for share in more for d in share]
        # The learned selector's update compiles to other last bits on another device count (a known gap,
        # docs/DESIGN.md, Seeds over devices): widened, its numbers would depend on when a device came free.
        invariant = not program.setup.controls.observation.tokens
        return train_settings(program.setup, [(self.named[n], d) for n, d in zip(program.names, run_dirs)],
                              dataclasses.replace(hooks, devices=held[0], widen=widen if invariant else None),
                              resume=started)

    def low_level(self, setup: Setup, run_dir: Path, hooks: RunHooks) -> dict:
        from jaxbridge.run import low_level_runs  # brax: imported only when used
        done = low_level_runs.finished(run_dir, setup.config)
        if done is not None:
            hooks.display.update(setup.config.cycles)
            return done
        if is_primary():
            rundir.fresh(run_dir)
        return low_level_runs.train_low_level(setup, run_dir, hooks)


def run_side_by_side(run, programs: list[Program], workers: int, stop: threading.Event) -> dict[str, list[dict]]:
    """`run(program)` for every program, `workers` at a time, in that order; {first name: its result}.
    After Ctrl-C or an error every running program checkpoints and stops; then the first error other
    than an interruption is raised, or one Interrupted naming each interrupted program's cycles."""
    with ThreadPoolExecutor(workers, thread_name_prefix="approach") as pool:
        futures = {program.names[0]: pool.submit(run, program) for program in programs}
        try:
            # Wake up now and then: the OS may deliver Ctrl-C's SIGINT to a worker thread, and Python
            # only runs the handler (raising KeyboardInterrupt here) when the main thread runs.
            pending = set(futures.values())
            while pending:
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_EXCEPTION)
                if any(f.exception() is not None for f in done):
                    break
        except KeyboardInterrupt:
            pass
        stop.set()  # after Ctrl-C or a fault: every running approach checkpoints and stops
        wait(futures.values())
    errors = {name: f.exception() for name, f in futures.items() if f.exception() is not None}
    faults = [e for e in errors.values() if not isinstance(e, Interrupted)]
    if faults:
        raise faults[0]
    if errors:
        cycles = ", ".join(f"{name} {e.cycle}" for name, e in errors.items())
        raise Interrupted(-1, f"interrupted; checkpoints saved ({cycles} cycles done)")
    return {name: f.result() for name, f in futures.items()}
