"""A command's wall time and peak memory at two commits, run as A/B pairs back to back on this machine.

    python -m bench.timings.ab --base f152312 [--head HEAD] [--pairs 2] -- train.py --env doorknobs --num-seeds 8

Each commit is checked out into its own worktree (a clean tree, whatever this checkout holds); each run
is a child process in that worktree with a cold, empty compilation cache of its own. The pairs run one
after another (A then B), so a machine whose speed drifts over the day slows both sides alike; the
figure is the median over pairs of B's wall time over A's. Prints one line per run and the ratio.
`--keep DIR` keeps each run's output there (runs-A1, runs-B1, ...), e.g. to compare their results.
"""
from __future__ import annotations

import contextlib
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench.command import CommandParser
from bench.records import ROOT, cold_cache, run_child


@contextlib.contextmanager
def checked_out(commits: dict[str, str], under: Path):
    """{side: a clean worktree of its commit under `under`}, removed afterwards."""
    trees = {}
    try:
        for side, commit in commits.items():
            trees[side] = under / side
            subprocess.run(["git", "worktree", "add", "--detach", "-f", str(trees[side]), commit], cwd=ROOT, check=True,
                           capture_output=True)
        yield trees
    finally:
        for tree in trees.values():
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT, capture_output=True)


def timed(tree: Path, command: list[str], out: Path) -> dict:
    """`python COMMAND --out OUT` in `tree` with a cold compilation cache: its wall time and peak memory."""
    with cold_cache() as env:
        run = run_child(["python", *command, "--out", str(out)], cwd=tree, env=env)
    schedules = [json.loads(p.read_text()) for p in out.glob("*/schedule.json")]  # where the commit writes one
    return {**run, "busy": [f"{s / sched['wall_s']:.0%}" for sched in schedules for s in sched["busy_s"].values()]}


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--base", required=True, help="commit A (the reference)")
    parser.add_argument("--head", default="HEAD", help="commit B (default: %(default)s)")
    parser.add_argument("--pairs", type=int, default=2, help="A/B pairs, back to back (default: %(default)s)")
    parser.add_argument("--keep", type=Path, default=None, help="keep each run's output under this directory "
                        "(default: deleted with the worktrees)")
    parser.add_argument("command", nargs="+", help="the script and its flags, e.g. train.py --env doorknobs --num-seeds 8")
    args = parser.parse_args(argv)
    commits = {"A": args.base, "B": args.head}
    with tempfile.TemporaryDirectory(prefix="jaxbridge-ab-") as tmp, checked_out(commits, Path(tmp)) as trees:
        ratios = []
        for pair in range(args.pairs):
            runs = {side: timed(tree, args.command, (args.keep or Path(tmp)) / f"runs-{side}{pair + 1}")
                    for side, tree in trees.items()}
            ratios.append(runs["B"]["wall_s"] / runs["A"]["wall_s"])
            for side, run in runs.items():
                print(f"pair {pair + 1} {side} ({commits[side]}): {run['wall_s']:.0f} s, peak RSS "
                      f"{run['peak_rss_mib'] / 2**10:.2f} GiB"
                      + (f", each core busy {', '.join(run['busy'])} of the training" if run["busy"] else ""), flush=True)
        print(f"B / A wall time: median {statistics.median(ratios):.3f} over {args.pairs} pairs "
              f"({', '.join(f'{r:.3f}' for r in ratios)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
