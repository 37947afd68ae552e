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
from pathlib import Path


from envs_jax import env_class
from jaxbridge.core import grid as hyper_grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import default_workers, split_devices
from jaxbridge.learn.setup import make_setup
from jaxbridge.run import checkpoint, comparison, rundir
from jaxbridge.run.runner import Interrupted, train_settings
from jaxbridge.run.scheduling import DevicePool
from jaxbridge.utils import pace
from jaxbridge.utils.distributed import is_primary, multi_process
from jaxbridge.utils.files import WriteError, write_atomic
from jaxbridge.utils.progress import ExperimentProgress

EXPERIMENT_FILE = "experiment.json"
SCHEDULE_FILE = "schedule.json"  # the wall time and each device's busy seconds (run/scheduling.py)
# Seconds per approach in `python -m bench.approaches` (Light Switch Door, 8 seeds, 2 at a time): the
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


def train_approaches(config: TrainConfig, approaches: list[str], experiment_dir: Path, progress: bool = True,
                     resume: bool = False, workers: int | None = None, devices: list | None = None,
                     replaced: Path | None = None, stop: threading.Event | None = None,
                     trained: threading.Event | None = None, tensorboard: bool = False,
                     grid: dict[str, tuple] | None = None) -> dict[str, dict]:
    """Train every approach (run directory `experiment_dir/<approach>`), or with a hyperparameter `grid`
    every approach and setting (`experiment_dir/<approach>@<setting>`), then write the comparison files
    (figure, results.md, results.csv), also after a fault or Ctrl-C for the runs that have files. Runs
    that differ only in leaf hyperparameters train as one program (runner.train_settings); the programs
    train `workers` at a time. With `resume`, finished runs are kept, started ones continue from their
    checkpoint and the others start. `replaced`: the run this one replaces, moved aside, deleted once
    this one's experiment file is written. `stop` (set by another thread) stops every program after its
    current cycle, checkpointed; `trained` is set after any cycle completes; `tensorboard`: event files
    per run (run/tensorboard.py). Returns each run's summary, in order."""
    named, primary = runs(config, approaches, grid), is_primary()  # only process 0 writes files
    if resume:
        check_resumable(experiment_dir, list(named))
    elif primary:
        write_experiment_file(experiment_dir, config, approaches, grid)
        rundir.discard(replaced)
    names = list(named)
    programs = [[names[i] for i in group] for group in hyper_grid.program_groups(list(named.values()))]
    # Across processes the programs take turns, in the same order everywhere: the gathers after each
    # cycle are collective, and two programs' gathers must not cross.
    workers = 1 if multi_process() else workers or default_workers(programs)
    what = f"{len(approaches)} approaches" + (f" x {len(names) // len(approaches)} settings" if grid else "")
    bar = ExperimentProgress({p[0]: config.cycles for p in programs}, f"{config.env} x{config.num_seeds} seeds, {what}",
                             min(workers, len(programs)), progress and primary)
    stop = stop or threading.Event()
    pool = DevicePool(split_devices(devices, min(workers, len(programs))), len(programs))
    program = ProgramRun(named, experiment_dir, env_class(config.env), bar, stop, trained, tensorboard, pool)
    order, unwritable = sorted(programs, key=lambda p: -COST.get(named[p[0]].approach, 0) * len(p)), False
    try:
        results = run_side_by_side(program, order, workers, stop)
        infos = {name: info for p in programs for name, info in zip(p, results[p[0]])}
        if primary:
            write_atomic(experiment_dir / SCHEDULE_FILE, json.dumps(pool.record(), indent=2) + "\n")
            pace.record(config.env, {named[n].approach: info["elapsed_s"] / (config.num_seeds * info["cycles"])
                                     for n, info in infos.items() if info and not grid})
        return {name: infos[name] for name in names}
    except WriteError:
        unwritable = True
        raise
    finally:
        bar.close()
        done = [n for n in names if (experiment_dir / n / "metrics.csv").is_file()]
        if done and primary and not unwritable:
            comparison.write_comparison(experiment_dir, config.env, comparison.run_labels(done))


def write_experiment_file(experiment_dir: Path, config: TrainConfig, approaches: list[str],
                          grid: dict[str, tuple] | None) -> None:
    """experiment.json: the base config, the approaches and the sweep's grid (what --resume reads)."""
    write_atomic(experiment_dir / EXPERIMENT_FILE, json.dumps(
        {"config": config.to_dict(), "approaches": approaches,
         **({"sweep": {k: list(v) for k, v in grid.items()}} if grid else {})}, indent=2) + "\n")


class ProgramRun:
    """Runs one program of an experiment (its runs that train as one, `program` their names): brax's
    low-level runs seed after seed, the others by train_settings on a share of the devices, which a
    worker takes from the pool for the program (with any spare shares it takes on the way) and gives
    back after it."""

    def __init__(self, named: dict[str, TrainConfig], experiment_dir: Path, env_cls, bar, stop: threading.Event,
                 trained: threading.Event | None, tensorboard: bool, pool: DevicePool):
        self.named, self.experiment_dir, self.env_cls, self.bar = named, experiment_dir, env_cls, bar
        self.stop, self.trained, self.tensorboard, self.pool = stop, trained, tensorboard, pool

    def __call__(self, program: list[str]) -> list[dict]:
        if self.stop.is_set():  # interrupted before this program's turn
            raise Interrupted(0)
        setup, held = make_setup(self.named[program[0]], self.env_cls), self.pool.take()
        try:
            bar = self.bar.for_program(program[0])
            if setup.approach.low_level:  # brax: seed after seed, one checkpoint, on the default device
                return [self.low_level(make_setup(self.named[n], self.env_cls), self.experiment_dir / n, bar)
                        for n in program]
            return self.train(setup, program, held, bar)
        finally:
            self.pool.give_back(held)

    def train(self, setup, program: list[str], held: list, bar) -> list[dict]:
        """The program's runs by train_settings on the first share `held`, widened onto spare ones."""
        run_dirs = [self.experiment_dir / name for name in program]
        started = all(checkpoint.sealed_steps(d / "checkpoints") for d in run_dirs)
        if not started and is_primary():
            for run_dir in run_dirs:
                rundir.fresh(run_dir)

        def widen(wanted) -> list:
            more = self.pool.spare(wanted)
            held.extend(more)
            return [d for share in more for d in share]
        return train_settings(setup, [(self.named[n], d) for n, d in zip(program, run_dirs)], resume=started,
                              bar=bar, stop=self.stop, devices=held[0], trained=self.trained,
                              tensorboard=self.tensorboard, widen=widen)

    def low_level(self, setup, run_dir: Path, bar) -> dict:
        from jaxbridge.run import low_level_runs  # brax: imported only when used
        done = low_level_runs.finished(run_dir, setup.config)
        if done is not None:
            bar.update(setup.config.cycles)
            return done
        if is_primary():
            rundir.fresh(run_dir)
        return low_level_runs.train_low_level(setup, run_dir, bar=bar, stop=self.stop)


def run_side_by_side(run, programs: list[list[str]], workers: int, stop: threading.Event) -> dict[str, list[dict]]:
    """`run(program)` for every program, `workers` at a time, in that order; {first name: its result}.
    After Ctrl-C or an error every running program checkpoints and stops; then the first error other
    than an interruption is raised, or one Interrupted naming each interrupted program's cycles."""
    with ThreadPoolExecutor(workers, thread_name_prefix="approach") as pool:
        futures = {program[0]: pool.submit(run, program) for program in programs}
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
