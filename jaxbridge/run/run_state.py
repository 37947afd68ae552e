"""What runs trained together keep between cycles, and where it is kept: their group (configs, run
directories, the seeds' slots), the state after the last completed cycle, its start (fresh or restored
from checkpoints), its checkpoints and the run files written from it."""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import jax
import numpy as np

from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh, describe
from jaxbridge.learn.online import CycleMetrics
from jaxbridge.learn.setup import Setup
from jaxbridge.run import artifacts, checkpoint
from jaxbridge.utils.distributed import is_primary, sync_processes
from jaxbridge.utils.files import write_atomic


@dataclass(frozen=True)
class RunGroup:
    """Runs trained as one program: a (config, run directory) per run, their seeds side by side in `slots`
    (run-major: slot i is run i // num_seeds, seed i % num_seeds). Only process 0 writes files."""

    setup: Setup
    settings: list[tuple[TrainConfig, Path]]
    slots: SeedMesh
    primary: bool = dataclasses.field(default_factory=is_primary)

    @property
    def configs(self) -> list[TrainConfig]:
        return [c for c, _ in self.settings]

    @property
    def run_dirs(self) -> list[Path]:
        return [d for _, d in self.settings]

    @property
    def written(self) -> list[tuple[TrainConfig, Path]]:
        """The runs this process writes files for."""
        return self.settings if self.primary else []

    def of_run(self, tree: Any, i: int) -> Any:
        """Run i's seeds of a slot-major tree."""
        n = self.setup.config.num_seeds
        return jax.tree.map(lambda x: x[i * n:(i + 1) * n], tree)


@dataclass(frozen=True)
class Done:
    """The learners and each run's metrics after the last completed cycle: replaced whole, so that
    Ctrl-C at any moment finds a consistent pair to checkpoint."""

    learners: Any
    histories: list[list[CycleMetrics]]

    @property
    def cycles(self) -> int:
        return len(self.histories[0])


def fresh_start(group: RunGroup) -> tuple[Done, float]:
    """New runs: every run's learners from the seeds' keys (made by its own setting's learner), its config.json
    written; no time spent yet."""
    fresh = [group.setup.init_learners(config) for config, _ in group.settings]
    for config, run_dir in group.written:
        write_atomic(run_dir / "config.json", json.dumps(config.to_dict(), indent=2) + "\n")
    return Done(_concat(fresh), [[] for _ in group.settings]), 0.0


def restored(group: RunGroup) -> tuple[Done, float]:
    """Runs continued from the latest cycle all of them checkpointed (later checkpoints discarded), and
    the time they had spent."""
    for config, run_dir in group.settings:
        check_checkpoint_belongs(config, run_dir)
    step = common_step(group.run_dirs)
    fresh = group.setup.init_learners()
    states = [checkpoint.restore(d / "checkpoints", fresh, step) for d in group.run_dirs]
    # Every process has read its checkpoints before process 0, which alone writes, deletes the later ones.
    sync_processes("restored")
    for run_dir in group.run_dirs if group.primary else []:
        checkpoint.discard_after(run_dir / "checkpoints", step)
    done = Done(_concat([state for state, _, _ in states]), [_history(record) for _, record, _ in states])
    return done, max(float(record["elapsed_s"]) for _, record, _ in states)


class Checkpointer:
    """Each run's checkpoint of a `Done` (its unpadded state, on one device), with the cycle saved last."""

    def __init__(self, group: RunGroup, elapsed: Callable[[], float], saved: int,
                 beside: Callable[[int], None] | None = None):
        """`beside(cycle)`: what else a save of `cycle` writes (a model repair's models)."""
        self.group, self.elapsed, self.saved, self.beside = group, elapsed, saved, beside

    def save(self, done: Done) -> None:
        state = self.group.slots.unpad(done.learners)
        for i, (config, run_dir) in enumerate(self.group.written):
            checkpoint.save(run_dir / "checkpoints", len(done.histories[i]), self.group.of_run(state, i),
                            checkpoint_record(config, done.histories[i], self.elapsed()), keep=config.keep_cycles)
        if self.beside is not None:
            self.beside(done.cycles)
        self.saved = done.cycles

    def save_if_behind(self, done: Done) -> None:
        if done.cycles > self.saved:
            self.save(done)


def write_run_files(group: RunGroup, done: Done, elapsed_s: float, writable: bool = True) -> list[dict | None]:
    """Each run's summary of the cycles completed (None before any), and (where this process writes and
    the disk takes it) its files: the files always describe the cycles completed so far."""
    seeds, devices = group.setup.config.seeds, describe(group.slots.devices)
    infos = [artifacts.summary(h, seeds, elapsed_s, devices) if h else None for h in done.histories]
    for (config, run_dir), history, info in zip(group.written if writable else [], done.histories, infos):
        if info:
            artifacts.write_run_files(run_dir, config.to_dict(), history, info, label=group.setup.approach.label)
    return infos


def checkpoint_record(config: TrainConfig, history: list[CycleMetrics], elapsed_s: float) -> dict:
    """What a checkpoint records beside the state: the config, the cycles so far and their metrics."""
    return {"cycle": len(history), "config": config.to_dict(), "elapsed_s": elapsed_s,
            "history": [{f.name: np.asarray(getattr(m, f.name)).tolist() for f in dataclasses.fields(m)}
                        for m in history]}


def _history(record: dict) -> list[CycleMetrics]:
    """Metrics back from a checkpoint record, exactly (float32 values round-trip through JSON)."""
    dtype = lambda v: np.float32 if isinstance(v[0], float) else np.int32
    unknown = {"test_decisions": np.nan}  # metrics a run of an older version did not record
    return [CycleMetrics(**{k: np.full(len(m["test_solve_rate"]), v, np.float32) for k, v in unknown.items()}
                         | {k: np.asarray(v, dtype(v)) for k, v in m.items()}) for m in record["history"]]


def _concat(states: list):
    return states[0] if len(states) == 1 else jax.tree.map(lambda *x: jax.numpy.concatenate(x), *states)


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
    differ = _differences(saved, config)
    if differ:
        raise checkpoint.CheckpointError(f"checkpoint {where} was written with another config ({'; '.join(differ)}); "
                              f"refusing to load it")


def _differences(saved, config, prefix: str = "") -> list[str]:
    """Each setting that differs, as "name there, here" (a learner's as learner.name)."""
    differ = []
    for f in dataclasses.fields(config):
        there, here = getattr(saved, f.name), getattr(config, f.name)
        if there != here and type(there) is type(here) and dataclasses.is_dataclass(here):
            differ += _differences(there, here, f"{prefix}{f.name}.")
        elif there != here:
            differ.append(f"{prefix}{f.name} {there} there, {here} here")
    return differ


def common_step(run_dirs: list[Path]) -> int:
    """The latest cycle every run checkpointed (runs trained together save together; a crash between
    their saves leaves the others one step ahead, which they then repeat exactly)."""
    shared = set.intersection(*(set(checkpoint.sealed_steps(d / "checkpoints")) for d in run_dirs))
    if not shared:
        raise checkpoint.CheckpointError(f"{', '.join(str(d) for d in run_dirs)}: no checkpoint of the same "
                                         f"cycle in every run trained together")
    return max(shared)
