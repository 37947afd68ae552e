"""Does learning the novelty into the planner's model compose fixes no training task showed? (issue 76)

    python -m bench.studies.model_repair --env multi_novelty              # development seeds 0-7, 100 cycles
    python -m bench.studies.model_repair --env doorknobs --seeds 400-431 --change "first run" --chosen-on "development seeds 0-7"
    python -m bench.studies.model_repair --env coffee --cycles 10 --allow-dirty   # a local try: records under RUNS/records

Steps, each as a user runs it (child processes, or the public API; a finished step is not run again, and
training resumes from its checkpoints):
  1. train.py --env E on the seeds: ours, the repair approach with invented and with given predicates
     (ours_model_repair, ours_model_repair_given), and on Multi Novelty the learned selector and a bridge
     per failure signature; metrics.csv holds each cycle's test solve rate and bridge decisions per test
     task, learned_operators.csv each seed's learned operators;
  2. eval.py RUN --sweep novelties: the final policies on more and more novelties;
  3. each repair run's learned planner alone (no bridge), on each test protocol's tasks and on the novelty
     sweep (jaxbridge.load(...).planner_alone, jaxbridge.sweep_novelties(..., planner_alone=True));
  4. on Multi Novelty, every approach's final policy on the held-out combinations; on Coffee, the oracle
     bridge (the fastest fix) on the same test tasks;
  5. python -m bench.timings.training: seconds per cycle of the repair approach as a ratio to ours'.
Writes into docs/results/E/ (on a test-seed set its ledger row first; code with uncommitted changes is
refused without --allow-dirty): STEM.csv, STEM_seeds.csv, STEM.png, STEM_sweep.csv/png (the run's
records, as the other studies'), STEM_cycles.csv (per approach, seed and cycle: test solve rate, bridge
decisions per test task, learned operators), STEM_alone.csv, STEM_held_out.csv or STEM_oracle.csv, one
seed's learned domain per repair approach (STEM_APPROACH.pddl) and STEM.json; STEM is model_repair on
development seeds and model_repair-FIRST-LAST on a test-seed set. `python -m bench.pages.render` puts them
into docs/results/model_repair.md.
"""
from __future__ import annotations

import csv
import json
import time
from pathlib import Path

import jaxbridge
from bench.records import run_child
from bench.study import (Steps, Study, csv_text, oracle_rows, run_study, summary_row, sweep_step, train_step, wall_s,
                         without_stdout, write_run_records)
from jaxbridge.utils.files import write_atomic

ENVS = ("multi_novelty", "light_switch_door", "doorknobs", "coffee")
REPAIR = ("ours_model_repair", "ours_model_repair_given")
APPROACHES = {env: ("ours", *REPAIR) for env in ENVS} | {
    "multi_novelty": ("ours", *REPAIR, "ours_learned_selection", "ours_per_signature")}


def planner_alone_rows(run: Path, env: str) -> dict:
    """Each repair run's learned planner alone: on every test protocol's tasks and on the novelty sweep."""
    start, rows = time.perf_counter(), []
    env_cls = jaxbridge.load_env(env)
    for name in REPAIR:
        policy = jaxbridge.load(run, name)
        rows += [summary_row(policy.planner_alone(test_protocol=p).per_seed(), approach=name, tasks=p)
                 for p in env_cls.test_protocols]
        swept = jaxbridge.sweep_novelties({name: run / name}, planner_alone=True).result
        rates = swept.solve_rate[name]  # [seeds, counts]
        rows += [summary_row(rates[:, k], approach=name, tasks=f"sweep: {count} {swept.counted}")
                 for k, count in enumerate(swept.counts)]
    return {"rows": rows, "wall_s": round(time.perf_counter() - start, 1)}


def held_out_rows(run: Path, names: list[str]) -> dict:
    """Every approach's final policy on its seeds' held-out combinations (Multi Novelty)."""
    start = time.perf_counter()
    rows = [summary_row(jaxbridge.load(run, name).evaluate(test_protocol="held_out").per_seed(), approach=name)
            for name in names]
    return {"rows": rows, "wall_s": round(time.perf_counter() - start, 1)}


def cycle_rows(run: Path) -> list[dict]:
    """Per approach, seed and cycle: the test solve rate, bridge decisions per test task and (repair runs)
    the seed's learned operators after the cycle."""
    read, rows = jaxbridge.read_experiment(run), []
    for name in read.approaches:
        metrics, learned = read.metrics[name], {}
        if (run / name / jaxbridge.LEARNED_CSV).is_file():
            with open(run / name / jaxbridge.LEARNED_CSV, newline="") as f:
                learned = {(int(r["seed"]), int(r["cycle"])): r["learned_operators"] for r in csv.DictReader(f)}
        for i, seed in enumerate(read.seeds):
            rows += [{"approach": name, "seed": seed, "cycle": c + 1,
                      "test_solve_rate": f"{metrics['test_solve_rate'][i, c]:.4f}",
                      "test_decisions": f"{metrics['test_decisions'][i, c]:.4f}",
                      "learned_operators": learned.get((seed, c + 1), "")}
                     for c in range(metrics["test_solve_rate"].shape[1])]
    return rows


class ModelRepair(Study):
    name, doc, page = "model_repair", __doc__, "docs/results/model_repair.md"
    envs, seeds, stem_by_seeds = ENVS, "0-7", True
    env_help = "the env to run on"
    regenerate = tuple(("--env", env, "--seeds", seeds) for seeds in ("400-431", "0-7") for env in ENVS)

    def flags(self, parser) -> None:
        parser.add_argument("--cost-cycles", type=int, default=None, help="cycles of the cost step (default: --cycles': "
                                                                          "its mean holds the relearning of a run that long)")

    def steps(self, args, steps: Steps) -> dict:
        names, run = list(APPROACHES[args.env]), args.runs / f"{args.env}-{args.seeds}"
        flags = ["--env", args.env, "--approaches", ",".join(names), "--first-seed", str(args.seed_list[0]),
                 "--num-seeds", str(len(args.seed_list)), "--cycles", str(args.cycles), "--no-progress"]
        done = {"run": run, "names": names, "train": steps.run("train", lambda: train_step(run, flags)),
                "sweep": steps.run("sweep", lambda: sweep_step(run)),
                "alone": steps.run("alone", lambda: planner_alone_rows(run, args.env))}
        if "held_out" in jaxbridge.load_env(args.env).test_protocols:
            done["held_out"] = steps.run("held_out", lambda: held_out_rows(run, names))
        if args.env == "coffee":
            protocol = jaxbridge.read_experiment(run).config.test_protocol
            done["oracle"] = steps.run("oracle", lambda: dict(zip(("rows", "wall_s"), oracle_rows(args.env, [protocol], args.seed_list))))
        done["cost"] = steps.run("cost", lambda: run_child(
            ["python", "-m", "bench.timings.training", "--env", args.env, "--seeds", f"0-{min(len(args.seed_list), 4) - 1}",
             "--cycles", str(args.cost_cycles or args.cycles), "--approach", "ours,ours_model_repair"], keep_stdout=True))
        return done

    def write(self, args, done: dict, out: Path) -> dict:
        run, stem = done["run"], self.stem(args)
        write_run_records(run, out, stem)
        write_atomic(out / f"{stem}_cycles.csv", csv_text(cycle_rows(run)))
        extra = [step for step in ("alone", "held_out", "oracle") if step in done]
        for step in extra:
            write_atomic(out / f"{stem}_{step}.csv", csv_text(done[step]["rows"]))
        for name in REPAIR:  # the first seed's learned operators (the whole domain: the run's models/seedN.pddl)
            model = jaxbridge.load(run, name).models[args.seed_list[0]]
            write_atomic(out / f"{stem}_{name}.pddl", model.pddl(learned_only=True))
        return {"approaches": done["names"], "cost": [line for line in done["cost"]["stdout"].splitlines() if "x ours'" in line],
                "schedule": json.loads((run / "schedule.json").read_text()),  # each core's busy seconds
                "steps": {"train": done["train"], "sweep": done["sweep"], "cost": without_stdout(done["cost"]),
                          **{step: {"wall_s": done[step]["wall_s"], "commit": done[step]["commit"]} for step in extra}},
                "wall_s": wall_s(done["train"], done["sweep"], done["cost"], *(done[step] for step in extra))}


STUDY = ModelRepair()

if __name__ == "__main__":
    run_study(STUDY)
