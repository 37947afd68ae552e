"""The comparison the paper says is missing, on one env's test seeds: ours beside the plan-repair baselines
(plan_progress: rewarded for reaching a later state of the stuck plan, which then resumes; and
plan_progress_replan: the same reward, then the planner replans), written as committed records.

    python -m bench.studies.plan_repair --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/plan_repair*
    python -m bench.studies.plan_repair --env light_switch_panel --change "a rerun" --chosen-on "development seeds 0-31"
        # the variant where committing to the plan is wrong

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. train.py --env E --approaches ours,plan_progress,plan_progress_replan on the seeds;
  2. eval.py RUN --sweep novelties: their final bridges on more and more novelties.
It writes plan_repair.csv (every run's statistics at every cycle), plan_repair_sweep.csv,
plan_repair.png, plan_repair_sweep.png and plan_repair.json (commit, commands, times, machine) into
docs/results/E/; `python -m bench.pages.render` puts the table into docs/results/plan_repair.md.
"""
from __future__ import annotations

from pathlib import Path

import jaxbridge
from bench.records import ENVS
from bench.study import Steps, Study, run_study, seed_flags, sweep_step, train_step, wall_s, write_run_records
from envs_jax import VARIANTS

APPROACHES = "ours,plan_progress,plan_progress_replan"


class PlanRepair(Study):
    name, doc, page = "plan_repair", __doc__, "docs/results/plan_repair.md"
    envs, seeds = ENVS + VARIANTS, "200-231"
    env_help = "the env to compare on (light_switch_panel: the variant where committing to the plan is wrong)"
    regenerate = tuple(("--env", env) for env in ENVS + ("light_switch_panel",))

    def steps(self, args, steps: Steps) -> dict:
        run = args.runs / args.env
        train = steps.run("train", lambda: train_step(run, ["--env", args.env, "--approaches", APPROACHES, *seed_flags(args)]))
        return {"run": run, "train": train, "sweep": steps.run("sweep", lambda: sweep_step(run))}

    def write(self, args, done: dict, out: Path) -> dict:
        jaxbridge.write_comparison(done["run"], title=args.env)
        write_run_records(done["run"], out, self.name)
        return {"approaches": list(jaxbridge.read_experiment(done["run"]).approaches),
                "steps": {"train": done["train"], "sweep": done["sweep"]}, "wall_s": wall_s(done["train"], done["sweep"])}


STUDY = PlanRepair()

if __name__ == "__main__":
    run_study(STUDY)
