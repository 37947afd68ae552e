"""Orbax checkpoints of the whole learner state (networks, target, optimizer, replay buffer, keys,
counters) plus a JSON record (config, cycle, metrics so far), each sealed by a SHA-256 manifest.

The manifest is written (atomically) only after orbax has finished, so a checkpoint without one was
cut short (a crash mid-save) and is skipped; a checkpoint whose files no longer match their manifest
(flipped bytes, truncation) is refused rather than loaded.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import shutil
import sys
import threading
from pathlib import Path
from typing import Any

import jax
import numpy as np
import orbax.checkpoint as ocp
from orbax.checkpoint import checkpoint_managers

from jaxbridge.learn.devices import is_prng_key
from jaxbridge.utils.distributed import multi_process
from jaxbridge.utils.errors import InputError
from jaxbridge.utils.files import WriteError, write_atomic

KEEP = 2


class CheckpointError(InputError):
    """A checkpoint is missing, incomplete, corrupted or does not fit this run."""


def _manager(directory: Path, keep: tuple[int, ...] = ()) -> ocp.CheckpointManager:
    # Synchronous saves: a failure (no space, read-only) raises here, in the saving thread, at once, and
    # no background thread outlives it.
    # Across processes (utils/distributed.py) each process reads alone and process 0 alone writes, from
    # states gathered on the host: no orbax barrier waits on the others.
    alone = {"multiprocessing_options": ocp.options.MultiprocessingOptions(
        primary_host=jax.process_index(), active_processes={jax.process_index()})} if multi_process() else {}
    # orbax's create=True refuses active_processes: across processes _save makes the directory
    kept = checkpoint_managers.AnyPreservationPolicy([checkpoint_managers.LatestN(n=KEEP),
                                                      checkpoint_managers.CustomSteps(steps=list(keep))])
    options = ocp.CheckpointManagerOptions(preservation_policy=kept,
                                           create=not alone, enable_async_checkpointing=False, **alone)
    return ocp.CheckpointManager(Path(directory).absolute(), options=options)


def _manifest_path(directory: Path, step: int) -> Path:
    return Path(directory) / f"{step}.sha256.json"


def _digests(step_dir: Path) -> dict[str, str]:
    return {str(p.relative_to(step_dir)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(step_dir.rglob("*")) if p.is_file()}


# Orbax keeps "the current save" in a process-wide counter: two saves at once (approaches in threads) can
# wait on each other's signal forever, so saves take turns (docs/RELIABILITY.md).
_SAVING = threading.Lock()


def save(directory: Path, step: int, state: Any, record: dict, keep: tuple[int, ...] = ()) -> None:
    """Save and seal checkpoint `step`, keeping the KEEP latest and those of the steps in `keep`; WriteError
    (naming the directory) if the files cannot be written."""
    directory = Path(directory)
    if multi_process():  # orbax takes only host arrays there; PRNG keys as their words (restore wraps them)
        state = jax.tree.map(lambda x: np.asarray(jax.random.key_data(x) if is_prng_key(x) else x), state)
    with _SAVING, _quiet():
        try:
            _save(directory, step, state, record, keep)
        except (WriteError, CheckpointError):
            raise
        except Exception as err:  # noqa: BLE001 -- orbax wraps OS errors in ValueError and others
            reason = _write_failure(err)
            if reason is None:  # not a failed write (a bug, a state that does not fit): as it is
                raise
            shutil.rmtree(directory / f"{step}.orbax-checkpoint-tmp", ignore_errors=True)
            raise WriteError(directory / str(step), reason) from None


QUIET = True  # orbax's and tensorstore's own reports of a failed save (tracebacks from their threads) go
# to /dev/null; save raises one WriteError instead. train.py --debug shows them (`set_quiet`).


def set_quiet(quiet: bool) -> None:
    """Whether a failed save is only the run's one-line report (train.py) or also orbax's and tensorstore's
    own reports (--debug). Besides a save's own stderr (`_quiet`), quiet drops what they print outside
    it: orbax's log of the failed background write, and the "Event loop is closed" tracebacks of
    tensorstore's late callbacks into the event loop orbax closed (reported through sys.unraisablehook)."""
    global QUIET
    QUIET = quiet
    logging.getLogger("absl").addFilter(_RAISED_WRITE_ERRORS)  # the same filter once, however often called
    if sys.unraisablehook is not _unraisablehook:
        global _default_unraisablehook
        _default_unraisablehook, sys.unraisablehook = sys.unraisablehook, _unraisablehook


class _DropRaisedWriteErrors(logging.Filter):
    """orbax logs a failed background write, traceback and all, before it raises the same error to the
    save that waits on it."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not (QUIET and "_SignalingThread.run() raised an exception" in str(record.msg))


_RAISED_WRITE_ERRORS = _DropRaisedWriteErrors()
_default_unraisablehook = sys.unraisablehook


def _unraisablehook(unraisable) -> None:
    if not (QUIET and unraisable.exc_type is RuntimeError and str(unraisable.exc_value) == "Event loop is closed"):
        _default_unraisablehook(unraisable)


@contextlib.contextmanager
def _quiet():
    if not QUIET:
        yield
        return
    sys.stderr.flush()
    saved, null = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 2)
    try:
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)


def _write_failure(err: Exception) -> str | None:
    """The OS's words for a failed write, out of orbax's and tensorstore's long messages; None when `err`
    is no failed write."""
    text = str(err)
    for words in ("No space left on device", "Read-only file system", "Permission denied", "Disk quota exceeded"):
        if words in text:
            return words
    if isinstance(err, OSError):
        return err.strerror or text
    return text.splitlines()[0][:200] if "os_error_code" in text else None


def _save(directory: Path, step: int, state: Any, record: dict, keep: tuple[int, ...]) -> None:
    if multi_process():
        directory.mkdir(parents=True, exist_ok=True)  # the manager does not, across processes
    unsealed = directory / str(step)
    if unsealed.exists() and not _manifest_path(directory, step).is_file():
        shutil.rmtree(unsealed)  # a save of this step that never completed: orbax would keep its files
    # Unseal first what this save makes orbax delete (it keeps the KEEP latest steps and those in `keep`): a
    # process stopped while orbax deletes a step (a third Ctrl-C) must not leave a half-deleted step with its manifest.
    sealed = sealed_steps(directory)
    for old in sealed[:max(0, len(sealed) - (KEEP - 1))]:
        if old not in keep:
            _manifest_path(directory, old).unlink()
    with _manager(directory, keep) as mgr:
        saved = mgr.save(step, args=ocp.args.Composite(state=ocp.args.StandardSave(state),
                                                       record=ocp.args.JsonSave(record)))
        mgr.wait_until_finished()
        if not saved:
            raise CheckpointError(f"orbax did not save checkpoint {step} in {directory} (it holds that step already)")
        kept = set(mgr.all_steps())
    write_atomic(_manifest_path(directory, step), json.dumps(_digests(directory / str(step))))
    for old in directory.glob("*.sha256.json"):  # manifests of checkpoints orbax has dropped
        if int(old.name.split(".")[0]) not in kept:
            old.unlink()


def sealed_steps(directory: Path) -> list[int]:
    """Steps with a complete checkpoint and its manifest, oldest first."""
    directory = Path(directory)
    if not directory.is_dir():
        return []
    return sorted(int(p.name) for p in directory.iterdir()
                  if p.is_dir() and p.name.isdigit() and _manifest_path(directory, int(p.name)).is_file())


def discard_after(directory: Path, step: int) -> None:
    """Delete the checkpoints after `step` (unsealed first): a run that resumes from `step` with others
    trained together saves those steps again."""
    directory = Path(directory)
    for later in [s for s in sealed_steps(directory) if s > step]:
        _manifest_path(directory, later).unlink()
        shutil.rmtree(directory / str(later))


def _read_manifest(directory: Path, step: int) -> dict[str, str]:
    path = _manifest_path(directory, step)
    try:
        manifest = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise CheckpointError(f"checkpoint manifest {path} is corrupted ({err}); refusing to load checkpoint {step}") from None
    if not (isinstance(manifest, dict) and all(isinstance(k, str) and isinstance(v, str) for k, v in manifest.items())):
        raise CheckpointError(f"checkpoint manifest {path} is corrupted (not a map of file names to digests); "
                              f"refusing to load checkpoint {step}")
    return manifest


def verify(directory: Path, step: int) -> None:
    directory = Path(directory)
    expected = _read_manifest(directory, step)
    actual = _digests(directory / str(step))
    if actual != expected:
        changed = sorted(set(expected) ^ set(actual) | {k for k in expected if actual.get(k) != expected[k]})
        raise CheckpointError(f"checkpoint {directory / str(step)} is corrupted or truncated "
                              f"({', '.join(changed[:3])}{' ...' if len(changed) > 3 else ''} changed); refusing to load it")


def _sealed_step(directory: Path, step: int | None) -> int:
    """The latest sealed checkpoint's step (or `step`), verified against its manifest."""
    steps = sealed_steps(directory)
    if step is None:
        if not steps:
            raise CheckpointError(f"no complete checkpoint in {directory}")
        step = steps[-1]
    elif step not in steps:
        raise CheckpointError(f"no complete checkpoint for step {step} in {directory}")
    verify(directory, step)
    return step


def read_record(directory: Path, step: int | None = None) -> tuple[dict, int]:
    """The JSON record (config, cycle, metrics) of the latest sealed checkpoint (or `step`), without
    the state: cheap enough to check that a checkpoint belongs to a run before building the run."""
    directory = Path(directory)
    step = _sealed_step(directory, step)
    with _manager(directory) as mgr:
        return mgr.restore(step, args=ocp.args.Composite(record=ocp.args.JsonRestore())).record, step


def restore(directory: Path, like: Any, step: int | None = None) -> tuple[Any, dict, int]:
    """Restore the state (shaped like `like`), its JSON record and its step: the latest sealed
    checkpoint unless `step` is given. Raises CheckpointError if there is none or it is damaged."""
    directory = Path(directory)
    step = _sealed_step(directory, step)
    abstract = jax.tree.map(ocp.utils.to_shape_dtype_struct, like)
    try:
        with _manager(directory) as mgr:
            restored = mgr.restore(step, args=ocp.args.Composite(state=ocp.args.StandardRestore(abstract),
                                                                 record=ocp.args.JsonRestore()))
    except (ValueError, KeyError, TypeError) as err:  # shapes or structure of another config
        raise CheckpointError(f"checkpoint {directory / str(step)} does not fit this run: {err}") from None
    state = jax.tree.map(lambda r, t: jax.random.wrap_key_data(r, impl=jax.random.key_impl(t))
                         if is_prng_key(t) and not is_prng_key(r) else r, restored.state, like)  # saved by several processes
    return state, restored.record, step
