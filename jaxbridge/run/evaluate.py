"""Evaluate a bridge on every seed's test tasks and summarise per seed."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxbridge.core.bridges import Bridge, PurePlanningBridge
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.meta_policy import Controls, EpisodeResult, MetaPolicy, rollout
from jaxbridge.core.tasks import TaskBatch, evaluation_batch, make_batch
from jaxbridge.learn.approaches import Approach
from jaxbridge.learn.setup import Setup
from jaxbridge.run.memory import check_evaluation, model_batches_fit
from jaxbridge.run.model_repair import load_models, planned_with
from jaxbridge.run.runner import load_learners
from jaxbridge.utils.progress import SlowWork


@dataclass
class SeedSummary:
    seed: int
    tasks: int
    solve_rate: float
    mean_steps: float
    planner_calls: float  # per task
    table_misses: int
    bridge_decisions: float  # per task
    stuck_events: float  # per task: novelties met (the planner got stuck)
    task_size: str  # e.g. "11 cells, 3 doors"; "N different tasks" when the seed's tasks differ


def batch_rollout(batch: TaskBatch, bridge: Bridge, bridge_params=None, seed: int = 0,
                  controls: Controls = Controls(), record: bool = False):
    """`rollout` of every task in the batch (bridge_params: None or batched over tasks), each episode's key
    drawn from `seed` as every evaluation draws it; (EpisodeResult, StepRecord or None)."""
    return rollout(MetaPolicy(batch.env, bridge, bridge_params, controls), batch.arrays,
                   jax.random.split(jax.random.key(seed), batch.size), batch.max_steps, record=record,
                   groups=jnp.asarray(batch.seeds, jnp.int32))


def run_bridge(batch: TaskBatch, bridge: Bridge, bridge_params=None, seed: int = 0,
               controls: Controls = Controls()) -> EpisodeResult:
    """One rollout of every task in the batch, its results on the host."""
    return jax.tree.map(np.asarray, batch_rollout(batch, bridge, bridge_params, seed, controls)[0])


def summarise(batch: TaskBatch, result: EpisodeResult) -> list[SeedSummary]:
    rows = []
    for seed in dict.fromkeys(batch.seeds.tolist()):
        mine = batch.seeds == seed
        rows.append(SeedSummary(
            seed=int(seed), tasks=int(mine.sum()), solve_rate=float(result.success[mine].mean()),
            mean_steps=float(result.steps[mine].mean()),
            planner_calls=float(result.planner_calls[mine].mean()),
            table_misses=int(result.table_misses[mine].sum()),
            bridge_decisions=float(result.bridge_decisions[mine].mean()),
            stuck_events=float(result.stuck_events[mine].mean()),
            task_size=_describe([s for s, m in zip(batch.specs, mine) if m])))
    return rows


def _describe(specs: list) -> str:
    """The seed's task size if all its tasks share it (Light Switch Door draws it once per seed), else a
    count (Doorknobs maps differ task by task; `eval.py --render` shows one)."""
    sizes = {s.describe() for s in specs}
    return sizes.pop() if len(sizes) == 1 else f"{len(sizes)} different tasks"


def format_table(rows: list[SeedSummary]) -> str:
    header = (f"{'seed':>4}  {'task size':<20} {'tasks':>5}  {'solve rate':>10}  {'mean steps':>10}  "
              f"{'planner calls/task':>18}  {'stuck/task':>10}  {'bridge decisions/task':>21}  {'table misses':>12}")
    lines = [header, "-" * len(header)]
    for r in rows:
        lines.append(f"{r.seed:>4}  {r.task_size:<20} {r.tasks:>5}  {r.solve_rate:>10.2f}  {r.mean_steps:>10.1f}  "
                     f"{r.planner_calls:>18.1f}  {r.stuck_events:>10.1f}  {r.bridge_decisions:>21.1f}  {r.table_misses:>12d}")
    n = sum(r.tasks for r in rows)
    mean = lambda f: sum(f(r) * r.tasks for r in rows) / n
    lines.append("-" * len(header))
    lines.append(f"{'all':>4}  {'':<20} {n:>5}  {mean(lambda r: r.solve_rate):>10.2f}  "
                 f"{mean(lambda r: r.mean_steps):>10.1f}  {mean(lambda r: r.planner_calls):>18.1f}  "
                 f"{mean(lambda r: r.stuck_events):>10.1f}  "
                 f"{mean(lambda r: r.bridge_decisions):>21.1f}  {sum(r.table_misses for r in rows):>12d}")
    return "\n".join(lines)


@dataclass
class TrainedPolicy:
    """A run's latest checkpoint as greedy bridges (one per seed) that run on any batch of its env's tasks."""

    setup: Setup
    step: int  # the checkpoint's cycle
    learners: Any  # stacked over config.seeds
    models: dict | None = None  # a repair run's learned models by seed (run/model_repair.py), its planner's
    planner_alone: bool = False  # its learned planner with no bridge (a repair run's)

    @property
    def config(self) -> TrainConfig:
        return self.setup.config

    @property
    def approach(self) -> Approach:
        return self.setup.approach

    @property
    def env_cls(self) -> type:
        return self.setup.env_cls

    def can_see(self, env) -> bool:
        """False where the approach's input cannot hold the env's tasks (the full-state ablations are
        sized to the largest test task)."""
        return env.full_state_fits or not self.approach.controls.observation.whole_state

    def on(self, batch: TaskBatch) -> tuple[Bridge, Any, Controls]:
        """(bridge, per-episode greedy params, controls) for the batch: each episode gets its seed's network
        (none with `planner_alone`)."""
        index = {seed: i for i, seed in enumerate(self.config.seeds)}
        if not set(batch.seeds.tolist()) <= index.keys():
            raise ValueError(f"the batch has tasks of seeds this run did not train ({self.config.seeds})")
        if self.planner_alone:
            return PurePlanningBridge(batch.env), None, Controls()
        return self.setup.greedy_policy(batch.env, self.learners, np.array([index[s] for s in batch.seeds.tolist()]))

    def planned(self, batch: TaskBatch) -> TaskBatch:
        """`batch` planned as the run plans: with its seeds' learned models (a repair run's), else as it is."""
        return batch if self.models is None else planned_with(batch, self.models)

    def run(self, batch: TaskBatch, seed: int = 0) -> EpisodeResult:
        bridge, greedy, controls = self.on(batch)
        return run_bridge(batch, bridge, greedy, seed, controls)


def load_policy(run_dir, cycle: int | None = None) -> TrainedPolicy:
    """The greedy policy of a run directory's checkpoint after `cycle` (default: the latest;
    CheckpointError/ValueError if unusable)."""
    setup, learners, step = load_learners(Path(run_dir), cycle)
    models = load_models(Path(run_dir), step, setup.config.seeds) if setup.approach.repairs_model else None
    return TrainedPolicy(setup, step, learners, models)


def evaluate_run(run_dir, sized_specs=None, num_tasks: int = 10, seed: int = 0, max_memory: int | None = None):
    """Greedy evaluation of a run's latest checkpoint on each seed's test tasks, or on tasks drawn by
    `sized_specs(rng) -> spec` (`policy_tasks`). Also returns the greedy policy it ran, (bridge,
    per-episode params, controls), so an episode can be re-run and drawn."""
    policy = load_policy(run_dir)
    batch = policy_tasks(policy, sized_specs, num_tasks, max_memory)
    bridge, greedy, controls = policy.on(batch)
    result = run_bridge(batch, bridge, greedy, seed, controls)
    return policy.config, policy.step, batch, result, (bridge, greedy, controls)


def sized_specs_per_seed(seeds: list[int], num_tasks: int, draw) -> dict[int, list]:
    """{seed: `num_tasks` specs drawn by `draw(rng) -> spec`}, the rng seeded from the seed (seed + 20000:
    apart from the seed's own training and test draws)."""
    return {s: [draw(rng) for _ in range(num_tasks)] for s in seeds for rng in [np.random.default_rng(s + 20000)]}


def policy_tasks(policy: TrainedPolicy, sized_specs=None, num_tasks: int = 10, max_memory: int | None = None,
                 seeds: list[int] | None = None, specs: list | None = None, protocol: str | None = None) -> TaskBatch:
    """The batch a policy is evaluated on: each of `seeds`' (default: the run's) test tasks under `protocol`
    (default: the run's); or
    `num_tasks` per seed drawn by `sized_specs(rng) -> spec` (`sized_specs_per_seed`); or every spec
    of `specs` for each seed. Drawn or given tasks are refused with TooBig if their plan tables would
    exceed `max_memory` bytes or the memory available, and so are any tasks a repair run plans with its learned
    models (tables per seed); the env has its quirks as the run trained."""
    config, env_cls = policy.config, policy.env_cls
    seeds = config.seeds if seeds is None else seeds
    if sized_specs is None and specs is None:
        batch = evaluation_batch(env_cls, seeds, config.num_test_tasks, protocol=protocol or config.test_protocol)
    else:
        sized = specs is None
        by_seed = sized_specs_per_seed(seeds, num_tasks, sized_specs) if sized else {s: list(specs) for s in seeds}
        specs, owners = [t for s in seeds for t in by_seed[s]], [s for s in seeds for _ in by_seed[s]]
        check_evaluation(env_cls, specs, max_memory)
        sweep = env_cls.novelty_sweep if sized else None  # its horizon rule scales with the tasks' size
        batch = make_batch(env_cls, specs, owners, horizons=[sweep.horizon(s) for s in specs] if sweep else None,
                           progress=SlowWork(f"{env_cls.name}: {'sized' if sized else 'given'} tasks and plan tables"))
    planned = policy.planned(dataclasses.replace(batch, env=batch.env.with_quirks(config.env_quirks)))
    if policy.models is not None:
        model_batches_fit(planned, max_memory)
    return planned


def format_comparison(evaluations: dict[str, list[SeedSummary]]) -> str:
    """Several evaluations side by side, one row per seed (blank where a run lacks the seed): solve
    rate, mean steps and bridge decisions per task of each, then the all-seed means."""
    labels = list(evaluations)
    width = max(24, *(len(label) for label in labels))
    seeds = sorted({r.seed for rows in evaluations.values() for r in rows})
    by_seed = {label: {r.seed: r for r in rows} for label, rows in evaluations.items()}
    cols = lambda r: f"{r.solve_rate:>6.2f} {r.mean_steps:>7.1f} {r.bridge_decisions:>9.1f}"
    blank = " " * len(cols(SeedSummary(0, 0, 0.0, 0.0, 0.0, 0, 0.0, 0.0, "")))
    lines = ["seed  " + "  ".join(f"{label:>{width}}" for label in labels),
             "      " + "  ".join(f"{'solve   steps decisions':>{width}}" for _ in labels)]
    lines.append("-" * len(lines[0]))
    for seed in seeds:
        cells = [cols(by_seed[l][seed]) if seed in by_seed[l] else blank for l in labels]
        lines.append(f"{seed:>4}  " + "  ".join(f"{c:>{width}}" for c in cells))
    lines.append("-" * len(lines[0]))
    totals = []
    for label in labels:
        rows = evaluations[label]
        n = sum(r.tasks for r in rows)
        mean = lambda f: sum(f(r) * r.tasks for r in rows) / n
        totals.append(cols(SeedSummary(-1, n, mean(lambda r: r.solve_rate), mean(lambda r: r.mean_steps), 0.0, 0,
                                       mean(lambda r: r.bridge_decisions), 0.0, "")))
    lines.append(" all  " + "  ".join(f"{c:>{width}}" for c in totals))
    return "\n".join(lines)
