"""The learned object selector on one env's test seeds (issue 37): ours (the env's hand-made features),
ours_closest_object (the paper's rule read off the object view) and ours_learned_selection (every object
a token, attention choosing), written as committed records.

    python -m bench.selection --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/selection*, on test seeds 300-331 (--seed-set); --change,
        # --chosen-on: its ledger row (bench.paper)
    python -m bench.selection --env coffee_distractor --change "a rerun" --chosen-on "development seeds 0-31"
        # a cup nearer the stuck robot than the jug

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. python -m bench.training: seconds per cycle of ours and of the learned selector, 8 seeds x 20
     cycles, a cycle of each in turn in one process (their ratio is the cost bar's figure);
  2. train.py --env E --approaches ... on the test seeds (side by side, as train.py schedules them); on
     a distractor env (DISTRACTOR_ENVS) no_feature_selection too;
  3. eval.py RUN --sweep novelties: the final bridges on more and more novelties;
  4. eval.py RUN --approach ours_learned_selection --attention: how often its most attended object at a
     bridge decision is the one the env's fix acts on; with --cycle N, the same of the checkpoints that
     training kept (--keep-cycles) at the table's earlier cycles: how attention changes over training.
It writes selection.csv, selection_sweep.csv, selection.png, selection_sweep.png and selection.json
(commit, commands, times, peak memory, the cost line, the attention lines, machine) into
docs/results/E/; `python -m bench.render` puts the tables into docs/results/selection.md. A finished step is not
run again (E-steps.json in the runs directory), and training resumes from its checkpoints.
"""
from __future__ import annotations

import json
import sys
import time

import jaxbridge
from bench.paper import (Steps, command_line, records_folder, seed_flags, seeds_text, test_seed_args, train_step,
                         write_record, write_run_records)
from bench.records import DISTRACTOR_ENVS, ENVS, git_commit, machine, run_child, shown
from bench.results_blocks import CYCLES

APPROACHES = ("ours", "ours_closest_object", "ours_learned_selection")
COST_SEEDS, COST_CYCLES = 8, 20
SEED_SET = 300  # the selector's shape was chosen after looking at 200-231: its headlines are on 300-331


def approaches(env: str) -> tuple[str, ...]:
    return APPROACHES + (("no_feature_selection",) if env in DISTRACTOR_ENVS else ())


def main(argv=None) -> int:
    args = test_seed_args("bench.selection", __doc__, "the env to compare the selections on", argv,
                          ENVS + DISTRACTOR_ENVS, seed_set=SEED_SET)
    env, runs = args.env, args.runs.resolve()
    runs.mkdir(parents=True, exist_ok=True)
    steps, run = Steps(runs / f"{env}-steps.json"), runs / env
    start = time.perf_counter()
    names = approaches(env)
    cost = steps.run("cost", lambda: run_child(["python", "-m", "bench.training", "--env", env, "--num-seeds", str(COST_SEEDS),
                                                "--cycles", str(COST_CYCLES), "--approach", "ours,ours_learned_selection"],
                                               keep_stdout=True))
    kept = [c for c in CYCLES if c < args.cycles]  # the table's earlier cycles: attention over training
    flags = ["--env", env, "--approaches", ",".join(names), *seed_flags(args)]
    train = steps.run("train", lambda: train_step(run, flags + (["--keep-cycles", ",".join(map(str, kept))] if kept else [])))
    sweep = steps.run("sweep", lambda: run_child(["python", "eval.py", shown(run), "--sweep", "novelties"]))
    looked = {c: steps.run(f"attention_{c}", lambda c=c: attention_at(run, ["--cycle", str(c)])) for c in kept}
    attention = steps.run("attention", lambda: attention_at(run, []))
    jaxbridge.write_comparison(run, jaxbridge.run_labels(names), env)

    out = records_folder(args)
    write_run_records(run, out, "selection")
    elapsed = {name: json.loads((run / name / "summary.json").read_text())["elapsed_s"] for name in names}
    record = {"env": env, "commit": git_commit(), "command": command_line(args), "seeds": seeds_text(args),
              "cycles": args.cycles, "approaches": list(names),
              "elapsed_s": elapsed, "cost": cost["stdout"].strip().splitlines()[-1],
              "attention": attention_line(attention), "attention_diagnosis": attention["stdout"].strip().splitlines()[-1],
              "attention_over_training": {c: attention_line(step).rpartition("; all ")[2] for c, step in looked.items()},
              "steps": {"cost": without_stdout(cost), "train": train, "sweep": sweep, "attention": without_stdout(attention),
                        **{f"attention_{c}": without_stdout(step) for c, step in looked.items()}},
              "wall_s": round(sum(step["wall_s"] for step in (cost, train, sweep, attention, *looked.values())), 1),
              "machine": machine()}
    return write_record(out / "selection.json", record, start)


def attention_at(run, flags: list[str]) -> dict:
    """eval.py --attention on the learned selector's run (its latest checkpoint, or that of `--cycle N`)."""
    return run_child(["python", "eval.py", shown(run), "--approach", "ours_learned_selection", "--attention", *flags],
                     keep_stdout=True)


def attention_line(step: dict) -> str:
    """eval.py --attention's per-seed line (the one before its diagnosis)."""
    return next(line for line in step["stdout"].splitlines() if line.startswith("attention on the fix's object"))


def without_stdout(step: dict) -> dict:
    return {k: v for k, v in step.items() if k != "stdout"}


if __name__ == "__main__":
    sys.exit(main())
