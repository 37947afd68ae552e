"""What a run will hold in memory, estimated before anything is built, so a run too big to fit is refused
in seconds instead of swapping for half an hour."""
from __future__ import annotations

import os

import jax
import numpy as np

from envs_jax import NoveltyEnv
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.tasks import TaskBatch, compiled_task, evaluation_specs, make_batch, test_specs, train_specs, training_specs
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.setup import Setup, make_learner, training_env
from jaxbridge.run.model_repair import KEPT_SEGMENTS
from jaxbridge.utils.errors import InputError
from planner.tables import table_shape

# A seed's learner state lives three times at once: the state a cycle reads (kept as the last good one),
# the state it returns, and the host copy a checkpoint writes.
STATE_COPIES = 3
RUNTIME_BYTES = 1 << 30  # JAX, XLA's compiled programs and Python, before any seed
# An evaluated task's plan table lives about four times at once: the compiled table each task keeps on
# the host, the padded stack, its device copy, and the host planner's cache plus the rollout's compare
# against every row.
TABLE_COPIES = 4
# A task planned with a learned model peaks at about 14 times its batch row's bytes while it runs (measured
# on Multi Novelty's sweep): the compiled table each task keeps, the stack, its device copy, and the
# rollout reading every invented atom of its model at each step. 16 leaves a margin.
MODEL_TABLE_COPIES = 16


class TooBig(InputError):
    """The estimate exceeds the memory allowed; the message says what to lower."""


def available_bytes() -> int:
    """Memory the system can give without swapping (Linux's MemAvailable; else all physical memory)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def tree_bytes(tree) -> int:
    def nbytes(x) -> int:
        if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key):  # a typed PRNG key: its raw words
            return int(np.prod(x.shape)) * 8
        return int(np.prod(x.shape)) * np.dtype(x.dtype).itemsize
    return sum(nbytes(x) for x in jax.tree.leaves(tree))


def state_bytes(config: TrainConfig, env_cls: type[NoveltyEnv], setup: Setup | None = None) -> int:
    """One seed's learner state for `config.approach`, from abstract shapes (nothing is allocated): of
    `setup`, the one the program runs; before any is built, a lower bound, a learner on the first seed's
    training tasks alone (the run's env holds every seed's, each dimension as large or larger), so that a
    run too big to fit is refused before its seeds' tasks are drawn. A low-level baseline's state needs its
    setup: 0 before one."""
    if setup is not None:
        return tree_bytes(jax.eval_shape(setup.init_learners)) // config.num_seeds
    approach = get_approach(config.approach)
    if approach.low_level:
        return 0
    env = training_env(config, env_cls, [config.first_seed])
    return tree_bytes(jax.eval_shape(make_learner(config, approach, env).init, jax.random.key(config.first_seed)))


def segments_bytes(config: TrainConfig, env_cls: type[NoveltyEnv]) -> int:
    """One seed's skill calls a model repair run keeps on the host (run/model_repair.py), 0 for another
    approach: each call two states of the object view, and about a kilobyte of Python around each."""
    if not get_approach(config.approach).repairs_model:
        return 0
    env = training_env(config, env_cls, [config.first_seed])
    return KEPT_SEGMENTS * 2 * (env.num_objects * (env.object_width + 3) * 4 + 1024)


def task_bytes(config: TrainConfig, env_cls: type[NoveltyEnv]) -> int:
    """One seed's training and test tasks with their plan tables (the first seed's), which every approach
    of an experiment shares; compiled by the envs the run's batches will have (each holds every seed's
    tasks, drawn by then for the setups), so the batches reuse these compilations (core/tasks.compiled_task)."""
    seed, episodes = config.first_seed, config.episodes_per_cycle
    kinds = [(train_specs(env_cls, seed, episodes), training_specs(env_cls, config.seeds, episodes)[0]),
             (test_specs(env_cls, seed, config.num_test_tasks, config.test_protocol),
              evaluation_specs(env_cls, config.seeds, config.num_test_tasks, config.test_protocol)[0])]
    return sum(tree_bytes(make_batch(env_cls, mine, [seed] * len(mine), env=env_cls.for_tasks(every)).arrays)
               for mine, every in kinds)


def limit_bytes(limit: int | None) -> tuple[int, str]:
    return (available_bytes(), "available") if limit is None else (limit, "allowed by --max-memory")


def totals(count: int, each: int, limit: int) -> tuple[int, int]:
    """(bytes for `count` items of `each` bytes plus the runtime, how many such items fit in `limit`)."""
    return RUNTIME_BYTES + count * each, max(0, (limit - RUNTIME_BYTES) // each)


def model_batches_fit(batch: TaskBatch, limit: int | None = None, lower: str = "--num-tasks") -> int:
    """How many batches like `batch`, planned with learned models, fit at once within `limit` bytes
    (default: what is available), at MODEL_TABLE_COPIES times their bytes each; TooBig, naming the flag
    `lower` to lower, if not even `batch` does."""
    limit, what = limit_bytes(limit)
    need, fit = totals(1, MODEL_TABLE_COPIES * tree_bytes(batch.arrays), limit)
    if fit < 1:
        raise TooBig(f"evaluating these {len(batch.specs)} tasks with their learned models needs about {need / 2**30:.1f} "
                     f"GiB, more than the {limit / 2**30:.1f} GiB {what}; lower {lower} or raise --max-memory")
    return fit


def check_training(config: TrainConfig, env_cls: type[NoveltyEnv], programs: list[tuple[TrainConfig, int, Setup | None]],
                   workers: int, limit: int | None = None) -> int:
    """The estimate for an experiment's programs (each its first run's config, its number of runs, trained
    side by side, and its setup: None before the setups are built, for `state_bytes`' lower bound) trained
    `workers` at a time (the largest together); TooBig if it exceeds `limit` bytes (default: the memory
    available now)."""
    limit, what = limit_bytes(limit)
    approaches = list(dict.fromkeys(c.approach for c, _, _ in programs))
    states = sorted((state_bytes(c, env_cls, setup) * runs for c, runs, setup in programs), reverse=True)
    repairs = sum(segments_bytes(c, env_cls) * runs for c, runs, _ in programs)
    built = all(setup is not None for _, _, setup in programs)  # else a lower bound: no seed's tables but the first's drawn
    per_seed = STATE_COPIES * sum(states[:max(1, workers)]) + (task_bytes(config, env_cls) if built else 0) + repairs
    need, fit = totals(config.num_seeds, per_seed, limit)
    if need > limit:
        raise TooBig(f"this run needs about {need / 2**30:.1f} GiB ({per_seed / 2**20:.1f} MiB per seed for "
                     f"{', '.join(approaches) if len(approaches) <= 2 else f'{workers} approaches at a time'}, "
                     f"x {config.num_seeds} seeds), more than the {limit / 2**30:.1f} GiB {what}; lower --num-seeds (about {fit} fit)"
                     f"{', --workers' if workers > 1 else ''} or --approaches, or raise --max-memory")
    return need


def check_evaluation(env_cls: type[NoveltyEnv], specs: list, limit: int | None = None) -> int:
    """The estimate for evaluating `specs` in one batch: their plan tables, padded to the largest (the
    env's `plan_bound`, else the first task's grounding); TooBig if it exceeds `limit` bytes."""
    limit, what = limit_bytes(limit)
    env = env_cls.for_tasks(specs)
    bounds = [env.plan_bound(spec) for spec in specs]
    if any(b is None for b in bounds):
        first = compiled_task(env, specs[0])  # the batch then built reuses it
        bounds = [(first.num_reachable, len(first.ground_ops))]
    states, operators = (max(b[i] for b in bounds) for i in range(2))
    per_task = TABLE_COPIES * tree_bytes(table_shape(states, operators, env.num_atoms))
    need, fit = totals(len(specs), per_task, limit)
    if need > limit:
        raise TooBig(f"evaluating these {len(specs)} tasks needs about {need / 2**30:.1f} GiB ({per_task / 2**20:.1f} MiB "
                     f"per task for plan tables of {states} states x {operators} operators), more than the "
                     f"{limit / 2**30:.1f} GiB {what}; lower --task-size or --num-tasks (about {fit} tasks fit), "
                     f"or raise --max-memory")
    return need
