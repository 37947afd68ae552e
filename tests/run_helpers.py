"""Running train.py in a child process, and what the safety and fault tests assert of its errors."""
import functools
import os
import select
import subprocess
import sys
import time
from pathlib import Path

# XLA's cheaper code generation, which the suite compiles with (conftest.py says why): no LLVM
# optimisation, and the CPU backend's older loop emitters, whose compiles take a third of the new
# fusion emitters' on the suite's programs (a cold tiny training: 16 -> 11 CPU s).
OLDER_EMITTERS = "--xla_cpu_use_fusion_emitters=false"
TEST_XLA_FLAGS = f"--xla_backend_optimization_level=0 --xla_llvm_disable_expensive_passes=true {OLDER_EMITTERS}"
ROOT = Path(__file__).resolve().parents[1]
QUICK = ["--approaches", "pure_planning", "--num-seeds", "1", "--no-progress"]


def with_fusion_emitters() -> dict:
    """This process's environment for a child that compiles with the fusion emitters, as users' runs do:
    for numbers that must not depend on the device count (the older emitters' loops over a device's seed
    slots round differently for 2 and 3 slots)."""
    return {**os.environ, "XLA_FLAGS": os.environ.get("XLA_FLAGS", "").replace(OLDER_EMITTERS, "").strip()}


def train(*args, timeout=600) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "train.py", *args], cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def cli_in_process(script: str, *args) -> subprocess.CompletedProcess:
    """`python script args` run in this process, through its `run_main` as `__main__` runs it: the exit
    code and what it printed, without a new interpreter's start-up (seconds each). For input refused
    before training starts; a training's threads, locks and signals belong in a child process."""
    import contextlib
    import io
    import signal

    import jaxbridge
    from jaxbridge.utils.cli import run_main

    out, err, handler, argv = io.StringIO(), io.StringIO(), signal.getsignal(signal.SIGINT), sys.argv
    with contextlib.chdir(ROOT), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            sys.argv = [script, *args]  # argparse names the program by it
            code = run_main(script_main(script), list(args))
        except SystemExit as exit_:  # argparse's refusals
            code = exit_.code
        finally:
            sys.argv = argv
            signal.signal(signal.SIGINT, handler)  # train.py's Ctrl-C handler, installed before its checks
            jaxbridge.release_locks()
    return subprocess.CompletedProcess([script, *args], code, out.getvalue(), err.getvalue())


@functools.cache
def script_main(script: str):
    """The `main(argv)` of a script of the repository root (train.py, eval.py), loaded once per process."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"cli_{Path(script).stem}", ROOT / script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main


def one_line_error(proc, code: int, *words: str) -> None:
    err = proc.stderr.strip()
    assert proc.returncode == code, proc.stderr
    assert "Traceback" not in err and err.count("\n") == 0, err
    assert all(w in err for w in words), err


def snapshot(directory: Path) -> dict:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def start_held(hold_after: int, signals: Path, *args, **popen) -> subprocess.Popen:
    """train.py that waits after sealing checkpoint `hold_after`, or before its first cycle for 0
    (tests/held_train.py): `signals`/held appears then, and it goes on once the test writes
    `signals`/release."""
    signals.mkdir(parents=True, exist_ok=True)
    return subprocess.Popen([sys.executable, str(ROOT / "tests" / "held_train.py"), str(hold_after), str(signals), *args],
                            cwd=ROOT, **{"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True, **popen})


def wait_for_line(proc: subprocess.Popen, text: str, seconds: float = 120) -> None:
    """Read the process's stderr pipe (its bytes, past any buffering) until `text` appears; fail if it
    ends or `seconds` pass first. Whatever follows stays for `proc.communicate()`."""
    fd, seen, deadline = proc.stderr.fileno(), b"", time.time() + seconds
    while text.encode() not in seen:
        left = deadline - time.time()
        ready = left > 0 and select.select([fd], [], [], left)[0]
        chunk = os.read(fd, 1 << 16) if ready else b""
        assert chunk, f"the process ended or went quiet before saying {text!r}: {seen.decode()!r}"
        seen += chunk


def wait_for(path: Path, proc: subprocess.Popen, seconds: float = 300) -> None:
    deadline = time.time() + seconds
    while not path.exists():
        assert proc.poll() is None and time.time() < deadline, f"{path} never appeared"
        time.sleep(0.05)


def read_scalars(directory: Path) -> dict[str, list[tuple[int, float]]]:
    """{tag: [(step, value)]} of the scalars in the TensorBoard event files of `directory`, read with
    the record framing of the format (length, its CRC, the Event proto, its CRC) and tensorboardX's proto."""
    import struct
    from tensorboardX.proto import event_pb2

    scalars: dict[str, list[tuple[int, float]]] = {}
    for path in sorted(directory.glob("events.out.tfevents.*")):
        data, at = path.read_bytes(), 0
        while at < len(data):
            (length,) = struct.unpack("<Q", data[at:at + 8])
            event = event_pb2.Event.FromString(data[at + 12:at + 12 + length])
            at += 12 + length + 4
            for value in event.summary.value:
                if value.HasField("simple_value"):
                    scalars.setdefault(value.tag, []).append((event.step, value.simple_value))
    return scalars


class Crash(Exception):
    """A fault injected into a training run."""


def trained_whole_and_resumed(setup, directory: Path, crash_at: int) -> tuple[Path, Path]:
    """`setup` trained in one go into directory/whole, and into directory/crashed with a crash before cycle
    `crash_at`, then resumed from its checkpoints: the two run directories."""
    import pytest

    from jaxbridge.run import rundir
    from jaxbridge.run.hooks import RunHooks
    from jaxbridge.run.runner import train

    whole, crashed = directory / "whole", directory / "crashed"
    for run_dir in (whole, crashed):
        rundir.prepare(run_dir, overwrite=False)
    train(setup, whole, RunHooks(progress=False))

    def crash(cycle, learners):
        if cycle == crash_at:
            raise Crash
        return learners

    with pytest.raises(Crash):
        train(setup, crashed, RunHooks(progress=False), fault_injection=crash)
    train(setup, crashed, RunHooks(progress=False), resume=True)
    return whole, crashed
