"""Print an experiment's results as a markdown table, each approach beside the authors' logged numbers
(docs/results/authors.csv), as RESULTS.md's headlines show them; redraw its comparison files, and copy
its figure where --figure says.

    python -m bench.pages.report runs/light_switch_door
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import jaxbridge
from bench.command import CommandParser
from bench.pages.results import approach_row, authors_row, authors_rows, by_approach, read_csv, table_header


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("experiment", type=Path, help="an experiment directory written by train.py")
    parser.add_argument("--figure", type=Path, default=None, help="also copy its curves.png here")
    args = parser.parse_args(argv)
    try:
        experiment = jaxbridge.read_experiment(args.experiment)
    except jaxbridge.InputError as err:
        print(f"bench.pages.report: {err}", file=sys.stderr)
        return 2
    jaxbridge.write_comparison(args.experiment)  # results.csv as this checkout computes it
    by_run, last = by_approach(read_csv(args.experiment / "results.csv"))
    authors = authors_rows(experiment.config.env)
    print(f"{experiment.config.env}, seeds {min(experiment.seeds)}-{max(experiment.seeds)}; each cell: mean [95% CI] "
          "over seeds, IQM [95% CI] beside it; the authors' rows: their mean [lowest, highest seed]\n")
    print("\n".join(table_header(last)))
    for name, cycles in by_run.items():
        print(approach_row(name, cycles, last))
        if name in authors:
            print(authors_row(name, authors[name]))
    if args.figure is not None:
        args.figure.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(args.experiment / "curves.png", args.figure)
        print(f"\nfigure copied to {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
