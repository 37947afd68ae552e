"""The run directory: metrics CSV, summary JSON, config JSON and the learning-curve figure (drawn by
viz/figures.py).

Every file is written atomically (jaxbridge/utils/files.py).
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from jaxbridge.utils import stats
from jaxbridge.utils.files import write_atomic
from jaxbridge.viz.figures import plot_curves
from jaxbridge.utils.smoothing import smooth

METRIC_FIELDS = ("test_solve_rate", "train_success_rate", "train_env_steps", "train_decisions", "test_env_steps",
                 "test_decisions", "epsilon", "loss", "q_abs_max", "buffer_size", "table_misses")
METRICS_CSV_FIELDS = (*METRIC_FIELDS, "test_smooth_reward", "train_smooth_reward")  # metrics.csv's columns after seed, cycle
REPORT_CYCLES = (10, 25, 50, 100)
STATISTICS_NOTE = (f"over seeds: mean and interquartile mean (IQM), each with its 95% percentile-bootstrap interval "
                   f"({stats.REPS} replicates, fixed generator), min and max")


def history_arrays(history: list) -> dict[str, np.ndarray]:
    """Per-cycle CycleMetrics (numpy) -> {field: float[seeds, cycles]}."""
    return {f: np.stack([np.asarray(getattr(m, f), np.float64) for m in history], axis=-1) for f in METRIC_FIELDS}


def metrics_csv(history: list, seeds: list[int]) -> str:
    arrays = history_arrays(history)
    test_smooth, train_smooth = smooth(arrays["test_solve_rate"]), smooth(arrays["train_success_rate"])
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(["seed", "cycle", *METRICS_CSV_FIELDS])
    for i, seed in enumerate(seeds):
        for c in range(len(history)):
            writer.writerow([seed, c + 1, *(f"{arrays[f][i, c]:.6g}" for f in METRIC_FIELDS),
                             f"{test_smooth[i, c]:.6g}", f"{train_smooth[i, c]:.6g}"])
    return out.getvalue()


def curve_statistics(test_rates: np.ndarray, train_rates: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """Per cycle, over seeds ([seeds, cycles] in): mean and IQM with 95% bootstrap intervals, min and max
    (utils/stats.describe) of the test solve rate and of the test and training smooth rewards, and the
    test solve rate's fall below its best before (utils/stats.describe_drop: does it keep what it
    learned?)."""
    series = {"test_solve_rate": test_rates, "test_smooth_reward": smooth(test_rates),
              "train_smooth_reward": smooth(train_rates)}
    return {**{name: stats.describe(values) for name, values in series.items()},
            "test_drop": stats.describe_drop(test_rates)}


def at_cycle(described: dict[str, np.ndarray], cycle: int) -> dict:
    """One table cell of a described curve: {mean, mean_ci, iqm, iqm_ci, min, max} at `cycle` (1-based)."""
    value = {key: float(v[cycle - 1]) for key, v in described.items()}
    cell = {}
    for name in stats.STATISTICS:
        cell[name] = value[name]
        cell[f"{name}_ci"] = [value[f"{name}_low"], value[f"{name}_high"]]
    return {**cell, "min": value["min"], "max": value["max"]}


def report_cells(curves: dict[str, dict[str, np.ndarray]], cycles: int) -> dict:
    """The cells of the results tables (at_cycle) from curve_statistics over `cycles` cycles: the test solve
    rate at the report cycles reached, the test and training smooth rewards at the last cycle."""
    return {"test_solve_rate_at": {str(c): at_cycle(curves["test_solve_rate"], c) for c in REPORT_CYCLES if c <= cycles},
            "smooth_reward_final": at_cycle(curves["test_smooth_reward"], cycles),
            "train_smooth_reward_final": at_cycle(curves["train_smooth_reward"], cycles),
            "test_drop_final": at_cycle(curves["test_drop"], cycles)}


def summary(history: list, seeds: list[int], elapsed_s: float, devices: str | None = None) -> dict:
    """Headline numbers: the paper's tables for this run, as statistics over its seeds
    (`devices`: what ran it, e.g. "2 cpu"; informational, the numbers do not depend on it)."""
    arrays = history_arrays(history)
    curves = curve_statistics(arrays["test_solve_rate"], arrays["train_success_rate"])
    cycles = len(history)
    cells = report_cells(curves, cycles)
    return {
        "seeds": seeds, "seed_range": stats.seed_range(seeds), "cycles": cycles, "elapsed_s": round(elapsed_s, 2),
        **({"devices": devices} if devices else {}),
        "statistics": STATISTICS_NOTE,
        **cells,
        "smooth_reward_final": {**cells["smooth_reward_final"],
                                "per_seed": [round(float(x), 4) for x in smooth(arrays["test_solve_rate"])[:, -1]]},
        "per_cycle": {name: {key: [round(float(x), 4) for x in v] for key, v in described.items()}
                      for name, described in curves.items()},
        "train_success_rate_final": float(arrays["train_success_rate"][:, -1].mean()),
        "train_env_steps_total": int(arrays["train_env_steps"].sum()),
        "bridge_decisions_total": int(arrays["train_decisions"].sum()),
        "table_misses_total": int(arrays["table_misses"].sum()),
    }


def write_run_files(run_dir: Path, config_dict: dict, history: list, info: dict, label: str = "ours") -> None:
    """metrics.csv, summary.json (`info`, this run's summary) and curves.png of a run."""
    write_atomic(run_dir / "metrics.csv", metrics_csv(history, info["seeds"]))
    write_atomic(run_dir / "summary.json", json.dumps(info, indent=2) + "\n")
    curves = {label: {name: {k: np.asarray(v) for k, v in described.items()}
                      for name, described in info["per_cycle"].items()}}
    write_atomic(run_dir / "curves.png", plot_curves(curves, f"{config_dict['env']}, seeds {info['seed_range']}"))
