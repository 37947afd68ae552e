"""The departure table: the effect of each departure from the authors' code
that a config switches (docs/design/approaches.md, "Departures"), measured on validation seeds (default 100-115).

    python -m bench.probes.departures --env light_switch_door [--seeds 100-115] [--out runs/departures]
                               [--rows all|NAME,...] [--directions minus,plus]

Per row, our method is trained twice: our default with that one setting set to the authors' value
("minus": what the departure buys us), and the authors' preset with that one setting set to ours
("plus": what it would buy them); plus the two references, our default and the authors' preset. Each
run is an experiment directory under --out/<env>/<run>; a finished run is read back, a started one
resumed, so the command continues where it stopped. Prints the table: mean and IQM test solve rate at
cycles 25 and 100 with 95% bootstrap intervals over the seeds. Each run of 16 seeds takes minutes on
2 cores; `--rows` picks fewer rows (two runs each, plus the two references).
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import jaxbridge
from bench.command import CommandParser
from jaxbridge import TrainConfig
from jaxbridge.utils import stats

CYCLES = (25, 100)  # the table's columns (a shorter run reports its last cycle)


def rows(env: str) -> dict[str, tuple[dict, dict]]:
    """{departure: (our values, the authors' values)} of every switchable departure where they differ on `env`."""
    ours, theirs = jaxbridge.preset_values("jaxbridge", env), jaxbridge.preset_values("authors", env)
    base = jaxbridge.make_config(env)
    groups = {"clip_bootstrap": ("clip_bootstrap", "q_ensemble"),  # Doorknobs' two guards are one departure
              "fit_patience": ("fit_patience", "updates_per_cycle")}  # the fitting schedule is one
    grouped = {f for fields in groups.values() for f in fields}
    fields = [f for f in theirs if f != "preset" and f not in grouped] + list(groups)
    out = {}
    for name in fields:
        members = groups.get(name, (name,))
        mine = {f: ours.get(f, getattr(base.learner if hasattr(base.learner, f) else base, f)) for f in members}
        authors = {f: theirs[f] for f in members}
        if mine != authors:
            out[name] = (mine, authors)
    return out


def runs(env: str, names: list[str], directions: list[str]) -> dict[str, TrainConfig]:
    """{run name: config} of the references and each row's runs."""
    table = rows(env)
    default, authors = jaxbridge.make_config(env), jaxbridge.make_config(env, preset="authors")
    out = {"default": default, "authors": authors}
    for name in names:
        mine, theirs = table[name]
        if "minus" in directions:
            out[f"default-minus-{name}"] = dataclasses.replace(default, **theirs)
        if "plus" in directions:
            out[f"authors-plus-{name}"] = dataclasses.replace(authors, **mine)
    return out


def train_or_read(config: TrainConfig, experiment: Path, devices: list) -> dict:
    """Train `config`'s ours into `experiment` unless it is finished there (resuming a started run);
    its test solve rates' statistics at CYCLES."""
    done = experiment / "ours" / "metrics.csv"
    finished = (done.is_file()
                and jaxbridge.read_experiment(experiment).metrics["ours"]["test_solve_rate"].shape[1] == config.cycles)
    if not finished and (experiment / "experiment.json").is_file():
        jaxbridge.resume(experiment, devices=devices)
    elif not finished:  # every field as given: the config is `config` exactly
        experiment.parent.mkdir(parents=True, exist_ok=True)
        fields = {f.name: getattr(config, f.name) for f in dataclasses.fields(config) if f.name != "env"}
        jaxbridge.train(config.env, "ours", out=experiment.parent, name=experiment.name, devices=devices, **fields)
    cells = jaxbridge.read_experiment(experiment).cells("ours", [min(c, config.cycles) for c in CYCLES])
    return {c: cells[min(c, config.cycles)] for c in CYCLES}


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door", seeds="100-115")
    parser.add_argument("--out", type=Path, default=Path("runs/departures"), help="(default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=100, help="cycles per run (default: %(default)s)")
    parser.add_argument("--rows", default="all", help="departures to measure, comma-separated, or all (default: all)")
    parser.add_argument("--directions", default="minus,plus", help="minus, plus or both (default: %(default)s)")
    args = parser.parse_args()
    devices = jaxbridge.local_devices()  # before JAX starts
    table = rows(args.env)
    names = list(table) if args.rows == "all" else args.rows.split(",")
    unknown = [n for n in names if n not in table]
    if unknown:
        parser.error(f"no departure {', '.join(unknown)} on {args.env}; it has {', '.join(table)}")
    planned = runs(args.env, names, args.directions.split(","))
    results = {}
    for i, (name, config) in enumerate(planned.items(), 1):
        config = dataclasses.replace(config, num_seeds=len(args.seed_list), first_seed=args.seed_list[0],
                                     cycles=args.cycles)
        start = time.perf_counter()
        results[name] = train_or_read(config, args.out / args.env / name, devices)
        print(f"[{i}/{len(planned)}] {name}: {time.perf_counter() - start:.0f} s", flush=True)

    print(f"\n{args.env}, ours, seeds {args.seeds}: test solve rate, mean and IQM [95% bootstrap CI]\n")
    print("| run | what changes | " + " | ".join(f"mean at {c} | IQM at {c}" for c in CYCLES) + " |")
    print("|---|---|" + "---|---|" * len(CYCLES))
    for name, cells in results.items():
        row = name.split("-", 2)[-1] if "-" in name else ""
        mine, theirs = table.get(row, ({}, {}))
        words = lambda values: ", ".join(f"{k} {v}" for k, v in values.items())
        change = (f"{words(theirs)} (ours: {words(mine)})" if name.startswith("default-") else
                  f"{words(mine)} (authors: {words(theirs)})" if name.startswith("authors-") else "reference")
        print(f"| {name} | {change} | " + " | ".join(f"{stats.cell_text(cells[c])} | {stats.cell_text(cells[c], 'iqm')}"
                                                  for c in CYCLES) + " |")


if __name__ == "__main__":
    main()
