"""A training's files read back through the public API: read_experiment, Experiment.cells, write_comparison,
run_labels and preset_values, against the internals train.py writes with (no training: the committed run)."""
import csv
import shutil
from pathlib import Path

import numpy as np
import pytest

import jaxbridge

RUN = Path(__file__).parent / "data" / "v11_run"  # ours, light_switch_door: one seed, one cycle


@pytest.fixture
def experiment_dir(tmp_path):
    """An experiment directory of two runs made of the committed run's files (the second's rates changed)."""
    from jaxbridge.run.experiments import write_experiment_file

    config = jaxbridge.read_experiment(RUN).config
    out = tmp_path / "light_switch_door"
    for name in ("ours", "random"):
        shutil.copytree(RUN, out / name, ignore=shutil.ignore_patterns("checkpoints"))
    rows = list(csv.DictReader((out / "random" / "metrics.csv").open()))
    for row in rows:
        row["test_solve_rate"] = "0.25"
    with open(out / "random" / "metrics.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    write_experiment_file(out, config, ["ours", "random"], None)
    return out


def test_read_experiment_gives_train_s_experiment_of_a_run_and_of_an_experiment_directory(experiment_dir):
    lone = jaxbridge.read_experiment(RUN)
    assert lone.approaches == ("ours",) and lone.run_dir == RUN and "per_cycle" in lone.summaries["ours"]
    rates = lone.metrics["ours"]["test_solve_rate"]
    assert rates.shape == (1, 1) and list(lone.metrics["ours"]) == list(csv.DictReader(RUN.joinpath("metrics.csv").open()).fieldnames[2:])
    both = jaxbridge.read_experiment(experiment_dir)
    assert both.approaches == ("ours", "random") and both.seeds == lone.seeds
    np.testing.assert_array_equal(both.metrics["ours"]["test_solve_rate"], rates)
    assert (both.metrics["random"]["test_solve_rate"] == 0.25).all() and both.curve("random").shape == (1,)
    cells = both.cells("random", [1])
    assert cells[1]["mean"] == 0.25 and cells[1]["mean_ci"] == [0.25, 0.25] and both.cells("random") == cells
    with pytest.raises(jaxbridge.InputError):
        jaxbridge.read_experiment(experiment_dir.parent)


def test_write_comparison_draws_what_training_draws(experiment_dir, tmp_path):
    from jaxbridge.run import comparison

    reference = tmp_path / "reference"
    shutil.copytree(experiment_dir, reference)
    comparison.write_comparison(reference, "light_switch_door", comparison.run_labels(["ours", "random"]))
    files = jaxbridge.write_comparison(experiment_dir)
    assert [f.name for f in files] == ["curves.png", "results.md", "results.csv"]
    for f in files:
        assert f.read_bytes() == (reference / f.name).read_bytes(), f.name
    # any folder of runs, given labels and a title
    jaxbridge.write_comparison(experiment_dir, {"random": "a", "ours": "b"}, "my title")
    text = (experiment_dir / "results.md").read_text()
    assert text.startswith("# my title") and text.index("| a |") < text.index("| b |")


def test_run_labels_and_preset_values():
    assert jaxbridge.run_labels(["ours", "maple_q@gamma=0.9"]) == {"ours": "ours", "maple_q@gamma=0.9": "Maple Q (pure RL) gamma=0.9"}
    authors = jaxbridge.preset_values("authors", "light_switch_door")
    assert authors["preset"] == "authors" and authors["batch_size"] == 64
    assert jaxbridge.make_config("light_switch_door", preset="authors").learner.batch_size == authors["batch_size"]
    for bad in (lambda: jaxbridge.run_labels(["nope"]), lambda: jaxbridge.preset_values("nope", "coffee")):
        with pytest.raises(jaxbridge.InputError):
            bad()
