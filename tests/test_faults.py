"""Faults during a run, with real signals and real failed writes: Ctrl-C once during start-up and three
times during training, a full disk and a run directory turned read-only (as any user, root too). Pure planning
runs: the same runner and checkpoints as learning ones, compiled faster."""
import contextlib
import ctypes
import errno
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from run_helpers import QUICK, one_line_error, start_held, wait_for, wait_for_line

from jaxbridge.run import checkpoint

# ---- Ctrl-C, with real signals --------------------------------------------------------------------------
def test_ctrl_c_during_start_up_exits_at_once_saying_nothing_was_trained(tmp_path):
    # held before its first cycle: the press lands during start-up however fast the machine
    proc = start_held(0, tmp_path / "signals", *QUICK, "--cycles", "5", "--out", str(tmp_path), "--name", "early")
    wait_for(tmp_path / "signals" / "held", proc)
    assert (tmp_path / "early" / ".lock").exists()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "nothing was trained" in err and "Traceback" not in err
    assert not (tmp_path / "early" / ".lock").exists()


def test_three_ctrl_c_exit_130_without_corrupting_anything(tmp_path):
    run, signals = tmp_path / "t" / "pure_planning", tmp_path / "signals"
    # held after checkpoint 2, mid-run: it cannot finish between the presses, and each press waits for
    # the previous one's answer (signals sent at once could merge into one)
    proc = start_held(2, signals, "--approaches", "pure_planning", "--num-seeds", "2", "--cycles", "4",
                      "--checkpoint-every", "1", "--no-progress", "--out", str(tmp_path), "--name", "t")
    wait_for(signals / "held", proc)
    for answer in ("stopping after the current cycle", "still finishing the checkpoint"):
        proc.send_signal(signal.SIGINT)
        wait_for_line(proc, answer)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err and "terminate" not in err, err
    assert "quit at once" in err
    sealed = checkpoint.sealed_steps(run / "checkpoints")
    assert sealed and all(checkpoint.read_record(run / "checkpoints", s)[1] == s for s in sealed)  # each verifies


# ---- a full disk and a read-only run directory, for any user ---------------------------------------------
# Neither needs a mount (root only): the disk fills by the child's file-size limit (RLIMIT_FSIZE) dropping to
# 0, so every write that would grow a file fails, EFBIG as ENOSPC would; read-only is the run directory's
# permissions, which a root child obeys once it runs without root's privileges.
LEARNING = ["--approaches", "pure_planning", "--num-seeds", "2", "--checkpoint-every", "2", "--no-progress"]


def ignores_sigxfsz(pid: int) -> bool:
    """Whether process `pid` ignores SIGXFSZ, so that a write past its file-size limit fails (EFBIG) instead
    of killing it (Python ignores it at start-up; checked, not assumed)."""
    status = Path(f"/proc/{pid}/status").read_text()
    ignored = int(next(line for line in status.splitlines() if line.startswith("SigIgn:")).split()[1], 16)
    return bool(ignored >> (signal.SIGXFSZ - 1) & 1)


PR_GET_SECUREBITS, PR_SET_SECUREBITS, SECBIT_NOROOT = 27, 28, 1


@contextlib.contextmanager
def children_without_root_privileges():
    """Children started in the block run, as root, without root's privileges: SECBIT_NOROOT (a thread
    attribute, inherited) makes their exec grant no capabilities, no CAP_DAC_OVERRIDE, so file permissions
    bind them as any user's. This thread keeps its own; as another user there is nothing to drop."""
    if os.geteuid() != 0:
        yield
        return
    libc = ctypes.CDLL(None, use_errno=True)
    before = libc.prctl(PR_GET_SECUREBITS, 0, 0, 0, 0)

    def secure_bits(bits: int) -> None:
        if before < 0 or libc.prctl(PR_SET_SECUREBITS, bits, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_SET_SECUREBITS): root's children cannot drop its privileges")

    secure_bits(before | SECBIT_NOROOT)
    try:
        yield
    finally:
        secure_bits(before)


def test_a_full_disk_stops_the_run_in_one_line_naming_the_last_checkpoint(tmp_path):
    # held after checkpoint 2 while its file-size limit drops to 0: the next write fails however large orbax's files
    proc = start_held(2, tmp_path / "signals", *LEARNING, "--cycles", "6", "--out", str(tmp_path), "--name", "full")
    try:
        wait_for(tmp_path / "signals" / "held", proc)
        assert ignores_sigxfsz(proc.pid)
        resource.prlimit(proc.pid, resource.RLIMIT_FSIZE, (0, resource.prlimit(proc.pid, resource.RLIMIT_FSIZE)[1]))
        (tmp_path / "signals" / "release").touch()
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    one_line_error(subprocess.CompletedProcess(proc.args, proc.returncode, "", err), 4, os.strerror(errno.EFBIG),
                   "the last complete checkpoints are pure_planning cycle 2;", f"--resume {tmp_path / 'full'}")
    assert checkpoint.sealed_steps(tmp_path / "full" / "pure_planning" / "checkpoints")[-1] == 2


def set_writable(root, writable: bool) -> None:
    """`root` and everything under it read-only (directories r-x, files r--) or back to writable."""
    paths = [root, *root.rglob("*")]
    for path in (paths if writable else reversed(paths)):  # a directory's contents before the directory
        path.chmod((0o755 if writable else 0o555) if path.is_dir() else (0o644 if writable else 0o444))


def test_a_run_directory_turned_read_only_stops_the_run_in_one_line(tmp_path):
    experiment = tmp_path / "ro"
    run = experiment / "pure_planning"
    # held after checkpoint 4 while its directory turns read-only: the run is mid-way however fast
    with children_without_root_privileges():
        proc = start_held(4, tmp_path / "signals", *LEARNING, "--cycles", "8", "--out", str(tmp_path), "--name", "ro")
    try:
        wait_for(tmp_path / "signals" / "held", proc)
        set_writable(experiment, False)
        (tmp_path / "signals" / "release").touch()
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
        if experiment.exists():
            set_writable(experiment, True)
    one_line_error(subprocess.CompletedProcess(proc.args, proc.returncode, "", err), 4, os.strerror(errno.EACCES),
                   "the last complete checkpoints are pure_planning cycle 4;")
    assert checkpoint.sealed_steps(run / "checkpoints")[-1] == 4
    checkpoint.verify(run / "checkpoints", 4)  # what --resume will load is whole


QUIET_REPORTS = """
import sys
from jaxbridge.run import checkpoint
checkpoint.set_quiet({quiet})

class LateCallback:  # raises where Python can only report it (as tensorstore's late callbacks do)
    def __init__(self, err): self.err = err
    def __del__(self): raise self.err

LateCallback(RuntimeError("Event loop is closed"))
LateCallback(ValueError("a real bug"))
"""


@pytest.mark.parametrize("quiet", [True, False])
def test_quiet_drops_only_the_closed_event_loop_reports(quiet):
    err = subprocess.run([sys.executable, "-c", QUIET_REPORTS.format(quiet=quiet)], capture_output=True,
                         text=True, timeout=120).stderr
    assert "a real bug" in err
    assert ("Event loop is closed" in err) is not quiet, err
