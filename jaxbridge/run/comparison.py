"""The comparison of approaches in an experiment directory: the paper-style figure and the tables of
reference/results.md (test solve rate at cycles 10/25/50/100, smooth reward at the last cycle).

Everything is read back from each approach's metrics.csv, so the files can be rebuilt from a finished
(or partly finished) experiment at any time: `python -m bench.report runs/<env>`.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from jaxbridge.learn.approaches import Approach
from jaxbridge.run.artifacts import REPORT_CYCLES, plot_curves
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.smoothing import smooth


def read_metrics(run_dir: Path, fields=("test_solve_rate", "train_success_rate")) -> dict[str, np.ndarray]:
    """{field: float[seeds, cycles]} from a run's metrics.csv."""
    with open(run_dir / "metrics.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    seeds = sorted({int(r["seed"]) for r in rows})
    cycles = max(int(r["cycle"]) for r in rows)
    out = {k: np.full((len(seeds), cycles), np.nan) for k in fields}
    for r in rows:
        i, c = seeds.index(int(r["seed"])), int(r["cycle"]) - 1
        for k in fields:
            out[k][i, c] = float(r[k])
    return out


def summary_rows(metrics: dict[Approach, dict[str, np.ndarray]]) -> list[dict]:
    """One row per approach ({approach: read_metrics(...)}): mean/min/max test solve rate at the report
    cycles, smooth rewards."""
    rows = []
    for approach, m in metrics.items():
        test, train = m["test_solve_rate"], m["train_success_rate"]
        cycles = test.shape[1]
        row = {"approach": approach.name, "label": approach.label, "seeds": test.shape[0], "cycles": cycles}
        for c in REPORT_CYCLES:
            if c <= cycles:
                col = test[:, c - 1]
                row[f"cycle_{c}"] = (col.mean(), col.min(), col.max())
        row["smooth_test"] = float(smooth(test)[:, -1].mean())
        row["smooth_train"] = float(smooth(train)[:, -1].mean())
        rows.append(row)
    return rows


def results_csv(rows: list[dict]) -> str:
    out = io.StringIO()
    writer = csv.writer(out)
    header = ["approach", "seeds", "cycles"]
    for c in REPORT_CYCLES:
        header += [f"test_cycle_{c}_mean", f"test_cycle_{c}_min", f"test_cycle_{c}_max"]
    writer.writerow(header + ["test_smooth_reward_final", "train_smooth_reward_final"])
    for r in rows:
        values = [r["approach"], r["seeds"], r["cycles"]]
        for c in REPORT_CYCLES:
            values += [f"{v:.4f}" for v in r[f"cycle_{c}"]] if f"cycle_{c}" in r else ["", "", ""]
        writer.writerow(values + [f"{r['smooth_test']:.4f}", f"{r['smooth_train']:.4f}"])
    return out.getvalue()


def results_markdown(env: str, rows: list[dict]) -> str:
    def cell(value):
        mean, low, high = value
        return f"{mean:.2f}" if low == high else f"{mean:.2f} [{low:.2f}, {high:.2f}]"

    last = max(r["cycles"] for r in rows)
    lines = [f"# {env}: test solve rate, mean [min, max] over seeds", "",
             "| approach | seeds | " + " | ".join(f"cycle {c}" for c in REPORT_CYCLES) +
             f" | smooth reward at cycle {last} (test) | (training) |",
             "|---|---|" + "---|" * (len(REPORT_CYCLES) + 2)]
    for r in rows:
        cells = [cell(r[f"cycle_{c}"]) if f"cycle_{c}" in r else "" for c in REPORT_CYCLES]
        lines.append(f"| {r['label']} | {r['seeds']} | " + " | ".join(cells) +
                     f" | {r['smooth_test']:.3f} | {r['smooth_train']:.3f} |")
    lines += ["", "Smooth reward at cycle c: the sum of the solve rates of cycles c-25 .. c-1, divided by 25 "
              "(reference/results.md)."]
    return "\n".join(lines) + "\n"


def write_comparison(experiment_dir: Path, env: str, approaches: list[Approach]) -> list[dict]:
    """curves.png (one line per approach, band over seeds), results.md and results.csv."""
    metrics = {a: read_metrics(experiment_dir / a.name) for a in approaches}
    rows = summary_rows(metrics)
    curves = {a.label: {"test": m["test_solve_rate"], "train": m["train_success_rate"]} for a, m in metrics.items()}
    seeds = rows[0]["seeds"]
    write_atomic(experiment_dir / "curves.png", plot_curves(curves, f"{env}, {seeds} seeds per approach"))
    write_atomic(experiment_dir / "results.md", results_markdown(env, rows))
    write_atomic(experiment_dir / "results.csv", results_csv(rows))
    return rows
