"""Faults during a run, with real signals and real filesystems: Ctrl-C once during start-up and three times
during training, a full disk and a filesystem turned read-only (a small tmpfs mount, as root). Pure planning runs: the same
runner and checkpoints as learning ones, compiled faster."""
import errno
import os
import signal
import subprocess
import sys

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


# ---- a full disk and a read-only filesystem -------------------------------------------------------------
@pytest.fixture
def small_disk(tmp_path):
    """A 20 MB tmpfs at tmp_path/disk (mounting needs root, else the test is skipped)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=20m", "tmpfs", str(disk)], capture_output=True).returncode:
        pytest.skip("this machine does not allow mounting a tmpfs")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def fill(disk) -> None:
    """Write to `disk` until not one more byte fits: the run's next write fails, whatever its size."""
    fd = os.open(disk / "filler", os.O_WRONLY | os.O_CREAT)
    try:
        for size in (1 << 20, 1 << 12, 1):
            try:
                while True:
                    os.write(fd, b"\0" * size)
            except OSError as e:
                assert e.errno == errno.ENOSPC, e
    finally:
        os.close(fd)


LEARNING = ["--approaches", "pure_planning", "--num-seeds", "2", "--checkpoint-every", "2", "--no-progress"]


def test_a_full_disk_stops_the_run_in_one_line_naming_the_last_checkpoint(small_disk, tmp_path):
    # held after checkpoint 2 while the disk is filled: the next write fails however large orbax's files
    proc = start_held(2, tmp_path / "signals", *LEARNING, "--cycles", "6", "--out", str(small_disk), "--name", "full")
    try:
        wait_for(tmp_path / "signals" / "held", proc)
        fill(small_disk)
        (tmp_path / "signals" / "release").touch()
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    one_line_error(subprocess.CompletedProcess(proc.args, proc.returncode, "", err), 4, "No space left on device",
                   "the last complete checkpoints are pure_planning cycle 2;", f"--resume {small_disk / 'full'}")
    assert checkpoint.sealed_steps(small_disk / "full" / "pure_planning" / "checkpoints")[-1] == 2


def test_a_filesystem_turned_read_only_stops_the_run_in_one_line(small_disk, tmp_path):
    run = small_disk / "ro" / "pure_planning"
    # held after checkpoint 4 while the filesystem turns read-only: the run is mid-way however fast
    proc = start_held(4, tmp_path / "signals", *LEARNING, "--cycles", "8", "--out", str(small_disk), "--name", "ro")
    try:
        wait_for(tmp_path / "signals" / "held", proc)
        subprocess.run(["mount", "-o", "remount,ro", str(small_disk)], check=True)
        (tmp_path / "signals" / "release").touch()
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
        subprocess.run(["mount", "-o", "remount,rw", str(small_disk)], capture_output=True)
    one_line_error(subprocess.CompletedProcess(proc.args, proc.returncode, "", err), 4, "Read-only file system",
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
