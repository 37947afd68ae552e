"""Writing files atomically: a temporary file in the same directory, then a rename, so an interrupted
write never leaves a truncated file behind."""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

class WriteError(Exception):
    """A run's file could not be written (no space, read-only, permission): one line naming the path."""

    def __init__(self, path: Path | str, reason: str):
        super().__init__(f"cannot write {path}: {reason}")
        self.path, self.reason = Path(path), reason


def write_atomic(path: Path, data: str | bytes) -> None:
    path = Path(path)
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        _write_atomic(path, data, mode)
    except OSError as err:
        raise WriteError(path, err.strerror or str(err)) from None


def _write_atomic(path: Path, data: str | bytes, mode: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode) as f:
            f.write(data)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual permissions
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
