"""Print an experiment's results as the markdown table of docs/RESULTS.md, each approach beside the
authors' numbers, rebuild its comparison files, and copy its figure into docs/figures/.

    python -m bench.report runs/light_switch_door
"""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from jaxbridge.run.artifacts import REPORT_CYCLES, report_cells
from jaxbridge.run.comparison import run_labels, write_comparison
from jaxbridge.run.experiments import is_experiment_dir, load_experiment, runs
from jaxbridge.utils import stats

# reference/results.md: test solve rate, mean [min, max] over the seeds with logs; smooth reward at 100.
AUTHORS = {
    "light_switch_door": {
        "ours": ("0.33 [0, 1]", "0.72 [0, 1]", "0.57 [0, 1]", "0.64 [0, 1]", "0.74", "8 seeds"),
        "no_feature_selection": ("-", "-", "-", "-", "-", "log not public"),
        "no_callplanner": ("0", "0", "0", "0", "0", "7 seeds"),
        "random": ("0", "0", "0", "0", "0", "6 seeds"),
        "pure_planning": ("0 (single evaluation)", "", "", "", "", "4 seeds"),
        "maple_q": ("0", "0", "0", "0", "0", "6 seeds; grounded on the training task only"),
    },
    "doorknobs": {
        "ours": ("0.30", "0.70", "1.00", "1.00", "0.996", "1 seed"),
        "pure_planning": ("0 (single evaluation)", "", "", "", "", "6 seeds"),
    },
    "coffee": {
        "ours": ("0.14 [0, 1]", "0.00", "0.14 [0, 1]", "0.06 [0, 0.2]", "~0.04", "7 seeds"),
        "pure_planning": ("0 (single evaluation)", "", "", "", "", "4 seeds"),
    },
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experiment", type=Path, help="an experiment directory written by train.py")
    parser.add_argument("--figure", type=Path, default=None,
                        help="where to copy its curves.png (default: docs/figures/<env>_approaches.png)")
    args = parser.parse_args()
    if not is_experiment_dir(args.experiment):
        sys.exit(f"error: {args.experiment} is not an experiment directory (no experiment.json)")
    config, approaches, grid = load_experiment(args.experiment)
    names = [n for n in runs(config, approaches, grid) if (args.experiment / n / "metrics.csv").is_file()]
    rows = write_comparison(args.experiment, config.env, run_labels(names))
    authors = AUTHORS.get(config.env, {})
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
        if row["approach"] in authors:
            *values, smooth, note = authors[row["approach"]]
            print(f"| {row['label']} (authors, {note}) | | " + " | ".join(values) + f" | {smooth} | |")
    target = args.figure or Path("docs/figures") / f"{config.env}_approaches.png"
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy(args.experiment / "curves.png", target)
    print(f"\nfigure copied to {target}")


if __name__ == "__main__":
    main()
