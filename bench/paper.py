"""One env's headline on the test seeds, regenerated from nothing and written as committed records.

    python -m bench.paper --env light_switch_door --change "a rerun" --chosen-on "development seeds 0-31"   # -> docs/results/light_switch_door/
    python -m bench.paper --env doorknobs --runs /tmp/paper --change "first run" --chosen-on -

--change and --chosen-on are the run's row in the test-seed ledger (docs/results/ledger.csv, bench/ledger.py),
written before any work; uncommitted code is refused (--allow-dirty: a local try, records outside docs/).

Each step runs as a user would run it (the same commands, in child processes; wall time and peak memory
of each are recorded):
  1. train.py --env E on the test seeds: the approaches of the paper's figure for E (train.py's default);
  2. train.py --env E --approaches ours --preset authors on the same seeds;
  3. the oracle bridge on the same test tasks, under each of those runs' test protocols: the ceiling;
  4. eval.py RUN --sweep novelties: every approach's final bridges on more and more novelties.
It then writes docs/results/E/: results.csv (every run's statistics at every cycle), oracle.csv (the
ceiling per seed), sweep.csv, figure.png, sweep.png and run.json (commit, commands, wall times, peak
memory, machine). `python -m bench.render` turns the records into the tables of docs/RESULTS.md.

A step that has finished is not run again (steps.json in the runs directory says which have), so a
stopped command continues where it left off; training resumes from its checkpoints.
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import shutil
import sys
import time
from pathlib import Path

import jaxbridge
from bench.ledger import add_reason_flags, append, seed_set
from bench.records import (ENVS, RECORDS, ROOT, TEST_SEEDS, TEST_SETS, check_clean, git_commit, machine, refuse, run_child,
                           shown)
from bench.results_blocks import PRESET_RUN
from jaxbridge.utils.files import write_atomic


def train_step(experiment: Path, flags: list[str]) -> dict:
    """train.py into `experiment`, resuming it where an earlier attempt left it."""
    if (experiment / "experiment.json").is_file():
        return {**run_child(["python", "train.py", "--resume", shown(experiment)]), "resumed": True}
    return run_child(["python", "train.py", *flags, "--out", shown(experiment.parent), "--name", experiment.name])


def oracle_rows(env: str, protocols: list[str], seeds: list[int]) -> tuple[list[dict], float]:
    """The oracle bridge on every seed's test tasks under each protocol: one row per protocol and seed."""
    start, rows = time.perf_counter(), []
    for protocol in protocols:
        episodes = jaxbridge.hand_made(env, "oracle", protocol).evaluate(seeds=seeds)
        for seed, solve_rate in episodes.per_seed().items():
            rows.append({"protocol": protocol, "seed": seed, "tasks": int((episodes.seeds == seed).sum()),
                         "solve_rate": f"{solve_rate:.4f}"})
    return rows, round(time.perf_counter() - start, 1)


def results_rows(experiment: Path, renamed: dict[str, str] | None = None) -> list[dict]:
    with open(experiment / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        row["approach"] = (renamed or {}).get(row["approach"], row["approach"])
    return rows


def write_run_records(run: Path, records: Path, name: str) -> None:
    """An experiment's table (results.csv's rows), each seed's last cycle, figure and generalisation sweep
    (eval.py --sweep novelties) as `name`.csv, `name`_seeds.csv, `name`.png, `name`_sweep.csv and
    `name`_sweep.png in `records`."""
    records.mkdir(parents=True, exist_ok=True)
    (records / f"{name}.csv").write_text(csv_text(results_rows(run)))
    (records / f"{name}_seeds.csv").write_text(csv_text(seed_rows(run)))
    shutil.copy(run / "curves.png", records / f"{name}.png")
    for suffix in ("csv", "png"):
        shutil.copy(run / f"sweep_novelties.{suffix}", records / f"{name}_sweep.{suffix}")


def seed_rows(experiment: Path) -> list[dict]:
    """Each run's seeds at its last cycle (test solve rate, smooth test reward): what a ratio between two
    approaches needs for its paired interval."""
    rows, read = [], jaxbridge.read_experiment(experiment)
    for run in sorted(read.metrics):
        metrics = read.metrics[run]
        rows += [{"approach": run, "seed": seed, "cycle": metrics["test_solve_rate"].shape[1],
                  "test_solve_rate": f"{metrics['test_solve_rate'][i, -1]:.4f}",
                  "test_smooth_reward": f"{metrics['test_smooth_reward'][i, -1]:.4f}"}
                 for i, seed in enumerate(read.seeds)]
    return rows


def csv_text(rows: list[dict]) -> str:
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return out.getvalue()


class Steps:
    """The finished steps' figures, kept beside the runs so that a stopped command does not redo them."""

    def __init__(self, path: Path):
        self.path = path
        self.done = json.loads(path.read_text()) if path.is_file() else {}

    def run(self, name: str, step) -> dict:
        """`step()`'s figures, run now unless an earlier call finished it; saved at once."""
        if name not in self.done:
            commit = git_commit()  # the code the step runs (a later record step may be at another commit)
            self.done[name] = {**step(), "commit": commit}
            self.path.write_text(json.dumps(self.done, indent=2) + "\n")
        return self.done[name]


def test_seed_args(module: str, doc: str, env_help: str, argv, envs: tuple[str, ...] = ENVS,
                   seed_set: int = TEST_SEEDS[0]) -> argparse.Namespace:
    """The flags of a bench command that trains on a test-seed set and writes records; the run's ledger
    row appended and the records' folder settled (`begin`)."""
    parser = argparse.ArgumentParser(prog=f"python -m {module}", description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    runs = module.removeprefix("bench.")
    parser.add_argument("--env", required=True, choices=envs, help=env_help)
    parser.add_argument("--runs", type=Path, default=ROOT / "runs" / runs,
                        help=f"where the training runs go (default: runs/{runs})")
    parser.add_argument("--records", type=Path, default=RECORDS,
                        help="where the env's records go (default: docs/results)")
    parser.add_argument("--seed-set", type=int, default=seed_set, choices=sorted(TEST_SETS),
                        help="the test-seed set's first seed (default: %(default)s)")
    parser.add_argument("--num-seeds", type=int, default=TEST_SETS[seed_set],
                        help="seeds of the set, from its first (default: %(default)s; fewer only to try the command out)")
    parser.add_argument("--cycles", type=int, default=100, help="learning cycles (default: %(default)s, the paper's)")
    parser.add_argument("--allow-dirty", action="store_true",
                        help="run on code with uncommitted changes (a local try): the records go to RUNS/records, "
                             "not docs/; the ledger row is written all the same")
    add_reason_flags(parser)
    args = parser.parse_args(argv)
    args.module, args.seed_default = module, seed_set
    begin(args)
    return args


def begin(args: argparse.Namespace) -> None:
    """Before any work: refuse dirty code without --allow-dirty (exit 2), append the run's ledger row,
    and point args.records where this run's records may go (outside docs/ for dirty code)."""
    try:
        seeds = seed_set(args.seed_set, args.num_seeds)
    except ValueError as err:
        refuse(f"{args.module}: {err}")
    changed = check_clean(args.module, args.allow_dirty)
    if changed:
        args.records = args.runs.resolve() / "records"
        print(f"{args.module}: uncommitted code: the records go to {args.records}", flush=True)
    append(seeds, args.env, command_line(args), args.change, args.chosen_on, git_commit(changed))


def command_line(args: argparse.Namespace) -> str:
    """The command as a record and the ledger show it: the flags that differ from their defaults."""
    flags = (("seed-set", args.seed_set, args.seed_default), ("num-seeds", args.num_seeds, TEST_SETS[args.seed_set]),
             ("cycles", args.cycles, 100))
    return f"python -m {args.module} --env {args.env}" + "".join(f" --{f} {v}" for f, v, default in flags if v != default)


def seed_flags(args: argparse.Namespace) -> list[str]:
    """train.py's flags for the run's seeds and cycles."""
    return ["--num-seeds", str(args.num_seeds), "--first-seed", str(args.seed_set), "--cycles", str(args.cycles)]


def seeds_text(args: argparse.Namespace) -> str:
    return seed_set(args.seed_set, args.num_seeds)  # checked in `begin`


def records_folder(args: argparse.Namespace) -> Path:
    """The env's records folder, made, before the first record file is written; refused (exit 2) if the
    code changed under a run that began clean."""
    check_clean(args.module, args.allow_dirty, during=True)
    out = args.records / args.env
    out.mkdir(parents=True, exist_ok=True)
    return out


def write_record(path: Path, record: dict, start: float) -> int:
    """Write a bench command's record (its folder from `records_folder`) and say what it did; its exit status."""
    write_atomic(path, json.dumps(record, indent=2) + "\n")
    print(f"{record['command']}: done ({time.perf_counter() - start:.0f} s in this call) -> {path.parent}/; "
          "render the docs with: python -m bench.render")
    return 0


def main(argv=None) -> int:
    args = test_seed_args("bench.paper", __doc__, "the env whose headline to regenerate", argv)
    seeds = seed_flags(args)
    env, runs = args.env, args.runs.resolve()
    runs.mkdir(parents=True, exist_ok=True)
    steps = Steps(runs / f"{env}-steps.json")
    main_run, preset_run = runs / env, runs / f"{env}_authors"
    start = time.perf_counter()

    train = steps.run("train", lambda: train_step(main_run, ["--env", env, *seeds]))
    preset = steps.run("train_authors_preset", lambda: train_step(
        preset_run, ["--env", env, "--approaches", "ours", "--preset", "authors", *seeds]))
    experiment, preset_config = jaxbridge.read_experiment(main_run), jaxbridge.read_experiment(preset_run).config
    config, approaches = experiment.config, list(experiment.approaches)
    protocols = list(dict.fromkeys([config.test_protocol, preset_config.test_protocol]))
    test_seeds = list(range(args.seed_set, args.seed_set + args.num_seeds))
    oracle = steps.run("oracle", lambda: dict(zip(("rows", "wall_s"), oracle_rows(env, protocols, test_seeds))))
    sweep = steps.run("sweep", lambda: run_child(["python", "eval.py", shown(main_run), "--sweep", "novelties"]))

    out = records_folder(args)
    # the tables and figure as this checkout draws them
    jaxbridge.write_comparison(main_run, title=env)
    jaxbridge.write_comparison(preset_run, title=env)
    rows = results_rows(main_run) + results_rows(preset_run, {"ours": PRESET_RUN})
    (out / "results.csv").write_text(csv_text(rows))
    (out / "oracle.csv").write_text(csv_text(oracle["rows"]))
    shutil.copy(main_run / "sweep_novelties.csv", out / "sweep.csv")
    shutil.copy(main_run / "sweep_novelties.png", out / "sweep.png")
    shutil.copy(main_run / "curves.png", out / "figure.png")
    record = {"env": env, "commit": git_commit(), "command": command_line(args), "seeds": seeds_text(args),
              "approaches": approaches,
              "config_version": json.loads((main_run / "ours" / "config.json").read_text())["config_version"],
              "test_protocols": {"main": protocols[0], "authors_preset": protocols[-1]},
              "steps": {"train": train, "train_authors_preset": preset,
                        "oracle": {"protocols": protocols, "wall_s": oracle["wall_s"]}, "sweep": sweep},
              "wall_s": round(sum(s["wall_s"] for s in (train, preset, sweep)) + oracle["wall_s"], 1),
              "machine": machine()}
    return write_record(out / "run.json", record, start)


if __name__ == "__main__":
    sys.exit(main())
