"""The comparison of approaches in an experiment directory: the paper-style figure and the tables of
the paper's results section (test solve rate at cycles 10/25/50/100, smooth reward at the last cycle), each
value a mean or IQM over seeds with its 95% bootstrap interval (utils/stats).

Everything is read back from each approach's metrics.csv, so the files can be rebuilt from a finished
(or partly finished) experiment at any time: `python -m bench.pages.report runs/<env>`.
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from jaxbridge.learn.approaches import get_approach
from jaxbridge.run.artifacts import REPORT_CYCLES, STATISTICS_NOTE, curve_statistics, report_cells
from jaxbridge.viz.figures import plot_curves
from jaxbridge.utils import stats
from jaxbridge.utils.files import write_atomic


def read_metrics(run_dir: Path, fields=("test_solve_rate", "train_success_rate")) -> dict[str, np.ndarray]:
    """{field: float[seeds, cycles]} of the `fields` a run's metrics.csv has (an older run's lacks later
    ones), and "seeds": the seeds of the rows."""
    with open(run_dir / "metrics.csv", newline="") as f:
        reader = csv.DictReader(f)
        rows, columns = list(reader), reader.fieldnames
    seeds = sorted({int(r["seed"]) for r in rows})
    cycles = max(int(r["cycle"]) for r in rows)
    fields = [k for k in fields if k in columns]
    out = {k: np.full((len(seeds), cycles), np.nan) for k in fields}
    for r in rows:
        i, c = seeds.index(int(r["seed"])), int(r["cycle"]) - 1
        for k in fields:
            out[k][i, c] = float(r[k])
    return {**out, "seeds": seeds}


def summary_rows(metrics: dict[str, tuple[str, dict[str, np.ndarray]]]) -> list[dict]:
    """One row per run ({run name: (label, read_metrics(...))}): its per-cycle statistics over seeds
    (artifacts.curve_statistics) and its seeds."""
    return [{"approach": name, "label": label, "seeds": m["seeds"], "cycles": m["test_solve_rate"].shape[1],
             "curves": curve_statistics(m["test_solve_rate"], m["train_success_rate"])}
            for name, (label, m) in metrics.items()]


CSV_STATISTICS = (*(f"{name}{end}" for name in stats.STATISTICS for end in ("", "_low", "_high")), "min", "max")


def results_csv(rows: list[dict]) -> str:
    """One row per run (approach, or approach@setting) and cycle: every statistic of every curve
    (artifacts.curve_statistics)."""
    out = io.StringIO()
    writer = csv.writer(out)
    names = list(rows[0]["curves"])
    writer.writerow(["approach", "seeds", "cycle"] + [f"{n}_{s}" for n in names for s in CSV_STATISTICS])
    for r in rows:
        for c in range(r["cycles"]):
            writer.writerow([r["approach"], len(r["seeds"]), c + 1]
                            + [f"{r['curves'][n][s][c]:.4f}" for n in names for s in CSV_STATISTICS])
    return out.getvalue()


def results_markdown(env: str, rows: list[dict]) -> str:
    last = max(r["cycles"] for r in rows)
    seeds = sorted({s for r in rows for s in r["seeds"]})
    lines = [f"# {env}: test solve rate over seeds {stats.seed_range(seeds)}", ""]
    for statistic, title in (("mean", "Mean"), ("iqm", "Interquartile mean (IQM)")):
        lines += [f"## {title} [95% bootstrap CI]", "",
                  "| approach | seeds | " + " | ".join(f"cycle {c}" for c in REPORT_CYCLES) +
                  f" | smooth reward at cycle {last} (test) | (training) | cycle {last} minus the best before |",
                  "|---|---|" + "---|" * (len(REPORT_CYCLES) + 3)]
        for r in rows:
            cells = report_cells(r["curves"], r["cycles"])
            at = [stats.cell_text(cells["test_solve_rate_at"][str(c)], statistic) if c <= r["cycles"] else ""
                  for c in REPORT_CYCLES]
            lines.append(f"| {r['label']} | {len(r['seeds'])} | " + " | ".join(at) + f" | "
                         f"{stats.cell_text(cells['smooth_reward_final'], statistic)} | "
                         f"{stats.cell_text(cells['train_smooth_reward_final'], statistic)} | "
                         f"{stats.cell_text(cells['test_drop_final'], statistic, signed=True)} |")
        lines.append("")
    lines += [f"Statistics {STATISTICS_NOTE}; every cycle's values are in results.csv. Smooth reward at cycle c: "
              "the sum of the solve rates of cycles c-25 .. c-1, divided by 25 (the paper's results section). The last column: "
              "the statistic at the last cycle minus its highest value at any cycle before (0 or above: the approach "
              "keeps what it learned; below 0: it lost that much), with the interval of that difference."]
    return "\n".join(lines) + "\n"


def write_comparison(experiment_dir: Path, env: str, runs: dict[str, str]) -> list[dict]:
    """curves.png (one line per run, mean with its 95% CI and min-max bands), results.md and results.csv;
    `runs`: {run directory name: label}, e.g. {"ours": "ours"} (experiments.run_labels)."""
    rows = summary_rows({name: (label, read_metrics(experiment_dir / name)) for name, label in runs.items()})
    seeds = sorted({s for r in rows for s in r["seeds"]})
    curves = {r["label"]: r["curves"] for r in rows}
    write_atomic(experiment_dir / "curves.png", plot_curves(curves, f"{env}, seeds {stats.seed_range(seeds)}"))
    write_atomic(experiment_dir / "results.md", results_markdown(env, rows))
    write_atomic(experiment_dir / "results.csv", results_csv(rows))
    return rows


def run_labels(names: list[str]) -> dict[str, str]:
    """{run directory name: its line's label}: the approach's label, then its setting if any."""
    labels = {}
    for name in names:
        approach, _, setting = name.partition("@")
        labels[name] = get_approach(approach).label + (f" {setting}" if setting else "")
    return labels
