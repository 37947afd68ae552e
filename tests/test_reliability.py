"""Faults: a run killed mid-training resumes exactly; damaged checkpoints are refused; a NaN stops the
run keeping the last good checkpoint; bad input gets one line and exit code 2."""
import csv
import json
import os
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxbridge.run import checkpoint
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.setup import make_setup
from jaxbridge.run import rundir
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import NumericalFault, train
from run_helpers import cli_in_process, start_held, wait_for

ROOT = Path(__file__).resolve().parents[1]
SMALL = ["--num-seeds", "2", "--cycles", "6", "--updates-per-cycle", "50", "--checkpoint-every", "1", "--no-progress",
         "--approaches", "ours"]


def cli(*args):
    return subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=600)


def final_params(run_dir: Path):
    config = TrainConfig.from_dict(json.loads((run_dir / "config.json").read_text()))
    state, _, step = checkpoint.restore(run_dir / "checkpoints", make_setup(config).init_learners())
    return step, jax.tree.leaves(state.params)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    proc = cli("train.py", *SMALL, "--out", str(out), "--name", "whole")
    assert proc.returncode == 0, proc.stderr
    return out / "whole" / "ours"


def test_a_run_killed_mid_training_resumes_to_identical_metrics_and_parameters(uninterrupted, tmp_path):
    run_dir = tmp_path / "killed" / "ours"
    # held right after checkpoint 3, so the kill lands there however fast the machine
    proc = start_held(3, tmp_path / "signals", *SMALL, "--out", str(tmp_path), "--name", "killed",
                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wait_for(tmp_path / "signals" / "held", proc)
    assert checkpoint.sealed_steps(run_dir / "checkpoints")[-1] == 3
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    resumed = cli("train.py", "--resume", str(run_dir.parent), "--no-progress")  # the experiment directory
    assert resumed.returncode == 0, resumed.stderr
    assert (run_dir / "metrics.csv").read_text() == (uninterrupted / "metrics.csv").read_text()
    step_a, params_a = final_params(uninterrupted)
    step_b, params_b = final_params(run_dir)
    assert step_a == step_b == 6
    assert all(np.array_equal(a, b) for a, b in zip(params_a, params_b))


@pytest.mark.parametrize("damage", ["flip", "truncate"])
def test_a_damaged_checkpoint_is_refused(uninterrupted, tmp_path, damage):
    import shutil
    run_dir = tmp_path / "copy"
    shutil.copytree(uninterrupted, run_dir)
    latest = run_dir / "checkpoints" / "6"
    target = max((p for p in latest.rglob("*") if p.is_file()), key=lambda p: p.stat().st_size)
    data = bytearray(target.read_bytes())
    if damage == "flip":
        data[len(data) // 2] ^= 0xFF
    else:
        data = data[: len(data) // 2]
    target.write_bytes(bytes(data))
    for args in (["eval.py", str(run_dir)], ["train.py", "--resume", str(run_dir)]):
        proc = cli_in_process(*args)
        assert proc.returncode == 2 and "corrupted" in proc.stderr and "Traceback" not in proc.stderr


def test_a_non_finite_q_function_stops_the_run_and_keeps_the_last_good_checkpoint(tmp_path):
    config = TrainConfig(num_seeds=2, cycles=4, updates_per_cycle=20, checkpoint_every=1, num_test_tasks=2)
    run_dir = tmp_path / "nan"
    rundir.prepare(run_dir, overwrite=False)

    def poison(cycle, learners):
        if cycle != 3:
            return learners
        params = jax.tree.map(lambda x: x.at[1].set(jnp.nan), learners.params)  # seed 1's network
        return learners.replace(params=params)

    with pytest.raises(NumericalFault, match="cycle 3 in seed 1.*checkpoint is of cycle 2"):
        train(make_setup(config), run_dir, RunHooks(progress=False), fault_injection=poison)
    assert checkpoint.sealed_steps(run_dir / "checkpoints") == [1, 2]
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    assert {r["cycle"] for r in rows} == {"1", "2"}  # the files cover the good cycles only


def test_a_save_started_while_another_is_inside_orbax_waits_for_it(tmp_path, monkeypatch):
    """Approaches train in worker threads and checkpoint whenever their cycles end; orbax's save is not
    safe to run twice at once in one process (without the lock in checkpoint.save, one of two
    concurrent saves failed at once here, and in a real run both hung for 300 s). The second save is
    started while the first is held inside orbax's part, and held there until the second has found the
    lock taken; without the lock it walks in beside the first, which is recorded and fails the test."""
    state, errors, overlaps, inside = {"w": jnp.ones((64, 32))}, [], [], []
    first_inside, second_waits = threading.Event(), threading.Event()
    real_save, real_lock = checkpoint._save, checkpoint._SAVING

    class WatchedLock:  # checkpoint.save's lock, saying when the second save finds it held
        def __enter__(self):
            if not real_lock.acquire(blocking=False):
                if threading.current_thread().name == "second":
                    second_waits.set()
                real_lock.acquire()

        def __exit__(self, *exc):
            real_lock.release()

    def watched_save(directory, step, state, record, keep):
        if inside:  # a save beside another: what the lock prevents
            overlaps.append((inside[0], directory.name))
            second_waits.set()
            raise RuntimeError("two saves at once")
        inside.append(directory.name)
        try:
            if directory.name == "first":
                first_inside.set()
                assert second_waits.wait(timeout=120), "the second save never tried to start"
            real_save(directory, step, state, record, keep)
        finally:
            inside.pop()

    monkeypatch.setattr(checkpoint, "_SAVING", WatchedLock())
    monkeypatch.setattr(checkpoint, "_save", watched_save)

    def save(name):
        try:
            checkpoint.save(tmp_path / name, 1, state, {"cycle": 1})
        except Exception as err:  # noqa: BLE001 - reported below
            errors.append(err)

    first, second = (threading.Thread(target=save, args=(name,), name=name, daemon=True)
                     for name in ("first", "second"))
    first.start()
    assert first_inside.wait(timeout=120)
    second.start()
    for t in (first, second):
        t.join(timeout=240)
    assert not first.is_alive() and not second.is_alive()
    assert second_waits.is_set() and overlaps == [] and errors == [], (overlaps, errors)
    for name in ("first", "second"):
        assert checkpoint.sealed_steps(tmp_path / name) == [1]
        checkpoint.verify(tmp_path / name, 1)


def test_a_step_orbax_will_delete_is_unsealed_before_the_save_that_deletes_it(tmp_path, monkeypatch):
    """orbax keeps the latest checkpoints and deletes older ones while it saves; a third Ctrl-C can stop
    the process mid-deletion (seen in CI: a half-deleted step 1 still had its manifest and read as
    corrupted). So when orbax starts a save, what it will drop is no longer sealed."""
    import orbax.checkpoint as ocp

    state, sealed_at_save = {"w": jnp.ones((4, 3))}, []
    for step in (1, 2):
        checkpoint.save(tmp_path, step, state, {"cycle": step})
    original = ocp.CheckpointManager.save

    def watched(self, step, *args, **kwargs):
        sealed_at_save.append(checkpoint.sealed_steps(tmp_path))
        return original(self, step, *args, **kwargs)

    monkeypatch.setattr(ocp.CheckpointManager, "save", watched)
    checkpoint.save(tmp_path, 3, state, {"cycle": 3})
    assert sealed_at_save == [[2]] and checkpoint.sealed_steps(tmp_path) == [2, 3]
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.isdigit()) == ["2", "3"]


def test_a_checkpoint_of_another_config_version_is_refused(uninterrupted, tmp_path):
    import shutil
    run_dir = tmp_path / "old"
    shutil.copytree(uninterrupted, run_dir)
    config = json.loads((run_dir / "config.json").read_text())
    config["config_version"] = 0
    (run_dir / "config.json").write_text(json.dumps(config))
    proc = cli_in_process("train.py", "--resume", str(run_dir))
    assert proc.returncode == 2 and "config version 0 is not supported" in proc.stderr


@pytest.mark.parametrize("field,value,message", [
    ("env", "doorknobs", "was written by a light_switch_door run of ours, but the run is doorknobs of ours"),
    ("num_seeds", 3, "was written with another config (num_seeds 2 there, 3 here)"),
])
def test_a_checkpoint_of_another_env_or_config_is_refused(uninterrupted, tmp_path, field, value, message):
    """A run directory whose checkpoints came from elsewhere (copied in, or config.json edited)."""
    import shutil
    run_dir = tmp_path / "mixed"
    shutil.copytree(uninterrupted, run_dir)
    config = json.loads((run_dir / "config.json").read_text())
    config[field] = value
    (run_dir / "config.json").write_text(json.dumps(config))
    for command in (["train.py", "--resume"], ["eval.py"]):
        proc = cli_in_process(*command, str(run_dir))
        assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr, proc.stderr


@pytest.mark.parametrize("args,message", [
    (["train.py", "--resume", "/nonexistent/run"], "not a run directory"),
    (["train.py", "--resume", "runs", "--cycles", "3"], "drop --cycles"),
    (["train.py", "--out", "/proc/no/such/place", "--cycles", "1"], "cannot write experiment directory"),
    (["train.py", "--episodes-per-cycle", "400"], "must fit the replay buffer"),
    (["eval.py", "--help-me"], "unrecognized arguments"),
])
def test_more_bad_input(args, message):
    proc = cli_in_process(*args)
    assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr


def test_ctrl_c_saves_a_checkpoint_of_the_last_completed_cycle(uninterrupted, tmp_path):
    run_dir = tmp_path / "interrupted" / "ours"
    args = ["--num-seeds", "2", "--cycles", "30", "--updates-per-cycle", "50", "--checkpoint-every", "100",
            "--approaches", "ours"]
    # Python's Ctrl-C handler installed explicitly in the child: a test run started in the background
    # passes SIGINT down ignored, and Python then installs no KeyboardInterrupt handler at all.
    argv = ["train.py", *args, "--out", str(tmp_path), "--name", "interrupted"]
    child = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
             f"sys.argv = {argv!r}; runpy.run_path('train.py', run_name='__main__')")
    proc = subprocess.Popen([sys.executable, "-c", child], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen = b""
    # Interrupt once the progress lines (every 5% or 30 s) show a cycle from the second on.
    while not any(int(done) >= 2 for done in re.findall(rb" (\d+)/30 cycles", seen)):
        chunk = proc.stderr.read1(4096)
        assert chunk, "the run ended before it could be interrupted"
        seen += chunk
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=300)
    err = (seen + rest).decode()
    assert proc.returncode == 130 and "--resume" in err and "Traceback" not in err
    saved = checkpoint.sealed_steps(run_dir / "checkpoints")
    assert len(saved) == 1 and 2 <= saved[0] < 30  # checkpoint_every 100: Ctrl-C saved it
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    assert len(rows) == 2 * saved[0]  # the files cover exactly the completed cycles
    whole = {(r["seed"], r["cycle"]): r for r in csv.DictReader((uninterrupted / "metrics.csv").open())}
    assert all(r == whole[(r["seed"], r["cycle"])] for r in rows if int(r["cycle"]) <= 6)


def test_kept_steps_outlive_the_latest_two_and_stay_sealed(tmp_path):
    """train.py --keep-cycles: the steps in `keep` stay, sealed, while the latest two move on past them."""
    state = {"w": jnp.ones((4, 3))}
    for step in range(1, 6):
        checkpoint.save(tmp_path, step, state, {"cycle": step}, keep=(1, 3))
    assert checkpoint.sealed_steps(tmp_path) == [1, 3, 4, 5]
    assert sorted(int(p.name) for p in tmp_path.iterdir() if p.name.isdigit()) == [1, 3, 4, 5]
    for step in (1, 3):
        checkpoint.verify(tmp_path, step)
    with pytest.raises(checkpoint.CheckpointError, match="no complete checkpoint for step 2"):
        checkpoint.restore(tmp_path, state, 2)
