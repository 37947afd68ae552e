"""The test suite's wall time, as the README's second command runs it, into docs/results/suite.json.

    python -m bench.suite

Runs `python -m pytest` from the repository root (its persistent compilation cache as it is: run it on a
fresh clone, as CI does, for the figure docs/PERFORMANCE.md quotes) and records the wall time, the
outcome line and the machine.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time

from bench.records import ROOT, SUITE, git_commit, machine


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.suite", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.parse_args(argv)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pytest"], cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - start
    outcome = next((line.strip("= ") for line in reversed(proc.stdout.splitlines()) if re.search(r"\d+ passed", line)), "")
    if proc.returncode != 0:
        sys.stdout.write(proc.stdout[-5000:])
        raise SystemExit(f"bench.suite: the suite failed (exit {proc.returncode}); nothing recorded")
    record = {"command": "python -m pytest", "wall_s": round(wall, 1), "outcome": outcome, "commit": git_commit(),
              "machine": machine()}
    SUITE.write_text(json.dumps(record, indent=2) + "\n")
    print(f"bench.suite: {outcome} in {wall:.0f} s -> {SUITE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
