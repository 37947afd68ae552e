"""The Python API from a script: examples/quickstart.py trains, plots, loads and evaluates; a loaded run
evaluates on its test tasks, on tasks of a size and on given tasks, and draws an episode."""
import contextlib
import csv
import io
import runpy
import tempfile
import sys
from pathlib import Path

import numpy as np
import pytest

import jaxbridge

ROOT = Path(__file__).resolve().parents[1]


def rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


@pytest.fixture(scope="module")
def quickstart(tmp_path_factory):
    """examples/quickstart.py run as a script, in this process (the programs it compiles serve the tests
    below), with 2 seeds x 2 cycles (its default 20 cycles, for the suite's time: the same calls)."""
    out = tmp_path_factory.mktemp("quick")
    printed = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(printed):
        patch.setattr(sys, "argv", ["quickstart.py", "--seeds", "2", "--cycles", "2", "--out", str(out)])
        runpy.run_path(str(ROOT / "examples" / "quickstart.py"), run_name="__main__")
    return out, printed.getvalue()


def test_the_quickstart_example_trains_plots_loads_and_evaluates(quickstart):
    out, printed = quickstart
    assert (out / "quickstart.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    last = [float(r["test_solve_rate"]) for r in rows((out / "quickstart" / "ours" / "metrics.csv").read_text())
            if r["cycle"] == "2"]
    # train's arrays are the run's metrics.csv; evaluate ran 10 sized tasks per seed
    assert f"test solve rate at cycle 2: {np.mean(last):.2f} (seeds: {[round(x, 2) for x in last]})" in printed
    assert "40-cell tasks, 3 doors" in printed and "over 20 episodes" in printed


def test_load_evaluates_and_renders_a_trained_run_from_python(quickstart, tmp_path):
    out, _ = quickstart
    policy = jaxbridge.load(out / "quickstart")  # the experiment's "ours" run
    assert policy.cycle == 2 and policy.config.seeds == [0, 1]
    last = {int(r["seed"]): float(r["test_solve_rate"]) for r in rows((out / "quickstart" / "ours" / "metrics.csv").read_text())
            if r["cycle"] == "2"}
    assert policy.evaluate().per_seed() == last  # each seed's test tasks, as the last cycle's test
    spec = jaxbridge.tasks("light_switch_door", [7], num_tasks=1, size={"cells": 12, "doors": 2})[7][0]
    mine = policy.evaluate(tasks=[spec], seeds=[1])
    assert mine.specs == [spec] and mine.seeds.tolist() == [1] and mine.steps.shape == (1,)
    png = policy.render(tmp_path / "episode.png", tasks=[spec], seeds=[1])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="unknown approach"):
        jaxbridge.train("light_switch_door", approaches="ourz", seeds=1, cycles=1)
    listed = jaxbridge.prepare("light_switch_door", approaches="ours, random", seeds=1, cycles=1, out=tmp_path / "listed")
    assert "training ours, random bridge x 1 seeds" in listed.describe()
    listed.release()


def test_train_without_out_returns_the_same_numbers_and_leaves_no_files(quickstart, tmp_path, monkeypatch):
    out, _ = quickstart
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # where the run's temporary directory goes
    experiment = jaxbridge.train("light_switch_door", seeds=2, cycles=1)  # the example's config, one cycle
    assert experiment.run_dir is None and list(tmp_path.iterdir()) == []
    example = rows((out / "quickstart" / "ours" / "metrics.csv").read_text())
    for column, values in experiment.metrics["ours"].items():
        assert values.shape == (2, 1)
        if "smooth" not in column:  # the smooth reward's window reaches past cycle 1 in the example
            assert values[:, 0].tolist() == [float(r[column]) for r in example if r["cycle"] == "1"], column
