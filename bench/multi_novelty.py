"""Does one bridge suffice where several kinds of novelty stall the planner? (issue 54, Multi Novelty)

    python -m bench.multi_novelty                       # development seeds 0-7, 100 cycles -> runs/multi_novelty_bench/
    python -m bench.multi_novelty --cycles 20 --runs /tmp/mn --records /tmp/mn/records

Steps, each as a user runs it (child processes; wall time and peak memory recorded; a finished step is
not run again, and training resumes from its checkpoints):
  1. train.py --env multi_novelty (its default approaches, or --approaches) on the seeds: the test tasks;
  2. the same with --test-protocol held_out: the held-out combinations (doors with both locks);
  3. each approach's final bridges on tasks holding one kind alone (KIND_TASKS per kind, the same for
     every seed): which kinds it solves;
  4. python -m bench.training: seconds per cycle of each approach, one after another in one process, as
     a ratio to ours'.
Writes, into --records: results.csv (test solve rate at cycles 10/25/50/100 per approach and protocol, mean
with its 95% bootstrap interval over seeds), kinds.csv (per approach and kind at the last cycle), and
multi_novelty.json (commit, commands, wall times, the cost lines, machine). Development seeds only by
default; the test seeds' headline is the lead's run, with its ledger row (docs/RESULTS.md, Seeds).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import jaxbridge
from bench.paper import Steps, csv_text, train_step
from bench.records import git_commit, machine, run_child
from jaxbridge.utils.stats import bootstrap_ci
from jaxbridge.utils.files import write_atomic

ENV = "multi_novelty"
AT_CYCLES = (10, 25, 50, 100)
PROTOCOLS = {"test": "jaxbridge", "held_out": "held_out"}
KIND_TASKS = 8  # tasks per kind alone, the same for every seed


def kind_tasks() -> dict[str, list]:
    """Tasks holding one kind alone (a door with both locks: the held-out combination alone), drawn once."""
    from envs_jax.multi_novelty.tasks import BOTH, KEYCARD, LATCHED, task_of
    kinds = {"keycard": (KEYCARD,), "latched": (LATCHED,), "both": (BOTH,), "fuse": ()}
    tasks = {}
    for index, (kind, locks) in enumerate(kinds.items()):
        rng = np.random.default_rng([54, index])
        tasks[kind] = [task_of(rng, int(rng.integers(6, 12)), locks, fuse_blown=kind == "fuse") for _ in range(KIND_TASKS)]
    return tasks


def interval_row(scores: np.ndarray) -> dict:
    low, high = bootstrap_ci(scores)
    return {"mean": f"{scores.mean():.3f}", "low": f"{float(low):.3f}", "high": f"{float(high):.3f}"}


def curve_rows(run: Path, protocol: str, approaches: list[str]) -> list[dict]:
    """The test solve rate at AT_CYCLES per approach of a run, per seed from its metrics.csv."""
    rows, metrics = [], jaxbridge.read_experiment(run).metrics
    for name in approaches:
        rates = metrics[name]["test_solve_rate"]  # [seeds, cycles]
        for cycle in (c for c in AT_CYCLES if c <= rates.shape[1]):
            rows.append({"approach": name, "protocol": protocol, "cycle": cycle, "seeds": rates.shape[0],
                         **interval_row(rates[:, cycle - 1])})
    return rows


def kind_rows(run: Path, approaches: list[str]) -> list[dict]:
    """Each approach's final greedy bridges on each kind alone: per seed, the fraction solved."""
    rows = []
    for name in approaches:
        policy = jaxbridge.load(run, name)
        for kind, specs in kind_tasks().items():
            per_seed = np.array(list(policy.evaluate(tasks=specs).per_seed().values()))
            rows.append({"approach": name, "kind": kind, "seeds": len(per_seed), **interval_row(per_seed)})
    return rows


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m bench.multi_novelty", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--approaches", default=None, help="train.py's --approaches (default: the env's default)")
    parser.add_argument("--first-seed", type=int, default=0, help="first seed (default: %(default)s, development)")
    parser.add_argument("--num-seeds", type=int, default=8, help="seeds (default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=100, help="cycles (default: %(default)s)")
    parser.add_argument("--cost-cycles", type=int, default=10, help="cycles of the cost step (default: %(default)s)")
    parser.add_argument("--runs", type=Path, default=Path("runs/multi_novelty_bench"), help="where the runs go")
    parser.add_argument("--records", type=Path, default=None, help="where the records go (default: RUNS/records)")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse(argv)
    names = args.approaches.split(",") if args.approaches else jaxbridge.default_approaches(jaxbridge.load_env(ENV))
    runs, start = args.runs.resolve(), time.perf_counter()
    runs.mkdir(parents=True, exist_ok=True)
    records = (args.records or runs / "records").resolve()
    steps = Steps(runs / "steps.json")
    flags = ["--env", ENV, "--approaches", ",".join(names), "--first-seed", str(args.first_seed), "--num-seeds",
             str(args.num_seeds), "--cycles", str(args.cycles), "--no-progress"]
    done = {protocol: steps.run(f"train_{protocol}", lambda p=protocol: train_step(
        runs / p, flags + ["--test-protocol", PROTOCOLS[p]])) for protocol in PROTOCOLS}
    rows = [row for protocol in PROTOCOLS for row in curve_rows(runs / protocol, protocol, names)]
    kinds = kind_rows(runs / "test", names)
    learned = [n for n in names if n not in ("random", "pure_planning")]
    ordered = ["ours"] + [n for n in learned if n != "ours"]
    cost = steps.run("cost", lambda: run_child(["python", "-m", "bench.training", "--env", ENV, "--num-seeds",
                                                str(args.num_seeds), "--cycles", str(args.cost_cycles),
                                                "--approach", ",".join(ordered)], keep_stdout=True))
    records.mkdir(parents=True, exist_ok=True)
    write_atomic(records / "results.csv", csv_text(rows))
    write_atomic(records / "kinds.csv", csv_text(kinds))
    record = {"env": ENV, "commit": git_commit(), "command": "python -m bench.multi_novelty " + " ".join(argv or sys.argv[1:]),
              "seeds": f"{args.first_seed}-{args.first_seed + args.num_seeds - 1}", "cycles": args.cycles,
              "approaches": names, "cost": [line for line in cost["stdout"].splitlines() if "x ours'" in line],
              "steps": {**done, "cost": {k: v for k, v in cost.items() if k != "stdout"}},
              "wall_s": round(time.perf_counter() - start, 1), "machine": machine()}
    write_atomic(records / "multi_novelty.json", json.dumps(record, indent=1) + "\n")
    for row in rows + kinds:
        print(", ".join(f"{k} {v}" for k, v in row.items()))
    print("\n".join(record["cost"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
