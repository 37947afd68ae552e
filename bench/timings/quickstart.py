"""The README's first command for each env, timed as a user runs it, into docs/results/quickstart.json.

    python -m bench.timings.quickstart                      # every env
    python -m bench.timings.quickstart --envs doorknobs

Runs `python train.py --env E --num-seeds 8` (the approaches of the paper's figure for E, tuning seeds
0-7, 100 cycles) in a child process with a cold compilation cache, as on a fresh clone, into a temporary directory (or --keep DIR), and records its wall time, its peak
resident memory, each device's busy seconds (the run's schedule.json), what it trained and the mean test
solve rate it reports at the last cycle per approach
(on tuning seeds: what the quick start should print, not a claim). The README and docs/PERFORMANCE.md
quote these records (python -m bench.pages.render).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from bench.command import CommandParser
from bench.records import (DIRTY_RECORDS, ENVS, QUICKSTART, check_clean, cold_cache, git_commit, machine, record_path,
                           run_child, shown)


def measure(env: str, out: Path) -> dict:
    """Train the env's quick start into out/ENV (which must not exist) and read back what it reports."""
    with cold_cache() as child_env:  # as on a fresh clone
        step = run_child(["python", "train.py", "--env", env, "--num-seeds", "8", "--out", str(out), "--name", env],
                         env=child_env)
    experiment = json.loads((out / env / "experiment.json").read_text())
    schedule = json.loads((out / env / "schedule.json").read_text())  # each device's busy seconds
    elapsed = {a: json.loads((out / env / a / "summary.json").read_text())["elapsed_s"] for a in experiment["approaches"]}
    final = {a: round(json.loads((out / env / a / "summary.json").read_text())
                      ["per_cycle"]["test_solve_rate"]["mean"][-1], 2) for a in experiment["approaches"]}
    return {"command": f"python train.py --env {env} --num-seeds 8", "wall_s": step["wall_s"],
            "peak_rss_mib": step["peak_rss_mib"], "approaches": experiment["approaches"], "seeds": "0-7",
            "final_test_solve_rate": final, "elapsed_s": elapsed, "schedule": schedule, "commit": git_commit(), "machine": machine()}


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__, dirty_records=shown(DIRTY_RECORDS))
    parser.add_argument("--envs", default=",".join(ENVS), help="comma-separated envs (default: all three)")
    parser.add_argument("--keep", type=Path, default=None, metavar="DIR",
                        help="train into DIR/ENV and keep the runs (default: a temporary directory, removed)")
    args = parser.parse_args(argv)
    envs = args.envs.split(",")
    unknown = [e for e in envs if e not in ENVS]
    if unknown:
        parser.error(f"unknown env {', '.join(unknown)}; choose from {', '.join(ENVS)}")
    record = record_path("bench.timings.quickstart", QUICKSTART, args.allow_dirty)
    record.parent.mkdir(parents=True, exist_ok=True)
    records = json.loads(record.read_text()) if record.is_file() else {}
    for env in envs:
        if args.keep is not None:
            records[env] = measure(env, args.keep)
        else:
            with tempfile.TemporaryDirectory() as tmp:
                records[env] = measure(env, Path(tmp))
        check_clean("bench.timings.quickstart", args.allow_dirty, during=True)
        record.write_text(json.dumps(records, indent=2) + "\n")  # each env as soon as it is measured
        print(f"bench.timings.quickstart: {env} {records[env]['wall_s']:.0f} s, peak RSS "
              f"{records[env]['peak_rss_mib'] / 2**10:.2f} GiB -> {record}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
