"""The test-seed ledger, docs/results/ledger.csv: one row for every run on a test-seed set, appended when
the run starts (dirty tree or not), so that a reader can see every time a set was used and why.

    python -m bench.ledger --env coffee --seeds 200-231 --ran "train.py --env coffee --first-seed 200 ..." \\
        --change "the step discount (step_gamma 0.99)" --chosen-on "development seeds 0-31"

The studies (bench/study.py) append their row themselves when they start on test seeds; this command is
for a test-seed run made any other way.
A row: the date, the seed set, the env, what ran, the code's commit (with "+changes" when the tree was
dirty), what changed since that set's previous run of the same study and on which seeds the change was
chosen. `python -m bench.pages.render` shows the ledger in docs/results/ledger.md.

    python -m bench.ledger --spent "the learned selector" --seeds 300-331 --change "its Coffee result ..."

writes a row that records no run: the set is spent for that subject (a result seen there motivated a
change to it), its fields say so.
"""
from __future__ import annotations

import csv
import datetime
import sys

from bench.command import CommandParser
from bench.records import RECORDS, TEST_SETS, git_commit

LEDGER = RECORDS / "ledger.csv"
FIELDS = ("date", "seeds", "env", "ran", "commit", "change", "chosen_on")
# The first rows were not written when their runs started: 8e898ed, which began the ledger, reconstructed them
# from the committed records' history (each record's commit, steps and commands).
RECONSTRUCTED = {"rows": 62, "at": "8e898ed"}
SPENT = "no run: the set is spent for {subject}"  # a spent row's `ran`; its env, change and chosen_on say why


def is_spent(row: dict) -> bool:
    return row["ran"].startswith(SPENT.partition("{")[0])


def spent_row(seeds: str, subject: str, why: str, commit: str | None = None) -> dict:
    """Append a row that records no run: `seeds` are spent for `subject` because of `why`."""
    return append(seeds, "all", SPENT.format(subject=subject), f"spent: {why}", "no run: nothing was chosen", commit)


def rows() -> list[dict]:
    """The ledger's rows, oldest first ([] before the first run)."""
    if not LEDGER.is_file():
        return []
    with open(LEDGER, newline="") as f:
        return list(csv.DictReader(f))


def append(seeds: str, env: str, ran: str, change: str, chosen_on: str, commit: str | None = None) -> dict:
    """Append one row (today's date, this checkout's commit unless given) and return it."""
    row = {"date": datetime.date.today().isoformat(), "seeds": seeds, "env": env, "ran": ran,
           "commit": commit or git_commit(), "change": change, "chosen_on": chosen_on}
    new = not LEDGER.is_file()
    with open(LEDGER, "a", newline="") as f:  # one short append: a row is never half in the file
        writer = csv.DictWriter(f, fieldnames=FIELDS, lineterminator="\n")
        if new:
            writer.writeheader()
        writer.writerow(row)
    return row


def seed_set(first: int, count: int) -> str:
    """A test-seed set's name in the ledger, e.g. "200-231"; ValueError outside the test sets."""
    size = TEST_SETS.get(first)
    if size is None or not 1 <= count <= size:
        known = ", ".join(f"{f}-{f + n - 1}" for f, n in TEST_SETS.items())
        raise ValueError(f"seeds {first}-{first + count - 1} are not within a test-seed set ({known})")
    return f"{first}-{first + count - 1}"


def main(argv=None) -> int:
    first = min(TEST_SETS)
    parser = CommandParser(__spec__.name, __doc__, seeds=f"{first}-{first + TEST_SETS[first] - 1}", test_seeds=True)
    parser.add_argument("--env", help="the env the run trained or evaluated on (required unless --spent)")
    parser.add_argument("--ran", help="the command that ran, as typed (required unless --spent)")
    parser.add_argument("--spent", metavar="SUBJECT",
                        help="record no run: the seed set is spent for SUBJECT (e.g. \"the learned selector\"); "
                             "--change says which result motivated which change")
    parser.add_argument("--commit", help="the code's commit it ran at (default: this checkout's, +changes if dirty)")
    parser.add_argument("--change", help="what changed since this seed set's previous run of the same study and why, in a "
                                         "line (\"first run\" for the first); with --spent: which result spent the set")
    parser.add_argument("--chosen-on", help="the seeds the change was chosen on, e.g. \"development seeds 0-31\" (\"-\" for "
                                            "a first run)")
    args = parser.parse_args(argv)
    try:
        seeds = seed_set(args.seed_list[0], len(args.seed_list))
    except ValueError as err:
        print(f"bench.ledger: {err}", file=sys.stderr)
        return 2
    needed = ("change",) if args.spent else ("env", "ran", "change", "chosen_on")
    if missing := [f"--{name.replace('_', '-')}" for name in needed if not getattr(args, name)]:
        print(f"bench.ledger: {' and '.join(missing)} needed {'with --spent' if args.spent else 'for a run'}", file=sys.stderr)
        return 2
    row = (spent_row(seeds, args.spent, args.change, args.commit) if args.spent else
           append(seeds, args.env, args.ran, args.change, args.chosen_on, args.commit))
    print(f"ledger: {row['date']} {row['seeds']} {row['env']} at {row['commit']} -> {LEDGER}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
