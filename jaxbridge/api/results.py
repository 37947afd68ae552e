"""A training's files read back: the Experiment of a finished (or partly finished) experiment directory,
the comparison of its runs (curves.png, results.md, results.csv) drawn again, and the runs' labels."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Mapping, Sequence

from jaxbridge.api.training import Experiment, _read_metrics
from jaxbridge.utils.errors import InputError, refusing


def read_experiment(run_dir: str | Path) -> Experiment:
    """The Experiment that training into `run_dir` returns, read back from its files: an experiment
    directory (experiment.json; its runs that have a metrics.csv, in train.py's order) or one approach's
    run directory (config.json). `metrics` as `train` gives them ([seeds, cycles] per metrics.csv column),
    `summaries` each run's summary.json (absent for a run still training). InputError for anything else."""
    from jaxbridge.run.experiments import is_experiment_dir, load_experiment, runs
    from jaxbridge.run.run_state import load_config

    run_dir = Path(run_dir)
    with refusing("run_dir"):
        if is_experiment_dir(run_dir):
            config, approaches, grid = load_experiment(run_dir)
            names = [name for name in runs(config, approaches, grid) if (run_dir / name / "metrics.csv").is_file()]
            folders = {name: run_dir / name for name in names}
        elif (run_dir / "config.json").is_file():
            config = load_config(run_dir)
            names, folders = [config.approach], {config.approach: run_dir}
        else:
            raise InputError(f"{run_dir} is neither an experiment directory (experiment.json) nor a run's (config.json)")
    summaries = {name: json.loads((folder / "summary.json").read_text())
                 for name, folder in folders.items() if (folder / "summary.json").is_file()}
    return Experiment(config, tuple(names), _read_metrics(run_dir, names), summaries, run_dir)


def run_labels(runs: Sequence[str]) -> dict[str, str]:
    """{run: the label train.py's figure and tables give it}: the approach's label, then its setting if any
    (`ours@learning_rate=0.001` -> "ours learning_rate=0.001"). InputError for an unknown approach."""
    from jaxbridge.run import comparison

    with refusing("runs"):
        return comparison.run_labels(list(runs))


def write_comparison(run_dir: str | Path, labels: Mapping[str, str] | None = None, title: str | None = None) -> list[Path]:
    """Draw the comparison of the runs under `run_dir` again, as training draws it: curves.png (a line per
    run: mean with its 95% interval and min-max bands), results.md and results.csv, from each run's
    metrics.csv. `labels`: {run folder: its label} in the tables' order (default: every run of the
    experiment directory, labelled by `run_labels`); `title`: the figure's and table's env (default: the
    experiment's). Any folder of runs with a metrics.csv each can be compared, given both. Returns the files."""
    from jaxbridge.run.comparison import write_comparison as write

    run_dir = Path(run_dir)
    if labels is None or title is None:
        experiment = read_experiment(run_dir)
        labels = run_labels(experiment.approaches) if labels is None else labels
        title = experiment.config.env if title is None else title
    write(run_dir, title, dict(labels))
    return [run_dir / name for name in ("curves.png", "results.md", "results.csv")]
