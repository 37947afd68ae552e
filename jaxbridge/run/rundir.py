"""Run directories: which directories are runs of ours, replacing one without losing anything, and the
lock that keeps two processes out of one directory."""
from __future__ import annotations

import json
import os
import shutil
import socket
import sys
import time
from pathlib import Path

from jaxbridge.utils.errors import InputError

LOCK = ".lock"
RUN_FILES = ("experiment.json", "config.json")  # an experiment directory, or one approach's run


class RunDirError(InputError):
    """A directory this run may not use (not ours, in use, a bad name): one line, exit 2."""


def check_name(name: str) -> None:
    """A run name is one plain path component: it can neither escape --out nor name --out itself."""
    if not name or name in (".", "..") or name != Path(name).name or "/" in name or "\\" in name:
        raise RunDirError(f"--name must be a plain directory name (no '/', not '.' or '..'), got {name!r}")


def is_run(path: Path) -> bool:
    return any((path / f).is_file() for f in RUN_FILES)


def prepare(run_dir: Path, overwrite: bool) -> Path | None:
    """Create `run_dir` for a new run. An existing non-empty one is refused, or with `overwrite`, if it is a
    run of ours that no live process holds, moved aside: the returned path, for the caller to delete once
    the new run has written its first files (`discard`)."""
    if run_dir.exists() and not run_dir.is_dir():
        raise RunDirError(f"{run_dir} exists and is not a directory")
    aside = None
    if run_dir.exists() and any(run_dir.iterdir()):
        refuse_if_locked(run_dir)
        if not overwrite:
            raise RunDirError(f"run directory {run_dir} already exists (pass --overwrite to replace it, "
                              f"or --resume {run_dir} to continue it)")
        if not is_run(run_dir):
            raise RunDirError(f"{run_dir} is not a run directory of train.py (no {' or '.join(RUN_FILES)}); "
                              f"--overwrite replaces only runs, so it was left untouched")
        aside = run_dir.with_name(f".{run_dir.name}.replaced-{os.getpid()}")
        os.replace(run_dir, aside)
    run_dir.mkdir(parents=True, exist_ok=True)
    return aside


def fresh(run_dir: Path) -> None:
    """An empty `run_dir` inside an experiment this process holds (an approach that has not started)."""
    shutil.rmtree(run_dir, ignore_errors=True)
    run_dir.mkdir(parents=True)


def discard(aside: Path | None) -> None:
    """Delete a replaced run moved aside by `prepare` (once the new run has written its first files)."""
    if aside is not None:
        shutil.rmtree(aside, ignore_errors=True)


def _holder(lock: Path) -> dict | None:
    """The lock's {"pid", "host", "since"}, or None if it cannot be read."""
    try:
        holder = json.loads(lock.read_text())
        return holder if isinstance(holder, dict) and isinstance(holder.get("pid"), int) else None
    except (OSError, ValueError):
        return None


def _gone(holder: dict) -> bool:
    """The holder's process no longer exists (only decidable on this host)."""
    if holder.get("host") != socket.gethostname():
        return False
    try:
        os.kill(holder["pid"], 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    return False


def _in_use(run_dir: Path, holder: dict | None) -> RunDirError:
    who = (f"process {holder['pid']} on {holder.get('host', '?')} (since {holder.get('since', '?')})" if holder
           else "another process (its lock file is unreadable)")
    return RunDirError(f"{run_dir} is in use by {who}; wait for it to finish, or delete {run_dir / LOCK} if it is gone")


def refuse_if_locked(run_dir: Path) -> None:
    lock = run_dir / LOCK
    if lock.exists():
        holder = _holder(lock)
        if holder is None or not _gone(holder):
            raise _in_use(run_dir, holder)


_HELD: set["RunLock"] = set()


def release_held() -> None:
    """Release every lock this process holds (before exiting without unwinding)."""
    for lock in list(_HELD):
        lock.release()


class RunLock:
    """`run_dir/.lock`, created atomically with this process's pid and host. A lock whose process is gone
    is taken over with a warning; one held by a live process (or another host) is refused."""

    def __init__(self, run_dir: Path):
        self.run_dir, self.path = Path(run_dir), Path(run_dir) / LOCK

    def acquire(self) -> "RunLock":
        me = json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "since": time.strftime("%Y-%m-%d %H:%M:%S")})
        while True:
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = _holder(self.path)
                if holder is None or not _gone(holder):
                    raise _in_use(self.run_dir, holder) from None
                print(f"warning: {self.run_dir} was locked by process {holder['pid']}, which is gone; taking it over",
                      file=sys.stderr)
                self.path.unlink(missing_ok=True)
                continue
            with os.fdopen(fd, "w") as f:
                f.write(me + "\n")
            _HELD.add(self)
            return self

    def release(self) -> None:
        _HELD.discard(self)
        holder = _holder(self.path)
        if holder is not None and holder["pid"] == os.getpid():
            try:
                self.path.unlink(missing_ok=True)
            except OSError:
                pass  # a read-only or vanished directory: the lock is stale from now on and will be taken over
