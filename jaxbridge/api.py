"""The Python API: train, load and evaluate from a script or notebook, and a whole run as one pure function.

    import jax, jaxbridge
    experiment = jaxbridge.train("light_switch_door", approaches="ours", seeds=4, cycles=20)
    experiment.curve("ours")                       # mean test solve rate per cycle
    policy = jaxbridge.load("runs/light_switch_door")
    policy.evaluate(task_size={"cells": 40, "doors": 3}).solve_rate

    config = jaxbridge.TrainConfig.for_env("light_switch_door", num_seeds=4, cycles=10)
    out = jax.jit(jaxbridge.make_train(config))()  # every cycle of every seed, one program, no files

docs/API.md shows each call with what it returns. train.py and eval.py are these calls behind flags.
"""
from __future__ import annotations

import tempfile
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from envs_jax import NoveltyEnv, env_class
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.online import TrainOutput
from jaxbridge.learn.setup import make_setup, seed_keys
from jaxbridge.run.artifacts import METRICS_CSV_FIELDS
from jaxbridge.run.comparison import read_metrics

__all__ = ["Episodes", "Experiment", "Hyper", "Policy", "TrainConfig", "TrainOutput", "load", "make_config", "make_env",
           "make_train", "seed_keys", "tasks", "train"]


def make_env(env: str | type[NoveltyEnv], **capacity) -> NoveltyEnv:
    """An env instance: `env` by name ("light_switch_door", "package.module:Class") or class, sized by its
    capacity fields (e.g. `make_env("light_switch_door", max_cells=40, max_doors=6)`; default: the
    class's defaults). Its methods are the env contract (envs_jax/base.py, docs/NEW_ENV.md)."""
    return _env_class(env)(**capacity)


def tasks(env: str | type[NoveltyEnv], seeds: int | Iterable[int], num_tasks: int = 10,
          size: dict[str, int] | None = None, protocol: str = "jaxbridge") -> dict[int, list]:
    """Each seed's task specs: its test tasks (`env.test_tasks(seed, num_tasks, protocol)`), or with `size`
    (the env's `task_sizes`, e.g. {"cells": 40, "doors": 3}) tasks of that size, drawn as eval.py
    --task-size draws them. `seeds`: a count (0..n-1) or the seeds. Returns {seed: [spec, ...]}."""
    from jaxbridge.run.evaluate import sized_specs_per_seed

    env_cls = _env_class(env)
    if size is None:
        return {s: list(env_cls.test_tasks(s, num_tasks, protocol)) for s in _seed_list(seeds)}
    return sized_specs_per_seed(_seed_list(seeds), num_tasks, lambda rng: env_cls.sized_task(rng, **size))


def make_config(env: str | type[NoveltyEnv] = "light_switch_door", seeds: int | Sequence[int] = 8, cycles: int = 100,
           **overrides) -> TrainConfig:
    """The TrainConfig of an env (the preset's values for it, `preset="authors"` for the authors') with
    `seeds` (a count from 0, or consecutive seeds), `cycles` and any field as a keyword."""
    listed = _seed_list(seeds)
    if listed != list(range(listed[0], listed[0] + len(listed))):
        raise ValueError(f"seeds must be consecutive, got {listed}")
    return TrainConfig.for_env(_env_name(env), first_seed=listed[0], num_seeds=len(listed), cycles=cycles, **overrides)


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
    """What `train` returns: every approach's metrics as arrays, and results.md's statistics."""

    config: TrainConfig  # the settings every approach shares (its `approach` field: the first's)
    approaches: tuple[str, ...]
    metrics: dict[str, dict[str, np.ndarray]]  # approach -> metrics.csv column -> float[seeds, cycles]
    summaries: dict[str, dict]  # approach -> summary.json: means, IQMs and 95% CIs at the report cycles
    run_dir: Path | None  # the experiment directory, where `out` was given

    @property
    def seeds(self) -> list[int]:
        return self.config.seeds

    def curve(self, approach: str = "ours", metric: str = "test_solve_rate") -> np.ndarray:
        """The mean over seeds of a metric per cycle (float[cycles])."""
        return self.metrics[approach][metric].mean(axis=0)


def train(env: str | type[NoveltyEnv] = "light_switch_door", approaches: str | Sequence[str] = "ours",
          seeds: int | Sequence[int] = 8, cycles: int = 100, out: str | Path | None = None, name: str | None = None,
          overwrite: bool = False, progress: bool = False, **overrides) -> Experiment:
    """Train approaches on an env as train.py does and return their metrics as arrays.

    `approaches`: a name or names (jaxbridge/learn/approaches.py: ours, no_callplanner, maple_q, ...);
    `seeds`: a count from 0 or consecutive seeds; `overrides`: any TrainConfig field (`help(TrainConfig)`),
    e.g. `preset="authors"`, `updates_per_cycle=500`. With `out`, the experiment directory `out/name`
    (default name: the env's) is written as train.py writes it, and `load` and eval.py read it; an
    existing one is refused (RunDirError) unless `overwrite` (a run of ours only, as train.py
    --overwrite). Without `out`, the run's files go to a temporary directory removed on return.
    `progress`: the progress bar on stderr.

        experiment = jaxbridge.train("doorknobs", approaches=["ours", "maple_q"], seeds=4, cycles=20)
        experiment.metrics["ours"]["test_solve_rate"].shape   # (4, 20)
    """
    from jaxbridge.run import rundir
    from jaxbridge.run.experiments import train_approaches

    names = [approaches] if isinstance(approaches, str) else list(approaches)
    for approach in names:
        get_approach(approach)  # ValueError naming the known ones
    base = make_config(env, seeds, cycles, approach=names[0], **overrides)
    with nullcontext(Path(out)) if out is not None else tempfile.TemporaryDirectory() as root:
        run_dir = Path(root) / (name or _env_class(env).name)
        replaced = rundir.prepare(run_dir, overwrite)
        summaries = train_approaches(base, names, run_dir, progress, replaced=replaced)
        metrics = {approach: read_metrics(run_dir / approach, METRICS_CSV_FIELDS) for approach in names}
    for columns in metrics.values():
        del columns["seeds"]  # the config's
    return Experiment(base, tuple(names), metrics, summaries, run_dir if out is not None else None)


@dataclass(frozen=True)
class Episodes:
    """What `Policy.evaluate` returns: one entry per episode (seed-major), and the tasks they ran."""

    seeds: np.ndarray  # int[episodes]: whose network (and, for test tasks, whose task)
    specs: list  # the task specs
    success: np.ndarray  # bool[episodes]
    steps: np.ndarray  # int[episodes]: env steps taken
    planner_calls: np.ndarray  # int[episodes]
    stuck_events: np.ndarray  # int[episodes]: times the plan got stuck (novelties met)
    bridge_decisions: np.ndarray  # int[episodes]

    @property
    def solve_rate(self) -> float:
        return float(self.success.mean())

    def per_seed(self) -> dict[int, float]:
        """Each seed's solve rate."""
        return {int(s): float(self.success[self.seeds == s].mean()) for s in dict.fromkeys(self.seeds.tolist())}


class Policy:
    """A run's latest checkpoint as greedy bridges, one per seed (`load`)."""

    def __init__(self, run_dir: str | Path):
        from jaxbridge.run.evaluate import load_policy

        self.run_dir = Path(run_dir)
        self._trained = load_policy(self.run_dir)

    @property
    def config(self) -> TrainConfig:
        return self._trained.config

    @property
    def cycle(self) -> int:
        """The checkpoint's cycle."""
        return self._trained.step

    def evaluate(self, tasks: Sequence | None = None, task_size: dict[str, int] | None = None,
                 seeds: Sequence[int] | None = None, num_tasks: int = 10, rollout_seed: int = 0) -> Episodes:
        """Greedy episodes: each seed's test tasks (default), `num_tasks` tasks per seed of `task_size`
        (as eval.py --task-size), or every spec of `tasks` with each seed's network. `seeds`: a subset
        of the run's (default: all). Rollouts draw from `rollout_seed`."""
        batch = self._batch(tasks, task_size, seeds, num_tasks)
        result = self._trained.run(batch, rollout_seed)
        return Episodes(np.asarray(batch.seeds), list(batch.specs), result.success, result.steps, result.planner_calls,
                        result.stuck_events, result.bridge_decisions)

    def render(self, path: str | Path, episode: int = 0, tasks: Sequence | None = None,
               task_size: dict[str, int] | None = None, seeds: Sequence[int] | None = None, num_tasks: int = 10,
               rollout_seed: int = 0) -> Path:
        """Draw one episode of `evaluate(...)`'s (index `episode`) to a PNG at `path`, as eval.py --render."""
        from jaxbridge.utils.files import write_atomic
        from jaxbridge.viz.render import render_episode, trace_episodes

        batch = self._batch(tasks, task_size, seeds, num_tasks)
        bridge, greedy, controls = self._trained.on(batch)
        trace = trace_episodes(batch, bridge, greedy, [episode], rollout_seed, controls)[0]
        write_atomic(Path(path), render_episode(batch.env, trace, f"greedy bridge of {self.config.approach}, "
                                                                  f"cycle {self.cycle}"))
        return Path(path)

    def _batch(self, tasks, task_size, seeds, num_tasks):
        from jaxbridge.run.evaluate import policy_tasks

        if tasks is not None and task_size is not None:
            raise ValueError("give tasks or task_size, not both")
        sized = None if task_size is None else (lambda rng: self._trained.env_cls.sized_task(rng, **task_size))
        seeds = None if seeds is None else [int(s) for s in seeds]
        return policy_tasks(self._trained, sized, num_tasks, seeds=seeds, specs=tasks)


def load(run_dir: str | Path) -> Policy:
    """The trained policy of a run directory (`train(..., out=...)`'s `out/name/approach`, or train.py's
    runs/ENV/APPROACH); an experiment directory gives its "ours" run."""
    run_dir = Path(run_dir)
    if not (run_dir / "checkpoints").is_dir() and (run_dir / "ours" / "checkpoints").is_dir():
        run_dir = run_dir / "ours"
    return Policy(run_dir)


# ---- helpers ----------------------------------------------------------------------------------------
def _env_class(env: str | type[NoveltyEnv]) -> type[NoveltyEnv]:
    return env_class(env) if isinstance(env, str) else env


def _env_name(env: str | type[NoveltyEnv]) -> str:
    """A name TrainConfig.env resolves: the registered name, or package.module:Class for a class."""
    if isinstance(env, str):
        return env
    try:
        if env_class(env.name) is env:
            return env.name
    except ValueError:  # not registered under its name
        pass
    return f"{env.__module__}:{env.__qualname__}"


def _seed_list(seeds: int | Iterable[int]) -> list[int]:
    listed = list(range(seeds)) if isinstance(seeds, int) else [int(s) for s in seeds]
    if not listed or min(listed) < 0:
        raise ValueError(f"seeds: a positive count or non-negative seeds, got {seeds!r}")
    return listed
