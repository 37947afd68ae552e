"""Training from Python: the config, a training prepared and run (new or resumed), its metrics as arrays,
and the whole run as one pure function."""
from __future__ import annotations

import dataclasses
import shutil
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from jaxbridge.api.config import config_and_env
from jaxbridge.api.envs import EnvLike, load_env
from jaxbridge.core import grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.tasks import train_specs
from jaxbridge.learn.approaches import APPROACHES, get_approach
from jaxbridge.learn.online import TrainOutput
from jaxbridge.learn.setup import make_setup
from jaxbridge.run import rundir
from jaxbridge.run.hooks import RunHooks
from jaxbridge.utils.distributed import is_primary
from jaxbridge.utils.errors import InputError, refusing
from jaxbridge.utils.stats import cell_text, ci_text


def make_train(config: TrainConfig) -> Callable[..., TrainOutput]:
    """The whole online-learning run of `config` as one pure function, PureJaxRL's shape:
    `train(keys=None, hyper=None) -> TrainOutput(learners, metrics)`, metrics' fields [seeds, cycles].

    Task batches and plan tables are built here, once; `train` touches no file and no host. `keys`: one
    per seed (default `seed_keys(config)`, as train.py starts them); `hyper`: the numeric
    hyperparameters as pytree leaves (default `Hyper.of(config)`). jit it; vmap it over keys, or over
    `Hyper` leaves (the vmapped runs go one after another, each the plain run's program, so each gives
    its own train.py numbers), e.g. two learning rates:

        hypers = jax.tree.map(lambda *v: jnp.stack(v), Hyper.of(c1), Hyper.of(c2))
        out = jax.jit(jax.vmap(train, in_axes=(None, 0)))(None, hypers)

    Its metrics are train.py's metrics.csv for the same config where no plan-table lookup missed (the
    host planner is not called inside; `metrics.table_misses` counts the misses, 0 on the built-in
    envs' tasks). Not for the low-level (brax) baselines."""
    from jaxbridge.learn.online import make_train as make_run

    return make_run(make_setup(config))


@dataclass(frozen=True)
class Experiment:
    """What a training returns: every run's metrics as arrays, and results.md's statistics."""

    config: TrainConfig  # the settings every run shares (its `approach` field: the first's)
    approaches: tuple[str, ...]  # the runs: approaches, or approach@setting in a sweep
    metrics: dict[str, dict[str, np.ndarray]]  # run -> metrics.csv column -> float[seeds, cycles]
    summaries: dict[str, dict]  # run -> summary.json: means, IQMs and 95% CIs at the report cycles
    run_dir: Path | None  # the experiment (or resumed run's) directory; None where it was temporary

    @property
    def seeds(self) -> list[int]:
        return self.config.seeds

    def curve(self, approach: str = "ours", metric: str = "test_solve_rate") -> np.ndarray:
        """The mean over seeds of a metric per cycle (float[cycles])."""
        return self.metrics[approach][metric].mean(axis=0)

    def cells(self, run: str = "ours", cycles: Sequence[int] | None = None) -> dict[int, dict]:
        """results.md's cells of a run's test solve rate: {cycle: {mean, mean_ci, iqm, iqm_ci, min, max}} over
        seeds, intervals the 95% bootstrap ones, as results.csv computes them; at `cycles` (default: the last)."""
        from jaxbridge.run.artifacts import at_cycle, curve_statistics

        rates = self.metrics[run]["test_solve_rate"]
        curve = curve_statistics(rates, self.metrics[run]["train_success_rate"])["test_solve_rate"]
        return {cycle: at_cycle(curve, cycle) for cycle in (cycles or [rates.shape[1]])}

    def report(self) -> str:
        """One line per run: its test solve rate at the last cycle, its smooth test reward there and its
        seconds; then what the numbers are (means over seeds with 95% intervals)."""
        lines = [_report_line(name, info) for name, info in self.summaries.items()]
        seeds = next(iter(self.summaries.values()))["seed_range"]
        return "\n".join([*lines, f"(means over seeds {seeds} [95% bootstrap intervals]; docs/RESULTS.md says how)"])


def _report_line(name: str, info: dict) -> str:
    rate, last = info["per_cycle"]["test_solve_rate"], info["cycles"]
    return (f"{name:>25}: test solve rate at cycle {last} {ci_text(rate['mean'][-1], (rate['mean_low'][-1], rate['mean_high'][-1]))}, "
            f"smooth test reward {cell_text(info['smooth_reward_final'])}, {info['elapsed_s']:.0f} s")


class Training:
    """A training ready to run: its config checked, its directory made and locked (`prepare`,
    `prepare_resume`). `run()` trains and returns the Experiment; `release()` gives the lock back where
    it will not run."""

    def __init__(self, config: TrainConfig, approaches: list[str], run_dir: Path, work: Callable[[RunHooks], dict],
                 hooks: RunHooks, lock: rundir.RunLock | None, temporary: Path | None = None, start_line: str = ""):
        self.config, self.approaches, self.run_dir = config, tuple(approaches), run_dir
        self._work, self._hooks, self._lock, self._temporary, self._start_line = work, hooks, lock, temporary, start_line

    def describe(self) -> str:
        """What this training trains, and what the env's default leaves out (train.py's first line)."""
        return self._start_line

    def run(self, stop: threading.Event | None = None, trained: threading.Event | None = None,
            debug: bool = False) -> Experiment:
        """Train. `stop` (set from another thread) stops every run after its current cycle, checkpointed
        (then `Interrupted` is raised); `trained` is set after any cycle completes. A file that cannot be
        written raises one WriteError; `debug` also lets orbax and tensorstore report it their way."""
        from jaxbridge.run.checkpoint import set_quiet

        set_quiet(not debug)
        try:
            summaries = self._work(dataclasses.replace(self._hooks, stop=stop, on_cycle=None if trained is None else trained.set))
            metrics = _read_metrics(self.run_dir, list(summaries)) if is_primary() else {}
            return Experiment(self.config, tuple(summaries), metrics, summaries,
                              None if self._temporary else self.run_dir)
        finally:
            self.release()
            if self._temporary is not None:
                shutil.rmtree(self._temporary, ignore_errors=True)

    @property
    def is_experiment(self) -> bool:
        """An experiment directory (approaches side by side, curves.png and results.md), not one run's."""
        from jaxbridge.run.experiments import is_experiment_dir

        return is_experiment_dir(self.run_dir)

    def release(self) -> None:
        if self._lock is not None:
            self._lock.release()

    def last_checkpoints(self) -> str | None:
        """Where a stopped training can resume from, in words ("ours cycle 20, random cycle 20"), or None
        before any checkpoint was complete."""
        from jaxbridge.run.checkpoint import sealed_steps

        out = self.run_dir
        runs = [out] if (out / "checkpoints").is_dir() else sorted(p for p in out.iterdir() if p.is_dir())
        sealed = {run.name: sealed_steps(run / "checkpoints") for run in runs}
        return ", ".join(f"{name} cycle {steps[-1]}" for name, steps in sealed.items() if steps) or None


def release_locks() -> None:
    """Release every run directory lock this process holds (before exiting without unwinding)."""
    rundir.release_held()


def _read_metrics(run_dir: Path, names: list[str]) -> dict[str, dict[str, np.ndarray]]:
    """Each run's metrics.csv columns (a lone run's directory is `run_dir` itself)."""
    from jaxbridge.run.artifacts import METRICS_CSV_FIELDS
    from jaxbridge.run.comparison import read_metrics

    lone = (run_dir / "metrics.csv").is_file()
    metrics = {name: read_metrics(run_dir if lone else run_dir / name, METRICS_CSV_FIELDS) for name in names}
    for columns in metrics.values():
        del columns["seeds"]  # the config's
    return metrics


def prepare(env: EnvLike | None = None, approaches: str | Sequence[str] | None = None,
            seeds: int | Sequence[int] | None = None, cycles: int | None = None, out: str | Path | None = None,
            name: str | None = None, overwrite: bool = False, sweep: Mapping[str, Sequence] | Sequence[str] | None = None,
            workers: int | None = None, devices: list | None = None, max_memory: float | None = None,
            progress: bool = False, tensorboard: bool = False, **overrides) -> Training:
    """`train`'s checks and directory, without training yet: the Training to `run()` (see `train`). Each
    program's setup is built here once; the checks and the training read it."""
    if name is not None:
        rundir.check_name(name)
    config, env_cls = config_and_env(env, seeds, cycles, **overrides)
    names = (default_approaches(env_cls) if approaches is None else all_approaches(env_cls) if approaches == "all"
             else _approach_list(approaches))
    hyper_grid = _sweep_grid(sweep, config)
    with _refusing_setups(config):
        _check_memory(config, env_cls, names, hyper_grid, workers, max_memory)  # a lower bound, before any draw
    _check_reachable(config, env_cls)
    experiment = _plan(config, names, hyper_grid, env_cls)
    _check_memory(config, env_cls, names, hyper_grid, workers, max_memory, experiment)  # the setups' own shapes
    temporary = None if out is not None else Path(tempfile.mkdtemp(prefix="jaxbridge-"))
    run_dir, replaced, lock = Path(out if out is not None else temporary) / (name or env_cls.name), None, None
    try:
        if is_primary():  # the other processes of a multi-process run write nothing (utils/distributed.py)
            replaced = rundir.prepare(run_dir, overwrite)
            lock = rundir.RunLock(run_dir).acquire()
    except OSError as err:
        raise InputError(f"cannot write experiment directory {run_dir}: {err.strerror}") from None
    from jaxbridge.run.experiments import train_approaches  # after the refusals: it loads orbax (~0.2 s)

    work = lambda hooks: train_approaches(experiment, run_dir, hooks, workers=workers, replaced=replaced)
    return Training(dataclasses.replace(config, approach=names[0]), names, run_dir, work,
                    RunHooks(progress, tensorboard=tensorboard, devices=devices), lock, temporary,
                    _start_line(config, env_cls, names, workers))


def prepare_resume(run_dir: str | Path, workers: int | None = None, devices: list | None = None,
                   progress: bool = False, tensorboard: bool = False) -> Training:
    """`resume`'s checks and lock, without training yet: the Training to `run()`."""
    from jaxbridge.run.experiments import check_resumable, is_experiment_dir, load_experiment, train_approaches
    from jaxbridge.run.run_state import load_config
    from jaxbridge.run.runner import train as train_run

    run_dir = Path(run_dir)
    with refusing():
        if is_experiment_dir(run_dir):
            config, approaches, hyper_grid = load_experiment(run_dir)
            experiment = _plan(config, approaches, hyper_grid, load_env(config.env))
            check_resumable(run_dir, list(experiment.named))
            work = lambda hooks: train_approaches(experiment, run_dir, hooks, resume=True, workers=workers)
        else:
            config, approaches = load_config(run_dir), None
            setup = make_setup(config, load_env(config.env))
            work = lambda hooks: {config.approach: train_run(setup, run_dir, hooks, resume=True)}
    lock = rundir.RunLock(run_dir).acquire() if is_primary() else None
    return Training(config, approaches or [config.approach], run_dir, work,
                    RunHooks(progress, tensorboard=tensorboard, devices=devices), lock)


def train(env: EnvLike | None = None, approaches: str | Sequence[str] | None = "ours",
          seeds: int | Sequence[int] | None = 8, cycles: int | None = None, out: str | Path | None = None,
          name: str | None = None, overwrite: bool = False, sweep: Mapping[str, Sequence] | None = None,
          progress: bool = False, **options) -> Experiment:
    """Train approaches on an env as train.py does and return their metrics as arrays.

    `env`: a registered name, `package.module:Class` or a NoveltyEnv subclass (default light_switch_door);
    `approaches`: a name, names or a comma-separated string (jaxbridge/learn/approaches.py: ours,
    no_callplanner, maple_q, ...; None: the paper's figure for the env, as train.py); `seeds`: a count from
    0 or consecutive seeds; `cycles`: default the preset's (100). `sweep`: {field: values}, every approach at every setting (the cartesian
    product), each its own run named approach@field=value. Other keywords: any TrainConfig field
    (`help(TrainConfig)`), e.g. `preset="authors"`, `updates_per_cycle=500`, and train.py's run options
    `workers`, `devices`, `max_memory` (GiB), `tensorboard`. With `out`, the experiment directory
    `out/name` (default name: the env's) is written as train.py writes it, and `load` and eval.py read
    it; an existing one is refused unless `overwrite` (a run of ours only). Without `out`, the files go
    to a temporary directory removed on return. `progress`: the progress bar on stderr. Bad input raises
    InputError (a ValueError) in one line, before anything is written.

        experiment = jaxbridge.train("doorknobs", approaches=["ours", "maple_q"], seeds=4, cycles=20)
        experiment.metrics["ours"]["test_solve_rate"].shape   # (4, 20)
    """
    return prepare(env, approaches, seeds, cycles, out, name, overwrite, sweep, progress=progress, **options).run()


def resume(run_dir: str | Path, progress: bool = False, **options) -> Experiment:
    """Continue an experiment directory (or one approach's run directory) from its latest checkpoints, with
    its saved config, as train.py --resume; finished runs are kept. `options`: workers, devices,
    tensorboard. Its numbers are those the run would have had uninterrupted."""
    return prepare_resume(run_dir, progress=progress, **options).run()


def default_approaches(env_cls) -> list[str]:
    """What train.py trains when no approaches are given: the paper's figure for the env."""
    return list(env_cls.default_approaches or APPROACHES)


def all_approaches(env_cls) -> list[str]:
    """What `approaches="all"` (train.py --approaches all) trains: the paper's six, then any other approach
    the env's default names (Multi Novelty's selector and per-signature bridges)."""
    return list(APPROACHES) + [a for a in default_approaches(env_cls) if a not in APPROACHES]


def _approach_list(approaches: str | Sequence[str]) -> list[str]:
    """The approaches by name (a name, names, or a comma-separated string as train.py takes), each known, none
    twice."""
    names = [n.strip() for n in approaches.split(",")] if isinstance(approaches, str) else list(approaches)
    for approach in names:
        with refusing("approaches"):
            get_approach(approach)
    if not names or len(set(names)) != len(names):
        raise InputError(f"approaches: one or more names, none twice; got {names}")
    return names


def _refusing_setups(config: TrainConfig):
    """Where setups are built: a network the config cannot build (e.g. the learned selector with the
    authors' input scaling) is refused naming the approaches; with a learner of your own, naming it."""
    from jaxbridge.core.learner_settings import registered
    from jaxbridge.learn.learner import LearnerContractError

    return refusing("approaches" if config.learner.name in registered() else "learner", (ValueError, LearnerContractError))


def _plan(config: TrainConfig, names: list[str], hyper_grid: dict[str, tuple], env_cls):
    """The experiment's programs with their setups (run/experiments.plan), built once; a learner of your own
    checked against the learner contract on them (learn/learner.check_learner: shapes only)."""
    from jaxbridge.core.learner_settings import registered
    from jaxbridge.learn.approaches import BridgeKind
    from jaxbridge.learn.learner import check_learner
    from jaxbridge.run.experiments import plan

    with _refusing_setups(config):
        experiment = plan(config, names, hyper_grid, env_cls)
        for program in experiment.programs if config.learner.name not in registered() else []:
            if program.setup.approach.bridge is BridgeKind.Q:
                check_learner(program.setup.learner, program.setup.config)
    return experiment


def _sweep_grid(sweep: Mapping[str, Sequence] | Sequence[str] | None, config: TrainConfig) -> dict[str, tuple]:
    """The hyperparameter grid ({} without one) of {field: values} or train.py's --sweep texts, checked
    as train.py checks them (a field of `config` or of its learner, by name)."""
    texts = list(sweep or []) if not isinstance(sweep, Mapping) else [
        f"{key}={','.join(_sweep_text(v) for v in values)}" for key, values in sweep.items()]
    with refusing():
        return grid.parse_sweeps(texts, config)


def _sweep_text(value) -> str:
    """A value as train.py --sweep writes it: hidden_sizes (64, 64) as 64x64, env quirks as a+b or none."""
    if isinstance(value, tuple) and all(isinstance(v, str) for v in value):
        return "+".join(value) or "none"
    return grid.value_text(value)


def _check_memory(config: TrainConfig, env_cls, names: list[str], hyper_grid: dict[str, tuple], workers: int | None,
                  max_memory: float | None, experiment=None) -> None:
    """Refuse a run whose memory estimate exceeds `max_memory` GiB (default: what is available), before
    anything of its size is built (run/memory.py): from `experiment`'s setups, the ones it will run, or
    before they are built from a lower bound that draws no seed's tasks but the first's."""
    from jaxbridge.learn.devices import default_workers
    from jaxbridge.run import memory
    from jaxbridge.run.experiments import program_names, runs

    if experiment is None:
        named = runs(config, names, hyper_grid)
        programs = [(named[group[0]], len(group), None) for group in program_names(named)]
    else:
        programs = [(experiment.named[p.names[0]], len(p.names), p.setup) for p in experiment.programs]
    memory.check_training(config, env_cls, programs, workers or default_workers(programs),
                          None if max_memory is None else int(max_memory * 2**30))


def _check_reachable(config: TrainConfig, env_cls) -> None:
    """Refuse a training horizon too short for some seed's training task ever to reach its goal."""
    needed = {seed: max(spec.min_steps for spec in train_specs(env_cls, seed, config.episodes_per_cycle))
              for seed in config.seeds}
    worst = max(needed, key=needed.get)
    if config.train_steps < needed[worst]:
        raise InputError(f"{{setting}} {config.train_steps} is too small to ever reach the goal: seed {worst}'s "
                         f"training task needs at least {needed[worst]} steps", "train_steps")


def _start_line(config: TrainConfig, env_cls, approaches: list[str], workers: int | None) -> str:
    """What a run trains, what the default leaves out, and how long it should take on this machine."""
    from jaxbridge.learn.devices import default_workers
    from jaxbridge.utils import pace

    line = (f"{env_cls.name}: training {', '.join(get_approach(a).label for a in approaches)} x {config.num_seeds} "
            f"seeds x {config.cycles} cycles")
    skipped = [a for a in all_approaches(env_cls) if a not in approaches]
    if approaches == default_approaches(env_cls) and skipped:
        line += f"; not {', '.join(get_approach(a).label for a in skipped)} ({env_cls.why_not_all}): --approaches all adds it"
    seconds = pace.estimate(env_cls.name, approaches, config.num_seeds * config.cycles, workers or default_workers(approaches))
    return line + (f"; about {seconds / 60:.0f} min at this machine's measured pace" if seconds is not None else
                   "; no time estimate until this machine has trained each of them once")
