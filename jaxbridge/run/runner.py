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
from jaxbridge.utils.distributed import is_primary
from jaxbridge.utils.files import WriteError, write_atomic
from jaxbridge.utils.progress import cycle_progress


class Interrupted(Exception):
    """Ctrl-C: the last completed cycle was checkpointed."""

    def __init__(self, cycle: int, message: str | None = None):
        super().__init__(message or f"interrupted after cycle {cycle}; checkpoint saved")
        self.cycle = cycle


class NumericalFault(Exception):
    """A non-finite loss or Q-value: the run stops, keeping the last good checkpoint."""


def checkpoint_record(config: TrainConfig, history: list[CycleMetrics], elapsed_s: float) -> dict:
    """What a checkpoint records beside the state: the config, the cycles so far and their metrics."""
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


def train(setup: Setup, run_dir: Path, progress: bool = True, resume: bool = False, **options) -> dict:
    """One run: `train_settings` with the setup's own config alone. Returns its summary."""
    return train_settings(setup, [(setup.config, run_dir)], progress, resume, **options)[0]


def train_settings(setup: Setup, settings: list[tuple[TrainConfig, Path]], progress: bool = True,
                   resume: bool = False, fault_injection: Callable | None = None, bar=None,
                   stop: threading.Event | None = None, devices: list | None = None,
                   trained: threading.Event | None = None, tensorboard: bool = False) -> list[dict]:
    """Run the cycles of every (config, run directory) in `settings` as one program (continuing each
    run's latest checkpoint with `resume`), writing each run's files and checkpoints into its directory.
    The configs differ from `setup.config` only in their numeric hyperparameters (config.LEAF_FIELDS),
    which the cycle takes as leaves (learn/online.Cycle): each run's numbers are those it gets alone.

    `fault_injection(cycle, learners) -> learners` lets tests corrupt the state before a cycle (slot
    i of the leading axis: setting i // num_seeds, seed i % num_seeds). `bar`: a progress bar shared
    with other runs (else its own). `stop`: when set (by another thread), checkpoint the last completed
    cycle and raise Interrupted; `trained` is set after each completed cycle. `devices`: the slot axis
    is sharded over them (default: the first local device); the numbers do not depend on them, and a
    run may resume on others. `tensorboard`: also log each cycle to event files (run/tensorboard.py).
    Returns each run's summary, in order."""
    start, config, primary = time.perf_counter(), setup.config, is_primary()  # only process 0 writes files
    configs, run_dirs = [c for c, _ in settings], [d for _, d in settings]
    seeds_per_run = config.num_seeds
    if resume:
        for c, run_dir in settings:
            check_checkpoint_belongs(c, run_dir)
    slots = SeedMesh(len(settings) * seeds_per_run, tuple(devices or jax.local_devices()[:1]), config.seed_block)
    fresh = setup.init_learners()
    histories: list[list[CycleMetrics]] = [[] for _ in settings]
    elapsed_before = 0.0
    if resume:
        step = common_step(run_dirs)
        for run_dir in run_dirs:
            checkpoint.discard_after(run_dir / "checkpoints", step)
        restored = [checkpoint.restore(d / "checkpoints", fresh, step) for d in run_dirs]
        learners = _concat([state for state, _, _ in restored])
        histories = [_history(record) for _, record, _ in restored]
        elapsed_before = max(float(record["elapsed_s"]) for _, record, _ in restored)
    else:
        learners = _concat([fresh] * len(settings))
        for c, run_dir in settings if primary else ():
            write_atomic(run_dir / "config.json", json.dumps(c.to_dict(), indent=2) + "\n")
    cycle = Cycle(setup, slots, configs)
    learners = slots.place(learners)  # checkpoints hold each run's unpadded state on one device
    last_saved = len(histories[0])
    elapsed = lambda: elapsed_before + time.perf_counter() - start
    of_run = lambda tree, i: jax.tree.map(lambda x: x[i * seeds_per_run:(i + 1) * seeds_per_run], tree)

    def save(learners, histories) -> None:
        nonlocal last_saved
        state = slots.unpad(learners)
        for i, (c, run_dir) in enumerate(settings if primary else ()):
            checkpoint.save(run_dir / "checkpoints", len(histories[i]), of_run(state, i),
                            checkpoint_record(c, histories[i], elapsed()))
        last_saved = len(histories[0])

    # (learners, histories) after the last completed cycle, replaced in one assignment so that Ctrl-C at
    # any point finds a consistent pair to checkpoint.
    done, unwritable = (learners, histories), False
    events = [CycleEvents(d, c.to_dict()) for c, d in settings] if tensorboard and primary else []
    own_bar = bar is None
    if own_bar:
        what = f"{len(settings)} settings x " if len(settings) > 1 else ""
        bar = cycle_progress(config.cycles, f"{config.env} {what}x{config.num_seeds} seeds", progress and primary,
                             last_saved)
    else:
        bar.update(last_saved)
    try:
        for c in range(last_saved + 1, config.cycles + 1):
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            learners = done[0] if fault_injection is None else fault_injection(c, done[0])
            updated, metrics = cycle(learners)
            metrics = jax.tree.map(np.asarray, slots.unpad(metrics))  # drop padding; gathered from every process
            per_run = [of_run(metrics, i) for i in range(len(settings))]
            for i, m in enumerate(per_run):
                message = _fault(m, c, config.seeds, last_saved)
                if message:
                    raise NumericalFault(message + (f" ({run_dirs[i].name})" if len(settings) > 1 else ""))
            done = (updated, [[*h, m] for h, m in zip(done[1], per_run)])
            if trained is not None:
                trained.set()
            for log, m in zip(events, per_run):
                log.cycle(c, m)
            shown = {} if own_bar else {"last": f"{config.approach} {c}"}
            bar.set_postfix(**shown, test=f"{metrics.test_solve_rate.mean():.2f}",
                            train=f"{metrics.train_success_rate.mean():.2f}", eps=f"{metrics.epsilon.mean():.2f}")
            bar.update()
            if c % config.checkpoint_every == 0 or c == config.cycles:
                save(*done)
    except KeyboardInterrupt:
        if len(done[1][0]) > last_saved:
            save(*done)
        raise Interrupted(len(done[1][0])) from None
    except WriteError:
        unwritable = True
        raise
    finally:
        if own_bar:
            bar.close()
        for log in events:
            log.close()
        infos = [artifacts.summary(h, config.seeds, elapsed(), describe(slots.devices)) if h else None
                 for h in done[1]]
        if primary and not unwritable:  # the files always describe the cycles completed so far
            for c, run_dir, history, info in zip(configs, run_dirs, done[1], infos):
                if info:
                    artifacts.write_run_files(run_dir, c.to_dict(), history, info, label=setup.approach.label)
    return infos


def _concat(states: list):
    return states[0] if len(states) == 1 else jax.tree.map(lambda *x: jax.numpy.concatenate(x), *states)


def common_step(run_dirs: list[Path]) -> int:
    """The latest cycle every run checkpointed (runs trained together save together; a crash between
    their saves leaves the others one step ahead, which they then repeat exactly)."""
    shared = set.intersection(*(set(checkpoint.sealed_steps(d / "checkpoints")) for d in run_dirs))
    if not shared:
        raise checkpoint.CheckpointError(f"{', '.join(str(d) for d in run_dirs)}: no checkpoint of the same "
                                         f"cycle in every run trained together")
    return max(shared)


def load_learners(run_dir: Path) -> tuple[Setup, object, int]:
    """A run's setup and latest learner state (with its cycle). No task is compiled: the template the
    checkpoint is restored into needs the training env's shapes, not the tasks."""
    config = load_config(run_dir)
    check_checkpoint_belongs(config, run_dir)
    setup = make_setup(config)
    if setup.approach.low_level:  # brax's policies, stacked over seeds (run/low_level_runs.py)
        from jaxbridge.learn.low_level import init_policies
        template = init_policies(setup)
    else:
        template = setup.init_learners()
    learners, record, step = checkpoint.restore(run_dir / "checkpoints", template)
    return setup, learners, step

