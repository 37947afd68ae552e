"""Ours with each built-in learner on one env's test seeds: double DQN (the paper's) beside PQN, written as
committed records.

    python -m bench.learners --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/learners*; --change, --chosen-on: its ledger row (bench.paper)

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. train.py --env E --approaches ours on the test seeds (double DQN, the default learner);
  2. train.py --env E --approaches ours --preset pqn on the same seeds (PQN with its values, chosen on Light
     Switch Door's tuning seeds 0-7: jaxbridge/core/presets.py).
It writes learners.csv (each learner's statistics at every cycle), learners.png and learners.json (commit,
commands, times, peak memory, machine) into docs/results/E/; `python -m bench.render` puts the table into
docs/results/learners.md. A finished step is not run again (E-steps.json in the runs directory), and training resumes
from its checkpoints.
"""
from __future__ import annotations

import shutil
import sys
import time

import jaxbridge
from bench.paper import (Steps, command_line, csv_text, records_folder, results_rows, seed_flags, seeds_text,
                         test_seed_args, train_step, write_record)
from bench.records import ENVS, git_commit, machine

LEARNERS = {"dqn": ("double DQN", []), "pqn": ("PQN", ["--preset", "pqn"])}  # run name: (label, train.py flags)


def main(argv=None) -> int:
    args = test_seed_args("bench.learners", __doc__, "the env to compare the learners on", argv, ENVS)
    env, runs = args.env, args.runs.resolve()
    runs.mkdir(parents=True, exist_ok=True)
    steps, start, seeds = Steps(runs / f"{env}-steps.json"), time.perf_counter(), seed_flags(args)
    trained = {name: steps.run(name, lambda name=name, flags=flags: train_step(
        runs / f"{env}-{name}", ["--env", env, "--approaches", "ours", *seeds, *flags]))
        for name, (_, flags) in LEARNERS.items()}

    compared = runs / f"{env}-compared"  # both runs side by side, for one table and one figure
    for name in LEARNERS:  # what the comparison reads of a run: its metrics.csv
        (compared / name).mkdir(parents=True, exist_ok=True)
        shutil.copy(runs / f"{env}-{name}" / "ours" / "metrics.csv", compared / name / "metrics.csv")
    jaxbridge.write_comparison(compared, {name: f"ours, {label}" for name, (label, _) in LEARNERS.items()}, env)

    out = records_folder(args)
    (out / "learners.csv").write_text(csv_text(results_rows(compared)))
    shutil.copy(compared / "curves.png", out / "learners.png")
    record = {"env": env, "commit": git_commit(), "command": command_line(args), "seeds": seeds_text(args),
              "cycles": args.cycles,
              "labels": {name: label for name, (label, _) in LEARNERS.items()}, "steps": trained,
              "wall_s": round(sum(step["wall_s"] for step in trained.values()), 1), "machine": machine()}
    return write_record(out / "learners.json", record, start)


if __name__ == "__main__":
    sys.exit(main())
