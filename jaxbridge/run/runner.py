"""The host side of training: the loop over cycles, read top to bottom in `train_settings`, with its
parts beside it (run/run_state.py: the state, its start, checkpoints and files): progress display,
exact resume, clean Ctrl-C and the numerical-fault guard."""
from __future__ import annotations

import dataclasses
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
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.model_repair import ModelRepair
from jaxbridge.run.scheduling import CycleTimes
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


def train(setup: Setup, run_dir: Path, hooks: RunHooks = RunHooks(), resume: bool = False,
          fault_injection: Callable | None = None) -> dict:
    """One run: `train_settings` with the setup's own config alone. Returns its summary."""
    return train_settings(setup, [(setup.config, run_dir)], hooks, resume, fault_injection)[0]


def train_settings(setup: Setup, settings: list[tuple[TrainConfig, Path]], hooks: RunHooks = RunHooks(),
                   resume: bool = False, fault_injection: Callable | None = None) -> list[dict]:
    """Run the cycles of every (config, run directory) in `settings` as one program (continuing each
    run's latest checkpoint with `resume`), writing each run's files and checkpoints into its directory.
    The configs differ from `setup.config` only in their leaf hyperparameters (core/settings.py),
    which the cycle takes as leaves (learn/online.Cycle): each run's numbers are those it gets alone.
    `hooks` (run/hooks.py): progress, stop, per-cycle callback, TensorBoard, the devices the slot axis
    is sharded over (the numbers do not depend on them; a run may resume, or widen, onto others).

    `fault_injection(cycle, learners) -> learners` lets tests corrupt the state before a cycle (slot
    i of the leading axis: setting i // num_seeds, seed i % num_seeds). Returns each run's summary."""
    start, config = time.perf_counter(), setup.config
    slots = SeedMesh(len(settings) * config.num_seeds, tuple(hooks.devices or jax.local_devices()[:1]), config.seed_block)
    group = RunGroup(setup, settings, slots)
    done, elapsed_before = restored(group) if resume else fresh_start(group)
    elapsed = lambda: elapsed_before + time.perf_counter() - start
    done = Done(slots.place(done.learners), done.histories)  # checkpoints hold each run's state on one device
    program = SlotProgram(group, resumed_at=done.cycles)
    saver = Checkpointer(group, elapsed, saved=done.cycles, beside=program.save_beside)
    display, writable = CycleDisplay(group, hooks, saved=done.cycles), True
    try:
        for c in range(done.cycles + 1, config.cycles + 1):
            if hooks.stop is not None and hooks.stop.is_set():
                raise KeyboardInterrupt
            done = program.next_cycle(done, c, fault_injection, saver.saved)
            if hooks.on_cycle is not None:
                hooks.on_cycle()
            display.cycle(c, [history[-1] for history in done.histories])
            if c % config.checkpoint_every == 0 or c == config.cycles or c in config.keep_cycles:
                saver.save(done)
            if hooks.widen is not None and c < config.cycles:
                done = program.widen(done, hooks.widen, config.cycles - c)
                saver.group = program.group
    except KeyboardInterrupt:
        saver.save_if_behind(done)
        raise Interrupted(done.cycles) from None
    except WriteError:
        writable = False
        raise
    finally:
        display.close()
        infos = write_run_files(program.group, done, elapsed(), writable)
    return [info and {**info, "pace": program.pace()} for info in infos]


class SlotProgram:
    """The group's cycle compiled for its devices, each cycle timed: its first (which compiles) apart,
    so that `widen` can tell whether more devices pay for compiling it again."""

    def __init__(self, group: RunGroup, resumed_at: int = 0):
        self.group, self.cycle = group, Cycle(group.setup, group.slots, group.configs)
        self.repair = ModelRepair(group.setup, group.slots.num_seeds) if group.setup.approach.repairs_model else None
        if self.repair is not None and resumed_at:
            self.repair.restore(group.run_dirs, resumed_at, self.cycle)
        self.times = CycleTimes()
        self.compiling_s, self.device_s, self.seed_cycles = 0.0, 0.0, 0  # for the pace (`pace`)

    def next_cycle(self, done: Done, c: int, fault_injection: Callable | None, last_saved: int) -> Done:
        start = time.perf_counter()
        done = next_cycle(self.cycle, self.group, done, c, fault_injection, last_saved)
        if self.repair is not None:
            self.repair.after_cycle(c, self.cycle)
        seconds = time.perf_counter() - start
        if self.times.first_s is None:
            self.compiling_s += seconds
        else:
            self.device_s += seconds * self.group.slots.num_devices
            self.seed_cycles += self.group.slots.num_seeds
        self.times.timed(seconds)
        return done

    def save_beside(self, cycle: int) -> None:
        """What the runs resume from besides their checkpoints of `cycle` (a model repair's models)."""
        if self.repair is not None and self.group.primary:
            self.repair.save(self.group.run_dirs, self.group.setup.config.seeds, cycle)

    def pace(self) -> dict | None:
        """Device-seconds per seed-cycle once compiled, and the seconds of the cycles that compiled (each
        with its cycle's work): a start-up estimate from a short run would otherwise be mostly compilation.
        None before a compiled cycle was timed."""
        if not self.seed_cycles:
            return None
        return {"seed_cycle_s": self.device_s / self.seed_cycles, "compile_s": self.compiling_s}

    def widen(self, done: Done, widen: Callable, cycles_left: int) -> Done:
        """`done` moved onto more devices, where `widen` offers some worth it (run/scheduling.py); the same
        per-seed program on more devices: the numbers stay the same."""
        old = self.group.slots

        def per_device(more: int) -> int:  # seeds one after another on each device, with `more` devices
            return SeedMesh(old.num_seeds, old.devices + (None,) * more, old.block).padded // (old.num_devices + more)

        more = widen(lambda count: self.times.worth_widening(per_device(0), per_device(count), cycles_left))
        if not more:
            return done
        self.group = dataclasses.replace(self.group, slots=SeedMesh(old.num_seeds, old.devices + tuple(more), old.block))
        self.cycle = Cycle(self.group.setup, self.group.slots, self.group.configs)
        if self.repair is not None:
            self.repair.retask(self.cycle)
        self.times.recompiled()
        return Done(self.group.slots.place(old.unpad(done.learners)), done.histories)


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

    def __init__(self, group: RunGroup, hooks: RunHooks, saved: int):
        config, bar = group.setup.config, hooks.display
        self.events = [CycleEvents(d, c.to_dict()) for c, d in group.written] if hooks.tensorboard else []
        self.own_bar, self.approach = bar is None, config.approach
        if self.own_bar:
            what = f"{len(group.settings)} settings x " if len(group.settings) > 1 else ""
            bar = cycle_progress(config.cycles, f"{config.env} {what}x{config.num_seeds} seeds",
                                 hooks.progress and group.primary, saved)
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


def load_learners(run_dir: Path, cycle: int | None = None) -> tuple[Setup, object, int]:
    """A run's setup and learner state after `cycle` (default: its latest checkpoint), with its cycle. No
    task is compiled: the template the checkpoint is restored into needs the training env's shapes, not
    the tasks."""
    config = load_config(run_dir)
    check_checkpoint_belongs(config, run_dir)
    setup = make_setup(config)
    learners, record, step = checkpoint.restore(run_dir / "checkpoints", setup.init_learners(), cycle)
    return setup, learners, step
