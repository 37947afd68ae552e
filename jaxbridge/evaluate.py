"""Evaluate a bridge on every seed's test tasks and summarise per seed."""
from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np

from jaxbridge.bridges import Bridge
from jaxbridge.meta_policy import Controls, EpisodeResult, rollout
from jaxbridge.tasks import TaskBatch


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


def run_bridge(batch: TaskBatch, bridge: Bridge, bridge_params=None, seed: int = 0,
               controls: Controls = Controls()) -> EpisodeResult:
    """One rollout of every task in the batch (bridge_params: None or batched over tasks)."""
    result, _ = rollout(batch.env, bridge, bridge_params, batch.tasks, batch.tables, batch.horizons,
                        jax.random.split(jax.random.key(seed), batch.size), batch.max_steps, controls=controls)
    return jax.tree.map(np.asarray, result)


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


def evaluate_run(run_dir, sized_specs=None, num_tasks: int = 10, seed: int = 0):
    """Greedy evaluation of a run's latest checkpoint on each seed's test tasks, or on tasks drawn by
    `sized_specs(rng) -> spec` (num_tasks per seed, rng seeded from the seed). Also returns the greedy
    policy it ran, (bridge, per-episode params, controls), so an episode can be re-run and drawn."""
    from jaxbridge.online import episode_params
    from jaxbridge.runner import load_learners
    from jaxbridge.tasks import make_batch

    config, experiment, learners, step = load_learners(run_dir)
    batch = experiment.test
    if sized_specs is not None:
        specs, owners = [], []
        for s in config.seeds:
            rng = np.random.default_rng(s + 20000)
            specs += [sized_specs(rng) for _ in range(num_tasks)]
            owners += [s] * num_tasks
        batch = make_batch(type(experiment.env), specs, owners)
    owner = np.searchsorted(np.asarray(config.seeds), batch.seeds)
    approach = experiment.approach
    bridge = approach.make_bridge(batch.env, experiment.net, config.n_sample)
    greedy = episode_params(learners, owner, np.zeros(len(owner), np.float32))
    result = run_bridge(batch, bridge, greedy, seed, approach.controls)
    return config, step, batch, result, (bridge, greedy, approach.controls)
