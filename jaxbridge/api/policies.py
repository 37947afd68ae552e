"""Bridges to evaluate and draw: a run's trained policy (`load`) or a hand-made bridge (`hand_made`)."""
from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from jaxbridge.api.config import default_test_protocol
from jaxbridge.api.envs import EnvLike, check_test_protocol, load_env, seed_list, sized_tasks
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.episode import Controls
from jaxbridge.core.tasks import TaskBatch
from jaxbridge.run.evaluate import format_comparison, format_table, run_bridge, summarise
from jaxbridge.utils.errors import InputError, refusing
from jaxbridge.utils.files import write_atomic


@dataclass(frozen=True)
class Episodes:
    """What `evaluate` returns: one entry per episode (seed-major), and the tasks they ran."""

    label: str  # whose bridge, e.g. "greedy bridge of ours, cycle 100"
    seeds: np.ndarray  # int[episodes]: whose network (and, for test tasks, whose task)
    specs: list  # the task specs
    success: np.ndarray  # bool[episodes]
    steps: np.ndarray  # int[episodes]: env steps taken
    planner_calls: np.ndarray  # int[episodes]
    stuck_events: np.ndarray  # int[episodes]: times the plan got stuck (novelties met)
    bridge_decisions: np.ndarray  # int[episodes]
    table_misses: np.ndarray  # int[episodes]: plan-table lookups the host planner answered
    batch: TaskBatch = field(repr=False)  # what ran, for `draw`
    result: Any = field(repr=False)

    @property
    def solve_rate(self) -> float:
        return float(self.success.mean())

    def per_seed(self) -> dict[int, float]:
        """Each seed's solve rate."""
        return {int(s): float(self.success[self.seeds == s].mean()) for s in dict.fromkeys(self.seeds.tolist())}

    def table(self) -> str:
        """eval.py's table: per seed the task size, solve rate, mean steps, planner calls, stuck events and
        bridge decisions per task, table misses; then every episode's."""
        return format_table(summarise(self.batch, self.result))


def side_by_side(evaluations: dict[str, Episodes]) -> str:
    """Several evaluations as one table, one row per seed: solve rate, mean steps, bridge decisions."""
    return format_comparison({label: summarise(e.batch, e.result) for label, e in evaluations.items()})


@dataclass(frozen=True)
class Drawn:
    """What `draw` drew: which episode, how it went, the bridge's work in words, and the files."""

    seed: int
    task: int
    success: bool
    steps: int
    summary: str  # e.g. "the bridge opened 2 doors"
    paths: tuple[Path, ...]


class Bridges:
    """Bridges that run on batches of an env's tasks: what `Policy` and `HandMade` share."""

    label = ""

    def on(self, batch: TaskBatch):
        """(bridge, per-episode bridge params, controls) for the batch."""
        raise NotImplementedError

    def episodes(self, batch: TaskBatch, rollout_seed: int = 0) -> Episodes:
        bridge, params, controls = self.on(batch)
        result = run_bridge(batch, bridge, params, rollout_seed, controls)
        return Episodes(self.label, np.asarray(batch.seeds), list(batch.specs), result.success, result.steps,
                        result.planner_calls, result.stuck_events, result.bridge_decisions, result.table_misses,
                        batch, result)

    def draw(self, episodes: Episodes, png: str | Path | None = None, gif: str | Path | None = None,
             episode: int | None = None, rollout_seed: int = 0) -> Drawn:
        """Re-run one of `episodes` (index `episode`; default: the first seed's solved episode on which the
        bridge did the most) with recording on; draw it to `png` and animate it to `gif` (one frame per
        step). The rollout seed must be the evaluation's."""
        from jaxbridge.viz.animate import render_gif  # matplotlib and PIL: only when drawing
        from jaxbridge.viz.episodes import pick_episode
        from jaxbridge.viz.render import drawer_for, render_episode, trace_episodes

        batch = episodes.batch
        if episode is not None and not 0 <= episode < batch.size:
            raise InputError(f"{{setting}} must be below {batch.size}, the number of evaluated tasks, got {episode}",
                             "render_task")
        with refusing():
            drawer = drawer_for(batch.env)
        chosen = [episode] if episode is not None else np.flatnonzero(batch.seeds == batch.seeds[0])
        bridge, params, controls = self.on(batch)
        traces = trace_episodes(batch, bridge, params, chosen, rollout_seed, controls, expected=episodes.result)
        trace = traces[0] if episode is not None else pick_episode(traces)
        drawn = []
        for path, draw in ((png, render_episode), (gif, render_gif)):
            if path is not None:
                try:
                    write_atomic(Path(path), draw(batch.env, trace, self.label))
                except OSError as err:
                    raise InputError(f"cannot write {path}: {err.strerror or err}") from None
                drawn.append(Path(path))
        return Drawn(int(trace.seed), int(trace.task), bool(trace.success), int(trace.steps),
                     drawer.bridge_summary(trace), tuple(drawn))


class Policy(Bridges):
    """A run's checkpoint as greedy bridges, one per seed (`load`): the latest, or that of `cycle`."""

    def __init__(self, run_dir: str | Path, cycle: int | None = None):
        from jaxbridge.run.evaluate import load_policy

        self.run_dir = Path(run_dir)
        with refusing():  # a config that does not load; CheckpointError is an InputError already
            self.trained = load_policy(self.run_dir, cycle)
        self.label = f"greedy bridge of {self.config.approach}, cycle {self.cycle}"

    @property
    def config(self) -> TrainConfig:
        return self.trained.config

    @property
    def models(self) -> dict | None:
        """A repair run's learned planner models by seed (`.pddl()` each), as its checkpoint's cycle had them;
        None for a run that learns none."""
        return self.trained.models

    @property
    def cycle(self) -> int:
        """The checkpoint's cycle."""
        return self.trained.step

    def on(self, batch: TaskBatch):
        return self.trained.on(batch)

    def evaluate(self, tasks: Sequence | None = None, task_size: dict[str, int] | None = None,
                 seeds: Sequence[int] | None = None, num_tasks: int = 10, rollout_seed: int = 0,
                 max_memory: float | None = None, test_protocol: str | None = None) -> Episodes:
        """Greedy episodes: each seed's test tasks (default; under another of the env's `test_protocols`
        with `test_protocol`, e.g. held-out combinations), `num_tasks` tasks per seed of `task_size` (as eval.py
        --task-size), or every spec of `tasks` with each seed's network. `seeds`: a subset of the run's
        (default: all). Rollouts draw from `rollout_seed`. Drawn or given tasks whose plan tables would
        exceed `max_memory` GiB (default: what is available) are refused (InputError)."""
        return self.episodes(self.tasks(tasks, task_size, seeds, num_tasks, max_memory, test_protocol), rollout_seed)

    def planner_alone(self, rollout_seed: int = 0, **which_tasks) -> Episodes:
        """A repair run's (ours_model_repair) learned planner alone on `evaluate`'s tasks (`which_tasks`, as
        there): no bridge, so a stall ends in failure (the planner plans again from the state it stalled in,
        and stalls again). InputError for a run that learns no model."""
        return self.alone().evaluate(rollout_seed=rollout_seed, **which_tasks)

    def alone(self) -> "Policy":
        """This run's learned planner with no bridge, as a Policy (InputError for a run that learns no model)."""
        if self.trained.models is None:
            raise InputError(f"{self.config.approach} learns no planner model: the planner alone is a model repair "
                             f"run's (ours_model_repair)")
        alone = copy.copy(self)
        alone.trained = dataclasses.replace(self.trained, planner_alone=True)
        alone.label = f"learned planner alone of {self.config.approach}, cycle {self.cycle}"
        return alone

    def with_domain(self, path: str | Path) -> "Policy":
        """This repair run planning with the PDDL domain in `path` (a run's models/seed<N>.pddl, edited or
        not) as every seed's model, each seed's samplers by operator name; InputError, in one line, for a
        run that learns no model, a file that does not read as a domain, or a foreign one (a type,
        predicate or skill some seed's model does not define)."""
        from planner import PDDLError, read_domain

        if self.trained.models is None:
            raise InputError(f"{self.config.approach} learns no planner model: a domain file replaces a model repair "
                             f"run's (ours_model_repair)")
        try:
            domain = read_domain(Path(path).read_text())
        except (OSError, UnicodeDecodeError, PDDLError) as err:
            raise InputError(f"{path}: {err}") from None
        skills = [skill.name for skill in load_env(self.config.env).skills]
        with_domain = copy.copy(self)
        try:
            models = {seed: model.with_domain(domain, skills) for seed, model in self.trained.models.items()}
        except InputError as err:
            raise InputError(f"{path}: {err}") from None
        with_domain.trained = dataclasses.replace(self.trained, models=models)
        with_domain.label = f"{self.label}, domain {Path(path).name}"
        return with_domain

    def attention(self, episodes: Episodes, rollout_seed: int = 0):
        """What a learned object selector (ours_learned_selection) looks at on `episodes`' tasks: per seed,
        the fraction of bridge decisions whose most attended object is the one the env's fix acts on
        (`NoveltyEnv.oracle_object`). An `Attention` (run/attention.py); InputError for another approach."""
        from jaxbridge.run.attention import attention_agreement

        with refusing("attention"):
            return attention_agreement(self.trained, episodes.batch, rollout_seed)

    def render(self, path: str | Path, episode: int = 0, rollout_seed: int = 0, **which_tasks) -> Path:
        """Draw episode `episode` of `evaluate(**which_tasks)` to a PNG at `path`, as eval.py --render."""
        self.draw(self.evaluate(rollout_seed=rollout_seed, **which_tasks), png=path, episode=episode,
                  rollout_seed=rollout_seed)
        return Path(path)

    def tasks(self, tasks=None, task_size=None, seeds=None, num_tasks: int = 10, max_memory=None,
              test_protocol=None) -> TaskBatch:
        """The batch `evaluate` runs (see there)."""
        from jaxbridge.run.evaluate import policy_tasks

        if tasks is not None and task_size is not None:
            raise InputError("give tasks or task_size, not both")
        if test_protocol is not None:
            if tasks is not None or task_size is not None:
                raise InputError("{setting} picks the seeds' test tasks; it does not go with given or sized tasks",
                                 "test_protocol")
            check_test_protocol(self.trained.env_cls, test_protocol)
        sized = None if task_size is None else sized_tasks(self.trained.env_cls, task_size)
        seeds = None if seeds is None else [int(s) for s in seeds]
        limit = None if max_memory is None else int(max_memory * 2**30)
        with refusing():
            return policy_tasks(self.trained, sized, num_tasks, limit, seeds=seeds, specs=tasks, protocol=test_protocol)


def load(run_dir: str | Path, approach: str | None = None, cycle: int | None = None,
         domain: str | Path | None = None) -> Policy:
    """The trained policy of a run directory (train.py's runs/ENV/APPROACH, or `train(..., out=...)`'s); an
    experiment directory gives its `approach` run (default ours; approach@setting in a sweep). `cycle`: the
    checkpoint saved after that cycle (a run keeps its latest two and those of its `keep_cycles`).
    `domain`: a repair run planning with that PDDL file's domain (`Policy.with_domain`)."""
    policy = Policy(run_directory(Path(run_dir), approach), cycle)
    return policy if domain is None else policy.with_domain(domain)


def run_directory(path: Path, approach: str | None = None) -> Path:
    """The run to load: `path` itself, or its approach's run inside an experiment directory."""
    if approach is not None and (Path(approach).name != approach or approach.startswith(".")):
        raise InputError(f"{{setting}} {approach!r}: a run name inside the experiment directory, not a path",
                         "approach")
    if (path / "experiment.json").is_file():
        chosen = path / (approach or "ours")
        if not (chosen / "config.json").is_file():
            raise InputError(f"{path} holds no {approach or 'ours'} run (it holds: "
                             f"{', '.join(runs_in(path)) or 'none'}); pick one with {{setting}}", "approach")
        return chosen
    if approach is not None and (path / "config.json").is_file():
        raise InputError(f"{{setting}} picks a run inside an experiment directory; {path} is a single run", "approach")
    if not (path / "config.json").is_file():
        raise InputError(f"{path} is not a run directory (no config.json); train one with train.py")
    return path


def runs_in(experiment: Path) -> list[str]:
    """The run directories an experiment directory holds, by name."""
    return sorted(p.name for p in Path(experiment).iterdir() if (p / "config.json").is_file())


class HandMade(Bridges):
    """A hand-made bridge on an env's test tasks (`hand_made`): oracle, random or none (pure planning)."""

    LABELS = {"oracle": "oracle bridge", "random": "random bridge", "none": "pure planning"}

    def __init__(self, env: EnvLike, bridge: str = "oracle", protocol: str | None = None):
        self.env_cls, self.bridge = load_env(env), bridge
        self.protocol = protocol or default_test_protocol(self.env_cls)
        check_test_protocol(self.env_cls, self.protocol)
        if bridge not in self.LABELS:
            raise InputError(f"unknown bridge {bridge!r}; choose from {', '.join(self.LABELS)}")
        self.label = self.LABELS[bridge]

    def on(self, batch: TaskBatch):
        from jaxbridge.core.bridges import make_bridge

        with refusing():  # an env without an oracle
            return make_bridge(self.bridge, batch.env), None, Controls()

    def tasks(self, seeds: int | Sequence[int] = 8, num_tasks: int = 10, max_memory: float | None = None) -> TaskBatch:
        """Each seed's test tasks of the protocol, with their plan tables (refused with InputError if they
        would exceed `max_memory` GiB, default what is available)."""
        from jaxbridge.core.tasks import evaluation_specs, make_batch
        from jaxbridge.run.memory import check_evaluation
        from jaxbridge.utils.progress import SlowWork

        with refusing():  # a protocol the env lacks
            specs, owners = evaluation_specs(self.env_cls, seed_list(seeds), num_tasks, self.protocol)
        check_evaluation(self.env_cls, specs, None if max_memory is None else int(max_memory * 2**30))
        batch = make_batch(self.env_cls, specs, owners, progress=SlowWork(f"{self.env_cls.name}: test tasks and plan tables"))
        self.on(batch)  # refuse a bridge the env lacks before any rollout
        return batch

    def evaluate(self, seeds: int | Sequence[int] = 8, num_tasks: int = 10, rollout_seed: int = 0,
                 max_memory: float | None = None) -> Episodes:
        """One episode of each seed's test tasks (`seeds`: a count from 0 or the seeds)."""
        return self.episodes(self.tasks(seeds, num_tasks, max_memory), rollout_seed)

    def describe(self, tasks: int) -> str:
        """The env, the bridge, `tasks` test tasks, and their protocol where it is not the env's default."""
        note = ("" if self.protocol == default_test_protocol(self.env_cls)
                else f" ({self.protocol} protocol: {self.env_cls.test_protocols[self.protocol]})")
        return f"{self.env_cls.name}, bridge = {self.bridge}, {tasks} test tasks{note}"


def hand_made(env: EnvLike, bridge: str = "oracle", protocol: str | None = None) -> HandMade:
    """A hand-made bridge to evaluate and draw as a trained policy is: "oracle" (the env's hand-written
    novelty fixer), "random" (a uniformly random applicable action whenever stuck) or "none" (pure
    planning: re-plan whenever stuck), on the env's test tasks of `protocol` (default: train.py's)."""
    return HandMade(env, bridge, protocol)
