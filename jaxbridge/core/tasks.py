"""Batches of tasks ready for the device: padded task arrays, plan tables and horizons."""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import NoveltyEnv
from planner.tables import CompiledTask, PlanTable, compile_task, stack_tables


@struct.dataclass
class TaskArrays:
    """What a rollout needs of B episodes' tasks, on the device: one pytree with leading axis B."""

    tasks: Any  # the env's Task struct
    tables: PlanTable  # the planner's plan tables
    horizons: jax.Array  # int32[B]: env steps per episode at most


@dataclass
class TaskBatch:
    """B tasks of one env, padded to one capacity: the device arrays a rollout needs, plus host views."""

    env: NoveltyEnv
    specs: list
    seeds: np.ndarray  # int[B]: the seed each task belongs to
    compiled: list[CompiledTask]
    arrays: TaskArrays

    @property
    def size(self) -> int:
        return len(self.specs)

    @property
    def max_steps(self) -> int:
        return int(np.max(np.asarray(self.arrays.horizons)))

    @property
    def tasks(self) -> Any:
        return self.arrays.tasks

    @property
    def horizons(self) -> jax.Array:
        return self.arrays.horizons


# A task is compiled once per process for an equal env (a frozen capacity) and spec: the compilation is a
# function of the two, and a shared CompiledTask keeps its uid, whose host planner stays registered (as
# approaches sharing one batch already share it). So the memory estimate's tables are the run's own, and
# a batch's repeated specs share one compilation.
@functools.lru_cache(maxsize=1 << 10)
def compiled_task(env: NoveltyEnv, spec) -> CompiledTask:
    """`spec`'s grounding, host planner and plan table under `env` (planner/tables.compile_task), once."""
    return compile_task(env, spec)


def make_batch(env_cls: type[NoveltyEnv], specs: list, seeds: list[int], horizons: list[int] | None = None,
               env: NoveltyEnv | None = None, progress: Callable[[int, int], None] | None = None) -> TaskBatch:
    """Pad and compile `specs` (test horizons by default) for an env sized to fit them all; `progress(done,
    total)` after each spec compiled."""
    env = env or env_cls.for_tasks(specs)
    compiled = []  # repeated specs (a seed's training task, once per episode) share one compilation
    for i, spec in enumerate(specs):
        compiled.append(compiled_task(env, spec))
        if progress is not None:
            progress(i + 1, len(specs))
    horizons = [s.horizon for s in specs] if horizons is None else horizons
    arrays = TaskArrays(tasks=env.stack_tasks(specs), tables=stack_tables(compiled),
                        horizons=jnp.asarray(horizons, jnp.int32))
    return TaskBatch(env=env, specs=list(specs), seeds=np.asarray(seeds), compiled=compiled, arrays=arrays)


def test_specs(env_cls: type[NoveltyEnv], seed: int, num_tasks: int = 10, protocol: str | None = None) -> list:
    """The seed's test tasks under one of the env's `test_protocols` (None: its default, the first);
    ValueError for a protocol the env does not have."""
    default = next(iter(env_cls.test_protocols))
    if protocol is not None and protocol != default and protocol not in env_cls.test_protocols:
        raise ValueError(f"{env_cls.name} has no test protocol {protocol!r}; it has {', '.join(env_cls.test_protocols)}")
    return list(_drawn_test_tasks(env_cls, seed, num_tasks, None if protocol == default else protocol))


def train_specs(env_cls: type[NoveltyEnv], seed: int, episodes: int) -> list:
    """The seed's training tasks, one per episode of a cycle."""
    return list(_drawn_train_tasks(env_cls, seed, episodes))


# A seed's tasks are drawn once per process: a run's checks, its programs' setups and its task batches all
# read the same draw (an env's draw is a function of the seed alone, env/base.py's contract).
@functools.lru_cache(maxsize=1 << 14)
def _drawn_train_tasks(env_cls: type[NoveltyEnv], seed: int, episodes: int) -> tuple:
    return tuple(env_cls.train_tasks(seed, episodes))


@functools.lru_cache(maxsize=1 << 14)
def _drawn_test_tasks(env_cls: type[NoveltyEnv], seed: int, num_tasks: int, protocol: str | None) -> tuple:
    if protocol is None:
        return tuple(env_cls.test_tasks(seed, num_tasks))  # an env with one protocol need not take the keyword
    return tuple(env_cls.test_tasks(seed, num_tasks, protocol=protocol))


def training_specs(env_cls: type[NoveltyEnv], seeds: Sequence[int], episodes: int) -> tuple[list, list[int]]:
    """Every seed's training tasks, one per episode of a cycle (seed-major order), and the seed each belongs to."""
    specs = [spec for seed in seeds for spec in _drawn_train_tasks(env_cls, seed, episodes)]
    return specs, [seed for seed in seeds for _ in range(episodes)]


def evaluation_specs(env_cls: type[NoveltyEnv], seeds: list[int], num_tasks: int = 10,
                     protocol: str | None = None) -> tuple[list, list[int]]:
    """Every seed's test tasks (seed-major order) and the seed each belongs to."""
    specs, owners = [], []
    for seed in seeds:
        tasks = test_specs(env_cls, seed, num_tasks, protocol)
        specs += tasks
        owners += [seed] * len(tasks)
    return specs, owners


def evaluation_batch(env_cls: type[NoveltyEnv], seeds: list[int], num_tasks: int = 10,
                     progress: Callable[[int, int], None] | None = None, protocol: str | None = None) -> TaskBatch:
    """Every seed's test tasks in one batch (seed-major order)."""
    return make_batch(env_cls, *evaluation_specs(env_cls, seeds, num_tasks, protocol), progress=progress)
