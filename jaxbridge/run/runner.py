"""The host side of training: the loop over cycles, read top to bottom in `train_settings`, with its
parts beside it (run/run_state.py: the state, its start, checkpoints and files): progress display,
exact resume, clean Ctrl-C and the numerical-fault guard."""
from __future__ import annotations

import dataclasses
import threading
import time
from pathlib import Path
from typing import Callable

import jax
import numpy as np

from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh
from jaxbridge.learn.online import Cycle, CycleMetrics
from jaxbridge.learn.setup import Setup, make_setup
from jaxbridge.run import checkpoint
from jaxbridge.run.run_state import (Checkpointer, Done, RunGroup, check_checkpoint_belongs, fresh_start, load_config,
                                     restored, write_run_files)
from jaxbridge.run.scheduling import worth_widening
from jaxbridge.run.tensorboard import CycleEvents
from jaxbridge.utils.files import WriteError
from jaxbridge.utils.progress import cycle_progress


class Interrupted(Exception):
    """Ctrl-C: the last completed cycle was checkpointed."""

    def __init__(self, cycle: int, message: str | None = None):
        super().__init__(message or f"interrupted after cycle {cycle}; checkpoint saved")
        self.cycle = cycle


class NumericalFault(Exception):
    """A non-finite loss or Q-value: the run stops, keeping the last good checkpoint."""


def train(setup: Setup, run_dir: Path, progress: bool = True, resume: bool = False, **options) -> dict:
    """One run: `train_settings` with the setup's own config alone. Returns its summary."""
    return train_settings(setup, [(setup.config, run_dir)], progress, resume, **options)[0]


def train_settings(setup: Setup, settings: list[tuple[TrainConfig, Path]], progress: bool = True,
                   resume: bool = False, fault_injection: Callable | None = None, bar=None,
                   stop: threading.Event | None = None, devices: list | None = None,
                   trained: threading.Event | None = None, tensorboard: bool = False,
                   widen: Callable[[Callable[[int], bool]], list] | None = None) -> list[dict]:
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
    `widen(wanted)`: after a cycle, more devices to shard the slots over (run/scheduling.py), where
    `wanted(count)` says they are worth their recompile. Returns each run's summary, in order."""
    start, config = time.perf_counter(), setup.config
    slots = SeedMesh(len(settings) * config.num_seeds, tuple(devices or jax.local_devices()[:1]), config.seed_block)
    group = RunGroup(setup, settings, slots)
    done, elapsed_before = restored(group) if resume else fresh_start(group)
    elapsed = lambda: elapsed_before + time.perf_counter() - start
    done = Done(slots.place(done.learners), done.histories)  # checkpoints hold each run's state on one device
    cycle, saver = Cycle(setup, slots, group.configs), Checkpointer(group, elapsed, saved=done.cycles)
    display, writable, timer = CycleDisplay(group, bar, progress, tensorboard, saved=done.cycles), True, CycleTimer()
    try:
        for c in range(done.cycles + 1, config.cycles + 1):
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt
            with timer:
                done = next_cycle(cycle, group, done, c, fault_injection, saver.saved)
            if trained is not None:
                trained.set()
            display.cycle(c, [history[-1] for history in done.histories])
            if c % config.checkpoint_every == 0 or c == config.cycles:
                saver.save(done)
            more = widen(timer.worth(group.slots, config.cycles - c)) if widen and c < config.cycles else []
            if more:  # the same per-seed program on more devices: the numbers stay the same
                group, done = widened(group, done, more)
                cycle, saver.group, timer = Cycle(setup, group.slots, group.configs), group, CycleTimer()
    except KeyboardInterrupt:
        saver.save_if_behind(done)
        raise Interrupted(done.cycles) from None
    except WriteError:
        writable = False
        raise
    finally:
        display.close()
        infos = write_run_files(group, done, elapsed(), writable)
    return infos


def widened(group: RunGroup, done: Done, devices: list) -> tuple[RunGroup, Done]:
    """The group's slots sharded over their devices and `devices` too, and the state moved onto them."""
    old = group.slots
    group = dataclasses.replace(group, slots=SeedMesh(old.num_seeds, old.devices + tuple(devices), old.block))
    return group, Done(group.slots.place(old.unpad(done.learners)), done.histories)


class CycleTimer:
    """Each cycle's seconds, the first's (which compiles) apart: whether more devices are worth it."""

    def __init__(self):
        self.first_s = self.last_s = None

    def __enter__(self):
        self.start = time.perf_counter()

    def __exit__(self, *exc):
        self.last_s = time.perf_counter() - self.start
        self.first_s = self.last_s if self.first_s is None else self.first_s

    def worth(self, slots: SeedMesh, cycles_left: int) -> Callable[[int], bool]:
        """`wanted(count)`: whether `count` more devices save more than they cost (run/scheduling.py)."""
        def wanted(count: int) -> bool:
            wider = SeedMesh(slots.num_seeds, slots.devices + (None,) * count, slots.block)
            compile_s = max(self.first_s - self.last_s, 0.0)
            return worth_widening(slots.padded // slots.num_devices, wider.padded // wider.num_devices, cycles_left,
                                  self.last_s, compile_s)
        return wanted


def next_cycle(cycle: Cycle, group: RunGroup, done: Done, c: int, fault_injection: Callable | None,
               last_saved: int) -> Done:
    """Cycle c from `done`: the new state, or NumericalFault if some seed's loss or Q went non-finite."""
    learners = done.learners if fault_injection is None else fault_injection(c, done.learners)
    updated, metrics = cycle(learners)
    metrics = jax.tree.map(np.asarray, group.slots.unpad(metrics))  # drop padding; gathered from every process
    per_run = [group.of_run(metrics, i) for i in range(len(group.settings))]
    for i, run_metrics in enumerate(per_run):
        message = _fault(run_metrics, c, group.setup.config.seeds, last_saved)
        if message:
            raise NumericalFault(message + (f" ({group.run_dirs[i].name})" if len(group.settings) > 1 else ""))
    return Done(updated, [[*history, m] for history, m in zip(done.histories, per_run)])


def _fault(metrics: CycleMetrics, cycle: int, seeds: list[int], last_saved: int) -> str | None:
    bad = ~np.isfinite(metrics.loss) | ~np.isfinite(metrics.q_abs_max)
    if not bad.any():
        return None
    return (f"non-finite loss or Q-value at cycle {cycle} in seed {seeds[int(np.argmax(bad))]}"
            f"{' (and others)' if bad.sum() > 1 else ''}; stopped, the last good checkpoint is of cycle "
            f"{last_saved}" if last_saved else f"non-finite loss or Q-value at cycle {cycle} in seed "
            f"{seeds[int(np.argmax(bad))]}; stopped before any checkpoint")


class CycleDisplay:
    """What shows each completed cycle: the progress bar (its own, or one shared with other runs) and
    TensorBoard's event files (`tensorboard`, on process 0)."""

    def __init__(self, group: RunGroup, bar, progress: bool, tensorboard: bool, saved: int):
        config = group.setup.config
        self.events = [CycleEvents(d, c.to_dict()) for c, d in group.written] if tensorboard else []
        self.own_bar, self.approach = bar is None, config.approach
        if self.own_bar:
            what = f"{len(group.settings)} settings x " if len(group.settings) > 1 else ""
            bar = cycle_progress(config.cycles, f"{config.env} {what}x{config.num_seeds} seeds", progress and group.primary,
                                 saved)
        else:
            bar.update(saved)
        self.bar = bar

    def cycle(self, c: int, per_run: list[CycleMetrics]) -> None:
        for log, metrics in zip(self.events, per_run):
            log.cycle(c, metrics)
        mean = lambda field: np.concatenate([getattr(m, field) for m in per_run]).mean()
        shown = {} if self.own_bar else {"last": f"{self.approach} {c}"}
        self.bar.set_postfix(**shown, test=f"{mean('test_solve_rate'):.2f}", train=f"{mean('train_success_rate'):.2f}",
                             eps=f"{mean('epsilon'):.2f}")
        self.bar.update()

    def close(self) -> None:
        if self.own_bar:
            self.bar.close()
        for log in self.events:
            log.close()


def load_learners(run_dir: Path) -> tuple[Setup, object, int]:
    """A run's setup and latest learner state (with its cycle). No task is compiled: the template the
    checkpoint is restored into needs the training env's shapes, not the tasks."""
    config = load_config(run_dir)
    check_checkpoint_belongs(config, run_dir)
    setup = make_setup(config)
    learners, record, step = checkpoint.restore(run_dir / "checkpoints", setup.init_learners())
    return setup, learners, step
