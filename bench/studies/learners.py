"""Ours with each built-in learner on one env's test seeds: double DQN (the paper's) beside PQN, written as
committed records.

    python -m bench.studies.learners --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/learners*

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. train.py --env E --approaches ours on the seeds (double DQN, the default learner);
  2. train.py --env E --approaches ours --preset pqn on the same seeds (PQN with its values, chosen on Light
     Switch Door's tuning seeds 0-7: jaxbridge/core/presets.py).
It writes learners.csv (each learner's statistics at every cycle), learners.png and learners.json (commit,
commands, times, peak memory, machine) into docs/results/E/; `python -m bench.pages.render` puts the table
into docs/results/learners.md.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import jaxbridge
from bench.records import ENVS
from bench.study import Steps, Study, csv_text, results_rows, run_study, seed_flags, train_step, wall_s
from jaxbridge.utils.files import write_atomic

LEARNERS = {"dqn": ("double DQN", []), "pqn": ("PQN", ["--preset", "pqn"])}  # run name: (label, train.py flags)


class Learners(Study):
    name, doc, page = "learners", __doc__, "docs/results/learners.md"
    envs, seeds, env_help = ENVS, "200-231", "the env to compare the learners on"
    regenerate = tuple(("--env", env) for env in ENVS)

    def steps(self, args, steps: Steps) -> dict:
        return {name: steps.run(name, lambda name=name, flags=flags: train_step(
            args.runs / f"{args.env}-{name}", ["--env", args.env, "--approaches", "ours", *seed_flags(args), *flags]))
            for name, (_, flags) in LEARNERS.items()}

    def write(self, args, done: dict, out: Path) -> dict:
        compared = args.runs / f"{args.env}-compared"  # both runs side by side, for one table and one figure
        for name in LEARNERS:  # what the comparison reads of a run: its metrics.csv
            (compared / name).mkdir(parents=True, exist_ok=True)
            shutil.copy(args.runs / f"{args.env}-{name}" / "ours" / "metrics.csv", compared / name / "metrics.csv")
        jaxbridge.write_comparison(compared, {name: f"ours, {label}" for name, (label, _) in LEARNERS.items()}, args.env)
        write_atomic(out / "learners.csv", csv_text(results_rows(compared)))
        shutil.copy(compared / "curves.png", out / "learners.png")
        return {"labels": {name: label for name, (label, _) in LEARNERS.items()}, "steps": done,
                "wall_s": wall_s(*done.values())}


STUDY = Learners()

if __name__ == "__main__":
    run_study(STUDY)
