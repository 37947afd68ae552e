"""The learned object selector on one env's test seeds (issue 37): ours (the env's hand-made features),
ours_closest_object (the paper's rule read off the object view) and ours_learned_selection (every object
a token, attention choosing), written as committed records.

    python -m bench.studies.selection --env light_switch_door --seeds 300-331 --change "a rerun" --chosen-on "development seeds 0-31"
        # -> docs/results/light_switch_door/selection*
    python -m bench.studies.selection --env coffee_distractor --seeds 300-331 --change "a rerun" --chosen-on "development seeds 0-31"
        # a cup nearer the stuck robot than the jug

Steps, each as a user runs it (child processes; wall time and peak memory recorded):
  1. python -m bench.timings.training: seconds per cycle of ours and of the learned selector, 8 seeds x 20
     cycles, a cycle of each in turn in one process (their ratio is the cost figure);
  2. train.py --env E --approaches ... on the seeds (side by side, as train.py schedules them); on a
     distractor env (DISTRACTOR_ENVS) no_feature_selection too;
  3. eval.py RUN --sweep novelties: the final bridges on more and more novelties;
  4. eval.py RUN --approach ours_learned_selection --attention: how often its most attended object at a
     bridge decision is the one the env's fix acts on; with --cycle N, the same of the checkpoints that
     training kept (--keep-cycles) at the table's earlier cycles: how attention changes over training.
It writes selection.csv, selection_sweep.csv, selection.png, selection_sweep.png and selection.json
(commit, commands, times, peak memory, the cost line, the attention lines, machine) into
docs/results/E/; `python -m bench.pages.render` puts the tables into docs/results/selection.md. Test seeds
200-231 and 300-331 are spent for the learned selector (bench/records.SPENT): its next verdict is one run on
400-431.
"""
from __future__ import annotations

import json
from pathlib import Path

import jaxbridge
from bench.records import CYCLES, DISTRACTOR_ENVS, ENVS, run_child, shown
from bench.study import Steps, Study, run_study, seed_flags, sweep_step, train_step, wall_s, without_stdout, write_run_records

APPROACHES = ("ours", "ours_closest_object", "ours_learned_selection")
COST_SEEDS, COST_CYCLES = 8, 20


def approaches(env: str) -> tuple[str, ...]:
    return APPROACHES + (("no_feature_selection",) if env in DISTRACTOR_ENVS else ())


def attention_at(run: Path, flags: list[str]) -> dict:
    """eval.py --attention on the learned selector's run (its latest checkpoint, or that of `--cycle N`)."""
    return run_child(["python", "eval.py", shown(run), "--approach", "ours_learned_selection", "--attention", *flags],
                     keep_stdout=True)


def attention_line(step: dict) -> str:
    """eval.py --attention's per-seed line (the one before its diagnosis)."""
    return next(line for line in step["stdout"].splitlines() if line.startswith("attention on the fix's object"))


class Selection(Study):
    name, doc, page = "selection", __doc__, "docs/results/selection.md"
    envs, seeds, env_help = ENVS + DISTRACTOR_ENVS, "400-431", "the env to compare the selections on"

    def steps(self, args, steps: Steps) -> dict:
        env, run = args.env, args.runs / args.env
        cost = steps.run("cost", lambda: run_child(
            ["python", "-m", "bench.timings.training", "--env", env, "--seeds", f"0-{COST_SEEDS - 1}", "--cycles",
             str(COST_CYCLES), "--approach", "ours,ours_learned_selection"], keep_stdout=True))
        kept = [c for c in CYCLES if c < args.cycles]  # the table's earlier cycles: attention over training
        flags = ["--env", env, "--approaches", ",".join(approaches(env)), *seed_flags(args)]
        train = steps.run("train", lambda: train_step(run, flags + (["--keep-cycles", ",".join(map(str, kept))] if kept else [])))
        return {"run": run, "cost": cost, "train": train, "sweep": steps.run("sweep", lambda: sweep_step(run)),
                "looked": {c: steps.run(f"attention_{c}", lambda c=c: attention_at(run, ["--cycle", str(c)])) for c in kept},
                "attention": steps.run("attention", lambda: attention_at(run, []))}

    def write(self, args, done: dict, out: Path) -> dict:
        run, names, looked, attention = done["run"], approaches(args.env), done["looked"], done["attention"]
        jaxbridge.write_comparison(run, jaxbridge.run_labels(names), args.env)
        write_run_records(run, out, self.name)
        elapsed = {name: json.loads((run / name / "summary.json").read_text())["elapsed_s"] for name in names}
        timed = (done["cost"], done["train"], done["sweep"], attention, *looked.values())
        return {"approaches": list(names), "elapsed_s": elapsed, "cost": done["cost"]["stdout"].strip().splitlines()[-1],
                "attention": attention_line(attention), "attention_diagnosis": attention["stdout"].strip().splitlines()[-1],
                "attention_over_training": {c: attention_line(step).rpartition("; all ")[2] for c, step in looked.items()},
                "steps": {"cost": without_stdout(done["cost"]), "train": done["train"], "sweep": done["sweep"],
                          "attention": without_stdout(attention),
                          **{f"attention_{c}": without_stdout(step) for c, step in looked.items()}},
                "wall_s": wall_s(*timed)}


STUDY = Selection()

if __name__ == "__main__":
    run_study(STUDY)
