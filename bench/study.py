"""The one shape of a study: a bench command that trains on a seed range, as a user would (train.py and
eval.py in child processes, or the public API), and writes committed records under docs/results/.

A study is a small declaration on `Study`: its name (the module bench.studies.NAME, its runs folder, the
ledger's study), its envs and default seeds (the seed policy), the flags of its own, its steps
(`Study.steps`, each kept in a Steps file so that a stopped command continues where it left off) and its
records (`Study.write`). `Study.main` does the rest the same way for every study:

  * one parser (bench/command.py's, as the probes' and timings', test seeds allowed): --env where the study
    has several, --seeds FIRST-LAST, --cycles, --runs, --records, --allow-dirty, --change and --chosen-on,
    then the study's own flags;
  * `begin`, before any work: uncommitted code refused (exit 2) unless --allow-dirty, whose records go
    to RUNS/records; on a test-seed set the run's reasons required and its ledger row appended;
  * the record: the study's fields beside its env, commit, command (`command_line`: the flags that
    differ from their defaults), seeds, cycles, wall time and machine, written whole.
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

import numpy as np

import jaxbridge
from bench.command import CommandParser
from bench.ledger import append, seed_set
from bench.records import RECORDS, ROOT, check_clean, git_commit, machine, on_test_seeds, refuse, run_child, shown
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.stats import bootstrap_ci

# The flags every study shares that do not change what it measures: left out of its command line.
PLUMBING = ("help", "runs", "records", "allow_dirty", "change", "chosen_on")


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
            self.path.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(self.path, json.dumps(self.done, indent=2) + "\n")
        return self.done[name]


class Study:
    name: str  # bench.studies.NAME, runs/NAME, the record's file stem unless `stem` says otherwise
    doc: str
    page: str  # the docs page its records render into
    envs: tuple[str, ...]  # --env's choices; one env: no --env flag
    seeds: str  # the default seed range, FIRST-LAST
    env_help: str = "the env to run on"
    stem_by_seeds: bool = False  # records on a test-seed set named NAME-FIRST-LAST (beside the development seeds')
    regenerate: tuple[tuple[str, ...], ...] = ()  # bench.regenerate's runs of it: each its flags

    # ------------------------------------------------------------ what a study declares

    def flags(self, parser: argparse.ArgumentParser) -> None:
        """The study's own flags."""

    def check(self, parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
        """Refuse flags that do not go together (parser.error)."""

    def steps(self, args: argparse.Namespace, steps: Steps) -> dict:
        """Run every step (each through `steps.run`, so that a finished one is read back); what `write` needs."""
        raise NotImplementedError

    def write(self, args: argparse.Namespace, done: dict, out: Path) -> dict:
        """Write the record's files into `out`; the record's own fields."""
        raise NotImplementedError

    # ------------------------------------------------------------ the same for every study

    @property
    def module(self) -> str:
        return f"bench.studies.{self.name}"

    def parser(self) -> argparse.ArgumentParser:
        parser = CommandParser(self.module, self.doc, envs=self.envs if len(self.envs) > 1 else None,
                               env_help=self.env_help, seeds=self.seeds, test_seeds=True, dirty_records="RUNS/records")
        parser.add_argument("--cycles", type=int, default=100, help="learning cycles (default: %(default)s, the paper's)")
        parser.add_argument("--runs", type=Path, default=ROOT / "runs" / self.name,
                            help=f"where the runs and finished steps go (default: runs/{self.name})")
        parser.add_argument("--records", type=Path, default=RECORDS, help="where the records go (default: docs/results)")
        parser.add_argument("--change", help="on test seeds: what changed since this seed set's previous run of the "
                                             "study and why, in a line (\"first run\" for the first); the ledger's")
        parser.add_argument("--chosen-on", help="on test seeds: the seeds the change was chosen on, e.g. \"development "
                                                "seeds 0-31\" (\"-\" for a first run); the ledger's")
        self.flags(parser)
        return parser

    def parse(self, argv) -> argparse.Namespace:
        parser = self.parser()
        args = parser.parse_args(argv)
        if len(self.envs) == 1:
            args.env = self.envs[0]
        args.on_test_seeds = on_test_seeds(args.seed_list)
        args.command = command_line(parser, args, self.module)
        self.check(parser, args)
        return args

    def begin(self, args: argparse.Namespace) -> None:
        """Before any work: refuse dirty code without --allow-dirty (exit 2), pointing a local try's records
        outside docs/; on a test-seed set, refuse a run without its reasons and append its ledger row."""
        changed = check_clean(self.module, args.allow_dirty)
        if changed:
            args.records = args.runs.resolve() / "records"
            print(f"{self.module}: uncommitted code: the records go to {args.records}", flush=True)
        if args.on_test_seeds:
            try:
                seeds = seed_set(args.seed_list[0], len(args.seed_list))
            except ValueError as err:
                refuse(f"{self.module}: {err}")
            if not (args.change and args.chosen_on):
                refuse(f"{self.module}: a run on test seeds needs --change and --chosen-on (its ledger row)")
            append(seeds, args.env, args.command, args.change, args.chosen_on, git_commit(changed))

    def stem(self, args: argparse.Namespace) -> str:
        return f"{self.name}-{args.seeds}" if self.stem_by_seeds and args.on_test_seeds else self.name

    def main(self, argv=None) -> int:
        args = self.parse(argv)
        self.begin(args)
        start = time.perf_counter()
        args.runs = args.runs.resolve()
        done = self.steps(args, Steps(args.runs / f"{args.env}-{args.seeds}-{args.cycles}-steps.json"))
        check_clean(self.module, args.allow_dirty, during=True)  # no record from code changed under the run
        out = args.records / args.env
        out.mkdir(parents=True, exist_ok=True)
        fields = self.write(args, done, out)
        record = {"env": args.env, "commit": git_commit(), "command": args.command, "seeds": args.seeds,
                  "cycles": args.cycles, **fields, "machine": machine()}
        path = out / f"{self.stem(args)}.json"
        write_atomic(path, json.dumps(record, indent=2) + "\n")
        print(f"{args.command}: done ({time.perf_counter() - start:.0f} s in this call) -> {shown(path.parent)}/; "
              "render the docs with: python -m bench.pages.render")
        return 0


def command_line(parser: argparse.ArgumentParser, args: argparse.Namespace, module: str) -> str:
    """The command as a record and the ledger show it: --env and --seeds, then every flag of what it
    measures that differs from its default (the ledger's reasons and the folders left out)."""
    words = [f"python -m {module}"] + ([f"--env {args.env}"] if "--env" in parser._option_string_actions else [])
    words.append(f"--seeds {args.seeds}")
    for action in parser._actions:
        if action.dest in (*PLUMBING, "env", "seeds") or getattr(args, action.dest) == action.default:
            continue
        value = getattr(args, action.dest)
        shown_value = (",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) or "none"
                       if isinstance(value, list) else f"{value:g}" if isinstance(value, float) else str(value))
        words.append(action.option_strings[0] if action.nargs == 0 else f"{action.option_strings[0]} {shown_value}")
    return " ".join(words)


# ---------------------------------------------------------------- the steps' helpers

def train_step(experiment: Path, flags: list[str]) -> dict:
    """train.py into `experiment`, resuming it where an earlier attempt left it."""
    if (experiment / "experiment.json").is_file():
        return {**run_child(["python", "train.py", "--resume", shown(experiment)]), "resumed": True}
    return run_child(["python", "train.py", *flags, "--out", shown(experiment.parent), "--name", experiment.name])


def seed_flags(args: argparse.Namespace) -> list[str]:
    """train.py's flags for the run's seeds and cycles."""
    return ["--num-seeds", str(len(args.seed_list)), "--first-seed", str(args.seed_list[0]), "--cycles", str(args.cycles)]


def sweep_step(run: Path) -> dict:
    """eval.py's novelty sweep of a run's final bridges."""
    return run_child(["python", "eval.py", shown(run), "--sweep", "novelties"])


def oracle_rows(env: str, protocols: list[str], seeds: list[int]) -> tuple[list[dict], float]:
    """The oracle bridge on every seed's test tasks under each protocol: one row per protocol and seed."""
    start, rows = time.perf_counter(), []
    for protocol in protocols:
        episodes = jaxbridge.hand_made(env, "oracle", protocol).evaluate(seeds=seeds)
        for seed, solve_rate in episodes.per_seed().items():
            rows.append({"protocol": protocol, "seed": seed, "tasks": int((episodes.seeds == seed).sum()),
                         "solve_rate": f"{solve_rate:.4f}"})
    return rows, round(time.perf_counter() - start, 1)


def summary_row(per_seed, **what) -> dict:
    """Per-seed values (Episodes.per_seed()'s, say) as mean [95% CI] over seeds, after `what` names the cell."""
    per_seed = np.asarray(list(per_seed.values()) if isinstance(per_seed, dict) else per_seed, np.float64)
    low, high = bootstrap_ci(per_seed)
    return {**what, "seeds": len(per_seed), "mean": f"{per_seed.mean():.3f}", "low": f"{float(low):.3f}",
            "high": f"{float(high):.3f}"}


def results_rows(experiment: Path, renamed: dict[str, str] | None = None) -> list[dict]:
    with open(experiment / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        row["approach"] = (renamed or {}).get(row["approach"], row["approach"])
    return rows


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


def write_run_records(run: Path, records: Path, name: str) -> None:
    """An experiment's table (results.csv's rows), each seed's last cycle, figure and generalisation sweep
    (eval.py --sweep novelties) as `name`.csv, `name`_seeds.csv, `name`.png, `name`_sweep.csv and
    `name`_sweep.png in `records`."""
    write_atomic(records / f"{name}.csv", csv_text(results_rows(run)))
    write_atomic(records / f"{name}_seeds.csv", csv_text(seed_rows(run)))
    shutil.copy(run / "curves.png", records / f"{name}.png")
    for suffix in ("csv", "png"):
        shutil.copy(run / f"sweep_novelties.{suffix}", records / f"{name}_sweep.{suffix}")


def csv_text(rows: list[dict]) -> str:
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return out.getvalue()


def without_stdout(step: dict) -> dict:
    return {k: v for k, v in step.items() if k != "stdout"}


def wall_s(*steps: dict) -> float:
    return round(sum(step["wall_s"] for step in steps), 1)


def run_study(study: Study) -> None:
    """A study module's `if __name__ == "__main__"`."""
    sys.exit(study.main())
