"""Orbax checkpoints of the whole learner state (networks, target, optimizer, replay buffer, keys,
counters) plus a JSON record (config, cycle, metrics so far)."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import jax
import orbax.checkpoint as ocp
from orbax.checkpoint import checkpoint_managers


def manager(directory: Path, keep: int = 2) -> ocp.CheckpointManager:
    options = ocp.CheckpointManagerOptions(preservation_policy=checkpoint_managers.LatestN(n=keep),
                                           create=True)
    return ocp.CheckpointManager(Path(directory).absolute(), options=options)


def save(directory: Path, step: int, state: Any, record: dict) -> None:
    with manager(directory) as mgr:
        mgr.save(step, args=ocp.args.Composite(state=ocp.args.StandardSave(state),
                                               record=ocp.args.JsonSave(record)))
        mgr.wait_until_finished()


def latest_step(directory: Path) -> int | None:
    if not Path(directory).is_dir():
        return None
    with manager(directory) as mgr:
        return mgr.latest_step()


def restore(directory: Path, like: Any, step: int | None = None) -> tuple[Any, dict, int]:
    """Restore the state (shaped like `like`), its JSON record and the step (latest by default)."""
    with manager(directory) as mgr:
        step = mgr.latest_step() if step is None else step
        if step is None:
            raise FileNotFoundError(f"no checkpoint in {directory}")
        abstract = jax.tree.map(ocp.utils.to_shape_dtype_struct, like)
        restored = mgr.restore(step, args=ocp.args.Composite(state=ocp.args.StandardRestore(abstract),
                                                             record=ocp.args.JsonRestore()))
    return restored.state, restored.record, step
