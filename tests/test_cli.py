"""The command lines: a short real training run, evaluating its checkpoint, and clean errors."""
import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd=ROOT):
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    proc = run("train.py", "--num-seeds", "2", "--cycles", "3", "--updates-per-cycle", "10",
               "--checkpoint-every", "2", "--out", str(out), "--name", "tiny", "--no-progress",
               "--approaches", "ours,pure_planning")
    assert proc.returncode == 0, proc.stderr
    return out / "tiny", proc


def test_train_writes_the_experiment_directory(short_run):
    experiment_dir, proc = short_run
    assert json.loads((experiment_dir / "experiment.json").read_text())["approaches"] == ["ours", "pure_planning"]
    results = list(csv.DictReader((experiment_dir / "results.csv").open()))
    assert [r["approach"] for r in results] == ["ours", "pure_planning"]
    assert all(r["seeds"] == "2" and r["cycles"] == "3" for r in results)
    assert float(results[1]["test_smooth_reward_final"]) == 0.0  # pure planning never passes a door
    table = (experiment_dir / "results.md").read_text()
    assert "| ours | 2 |" in table and "| pure planning | 2 |" in table
    assert (experiment_dir / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "pure_planning" in proc.stdout and "ours" in proc.stdout


def test_train_writes_the_run_directory(short_run):
    run_dir, proc = short_run[0] / "ours", short_run[1]
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    assert len(rows) == 2 * 3 and {r["seed"] for r in rows} == {"0", "1"}
    assert {r["cycle"] for r in rows} == {"1", "2", "3"}
    assert all(0.0 <= float(r["test_solve_rate"]) <= 1.0 for r in rows)
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["cycles"] == 3 and summary["seeds"] == [0, 1]
    config = json.loads((run_dir / "config.json").read_text())
    assert config["config_version"] == 2 and config["num_seeds"] == 2 and config["approach"] == "ours"
    assert (run_dir / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in (run_dir / "checkpoints").iterdir() if p.name.isdigit()) == ["2", "3"]
    assert "done in" in proc.stdout


def test_eval_loads_the_checkpoint(short_run):
    run_dir = short_run[0]  # the experiment directory: eval.py picks its "ours" run
    proc = run("eval.py", str(run_dir), "--num-tasks", "3")
    assert proc.returncode == 0, proc.stderr
    assert "checkpoint of cycle 3" in proc.stdout and "20 cells, 3 doors" not in proc.stdout
    lines = [line for line in proc.stdout.splitlines() if line.strip().startswith(("0 ", "1 "))]
    assert len(lines) == 2
    bigger = run("eval.py", str(run_dir), "--cells", "25", "--doors", "5", "--num-tasks", "2")
    assert bigger.returncode == 0, bigger.stderr
    assert "25 cells, 5 doors" in bigger.stdout


def test_an_existing_run_is_not_overwritten(short_run):
    run_dir = short_run[0]
    proc = run("train.py", "--cycles", "1", "--out", str(run_dir.parent), "--name", "tiny", "--no-progress")
    assert proc.returncode == 2 and "already exists" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("args,message", [
    (["train.py", "--env", "nowhere"], "invalid choice"),
    (["train.py", "--num-seeds", "0"], "positive integer"),
    (["train.py", "--cycles", "-3"], "positive integer"),
    (["train.py", "--approaches", "ours,clever"], "unknown approach clever"),
    (["train.py", "--approaches", "ours,ours"], "listed twice"),
    (["train.py", "--train-steps", "5"], "--train-steps 5 is too small to ever reach the goal: seed 0's"),
    (["train.py", "--env", "doorknobs", "--first-seed", "1", "--num-seeds", "3", "--train-steps", "11"],
     "seed 2's training task needs at least 12 steps"),
    (["eval.py", "--bridge", "clever"], "invalid choice"),
    (["eval.py", "/nonexistent/run"], "not a run directory"),
    (["eval.py", "--num-seeds", "x"], "positive integer"),
])
def test_bad_input_is_one_clear_line_and_exit_code_2(args, message):
    proc = run(*args)
    assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr


def test_eval_hand_made_bridges():
    proc = run("eval.py", "--bridge", "oracle", "--num-seeds", "2")
    assert proc.returncode == 0, proc.stderr
    last = proc.stdout.strip().splitlines()[-1].split()
    assert last[0] == "all" and float(last[2]) == 1.0  # every task solved
