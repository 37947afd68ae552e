"""Print an experiment's results as a markdown table, each approach beside the authors' logged numbers
(docs/results/authors.csv), rebuild its comparison files, and copy its figure where --figure says.

    python -m bench.report runs/light_switch_door
"""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from bench.results_blocks import authors_cell, authors_rows, authors_test_cells
from jaxbridge.run.artifacts import REPORT_CYCLES, report_cells
from jaxbridge.run.comparison import run_labels, write_comparison
from jaxbridge.run.experiments import is_experiment_dir, load_experiment, runs
from jaxbridge.utils import stats

def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experiment", type=Path, help="an experiment directory written by train.py")
    parser.add_argument("--figure", type=Path, default=None,
                        help="also copy its curves.png here")
    args = parser.parse_args()
    if not is_experiment_dir(args.experiment):
        sys.exit(f"error: {args.experiment} is not an experiment directory (no experiment.json)")
    config, approaches, grid = load_experiment(args.experiment)
    names = [n for n in runs(config, approaches, grid) if (args.experiment / n / "metrics.csv").is_file()]
    rows = write_comparison(args.experiment, config.env, run_labels(names))
    authors = authors_rows(config.env)
    seeds = stats.seed_range(sorted({s for row in rows for s in row["seeds"]}))
    print(f"Seeds {seeds}; mean [95% bootstrap CI] over seeds (the experiment's results.md adds the IQM)\n")
    print(f"| {config.env} | seeds | " + " | ".join(f"cycle {c}" for c in REPORT_CYCLES)
          + " | smooth reward at 100 (test) | smooth training reward at 100 |")
    print("|---|---|" + "---|" * (len(REPORT_CYCLES) + 2))
    for row in rows:
        cells = report_cells(row["curves"], row["cycles"])
        at = cells["test_solve_rate_at"]
        print(f"| **{row['label']}** (jaxbridge) | {stats.seed_range(row['seeds'])} | "
              + " | ".join(stats.cell_text(at[str(c)]) if str(c) in at else "-" for c in REPORT_CYCLES)
              + f" | **{stats.cell_text(cells['smooth_reward_final'])}** | {stats.cell_text(cells['train_smooth_reward_final'])} |")
        theirs = authors.get(row["approach"])
        if theirs:
            seeds = next(iter(theirs.values()))["seeds_with_logs"]
            print(f"| {row['label']} (authors, {seeds} seeds; docs/results/authors.csv) | | "
                  + " | ".join(authors_test_cells(theirs, REPORT_CYCLES))
                  + f" | {authors_cell(theirs.get(('smooth_reward', '100')))} | |")
    if args.figure is not None:
        args.figure.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(args.experiment / "curves.png", args.figure)
        print(f"\nfigure copied to {args.figure}")


if __name__ == "__main__":
    main()
