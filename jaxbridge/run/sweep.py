"""The generalisation sweep (the paper's Q2, taken further): trained bridges on tasks with more and more
novelty instances than they trained or were tested on (`eval.py RUN --sweep novelties`).

Each env states its sweep (`NoveltySweep`: what is counted, the counts, how to draw a task with k of them
and the task's horizon). The sweep's tasks are drawn once, from `sweep_seed`, and every seed of every
approach meets the same ones, so two lines differ only by their policies. All counts go into one batch:
one rollout (one compilation) per approach; a repair run's, whose tables are per seed and large, in as few
groups of seeds as memory allows.
"""
from __future__ import annotations

import csv
import io
from dataclasses import dataclass

import numpy as np

from envs_jax.base import NoveltyEnv
from jaxbridge.core.tasks import TaskBatch, make_batch
from jaxbridge.run.evaluate import TrainedPolicy
from jaxbridge.run.memory import model_batches_fit
from jaxbridge.utils import stats


@dataclass
class SweepResult:
    env: str
    counted: str  # what the counts count, e.g. "doors"
    setting: str  # e.g. "in a row of 60 cells"
    counts: tuple[int, ...]
    tasks_per_count: int
    solve_rate: dict[str, np.ndarray]  # line label -> float[seeds, counts]; NaN where the approach cannot see the tasks
    seeds: dict[str, list[int]]  # line label -> its seeds


def sweep_tasks(env_cls: type[NoveltyEnv], tasks_per_count: int, sweep_seed: int = 0) -> tuple[list, np.ndarray]:
    """(specs, int[len(specs)] the count of each): `tasks_per_count` tasks per count, each count's draw
    seeded by (sweep_seed, count) so that it does not depend on the other counts."""
    sweep = env_cls.novelty_sweep
    specs, counts = [], []
    for k in sweep.counts:
        rng = np.random.default_rng([sweep_seed, k])
        specs += [sweep.task(rng, k) for _ in range(tasks_per_count)]
        counts += [k] * tasks_per_count
    return specs, np.asarray(counts)


def sweep_batch(env_cls: type[NoveltyEnv], specs: list, seeds: list[int]) -> TaskBatch:
    """Every seed meets every spec (seed-major), each with the sweep's horizon for it."""
    horizon = env_cls.novelty_sweep.horizon
    return make_batch(env_cls, specs * len(seeds), [s for s in seeds for _ in specs],
                      horizons=[horizon(spec) for spec in specs] * len(seeds))


def evaluate_sweep(policies: dict[str, TrainedPolicy], tasks_per_count: int = 10, sweep_seed: int = 0,
                   rollout_seed: int = 0, progress=lambda label: None, max_memory: int | None = None) -> SweepResult:
    """Each policy (line label -> policy, all of one env) greedily on the sweep's tasks; a repair run's seeds
    in groups that fit `max_memory` bytes (default: what is available)."""
    envs = {p.env_cls for p in policies.values()}
    if len(envs) != 1:
        raise ValueError(f"a sweep compares runs of one env, got {', '.join(sorted(e.name for e in envs))}")
    env_cls = envs.pop()
    if env_cls.novelty_sweep is None:
        raise ValueError(f"env {env_cls.name} states no generalisation sweep (NoveltyEnv.novelty_sweep)")
    specs, counts = sweep_tasks(env_cls, tasks_per_count, sweep_seed)
    sweep = env_cls.novelty_sweep
    batches: dict = {}  # (seeds, visible counts) -> batch: approaches of one experiment share it
    rates, seeds_of = {}, {}
    for label, policy in policies.items():
        progress(label)
        seeds = list(policy.config.seeds)
        visible = tuple(k for k in sweep.counts if policy.can_see(env_cls.for_tasks(list_of(specs, counts == k))))
        rate = np.full((len(seeds), len(sweep.counts)), np.nan)
        if visible:
            chosen = np.isin(counts, visible)
            success = []
            for group in seed_groups(policy, env_cls, list_of(specs, chosen), seeds, max_memory):
                key = (tuple(group), visible)
                if key not in batches:
                    batches[key] = sweep_batch(env_cls, list_of(specs, chosen), group)
                success.append(policy.run(policy.planned(batches[key]), rollout_seed).success.reshape(len(group), -1))
            success = np.concatenate(success)
            for j, k in enumerate(sweep.counts):
                if k in visible:
                    rate[:, j] = success[:, counts[chosen] == k].mean(axis=1)
        rates[label], seeds_of[label] = rate, seeds
    return SweepResult(env_cls.name, sweep.counted, sweep.setting, sweep.counts, tasks_per_count, rates, seeds_of)


def seed_groups(policy: TrainedPolicy, env_cls: type[NoveltyEnv], specs: list, seeds: list[int],
                max_memory: int | None) -> list[list[int]]:
    """The seeds in the groups evaluated one batch each: all together, unless the policy plans with learned
    models (tables per seed, sized from its first seed's planned batch): then as many as fit."""
    if policy.models is None:
        return [seeds]
    size = model_batches_fit(policy.planned(sweep_batch(env_cls, specs, seeds[:1])), max_memory, "--sweep-tasks")
    return [seeds[i:i + size] for i in range(0, len(seeds), size)]


def list_of(specs: list, mask: np.ndarray) -> list:
    return [s for s, m in zip(specs, mask) if m]


def _cell(values: np.ndarray) -> str:
    if np.isnan(values).all():
        return "n/a"
    described = stats.describe(values)
    return stats.ci_text(float(described["mean"]), (described["mean_low"], described["mean_high"]))


def sweep_markdown(result: SweepResult) -> str:
    """Solve rate per count (rows) and line (columns): mean [95% bootstrap CI] over seeds."""
    labels = list(result.solve_rate)
    lines = [f"| {result.counted} | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for j, k in enumerate(result.counts):
        lines.append(f"| {k} | " + " | ".join(_cell(result.solve_rate[label][:, j]) for label in labels) + " |")
    return "\n".join(lines) + "\n"


def sweep_csv(result: SweepResult) -> str:
    """One row per line, seed and count; empty solve_rate where the approach cannot see the tasks."""
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(["line", "seed", result.counted.replace(" ", "_"), "tasks", "solve_rate"])
    for label, rate in result.solve_rate.items():
        for i, seed in enumerate(result.seeds[label]):
            for j, k in enumerate(result.counts):
                value = "" if np.isnan(rate[i, j]) else f"{rate[i, j]:.4f}"
                writer.writerow([label, seed, k, result.tasks_per_count, value])
    return out.getvalue()
