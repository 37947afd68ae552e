"""The host side of a low-level baseline's run (learn/low_level): its seeds one after another, each trained
by brax and evaluated after every cycle's agent steps, into the same run files as every approach's
(metrics.csv, summary.json, curves.png) and one checkpoint of every seed's last policy, which eval.py
loads as it loads any run's. Nothing is saved mid-run: an interrupted run trains again from its start."""
from __future__ import annotations

import json
import time
from pathlib import Path

import jax
import numpy as np

from jaxbridge.learn.brax_env import BridgeEnv
from jaxbridge.learn.devices import describe
from jaxbridge.learn.low_level import TRAINERS, Budget, evaluate
from jaxbridge.learn.online import CycleMetrics
from jaxbridge.learn.setup import Setup
from jaxbridge.run import artifacts, checkpoint
from jaxbridge.run.run_state import checkpoint_record
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import Interrupted
from jaxbridge.utils import compile_cache
from jaxbridge.utils.distributed import is_primary
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.progress import cycle_progress


def _of_seed(batch, seed: int):
    """The device arrays of `seed`'s episodes in a seed-major TaskBatch."""
    index = np.flatnonzero(batch.seeds == seed)
    return jax.tree.map(lambda x: x[index], batch.arrays)


def train_seed(setup: Setup, seed: int, on_cycle=None) -> tuple[list[dict], tuple]:
    """One seed: brax's agent from the stuck state of the seed's training task; after each cycle's agent
    steps, its greedy policy on the seed's test tasks and on its training task. One dict per cycle, and
    the last cycle's (normalizer, policy) params."""
    config, approach = setup.config, setup.approach
    controls = approach.controls  # a low-level approach's controls are the brax view's
    train_arrays, test_arrays = _of_seed(setup.train, seed), _of_seed(setup.test, seed)
    adapter = BridgeEnv(setup.train_env, jax.tree.map(lambda x: x[:1], train_arrays), controls.call_planner,
                        controls.observation.whole_state, key=jax.random.key(seed))
    budget = Budget(config.cycles, config.episodes_per_cycle * config.train_steps * config.low_level_budget,
                    config.train_steps)
    test_keys = jax.random.split(jax.random.key(seed), test_arrays.horizons.shape[0] + 1)
    rows, last_step, last_params = [], 0, None

    def evaluated(step: int, params) -> None:
        nonlocal last_step, last_params
        last_params = params
        test = evaluate(setup.test_env, approach, params, test_arrays, test_keys[1:], setup.test.max_steps)
        train = evaluate(setup.train_env, approach, params, adapter.task, test_keys[:1], config.train_steps)
        rows.append({"test_solve_rate": float(np.mean(test.success)),
                     "train_success_rate": float(np.mean(train.success)),
                     "train_env_steps": step - last_step, "train_decisions": step - last_step,
                     "test_env_steps": int(np.sum(test.steps)),
                     "table_misses": int(np.sum(test.table_misses) + np.sum(train.table_misses))})
        last_step = step
        if on_cycle is not None:
            on_cycle()

    TRAINERS[approach.algorithm](adapter, budget, seed, evaluated)
    return rows, last_params


def _history(per_seed: list[list[dict]]) -> list[CycleMetrics]:
    zero = np.zeros(len(per_seed), np.float32)
    field = lambda c, name, dtype: np.asarray([rows[c][name] for rows in per_seed], dtype)
    return [CycleMetrics(test_solve_rate=field(c, "test_solve_rate", np.float32),
                         train_success_rate=field(c, "train_success_rate", np.float32),
                         train_env_steps=field(c, "train_env_steps", np.int32),
                         train_decisions=field(c, "train_decisions", np.int32),
                         test_env_steps=field(c, "test_env_steps", np.int32), test_decisions=zero, epsilon=zero, loss=zero,
                         q_abs_max=zero, buffer_size=zero.astype(np.int32),
                         table_misses=field(c, "table_misses", np.int32))
            for c in range(len(per_seed[0]))]


def train_low_level(setup: Setup, run_dir: Path, hooks: RunHooks = RunHooks()) -> dict:
    """Every seed of the run, then its files; Interrupted (nothing saved) when `hooks.stop` is set between
    seeds. `hooks.display`: a progress display shared with other runs (else its own). Returns the run's
    summary."""
    config, start, primary, bar, stop = setup.config, time.perf_counter(), is_primary(), hooks.display, hooks.stop
    if primary:
        write_atomic(run_dir / "config.json", json.dumps(config.to_dict(), indent=2) + "\n")
    own_bar = bar is None
    if own_bar:
        bar = cycle_progress(config.cycles, f"{config.env} {config.approach} x{config.num_seeds} seeds",
                             hooks.progress and primary)
    per_seed, policies, evaluations = [], [], 0
    janitor = compile_cache.CacheJanitor()

    def evaluated() -> None:  # the bar counts cycles of all seeds: one per num_seeds evaluations
        nonlocal evaluations
        evaluations += 1
        if evaluations % config.num_seeds == 0:
            bar.update()

    try:
        for seed in config.seeds:
            if stop is not None and stop.is_set():
                raise Interrupted(0, f"interrupted in {config.approach} before seed {seed}; nothing saved")
            rows, params = train_seed(setup, seed, on_cycle=evaluated)
            per_seed.append(rows)
            policies.append(params)
            # brax's trainers compile closures anew per call and jax's caches keep every executable
            # (2,336 memory maps and ~150 MB per seed here): past ~28 seeds a process meets the kernel's
            # 65,530 maps and LLVM aborts.
            janitor()
    finally:
        if own_bar:
            bar.close()
    history, elapsed = _history(per_seed), time.perf_counter() - start
    info = artifacts.summary(history, config.seeds, elapsed, describe(jax.local_devices()[:1]))
    if primary:
        artifacts.write_run_files(run_dir, config.to_dict(), history, info, label=setup.approach.label)
        stacked = jax.tree.map(lambda *x: np.stack([np.asarray(v) for v in x]), *policies)
        checkpoint.save(run_dir / "checkpoints", config.cycles, stacked, checkpoint_record(config, history, elapsed))
    return info


def finished(run_dir: Path, config) -> dict | None:
    """The summary of a low-level run that completed all its cycles (its checkpoint is of the last), else
    None: `train.py --resume` keeps finished runs and trains the others again."""
    done = checkpoint.sealed_steps(run_dir / "checkpoints")
    if done and done[-1] == config.cycles and (run_dir / "summary.json").is_file():
        return json.loads((run_dir / "summary.json").read_text())
    return None
