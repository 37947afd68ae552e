"""Whether a change kept every number: each approach's metrics.csv at two commits, compared byte for byte.

    python -m bench.timings.identical --base f152312 --env doorknobs [--seeds 0-1] [--cycles 5]
                              [--approaches all,plan_progress,...] [--preset pqn]

Each commit is checked out into its own worktree and trains the same short experiment there
(`train.py --env E --approaches ... --first-seed F --num-seeds N --cycles C`); prints, per approach, "identical" or
"differs" (with the first differing line), and exits 1 if any differs. A column only one commit writes (a metric
added since) is left out of the comparison, and the line says so.
"""
from __future__ import annotations

import csv
import io
import sys
import tempfile
from pathlib import Path

from bench.command import CommandParser
from bench.timings.ab import checked_out
from bench.records import run_child

# Every approach kind: the paper's six, plan repair, selection, signatures, and the low-level baselines' plain pair.
EVERY = ("ours,no_feature_selection,no_callplanner,random,pure_planning,maple_q,plan_progress,plan_progress_replan,"
         "ours_closest_object,ours_learned_selection,ours_per_signature,ours_signature_conditioned,low_level_ppo,low_level_sac")


def first_difference(a: str, b: str) -> str:
    for i, (x, y) in enumerate(zip(a.splitlines(), b.splitlines()), 1):
        if x != y:
            return f"line {i}: {x!r} vs {y!r}"
    return f"lengths {len(a.splitlines())} vs {len(b.splitlines())} lines"


def shared_columns(a: str, b: str) -> tuple[str, str, list[str]]:
    """Two metrics.csv texts cut to the columns both have, in A's order, and the columns left out."""
    (rows_a, head_a), (rows_b, head_b) = ((list(r), r.fieldnames or []) for r in (csv.DictReader(io.StringIO(t)) for t in (a, b)))
    shared = [c for c in head_a if c in head_b]
    cut = lambda rows: "\n".join([",".join(shared), *(",".join(row[c] for c in shared) for row in rows)])
    return cut(rows_a), cut(rows_b), [c for c in head_a + head_b if c not in shared]


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__, seeds="0-1")
    parser.add_argument("--base", required=True, help="commit A (the reference)")
    parser.add_argument("--head", default="HEAD", help="commit B (default: %(default)s)")
    parser.add_argument("--env", required=True, help="the env to train on")
    parser.add_argument("--approaches", default=EVERY, help="train.py's --approaches (default: every kind)")
    parser.add_argument("--preset", default=None, help="train.py's --preset (e.g. pqn for PQN's run)")
    parser.add_argument("--cycles", type=int, default=5, help="cycles (default: %(default)s)")
    args = parser.parse_args(argv)
    flags = ["--env", args.env, "--approaches", args.approaches, "--first-seed", str(args.seed_list[0]),
             "--num-seeds", str(len(args.seed_list)), "--cycles", str(args.cycles), "--no-progress",
             *(["--preset", args.preset] if args.preset else [])]
    commits = {"A": args.base, "B": args.head}
    with tempfile.TemporaryDirectory(prefix="jaxbridge-identical-") as tmp, checked_out(commits, Path(tmp)) as trees:
        runs = {}
        for side, tree in trees.items():
            out = Path(tmp) / f"out-{side}"
            run_child(["python", "train.py", *flags, "--out", str(out), "--name", "x"], cwd=tree)
            runs[side] = {p.parent.name: p.read_text() for p in (out / "x").glob("*/metrics.csv")}
        differ = 0
        for name in sorted(runs["A"]):
            a, b, left_out = shared_columns(runs["A"][name], runs["B"].get(name, ""))
            same = a == b
            differ += not same
            print(f"{args.env} {name}: " + ("identical" if same else f"differs ({first_difference(a, b)})")
                  + (f" (not compared: {', '.join(left_out)}, written by one commit only)" if left_out else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
