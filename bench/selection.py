"""The learned object selector on one env's test seeds (issue 37): ours (the hand-made selection, the
closest interactable object's features) beside ours_learned_selection (every object as a token, attention
choosing), written as committed records.

    python -m bench.selection --env light_switch_door   # -> docs/results/light_switch_door/selection*

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. train.py --env E --approaches ours,ours_learned_selection --workers 1 on the test seeds (one after the
     other, so that each one's seconds per cycle are its own);
  2. eval.py RUN --sweep novelties: both final bridges on more and more novelties;
  3. eval.py RUN --approach ours_learned_selection --attention: how often its most attended object at a
     bridge decision is the one the env's fix acts on.
It writes selection.csv, selection_sweep.csv, selection.png, selection_sweep.png and selection.json
(commit, commands, times, peak memory, the attention line, machine) into docs/results/E/; `python -m
bench.render` puts the tables into docs/RESULTS.md. A finished step is not run again (E-steps.json in the
runs directory), and training resumes from its checkpoints.
"""
from __future__ import annotations

import json
import sys
import time

from bench.paper import Steps, command_line, test_seed_args, train_step, write_record, write_run_records
from bench.records import ENVS, TEST_SEEDS, git_commit, machine, run_child, shown
from jaxbridge.run.comparison import run_labels, write_comparison

APPROACHES = ("ours", "ours_learned_selection")


def main(argv=None) -> int:
    args = test_seed_args("bench.selection", __doc__, "the env to compare the selections on", argv, ENVS)
    first, count = TEST_SEEDS[0], args.num_seeds
    env, runs = args.env, args.runs.resolve()
    runs.mkdir(parents=True, exist_ok=True)
    steps, run = Steps(runs / f"{env}-steps.json"), runs / env
    start = time.perf_counter()
    train = steps.run("train", lambda: train_step(run, ["--env", env, "--approaches", ",".join(APPROACHES), "--workers",
                                                        "1", "--num-seeds", str(count), "--first-seed", str(first),
                                                        "--cycles", str(args.cycles)]))
    sweep = steps.run("sweep", lambda: run_child(["python", "eval.py", shown(run), "--sweep", "novelties"]))
    attention = steps.run("attention", lambda: run_child(["python", "eval.py", shown(run), "--approach",
                                                          "ours_learned_selection", "--attention"], keep_stdout=True))
    write_comparison(run, env, run_labels(list(APPROACHES)))

    out = args.records / env
    write_run_records(run, out, "selection")
    elapsed = {name: json.loads((run / name / "summary.json").read_text())["elapsed_s"] for name in APPROACHES}
    record = {"env": env, "commit": git_commit(), "command": command_line("bench.selection", args),
              "seeds": f"{first}-{first + count - 1}", "cycles": args.cycles, "approaches": list(APPROACHES),
              "elapsed_s": elapsed, "attention": attention["stdout"].strip().splitlines()[-1],
              "steps": {"train": train, "sweep": sweep, "attention": {k: v for k, v in attention.items() if k != "stdout"}},
              "wall_s": round(train["wall_s"] + sweep["wall_s"] + attention["wall_s"], 1), "machine": machine()}
    return write_record(out / "selection.json", record, start)


if __name__ == "__main__":
    sys.exit(main())
