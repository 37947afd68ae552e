"""Nothing lost, nobody's files touched: --overwrite and --name, the run lock with two real processes, runs
too big for memory, damaged manifests, lost checkpoints, one-line flag errors (tests/test_faults.py: Ctrl-C,
a full disk, a run directory turned read-only)."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from run_helpers import QUICK, cli_in_process, one_line_error, snapshot, start_held, train, wait_for

from jaxbridge.run import rundir

@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    """A finished small experiment (pure planning, 1 seed, 2 cycles); tests work on copies of it."""
    out = tmp_path_factory.mktemp("finished")
    proc = train(*QUICK, "--cycles", "2", "--out", str(out), "--name", "run")
    assert proc.returncode == 0, proc.stderr
    return out / "run"


def copy_of(run: Path, where: Path, name: str) -> Path:
    shutil.copytree(run, where / name)
    return where / name


def test_overwrite_replaces_only_runs_and_names_stay_inside_out(finished, tmp_path):
    precious = tmp_path / "precious"
    precious.mkdir()
    (precious / "thesis.txt").write_text("years of work")
    (tmp_path / "beside.txt").write_text("untouched")
    before = snapshot(tmp_path)
    one_line_error(cli_in_process("train.py", *QUICK, "--cycles", "1", "--out", str(tmp_path), "--name", "precious", "--overwrite"), 2,
                   "is not a run directory of train.py", "left untouched")
    one_line_error(cli_in_process("train.py", *QUICK, "--cycles", "1", "--out", str(tmp_path / "runs"), "--name", "..", "--overwrite"),
                   2, "--name must be a plain directory name")
    for name in (".", "a/b", "", "/abs"):  # the same check, in this process
        with pytest.raises(rundir.RunDirError, match="--name must be a plain directory name"):
            rundir.check_name(name)
    assert snapshot(tmp_path) == before

    run = copy_of(finished, tmp_path, "run")
    again = train(*QUICK, "--cycles", "1", "--out", str(tmp_path), "--name", "run", "--overwrite")
    assert again.returncode == 0, again.stderr
    assert {r.split(",")[1] for r in (run / "pure_planning" / "metrics.csv").read_text().split()[1:]} == {"1"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["beside.txt", "precious", "run"]  # nothing left aside
    assert snapshot(precious) == {"thesis.txt": b"years of work"}


def test_a_locked_run_directory_is_refused_to_a_second_process(tmp_path):
    run, signals = tmp_path / "c", tmp_path / "signals"
    # held after its first checkpoint, so it still holds the lock while the others try
    first = start_held(1, signals, "--approaches", "pure_planning", "--num-seeds", "2", "--cycles", "2",
                       "--checkpoint-every", "1", "--no-progress", "--out", str(tmp_path), "--name", "c")
    try:
        wait_for(signals / "held", first)
        holder = json.loads((run / ".lock").read_text())
        assert holder["pid"] == first.pid
        for proc in (cli_in_process("train.py", *QUICK, "--cycles", "1", "--out", str(tmp_path), "--name", "c", "--overwrite"),
                     cli_in_process("train.py", "--resume", str(run), "--no-progress")):
            one_line_error(proc, 2, f"is in use by process {first.pid}", "wait for it to finish")
        (signals / "release").touch()
        out, err = first.communicate(timeout=300)
    finally:
        first.kill()
    assert first.returncode == 0, err
    assert not (run / ".lock").exists()  # released at the end


def test_a_lock_whose_process_is_gone_is_taken_over_with_a_warning(finished, tmp_path):
    copy_of(finished, tmp_path, "r")
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    (tmp_path / "r" / ".lock").write_text(json.dumps({"pid": gone.pid, "host": os.uname().nodename, "since": "-"}))
    proc = train("--resume", str(tmp_path / "r"), "--no-progress")
    assert proc.returncode == 0 and f"locked by process {gone.pid}, which is gone; taking it over" in proc.stderr


def test_resume_of_an_experiment_whose_checkpoints_are_gone_is_refused(finished, tmp_path):
    copy_of(finished, tmp_path, "lost")
    shutil.rmtree(tmp_path / "lost" / "pure_planning" / "checkpoints")
    before = snapshot(tmp_path)
    one_line_error(cli_in_process("train.py", "--resume", str(tmp_path / "lost"), "--no-progress"), 2,
                   "has results but no complete checkpoint to resume from", "--overwrite")
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("manifest, tool, words", [
    ("{garbage", "train.py", ["checkpoint manifest", "2.sha256.json is corrupted"]),
    ("[1, 2]", "eval.py", ["checkpoint manifest", "2.sha256.json is corrupted (not a map"]),
])
def test_a_damaged_manifest_is_a_corrupted_checkpoint(finished, tmp_path, manifest, tool, words):
    copy_of(finished, tmp_path, "m")
    (tmp_path / "m" / "pure_planning" / "checkpoints" / "2.sha256.json").write_text(manifest)
    args = ["--resume", str(tmp_path / "m"), "--no-progress"] if tool == "train.py" else [str(tmp_path / "m"), "--approach", "pure_planning"]
    one_line_error(cli_in_process(tool, *args), 2, *words)


def test_a_run_too_big_for_memory_is_refused_with_its_estimate(tmp_path):
    one_line_error(cli_in_process("train.py", "--num-seeds", "100000", "--out", str(tmp_path)), 2, "this run needs about",
                   "x 100000 seeds), more than the", "GiB available; lower --num-seeds (about")
    one_line_error(cli_in_process("train.py", *QUICK, "--max-memory", "0.5", "--out", str(tmp_path)), 2,
                   "GiB allowed by --max-memory")
    assert not any(tmp_path.iterdir())  # refused before anything was written


def test_an_evaluation_too_big_for_memory_is_refused_with_its_estimate(finished):
    """Light Switch Door's plan tables grow with cells squared: 100000 cells is ~37 GiB per task, refused
    from the env's plan_bound before anything is grounded; Coffee has no bound, so its first task is."""
    evaluate = lambda *args: cli_in_process("eval.py", str(finished), "--approach", "pure_planning", *args)
    one_line_error(evaluate("--task-size", "cells=100000,doors=1"), 2, "evaluating these 10 tasks needs about",
                   "plan tables of 200000 states x 400000 operators), more than the", "GiB available; lower --task-size")
    one_line_error(evaluate("--task-size", "cells=40,doors=2", "--max-memory", "0.5"), 2, "allowed by --max-memory")
    one_line_error(cli_in_process("eval.py", "--env", "coffee", "--num-seeds", "3", "--max-memory", "0.5"), 2,
                   "evaluating these 30 tasks needs about")


def test_bad_flags_are_one_line_with_a_pointer_to_help():
    one_line_error(cli_in_process("train.py", "--num-seeds", "0"), 2, "train.py: error: argument --num-seeds: expected a positive integer",
                   "(see train.py --help)")
    one_line_error(cli_in_process("train.py", "--no-such-flag"), 2, "train.py: error: unrecognized arguments: --no-such-flag")
