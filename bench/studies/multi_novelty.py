"""Does one bridge suffice where several kinds of novelty stall the planner? (issue 54, Multi Novelty)

    python -m bench.studies.multi_novelty                       # development seeds 0-7, 100 cycles
    python -m bench.studies.multi_novelty --seeds 300-331 --change "first run" --chosen-on "development seeds 0-7"
    python -m bench.studies.multi_novelty --cycles 20 --allow-dirty   # a local try: records under RUNS/records

Steps, each as a user runs it (child processes; wall time and peak memory recorded; a finished step is
not run again, and training resumes from its checkpoints):
  1. train.py --env multi_novelty (its default approaches, or --approaches) on the seeds: the test tasks
     (--keep-cycles: the checkpoints of the table's earlier cycles, for the held-out combinations);
  2. eval.py RUN --sweep novelties: the final bridges on more and more novelties;
  3. each approach's bridges at the table's cycles on each seed's held-out combinations (eval.py RUN
     --test-protocol held_out [--cycle N]: doors with both locks; the training does not depend on the
     test tasks, so the bridges are those a run testing on them would train), and its final bridges on
     tasks holding one kind alone (KIND_TASKS per kind, the same for every seed): which kinds it solves;
  4. python -m bench.timings.training: seconds per cycle of each learned approach, a cycle of each in turn in
     one process, as a ratio to ours'.
Writes into docs/results/multi_novelty/ (on a test-seed set its ledger row first; code with uncommitted
changes is refused without --allow-dirty): STEM.csv, STEM_seeds.csv, STEM.png, STEM_sweep.csv/png (the
test tasks' run, as the other studies' records), STEM_held_out.csv, STEM_kinds.csv and STEM.json (commit,
commands, wall times, the cost lines, machine); STEM is multi_novelty on development seeds and
multi_novelty-FIRST-LAST on a test-seed set. `python -m bench.pages.render` puts them into
docs/results/multi_novelty.md.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

import jaxbridge
from bench.records import CYCLES, run_child
from bench.study import (Steps, Study, csv_text, run_study, summary_row, sweep_step, train_step, wall_s, without_stdout,
                         write_run_records)
from jaxbridge.utils.files import write_atomic

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


def greedy_rows(run: Path, approaches: list[str], kept: list[int]) -> dict:
    """Each approach's greedy bridges on its seeds' held-out combinations (at the `kept` cycles and the
    last), and its final bridges on each kind alone; with the seconds it took."""
    start, held_out, kinds = time.perf_counter(), [], []
    for name in approaches:
        for cycle in [*kept, None]:
            policy = jaxbridge.load(run, name, cycle)
            held_out.append(summary_row(policy.evaluate(test_protocol="held_out").per_seed(), approach=name, cycle=policy.cycle))
        kinds += [summary_row(policy.evaluate(tasks=specs).per_seed(), approach=name, kind=kind) for kind, specs in kind_tasks().items()]
    return {"held_out": held_out, "kinds": kinds, "wall_s": round(time.perf_counter() - start, 1)}


class MultiNovelty(Study):
    name, doc, page = "multi_novelty", __doc__, "docs/results/multi_novelty.md"
    envs, seeds, stem_by_seeds = (ENV,), "0-7", True
    regenerate = (("--seeds", "300-331"), ("--seeds", "0-7"))

    def flags(self, parser) -> None:
        parser.add_argument("--approaches", default=None, help="train.py's --approaches (default: the env's default)")
        parser.add_argument("--cost-cycles", type=int, default=10, help="cycles of the cost step (default: %(default)s)")

    def steps(self, args, steps: Steps) -> dict:
        names = args.approaches.split(",") if args.approaches else jaxbridge.default_approaches(jaxbridge.load_env(ENV))
        run, kept = args.runs / f"{self.stem(args)}-test", [c for c in CYCLES if c < args.cycles]
        flags = ["--env", ENV, "--approaches", ",".join(names), "--first-seed", str(args.seed_list[0]), "--num-seeds",
                 str(len(args.seed_list)), "--cycles", str(args.cycles), "--no-progress"]
        trained = steps.run("train", lambda: train_step(run, flags + (["--keep-cycles", ",".join(map(str, kept))] if kept else [])))
        sweep = steps.run("sweep", lambda: sweep_step(run))
        greedy = steps.run("greedy", lambda: greedy_rows(run, names, kept))
        learned = ["ours"] + [n for n in names if n not in NOT_LEARNED and n != "ours"]
        cost = steps.run("cost", lambda: run_child(["python", "-m", "bench.timings.training", "--env", ENV, "--seeds",
                                                    f"0-{min(len(args.seed_list), 8) - 1}", "--cycles", str(args.cost_cycles),
                                                    "--approach", ",".join(learned)], keep_stdout=True))
        return {"run": run, "names": names, "train": trained, "sweep": sweep, "greedy": greedy, "cost": cost}

    def write(self, args, done: dict, out: Path) -> dict:
        run, stem, greedy, cost = done["run"], self.stem(args), done["greedy"], done["cost"]
        write_run_records(run, out, stem)
        write_atomic(out / f"{stem}_held_out.csv", csv_text(greedy["held_out"]))
        write_atomic(out / f"{stem}_kinds.csv", csv_text(greedy["kinds"]))
        return {"approaches": done["names"], "cost": [line for line in cost["stdout"].splitlines() if "x ours'" in line],
                "schedule": json.loads((run / "schedule.json").read_text()),  # each core's busy seconds
                "steps": {"train": done["train"], "sweep": done["sweep"],
                          "greedy": {"wall_s": greedy["wall_s"], "commit": greedy["commit"]}, "cost": without_stdout(cost)},
                "wall_s": wall_s(done["train"], done["sweep"], greedy, cost)}


STUDY = MultiNovelty()

if __name__ == "__main__":
    run_study(STUDY)
