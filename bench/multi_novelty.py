"""Does one bridge suffice where several kinds of novelty stall the planner? (issue 54, Multi Novelty)

    python -m bench.multi_novelty                       # development seeds 0-7, 100 cycles
    python -m bench.multi_novelty --seeds 300-331 --change "first run" --chosen-on "development seeds 0-7"
    python -m bench.multi_novelty --cycles 20 --allow-dirty   # a local try: records under RUNS/records

Steps, each as a user runs it (child processes; wall time and peak memory recorded; a finished step is
not run again, and training resumes from its checkpoints):
  1. train.py --env multi_novelty (its default approaches, or --approaches) on the seeds: the test tasks
     (--keep-cycles: the checkpoints of the table's earlier cycles, for the held-out combinations);
  2. eval.py RUN --sweep novelties: the final bridges on more and more novelties;
  3. each approach's bridges at the table's cycles on each seed's held-out combinations (eval.py RUN
     --test-protocol held_out [--cycle N]: doors with both locks; the training does not depend on the
     test tasks, so the bridges are those a run testing on them would train), and its final bridges on
     tasks holding one kind alone (KIND_TASKS per kind, the same for every seed): which kinds it solves;
  4. python -m bench.training: seconds per cycle of each learned approach, a cycle of each in turn in
     one process, as a ratio to ours'.
Writes into docs/results/multi_novelty/ (on a test-seed set its ledger row first; code with uncommitted
changes is refused without --allow-dirty): STEM.csv, STEM_seeds.csv, STEM.png, STEM_sweep.csv/png (the
test tasks' run, as the other studies' records), STEM_held_out.csv, STEM_kinds.csv and STEM.json (commit,
commands, wall times, the cost lines, machine); STEM is multi_novelty on development seeds and
multi_novelty-FIRST-LAST on a test-seed set. `python -m bench.render` puts them into
docs/results/multi_novelty.md.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import jaxbridge
from bench.ledger import add_seed_run_flags, begin_on_seeds, on_test_seeds, seed_list
from bench.paper import Steps, csv_text, train_step, write_record, write_run_records
from bench.records import ROOT, check_clean, git_commit, machine, run_child, shown
from bench.results_blocks import CYCLES
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.stats import bootstrap_ci

ENV = "multi_novelty"
KIND_TASKS = 8  # tasks per kind alone, the same for every seed
NOT_LEARNED = ("random", "pure_planning")  # no cycle cost to compare


def kind_tasks() -> dict[str, list]:
    """Tasks holding one kind alone (a door with both locks: the held-out combination alone), drawn once."""
    from envs_jax.multi_novelty.tasks import BOTH, KEYCARD, LATCHED, task_of
    kinds = {"keycard": (KEYCARD,), "latched": (LATCHED,), "both": (BOTH,), "fuse": ()}
    tasks = {}
    for index, (kind, locks) in enumerate(kinds.items()):
        rng = np.random.default_rng([54, index])
        tasks[kind] = [task_of(rng, int(rng.integers(6, 12)), locks, fuse_blown=kind == "fuse") for _ in range(KIND_TASKS)]
    return tasks


def summary_row(episodes: jaxbridge.Episodes, **what) -> dict:
    """The fraction of tasks solved per seed as mean [95% CI] over seeds, after `what` names the cell."""
    per_seed = np.array(list(episodes.per_seed().values()))
    low, high = bootstrap_ci(per_seed)
    return {**what, "seeds": len(per_seed), "mean": f"{per_seed.mean():.3f}", "low": f"{float(low):.3f}",
            "high": f"{float(high):.3f}"}


def greedy_rows(run: Path, approaches: list[str], kept: list[int]) -> dict:
    """Each approach's greedy bridges on its seeds' held-out combinations (at the `kept` cycles and the
    last), and its final bridges on each kind alone; with the seconds it took."""
    start, held_out, kinds = time.perf_counter(), [], []
    for name in approaches:
        for cycle in [*kept, None]:
            policy = jaxbridge.load(run, name, cycle)
            held_out.append(summary_row(policy.evaluate(test_protocol="held_out"), approach=name, cycle=policy.cycle))
        kinds += [summary_row(policy.evaluate(tasks=specs), approach=name, kind=kind) for kind, specs in kind_tasks().items()]
    return {"held_out": held_out, "kinds": kinds, "wall_s": round(time.perf_counter() - start, 1)}


def parse(argv) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="python -m bench.multi_novelty", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", default="0-7",
                        help="consecutive seeds, FIRST-LAST (default: %(default)s, development seeds; the test set: 300-331)")
    parser.add_argument("--approaches", default=None, help="train.py's --approaches (default: the env's default)")
    parser.add_argument("--cycles", type=int, default=100, help="learning cycles (default: %(default)s)")
    parser.add_argument("--cost-cycles", type=int, default=10, help="cycles of the cost step (default: %(default)s)")
    parser.add_argument("--runs", type=Path, default=ROOT / "runs" / "multi_novelty",
                        help="where the runs and finished steps go (default: runs/multi_novelty)")
    add_seed_run_flags(parser)
    args = parser.parse_args(argv)
    args.seed_list = seed_list(args.seeds)
    args.stem = f"{ENV}-{args.seeds}" if on_test_seeds(args.seed_list) else ENV
    return args


def command_line(args: argparse.Namespace) -> str:
    """The command as the record and the ledger show it (not the ledger's reasons)."""
    shown_flags = [("approaches", args.approaches, None), ("cycles", args.cycles, 100), ("cost-cycles", args.cost_cycles, 10)]
    return f"python -m bench.multi_novelty --seeds {args.seeds}" + "".join(
        f" --{name} {value}" for name, value, default in shown_flags if value != default)


def main(argv=None) -> int:
    args = parse(argv)
    begin_on_seeds("bench.multi_novelty", ENV, args.seed_list, command_line(args), args)
    names = args.approaches.split(",") if args.approaches else jaxbridge.default_approaches(jaxbridge.load_env(ENV))
    runs, start = args.runs.resolve(), time.perf_counter()
    runs.mkdir(parents=True, exist_ok=True)
    steps = Steps(runs / f"{args.stem}-steps.json")
    flags = ["--env", ENV, "--approaches", ",".join(names), "--first-seed", str(args.seed_list[0]), "--num-seeds",
             str(len(args.seed_list)), "--cycles", str(args.cycles), "--no-progress"]
    run, kept = runs / f"{args.stem}-test", [c for c in CYCLES if c < args.cycles]
    trained = steps.run("train", lambda: train_step(run, flags + (["--keep-cycles", ",".join(map(str, kept))] if kept else [])))
    sweep = steps.run("sweep", lambda: run_child(["python", "eval.py", shown(run), "--sweep", "novelties"]))
    greedy = steps.run("greedy", lambda: greedy_rows(run, names, kept))
    learned = ["ours"] + [n for n in names if n not in NOT_LEARNED and n != "ours"]
    cost = steps.run("cost", lambda: run_child(["python", "-m", "bench.training", "--env", ENV, "--num-seeds",
                                                str(min(len(args.seed_list), 8)), "--cycles", str(args.cost_cycles),
                                                "--approach", ",".join(learned)], keep_stdout=True))
    check_clean("bench.multi_novelty", args.allow_dirty, during=True)
    out = args.records / ENV
    write_run_records(run, out, args.stem)
    write_atomic(out / f"{args.stem}_held_out.csv", csv_text(greedy["held_out"]))
    write_atomic(out / f"{args.stem}_kinds.csv", csv_text(greedy["kinds"]))
    record = {"env": ENV, "commit": git_commit(), "command": command_line(args), "seeds": args.seeds,
              "cycles": args.cycles, "approaches": names,
              "cost": [line for line in cost["stdout"].splitlines() if "x ours'" in line],
              "schedule": json.loads((run / "schedule.json").read_text()),  # each core's busy seconds
              "steps": {"train": trained, "sweep": sweep, "greedy": {"wall_s": greedy["wall_s"], "commit": greedy["commit"]},
                        "cost": {k: v for k, v in cost.items() if k != "stdout"}},
              "wall_s": round(sum(step["wall_s"] for step in (trained, sweep, greedy, cost)), 1), "machine": machine()}
    return write_record(out / f"{args.stem}.json", record, start)


if __name__ == "__main__":
    sys.exit(main())
