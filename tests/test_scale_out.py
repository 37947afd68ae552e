"""Past one program and one process: hyperparameter sweeps in one run (`train.py --sweep`: the grid, its
refusals, one program for the leaf hyperparameters, each setting equal to a plain run) and its exact
continuation on two processes on localhost (jax.distributed), also when one setting saved more cycles
than the others."""
import jaxbridge
import csv
import dataclasses
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from jaxbridge.core import grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.setup import make_setup
from jaxbridge.run import checkpoint
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import train
from run_helpers import cli_in_process

ROOT = Path(__file__).resolve().parents[1]
SWEEP = ["--sweep", "learning_rate=1e-3,3e-4", "--sweep", "epsilon_decay=3.8e-5,1e-3"]
SMALL = ["--env", "light_switch_door", "--approaches", "ours", "--num-seeds", "4", "--cycles", "4",
         "--updates-per-cycle", "30", "--checkpoint-every", "2", "--no-progress"]


def cli(*args):
    return subprocess.run([sys.executable, "train.py", *args], cwd=ROOT, capture_output=True, text=True, timeout=600)


def test_the_grid_is_the_cartesian_product_in_the_order_given():
    parsed = grid.parse_sweeps(["learning_rate=1e-3,3e-4", "n_sample=10,100", "hidden_sizes=64x64"])
    assert parsed == {"learning_rate": (1e-3, 3e-4), "n_sample": (10, 100), "hidden_sizes": ((64, 64),)}
    names = [grid.setting_name(s) for s in grid.settings(parsed)]
    assert names == ["learning_rate=0.001,n_sample=10,hidden_sizes=64x64",
                     "learning_rate=0.001,n_sample=100,hidden_sizes=64x64",
                     "learning_rate=0.0003,n_sample=10,hidden_sizes=64x64",
                     "learning_rate=0.0003,n_sample=100,hidden_sizes=64x64"]
    assert grid.settings({}) == [{}]


def test_settings_that_differ_in_leaves_only_share_a_program():
    base = TrainConfig()
    configs = [dataclasses.replace(base, **s) for s in grid.settings(
        grid.parse_sweeps(["gamma=0.8,0.9", "n_sample=10,100", "epsilon_end=0.05,0.1"]))]
    groups = grid.program_groups(configs)
    assert groups == [[0, 1, 4, 5], [2, 3, 6, 7]]  # by n_sample: the second key
    assert all(len({configs[i].n_sample for i in g}) == 1 for g in groups)
    # polyak_tau is not a leaf: one program per value
    assert len(grid.program_groups([dataclasses.replace(base, polyak_tau=t) for t in (0.001, 0.01)])) == 2


@pytest.mark.parametrize("text,message", [
    ("gamma=0.9,1.5", "gamma must be at least 0 and at most 1, got 1.5"),
    ("learning_rate=0", "learning_rate must be above 0"),
    ("n_sample=1.5", "n_sample: expected an integer"),
    ("learning_rate=fast", "learning_rate: expected a number"),
    ("nonsense=1", "nonsense: not a hyperparameter"),
    ("num_seeds=4,8", "num_seeds: sets the experiment"),
    ("activation=tanh", "activation must be one of leaky_relu, relu"),
    ("gamma=0.9,0.9", "a value is repeated"),
    ("gamma", "expected key=value1,value2"),
])
def test_invalid_sweep_values_are_refused(text, message):
    with pytest.raises(ValueError, match=message.replace("[", r"\[")):
        grid.parse_sweeps([text])


def test_train_refuses_a_bad_sweep_in_one_line():
    proc = cli_in_process("train.py", "--sweep", "gamma=0.5,2", "--cycles", "1")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == ["error: --sweep gamma=2.0: gamma must be at least 0 and at most 1, got 2.0"]


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    proc = cli(*SMALL, *SWEEP, "--out", str(out), "--name", "grid")
    assert proc.returncode == 0, proc.stderr
    return out / "grid"


def rows(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_two_by_two_sweep_writes_a_run_and_a_row_per_setting(swept):
    names = ["ours@learning_rate=0.001,epsilon_decay=3.8e-05", "ours@learning_rate=0.001,epsilon_decay=0.001",
             "ours@learning_rate=0.0003,epsilon_decay=3.8e-05", "ours@learning_rate=0.0003,epsilon_decay=0.001"]
    assert sorted(p.name for p in swept.iterdir() if p.is_dir()) == sorted(names)
    table = (swept / "results.md").read_text()
    assert all(f"| ours {name.partition('@')[2]} | 4 |" in table for name in names)
    assert {r["approach"] for r in rows(swept / "results.csv")} == set(names)
    # The leaves took effect: epsilon follows each setting's decay, the loss each setting's step size.
    metrics = {name: rows(swept / name / "metrics.csv") for name in names}
    last_eps = {name: float(m[-1]["epsilon"]) for name, m in metrics.items()}
    assert last_eps[names[1]] < last_eps[names[0]] and last_eps[names[3]] < last_eps[names[2]]
    assert [r["loss"] for r in metrics[names[0]]] != [r["loss"] for r in metrics[names[2]]]


def test_each_setting_equals_a_plain_run_with_it_byte_for_byte(swept, tmp_path):
    config = jaxbridge.make_config("light_switch_door", num_seeds=4, cycles=4, updates_per_cycle=30,
                                 checkpoint_every=2, learning_rate=3e-4, epsilon_decay=1e-3)
    train(make_setup(config), tmp_path, RunHooks(progress=False))
    slot = swept / "ours@learning_rate=0.0003,epsilon_decay=0.001"
    assert (tmp_path / "metrics.csv").read_text() == (slot / "metrics.csv").read_text()
    assert (tmp_path / "config.json").read_text() == (slot / "config.json").read_text()


def test_eval_picks_a_setting_of_a_sweep(swept, eval_main, capsys):
    assert eval_main([str(swept), "--approach", "ours@learning_rate=0.0003,epsilon_decay=0.001"]) == 0
    assert "ours@learning_rate=0.0003,epsilon_decay=0.001" in capsys.readouterr().out


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def two_processes(*args) -> list[subprocess.CompletedProcess]:
    """train.py as a run of 2 processes on localhost, one CPU device each."""
    flags = ["--devices", "1", "--coordinator", f"localhost:{free_port()}", "--num-processes", "2"]
    procs = [subprocess.Popen([sys.executable, "train.py", *args, *flags, "--process-id", str(i)], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(2)]
    return [subprocess.CompletedProcess(p.args, p.wait(timeout=600), *p.communicate()) for p in procs]


def test_two_processes_resume_a_one_process_sweep_to_its_numbers(swept, tmp_path):
    """Stopped after cycle 2 (one setting after cycle 4: settings save one after another), the sweep
    continues on 2 processes: every process restores, the cycles run across both, process 0 writes, and
    the files equal the uninterrupted one-process run's byte for byte."""
    copy = tmp_path / "grid"
    shutil.copytree(swept, copy)
    runs = sorted(p for p in copy.iterdir() if p.is_dir())
    for run in runs[1:]:  # checkpoints of cycles 2 and 4 (every 2): keep 2
        (run / "checkpoints" / "4.sha256.json").unlink()
        shutil.rmtree(run / "checkpoints" / "4")
        (run / "metrics.csv").unlink()
    saved = {run.name: (run / "checkpoints" / "2.sha256.json").stat().st_mtime_ns for run in runs}
    outputs = two_processes("--resume", str(copy), "--no-progress")
    assert [p.returncode for p in outputs] == [0, 0], outputs[0].stderr[-3000:] + outputs[1].stderr[-3000:]
    assert "done in" in outputs[0].stdout and "done in" not in outputs[1].stdout  # process 0 reports
    for run in runs:
        assert (run / "metrics.csv").read_text() == (swept / run.name / "metrics.csv").read_text()
    assert (copy / "results.md").read_text() == (swept / "results.md").read_text()
    # Continued, not started over: cycle 2's checkpoints are the ones from before, cycle 4's new.
    assert all((run / "checkpoints" / "2.sha256.json").stat().st_mtime_ns == saved[run.name] for run in runs)
    assert all(checkpoint.sealed_steps(run / "checkpoints") == [2, 4] for run in runs)
