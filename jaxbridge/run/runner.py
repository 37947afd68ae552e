"""The host side of training: the loop over cycles, progress display, run files and checkpoints,
exact resume, clean Ctrl-C and the numerical-fault guard."""
from __future__ import annotations

import dataclasses
import json
import threading
import time
from pathlib import Path
from typing import Callable

import jax
import numpy as np

from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh, describe
from jaxbridge.learn.online import Cycle, CycleMetrics
from jaxbridge.learn.setup import Setup, make_setup
from jaxbridge.run import artifacts, checkpoint
from jaxbridge.run.tensorboard import CycleEvents
from jaxbridge.utils.files import WriteError, write_atomic
from jaxbridge.utils.progress import cycle_progress


class Interrupted(Exception):
    """Ctrl-C: the last completed cycle was checkpointed."""

    def __init__(self, cycle: int, message: str | None = None):
        super().__init__(message or f"interrupted after cycle {cycle}; checkpoint saved")
        self.cycle = cycle


class NumericalFault(Exception):
    """A non-finite loss or Q-value: the run stops, keeping the last good checkpoint."""


def _record(config: TrainConfig, history: list[CycleMetrics], elapsed_s: float) -> dict:
    return {"cycle": len(history), "config": config.to_dict(), "elapsed_s": elapsed_s,
            "history": [{f.name: np.asarray(getattr(m, f.name)).tolist() for f in dataclasses.fields(m)}
                        for m in history]}


def _history(record: dict) -> list[CycleMetrics]:
    """Metrics back from a checkpoint record, exactly (float32 values round-trip through JSON)."""
    dtype = lambda v: np.float32 if isinstance(v[0], float) else np.int32
    return [CycleMetrics(**{k: np.asarray(v, dtype(v)) for k, v in m.items()}) for m in record["history"]]


def load_config(run_dir: Path) -> TrainConfig:
    """The config a run was started with; ValueError if missing, unreadable or of another version."""
    path = run_dir / "config.json"
    if not path.is_file():
        raise ValueError(f"{run_dir} is not a run directory (no config.json)")
    try:
        return TrainConfig.from_dict(json.loads(path.read_text()))
    except (json.JSONDecodeError, TypeError) as err:
        raise ValueError(f"{path} is not a valid run config: {err}") from None


def check_checkpoint_belongs(config: TrainConfig, run_dir: Path) -> None:
    """Refuse (CheckpointError) a run directory whose latest checkpoint was written by another run: of
    another env or approach, or with another config (its state would not fit, or would mean something
    else). Read from the checkpoint's record before anything is built."""
    record, step = checkpoint.read_record(run_dir / "checkpoints")
    where = run_dir / "checkpoints" / str(step)
    try:
        saved = TrainConfig.from_dict(record["config"])
    except (KeyError, TypeError, ValueError) as err:
        raise checkpoint.CheckpointError(f"checkpoint {where} has no readable config ({err}); refusing to load it") from None
    if (saved.env, saved.approach) != (config.env, config.approach):
        raise checkpoint.CheckpointError(f"checkpoint {where} was written by a {saved.env} run of {saved.approach}, but the run "
                              f"is {config.env} of {config.approach}; refusing to load it")
    differ = [f"{f.name} {getattr(saved, f.name)} there, {getattr(config, f.name)} here"
              for f in dataclasses.fields(config) if getattr(saved, f.name) != getattr(config, f.name)]
    if differ:
        raise checkpoint.CheckpointError(f"checkpoint {where} was written with another config ({'; '.join(differ)}); "
                              f"refusing to load it")


def _fault(metrics: CycleMetrics, cycle: int, seeds: list[int], last_saved: int) -> str | None:
    bad = ~np.isfinite(metrics.loss) | ~np.isfinite(metrics.q_abs_max)
    if not bad.any():
        return None
    return (f"non-finite loss or Q-value at cycle {cycle} in seed {seeds[int(np.argmax(bad))]}"
            f"{' (and others)' if bad.sum() > 1 else ''}; stopped, the last good checkpoint is of cycle "
            f"{last_saved}" if last_saved else f"non-finite loss or Q-value at cycle {cycle} in seed "
            f"{seeds[int(np.argmax(bad))]}; stopped before any checkpoint")


def train(setup: Setup, run_dir: Path, progress: bool = True, resume: bool = False,
          fault_injection: Callable | None = None, bar=None,
          stop: threading.Event | None = None, devices: list | None = None,
          trained: threading.Event | None = None, tensorboard: bool = False) -> dict:
    """Run the cycles of `setup.config` (continuing the latest checkpoint with `resume`), writing the run
    files and checkpoints into `run_dir`. `fault_injection(cycle, learners) -> learners` lets tests
    corrupt the state before a cycle (seed i is slot i of the leading axis). `bar`: a progress bar
    shared with other runs (else its own). `stop`: when set (by another thread), checkpoint the last
    completed cycle and raise Interrupted; `trained` is set after each completed cycle. `devices`: the seed axis is sharded over them (default: the
    first local device); the numbers do not depend on them, and a run may resume on others. `tensorboard`:
    also log each cycle to TensorBoard event files (run/tensorboard.py)."""
    start, config = time.perf_counter(), setup.config
    if resume:
        check_checkpoint_belongs(config, run_dir)
    seeds = SeedMesh(config.num_seeds, tuple(devices or jax.local_devices()[:1]), config.seed_block)
    learners = setup.init_learners()
    history: list[CycleMetrics] = []
    elapsed_before = 0.0
    if resume:
        learners, record, _ = checkpoint.restore(run_dir / "checkpoints", learners)
        history, elapsed_before = _history(record), float(record["elapsed_s"])
    else:
        write_atomic(run_dir / "config.json", json.dumps(config.to_dict(), indent=2) + "\n")
    cycle = Cycle(setup, seeds)
    learners = seeds.place(learners)  # checkpoints hold the unpadded state on one device
    last_saved = len(history)
    elapsed = lambda: elapsed_before + time.perf_counter() - start

    def save(learners, history) -> None:
        nonlocal last_saved
        checkpoint.save(run_dir / "checkpoints", len(history), seeds.unpad(learners),
                        _record(config, history, elapsed()))
        last_saved = len(history)

    # (learners, history) after the last completed cycle, replaced in one assignment so that Ctrl-C at
    # any point finds a consistent pair to checkpoint.
    done, unwritable = (learners, history), False
    events = CycleEvents(run_dir, config.to_dict()) if tensorboard else None
    own_bar = bar is None
    if own_bar:
        bar = cycle_progress(config.cycles, f"{config.env} x{config.num_seeds} seeds", progress, len(history))
    else:
        bar.update(len(history))
    try:
        for c in range(len(history) + 1, config.cycles + 1):
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            learners = done[0] if fault_injection is None else fault_injection(c, done[0])
            updated, metrics = cycle(learners)
            metrics = jax.tree.map(lambda x: np.asarray(x)[: config.num_seeds], metrics)  # drop padding
            message = _fault(metrics, c, config.seeds, last_saved)
            if message:
                raise NumericalFault(message)
            done = (updated, [*done[1], metrics])
            if trained is not None:
                trained.set()
            if events is not None:
                events.cycle(c, metrics)
            shown = {} if own_bar else {"last": f"{config.approach} {c}"}
            bar.set_postfix(**shown, test=f"{metrics.test_solve_rate.mean():.2f}",
                            train=f"{metrics.train_success_rate.mean():.2f}", eps=f"{metrics.epsilon.mean():.2f}")
            bar.update()
            if c % config.checkpoint_every == 0 or c == config.cycles:
                save(*done)
    except KeyboardInterrupt:
        if len(done[1]) > last_saved:
            save(*done)
        raise Interrupted(len(done[1])) from None
    except WriteError:
        unwritable = True
        raise
    finally:
        if own_bar:
            bar.close()
        if events is not None:
            events.close()
        info = artifacts.summary(done[1], config.seeds, elapsed(), describe(seeds.devices)) if done[1] else None
        if info and not unwritable:  # the files always describe the cycles completed so far
            artifacts.write_run_files(run_dir, config.to_dict(), done[1], info, label=setup.approach.label)
    return info


def load_learners(run_dir: Path) -> tuple[Setup, object, int]:
    """A run's setup and latest learner state (with its cycle). No task is compiled: the template the
    checkpoint is restored into needs the training env's shapes, not the tasks."""
    config = load_config(run_dir)
    check_checkpoint_belongs(config, run_dir)
    setup = make_setup(config)
    learners, record, step = checkpoint.restore(run_dir / "checkpoints", setup.init_learners())
    return setup, learners, step

