"""The comparison the paper says is missing, on one env's test seeds: ours beside the plan-repair baselines
(plan_progress: rewarded for reaching a later state of the stuck plan, which then resumes; and
plan_progress_replan: the same reward, then the planner replans), written as committed records.

    python -m bench.plan_repair --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/plan_repair*; --change, --chosen-on: its ledger row (bench.paper)
    python -m bench.plan_repair --env light_switch_panel --change "a rerun" --chosen-on "development seeds 0-31"
        # the variant where committing to the plan is wrong

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. train.py --env E --approaches ours,plan_progress,plan_progress_replan on the test seeds;
  2. eval.py RUN --sweep novelties: their final bridges on more and more novelties.
It writes plan_repair.csv (every run's statistics at every cycle), plan_repair_sweep.csv,
plan_repair.png, plan_repair_sweep.png and plan_repair.json (commit, commands, times, machine) into
docs/results/E/; `python -m bench.render` puts the table into docs/results/plan_repair.md. A finished step is not
run again (E-steps.json in the runs directory), and training resumes from its checkpoints.
"""
from __future__ import annotations

import sys
import time

import jaxbridge
from bench.paper import (Steps, command_line, records_folder, seed_flags, seeds_text, test_seed_args, train_step,
                         write_record, write_run_records)
from bench.records import ENVS, git_commit, machine, run_child, shown
from envs_jax import VARIANTS

APPROACHES = "ours,plan_progress,plan_progress_replan"


def main(argv=None) -> int:
    args = test_seed_args("bench.plan_repair", __doc__, "the env to compare on (light_switch_panel: the variant where "
                          "committing to the plan is wrong)", argv, ENVS + VARIANTS)
    env, runs = args.env, args.runs.resolve()
    runs.mkdir(parents=True, exist_ok=True)
    steps, run = Steps(runs / f"{env}-steps.json"), runs / env
    start = time.perf_counter()

    train = steps.run("train", lambda: train_step(run, ["--env", env, "--approaches", APPROACHES, *seed_flags(args)]))
    sweep = steps.run("sweep", lambda: run_child(["python", "eval.py", shown(run), "--sweep", "novelties"]))
    approaches = list(jaxbridge.read_experiment(run).approaches)
    jaxbridge.write_comparison(run, title=env)

    out = records_folder(args)
    write_run_records(run, out, "plan_repair")
    record = {"env": env, "commit": git_commit(), "command": command_line(args), "seeds": seeds_text(args),
              "approaches": approaches,
              "steps": {"train": train, "sweep": sweep},
              "wall_s": round(train["wall_s"] + sweep["wall_s"], 1), "machine": machine()}
    return write_record(out / "plan_repair.json", record, start)


if __name__ == "__main__":
    sys.exit(main())
