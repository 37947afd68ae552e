"""One env's headline on the test seeds, regenerated from nothing and written as committed records.

    python -m bench.studies.paper --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/
    python -m bench.studies.paper --env doorknobs --runs runs/paper_try --seeds 0-1 --cycles 2 --allow-dirty

Each step runs as a user would run it (the same commands, in child processes; wall time and peak memory
of each are recorded):
  1. train.py --env E on the seeds: the approaches of the paper's figure for E (train.py's default);
  2. train.py --env E --approaches ours --preset authors on the same seeds;
  3. the oracle bridge on the same test tasks, under each of those runs' test protocols: the ceiling;
  4. eval.py RUN --sweep novelties: every approach's final bridges on more and more novelties.
It then writes docs/results/E/: results.csv (every run's statistics at every cycle), oracle.csv (the
ceiling per seed), sweep.csv, figure.png, sweep.png and run.json (commit, commands, wall times, peak
memory, machine). `python -m bench.pages.render` turns the records into the tables of docs/RESULTS.md.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import jaxbridge
from bench.records import ENVS, PRESET_RUN
from bench.study import (Steps, Study, csv_text, oracle_rows, results_rows, run_study, seed_flags, sweep_step, train_step,
                         wall_s)
from jaxbridge.utils.files import write_atomic


class Paper(Study):
    name, doc, page = "paper", __doc__, "docs/RESULTS.md"
    envs, env_help = ENVS, "the env whose headline to regenerate"
    seeds = "200-231"  # the paper envs' test set: their headlines and nothing chosen on them
    regenerate = tuple(("--env", env) for env in ENVS)

    def stem(self, args) -> str:
        return "run"

    def steps(self, args, steps: Steps) -> dict:
        env, main_run, preset_run = args.env, args.runs / args.env, args.runs / f"{args.env}_authors"
        train = steps.run("train", lambda: train_step(main_run, ["--env", env, *seed_flags(args)]))
        preset = steps.run("train_authors_preset", lambda: train_step(
            preset_run, ["--env", env, "--approaches", "ours", "--preset", "authors", *seed_flags(args)]))
        protocols = list(dict.fromkeys(jaxbridge.read_experiment(run).config.test_protocol for run in (main_run, preset_run)))
        oracle = steps.run("oracle", lambda: dict(zip(("rows", "wall_s"), oracle_rows(env, protocols, args.seed_list))))
        return {"train": train, "train_authors_preset": preset, "protocols": protocols, "oracle": oracle,
                "sweep": steps.run("sweep", lambda: sweep_step(main_run)), "runs": (main_run, preset_run)}

    def write(self, args, done: dict, out: Path) -> dict:
        main_run, preset_run = done["runs"]
        for run in (main_run, preset_run):  # the tables and figure as this checkout draws them
            jaxbridge.write_comparison(run, title=args.env)
        write_atomic(out / "results.csv", csv_text(results_rows(main_run) + results_rows(preset_run, {"ours": PRESET_RUN})))
        write_atomic(out / "oracle.csv", csv_text(done["oracle"]["rows"]))
        for source, target in (("sweep_novelties.csv", "sweep.csv"), ("sweep_novelties.png", "sweep.png"),
                               ("curves.png", "figure.png")):
            shutil.copy(main_run / source, out / target)
        protocols, train, preset, sweep = done["protocols"], done["train"], done["train_authors_preset"], done["sweep"]
        return {"approaches": list(jaxbridge.read_experiment(main_run).approaches),
                "config_version": json.loads((main_run / "ours" / "config.json").read_text())["config_version"],
                "test_protocols": {"main": protocols[0], "authors_preset": protocols[-1]},
                "steps": {"train": train, "train_authors_preset": preset,
                          "oracle": {"protocols": protocols, "wall_s": done["oracle"]["wall_s"],
                                     "commit": done["oracle"]["commit"]}, "sweep": sweep},
                "wall_s": round(wall_s(train, preset, sweep) + done["oracle"]["wall_s"], 1)}


STUDY = Paper()

if __name__ == "__main__":
    run_study(STUDY)
