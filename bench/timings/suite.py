"""The test suite's wall time, as the README's second command runs it, into docs/results/suite.json; with
--claims, the paper's claims on every env (tests/test_claims.py, `-m claims`) into suite_claims.json.

    python -m bench.timings.suite [--claims]

Runs `python -m pytest` from the repository root (its persistent compilation cache as it is: run it on a
fresh clone, as CI does, for the figure docs/PERFORMANCE.md quotes) and records the wall time, the
outcome line and the machine.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import time

from bench.command import CommandParser
from bench.records import DIRTY_RECORDS, ROOT, SUITE, SUITE_CLAIMS, check_clean, git_commit, machine, record_path, shown


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__, dirty_records=shown(DIRTY_RECORDS))
    parser.add_argument("--claims", action="store_true",
                        help="time the claim tests (python -m pytest -m claims) instead of the default suite")
    args = parser.parse_args(argv)
    command, path = (["-m", "pytest", "-m", "claims"], SUITE_CLAIMS) if args.claims else (["-m", "pytest"], SUITE)
    path = record_path("bench.timings.suite", path, args.allow_dirty)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *command], cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - start
    outcome = next((line.strip("= ") for line in reversed(proc.stdout.splitlines()) if re.search(r"\d+ passed", line)), "")
    if proc.returncode != 0:
        sys.stdout.write(proc.stdout[-5000:])
        raise SystemExit(f"bench.timings.suite: the suite failed (exit {proc.returncode}); nothing recorded")
    record = {"command": " ".join(["python", *command]), "wall_s": round(wall, 1), "outcome": outcome,
              "commit": git_commit(check_clean("bench.timings.suite", args.allow_dirty, during=True)), "machine": machine()}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2) + "\n")
    print(f"bench.timings.suite: {outcome} in {wall:.0f} s -> {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
