"""The learned selector's runs on test seeds, as history: every bench.studies.selection record that git holds on a
test-seed set, with its smooth test reward at the last cycle, learned selection over ours (and its 95%
interval where the record kept per-seed values) -> docs/results/selection_history.csv, which
docs/results/selection.md renders. Both test sets it ran on are spent for the selector (the ledger says
why), so the table judges nothing: it shows what each run measured, in the order they landed.

    python -m bench.pages.selection_history
"""
from __future__ import annotations

import csv
import io
import json
import sys

from bench.command import CommandParser
from bench.records import ENVS, DISTRACTOR_ENVS, RECORDS, ROOT, _git
from bench.pages.results import by_approach, seed_values
from bench.study import csv_text
from jaxbridge.utils import stats
from jaxbridge.utils.files import write_atomic

HISTORY = RECORDS / "selection_history.csv"


def at(commit: str, path: str) -> str:
    return _git("show", f"{commit}:{path}")


def measured(commit: str, env: str) -> dict:
    """One record's row: the ratio of the two approaches' mean smooth test reward at the last cycle."""
    folder = f"{RECORDS.relative_to(ROOT).as_posix()}/{env}"
    record = json.loads(at(commit, f"{folder}/selection.json"))
    by_run, last = by_approach(list(csv.DictReader(io.StringIO(at(commit, f"{folder}/selection.csv")))))
    reward = {name: float(by_run[name][last]["test_smooth_reward_mean"]) for name in ("ours_learned_selection", "ours")}
    seeds_text = at(commit, f"{folder}/selection_seeds.csv")
    low = high = ""
    if seeds_text:
        seeds = list(csv.DictReader(io.StringIO(seeds_text)))
        low, high = (f"{v:.3f}" for v in stats.ratio_ci(*(seed_values(seeds, a, "test_smooth_reward") for a in
                                                           ("ours_learned_selection", "ours")))[1:])
    return {"landed": commit, "env": env, "seeds": record["seeds"], "trained_at": record["commit"],
            "ratio": f"{reward['ours_learned_selection'] / reward['ours']:.3f}", "low": low, "high": high}


def history() -> list[dict]:
    """Every landed change of a selection.csv, oldest first."""
    rows = []
    for commit in reversed(_git("log", "--format=%H", "--", "docs/results/*/selection.csv").split()):
        changed = _git("show", "--name-only", "--format=", commit, "--", "docs/results/*/selection.csv").split()
        rows += [measured(commit, env) for env in ENVS + DISTRACTOR_ENVS
                 if f"docs/results/{env}/selection.csv" in changed]
    return rows


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.parse_args(argv)
    rows = history()
    if not rows:
        print("bench.pages.selection_history: git holds no selection record here (a clone without history?)", file=sys.stderr)
        return 2
    write_atomic(HISTORY, csv_text(rows))  # written whole, once every row is read
    print(f"bench.pages.selection_history: {len(rows)} records -> {HISTORY.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())


def block() -> str:
    """docs/results/selection.md's history table, from HISTORY."""
    if not HISTORY.is_file():
        return "_Not generated yet: `python -m bench.pages.selection_history`._\n"
    with open(HISTORY, newline="") as f:
        rows = list(csv.DictReader(f))
    lines = ["| landed in | env | test seeds | trained at | smooth test reward at the last cycle, learned selection over ours |",
             "|---|---|---|---|---|"]
    for row in rows:
        ratio = float(row["ratio"])
        shown = stats.ci_text(ratio, (float(row["low"]), float(row["high"]))) if row["low"] else f"{ratio:.2f}"
        trained = row["trained_at"][:7] + (" (uncommitted changes)" if row["trained_at"].endswith("+changes") else "")
        lines.append(f"| {row['landed'][:7]} | {row['env']} | {row['seeds']} | {trained} | {shown} |")
    return "\n".join(lines) + "\n"
