"""Seconds until a run too big for memory is refused (docs/RELIABILITY.md; target: under 5 s), each case
a fresh `train.py` / `eval.py` process as a user starts it, timed over --repeats runs.

    python -m bench.timings.refusal [--repeats 5]
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.command import CommandParser

ROOT = Path(__file__).resolve().parents[2]  # the repository


def cases(out: Path) -> dict[str, list[str]]:
    """{name: argv}; the evaluation refuses a run's checkpoint on larger tasks, so a 1-cycle run is made first."""
    run = out / "tiny"
    subprocess.run([sys.executable, "train.py", "--approaches", "pure_planning", "--num-seeds", "1", "--cycles", "1",
                    "--no-progress", "--out", str(out), "--name", "tiny"], cwd=ROOT, check=True, capture_output=True)
    return {"train.py --num-seeds 100000": ["train.py", "--num-seeds", "100000", "--out", str(out)],
            "eval.py RUN --task-size cells=100000,doors=1": ["eval.py", str(run), "--approach", "pure_planning",
                                                             "--task-size", "cells=100000,doors=1"]}


def time_refusal(argv: list[str]) -> tuple[float, str]:
    """(seconds, the one-line error) of a command that must exit 2."""
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *argv], cwd=ROOT, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 2:
        sys.exit(f"error: {' '.join(argv)} exited {proc.returncode}, not 2 (refused): {proc.stderr[-500:]}")
    return seconds, proc.stderr.strip()


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--repeats", type=int, default=5, help="processes timed per case (default: %(default)s)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as out:
        for name, argv in cases(Path(out)).items():
            times, message = [], ""
            for _ in range(args.repeats):
                seconds, message = time_refusal(argv)
                times.append(seconds)
            print(f"{name}: median {statistics.median(times):.2f} s, min {min(times):.2f}, max {max(times):.2f} "
                  f"({args.repeats} processes)\n    {message}")


if __name__ == "__main__":
    main()
