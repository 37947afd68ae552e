"""The blocks of docs/RESULTS.md and the study pages under docs/results/: each env's headline table and its
generalisation sweep, from bench.studies.paper's records and the authors' logged numbers."""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np

import jaxbridge
from bench.records import CYCLES, DISTRACTOR_ENVS, ENVS, PRESET_RUN, RECORDS, current_command, on_test_seeds
from envs_jax import VARIANTS
from jaxbridge.utils import stats

ENV_TITLES = {"light_switch_door": "Light Switch Door", "doorknobs": "Doorknobs", "coffee": "Coffee",
              "light_switch_panel": "Light Switch Panel", "coffee_distractor": "Coffee Distractor",
              "doorknobs_distractor": "Doorknobs Distractor", "multi_novelty": "Multi Novelty"}


def commit_text(record: dict) -> str:
    """The code a record came from, whole: its commit, a word where the tree had uncommitted changes, and
    the commits of its steps that ran at another one (a resumed or kept step)."""
    def whole(commit: str) -> str:
        head, dirty, _ = commit.partition("+changes")
        return f"{head}{' with uncommitted changes' if dirty else ''}"
    others = {name: step["commit"] for name, step in record.get("steps", {}).items()
              if isinstance(step, dict) and step.get("commit", record["commit"]) != record["commit"]}
    steps = "; ".join(f"{name} at {whole(commit)}" for name, commit in others.items())
    return f"commit {whole(record['commit'])}" + (f" (its steps: {steps})" if steps else "")


def restarted(record: dict) -> bool:
    """A step restarted after a stop (paper.train_step's "resumed"), or a record holding one: timed from its
    restart, since the stopped attempt's seconds are not known."""
    return bool(record.get("resumed")) or any(isinstance(step, dict) and step.get("resumed")
                                              for step in record.get("steps", {}).values())


def seconds_text(record: dict) -> str:
    """A record's or step's wall time; a lower bound where it was `restarted`, and it says so."""
    if restarted(record):
        return f"at least {record['wall_s']:,.0f} s (timed from a restart)"
    return f"{record['wall_s']:,.0f} s"


def ledger_table() -> str:
    """RESULTS.md's view of the test-seed ledger: per seed set, env and study, how many rows (runs and
    record writes) it has and the latest row's change and the seeds it was chosen on."""
    from bench import ledger
    groups: dict[tuple, list[dict]] = {}
    for row in ledger.rows():
        study = re.search(r"bench\.[\w.]+\w", current_command(row["ran"]))
        name = row["ran"] if ledger.is_spent(row) else study[0] if study else "by hand"
        groups.setdefault((row["seeds"], row["env"], name), []).append(row)
    first = ledger.RECONSTRUCTED
    lines = [f"Its first {first['rows']} rows were not written as their runs started: {first['at']}, which began the "
             "ledger, reconstructed them from the committed records' history (each record's commit, steps and "
             "commands); every later row was appended by its command as the run started.", "",
             "| seeds | env | study | rows | first, last date | the latest change | chosen on |", "|---|---|---|---|---|---|---|"]
    for (seeds, env, study), rows in groups.items():
        latest = next(r for r in reversed(rows) if r["change"] != "-") if any(r["change"] != "-" for r in rows) else rows[-1]
        lines.append(f"| {seeds} | {env} | {study} | {len(rows)} | {rows[0]['date']}, {rows[-1]['date']} | "
                     f"{latest['change']} | {latest['chosen_on']} |")
    return "\n".join(lines) + "\n"


def label(run: str) -> str:
    return "ours, `--preset authors`" if run == PRESET_RUN else jaxbridge.run_labels([run])[run]


# ---------------------------------------------------------------- reading the records

def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_json(path: Path) -> dict | None:
    return json.loads(path.read_text()) if path.is_file() else None


def env_record(env: str) -> dict | None:
    """An env's bench.studies.paper records, or None before bench.studies.paper has written them."""
    folder = RECORDS / env
    run = read_json(folder / "run.json")
    if run is None:
        return None
    return {"run": run, "results": read_csv(folder / "results.csv"), "oracle": read_csv(folder / "oracle.csv"),
            "sweep": read_csv(folder / "sweep.csv")}


def authors_rows(env: str) -> dict[str, dict[tuple[str, str], dict]]:
    """{approach: {(quantity, cycle): row}} of the authors' logged numbers for `env`."""
    out: dict[str, dict] = {}
    for row in read_csv(RECORDS / "authors.csv"):
        if row["env"] == env:
            out.setdefault(row["approach"], {})[(row["quantity"], row["cycle"])] = row
    return out


# ---------------------------------------------------------------- cells

def stat_cell(row: dict, name: str, signed: bool = False) -> str:
    """Mean [95% CI] and, beside it, IQM [95% CI] of curve `name` in a results.csv row."""
    f = lambda s: float(row[f"{name}_{s}"])
    mean = stats.ci_text(f("mean"), (f("mean_low"), f("mean_high")), signed)
    iqm = stats.ci_text(f("iqm"), (f("iqm_low"), f("iqm_high")), signed)
    return f"{mean}<br>IQM {iqm}"


def drop_cell(row: dict) -> str:
    """The last cycle's statistic minus its best before, where the record has it."""
    return stat_cell(row, "test_drop", signed=True) if "test_drop_mean" in row else ""


def mean_ci(values: list[float]) -> str:
    """Mean [95% bootstrap CI] over seeds of per-seed values."""
    described = stats.describe(np.asarray(values))
    return stats.ci_text(float(described["mean"]), (float(described["mean_low"]), float(described["mean_high"])))


def authors_cell(row: dict | None) -> str:
    """The authors' number as their logs give it: mean [lowest, highest seed] (note)."""
    if row is None:
        return ""
    low, high = row["min"], row["max"]
    return (row["mean"] + (f" [{low}, {high}]" if low and high and low != high else "")
            + (f" ({row['note']})" if row["note"] else ""))


def authors_test_cells(theirs: dict, cycles) -> list[str]:
    """The authors' test solve rate at `cycles`; a single evaluation (pure planning) in the first cell."""
    single = theirs.get(("test_solve_rate", ""))
    if single:
        return [authors_cell(single)] + [""] * (len(cycles) - 1)
    return [authors_cell(theirs.get(("test_solve_rate", str(c)))) for c in cycles]


# ---------------------------------------------------------------- blocks

def by_approach(results: list[dict]) -> tuple[dict[str, dict[int, dict]], int]:
    """results.csv rows as {approach: {cycle: row}}, and the last cycle."""
    by_run: dict[str, dict[int, dict]] = {}
    for row in results:
        by_run.setdefault(row["approach"], {})[int(row["cycle"])] = row
    return by_run, max(max(cycles) for cycles in by_run.values())


def table_header(last: int) -> list[str]:
    return ["| approach | cycle " + " | cycle ".join(map(str, CYCLES)) + f" | smooth reward at {last} (test) | (training) "
            f"| cycle {last} minus the best before |", "|---|" + "---|" * (len(CYCLES) + 3)]


def approach_row(name: str, cycles: dict[int, dict], last: int, shown: str | None = None) -> str:
    """An approach's test solve rate at CYCLES, smooth rewards and drop from its best, from results.csv rows;
    `shown`: its label in the table (default: the approach's)."""
    return (f"| **{shown or label(name)}** | " + " | ".join(stat_cell(cycles[c], "test_solve_rate") if c in cycles else ""
                                                 for c in CYCLES)
            + f" | {stat_cell(cycles[last], 'test_smooth_reward')} | {stat_cell(cycles[last], 'train_smooth_reward')} "
            f"| {drop_cell(cycles[last])} |")


def headline(env: str) -> str:
    """RESULTS.md's table for `env`: every approach, ours with --preset authors, the oracle's ceiling
    under each test protocol, and the authors' logged numbers, with the command that made them."""
    record = env_record(env)
    if record is None:
        return f"_Not generated yet: `python -m bench.studies.paper --env {env}`._\n"
    run = record["run"]
    by_run, last = by_approach(record["results"])
    lines = [f"Test seeds {run['seeds']}, {int(record['results'][0]['seeds'])} seeds x {last} cycles; each cell: "
             "mean [95% CI] over seeds, IQM [95% CI] beside it; the authors' rows: their mean [lowest, highest "
             "seed] (docs/results/authors.csv).", "", *table_header(last)]
    authors = authors_rows(env)
    for name, cycles in by_run.items():
        lines.append(approach_row(name, cycles, last))
        if name in authors and name != PRESET_RUN:
            lines.append(authors_row(name, authors[name]))
    lines += ceiling_rows(record) + ["", provenance(run), "", f"![{ENV_TITLES[env]}, test seeds](results/{env}/figure.png)"]
    return "\n".join(lines) + "\n"


def authors_row(name: str, theirs: dict) -> str:
    seeds = next(iter(theirs.values()))["seeds_with_logs"]
    return (f"| {label(name)}, the authors ({seeds} seed{'' if seeds == '1' else 's'}) | " + " | ".join(authors_test_cells(theirs, CYCLES))
            + f" | {authors_cell(theirs.get(('smooth_reward', '100')))} | | |")


def ceiling_rows(record: dict) -> list[str]:
    """The oracle's ceiling under each test protocol of the record's runs, as a flat table row."""
    rows = []
    for protocol in record["run"]["steps"]["oracle"]["protocols"]:
        which = [k for k, v in record["run"]["test_protocols"].items() if v == protocol]
        cell = ceiling(record, protocol)
        rows.append(f"| the oracle's ceiling ({protocol} test tasks: "
                    + " and ".join("the runs above" if k == "main" else "the preset's" for k in which) + ") | "
                    + " | ".join([cell] * len(CYCLES)) + f" | {cell} | | |")
    return rows


def provenance(run: dict) -> str:
    """The command that made the record, its time, memory, machine and commit."""
    steps = run["steps"]
    return (f"`{rerun_command(run)}`: {seconds_text(run)} on {machine_text(run['machine'])} (training "
            f"{seconds_text(steps['train'])}, peak RSS {steps['train']['peak_rss_mib'] / 2**10:.1f} GiB; "
            f"`--preset authors` {seconds_text(steps['train_authors_preset'])}), {commit_text(run)}.")


def ceiling(record: dict, protocol: str) -> str:
    """The oracle's mean test solve rate [95% CI] over seeds under `protocol`."""
    return mean_ci([float(r["solve_rate"]) for r in record["oracle"] if r["protocol"] == protocol])


def stat_row(record: dict, run: str) -> dict:
    """The figures the README quotes for `run`: seeds, mean [95% CI] at cycles 10 and 100, the ceiling."""
    rows = {int(r["cycle"]): r for r in record["results"] if r["approach"] == run}
    value = lambda c, s: float(rows[c][f"test_solve_rate_{s}"])
    mean = lambda c: stats.ci_text(value(c, "mean"), (value(c, "mean_low"), value(c, "mean_high")))
    return {"seeds": int(rows[1]["seeds"]), "at10": mean(10), "at100": mean(max(rows)),
            "ceiling": ceiling(record, record["run"]["test_protocols"]["main"])}


def machine_text(machine: dict) -> str:
    return f"{machine['cpu_cores']} {machine['processor']} cores (jax {machine['jax']})"


def sweep_table(env: str) -> str:
    """generalisation.md's table for `env`: solve rate per novelty count (rows) and approach (columns)."""
    record = env_record(env)
    if record is None:
        return f"_Not generated yet: `python -m bench.studies.paper --env {env}`._\n"
    run = record["run"]
    return (novelty_table(env, record["sweep"], run["seeds"], step_command(run, "sweep"))
            + f"\n![{ENV_TITLES[env]}, generalisation](./{env}/sweep.png)\n")


def seeds_label(seeds: str) -> str:
    """"test seeds 300-331" or "development seeds 0-7": a record's seeds (FIRST-LAST) with what they are."""
    return f"{'test' if on_test_seeds([int(seeds.partition('-')[0])]) else 'development'} seeds {seeds}"


def novelty_table(env: str, sweep_rows: list[dict], seeds: str, command: str) -> str:
    """Solve rate per novelty count (rows) and line (columns) of a sweep.csv: mean [95% CI] over seeds."""
    counted = counted_column(sweep_rows)
    lines_by_label: dict[str, dict[int, list[float]]] = {}
    for row in sweep_rows:
        lines_by_label.setdefault(row["line"], {}).setdefault(int(row[counted]), []).append(
            float(row["solve_rate"]) if row["solve_rate"] else float("nan"))
    counts = sorted(next(iter(lines_by_label.values())))
    tasks = sweep_rows[0]["tasks"]
    sweep = jaxbridge.load_env(env).novelty_sweep
    out = [f"The number of {sweep.counted} {sweep.setting}: the final bridges of {seeds_label(seeds)}, "
           f"{tasks} tasks per count and seed; mean [95% CI] over seeds (`{command}`).", "",
           f"| {counted.replace('_', ' ')} | " + " | ".join(lines_by_label) + " |", "|---|" + "---|" * len(lines_by_label)]
    for k in counts:
        cells = ["n/a" if np.isnan(by_count[k]).all() else mean_ci(by_count[k]) for by_count in lines_by_label.values()]
        out.append(f"| {k} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def plan_repair(env: str) -> str:
    """docs/results/plan_repair.md's table for `env`: ours and the two plan-repair baselines on the test seeds,
    then their generalisation sweep (bench.studies.plan_repair's records)."""
    folder = RECORDS / env
    run = read_json(folder / "plan_repair.json")
    if run is None:
        return f"_Not generated yet: `python -m bench.studies.plan_repair --env {env}`._\n"
    results = read_csv(folder / "plan_repair.csv")
    by_run, last = by_approach(results)
    lines = [f"Test seeds {run['seeds']}, {int(results[0]['seeds'])} seeds x {last} cycles; each cell: mean [95% CI] "
             "over seeds, IQM [95% CI] beside it.", "", *table_header(last)]
    lines += [approach_row(name, cycles, last) for name, cycles in by_run.items()]
    lines += ["", f"`{rerun_command(run)}`: {seconds_text(run)} on {machine_text(run['machine'])}, "
              f"{commit_text(run)}.", "", f"![{ENV_TITLES[env]}, plan repair]({env}/plan_repair.png)", "",
              novelty_table(env, read_csv(folder / "plan_repair_sweep.csv"), run["seeds"], step_command(run, "sweep"))]
    return "\n".join(lines)


def cycles_to(cycles: dict[int, dict], level: float = 0.9) -> str:
    """The first cycle whose mean test solve rate over seeds reaches `level`, from results.csv rows."""
    return next((str(c) for c in sorted(cycles) if float(cycles[c]["test_solve_rate_mean"]) >= level), "not reached")


def learners(env: str) -> str:
    """docs/results/learners.md's table of ours with each learner on `env`'s test seeds (bench.studies.learners' records): test
    solve rates, cycles to a mean of 0.9, each run's seconds per cycle and peak memory."""
    folder = RECORDS / env
    run = read_json(folder / "learners.json")
    if run is None:
        return f"_Not generated yet: `python -m bench.studies.learners --env {env}`._\n"
    by_run, last = by_approach(read_csv(folder / "learners.csv"))
    shown = {name: f"ours, {text}" for name, text in run["labels"].items()}
    lines = [f"Test seeds {run['seeds']}, {last} cycles; each cell: mean [95% CI] over seeds, IQM [95% CI] beside it.",
             "", *table_header(last)]
    lines += [approach_row(name, cycles, last, shown[name]) for name, cycles in by_run.items()]
    lines += ["", "| learner | cycles to a mean of 0.9 | seconds per cycle (the whole run's wall time / cycles) "
              "| peak memory (MiB) |", "|---|---|---|---|"]
    for name, cycles in by_run.items():
        step = run["steps"][name]
        per_cycle = f"{step['wall_s'] / last:.2f}" + (" or more (timed from a restart)" if restarted(step) else "")
        lines.append(f"| {shown[name]} | {cycles_to(cycles)} | {per_cycle} | {step['peak_rss_mib']:,.0f} |")
    lines += ["", f"`{rerun_command(run)}`: {seconds_text(run)} on {machine_text(run['machine'])} (the two trainings "
              f"one after another), {commit_text(run)}.", "", f"![{ENV_TITLES[env]}, learners]({env}/learners.png)", ""]
    return "\n".join(lines)


def bar_text(value: float, interval: tuple[float, float] | None, bar: float, source: str, at_least: bool = True) -> str:
    """A measured figure against its bar, judged by one rule (stats.verdict): "0.80 [0.71, 0.88]: missed
    (the bar, issue 55: 0.9 or more)"."""
    digits = 3 if f"{value:.2f}" == f"{bar:.2f}" else 2  # 0.897 is not shown as the bar it misses
    shown = f"{value:.{digits}f}" + (f" [{interval[0]:.2f}, {interval[1]:.2f}]" if interval is not None else "")
    return (f"{shown}: {stats.verdict(value, interval, bar, at_least)} (the bar, {source}: {bar:g} "
            f"{'or more' if at_least else 'at most'})")


def seed_values(rows: list[dict], approach: str, column: str) -> np.ndarray:
    """An approach's per-seed values of `column`, in seed order (a *_seeds.csv's rows)."""
    return np.array([float(r[column]) for r in sorted(rows, key=lambda r: int(r["seed"])) if r["approach"] == approach])


def counted_column(sweep_rows: list[dict]) -> str:
    """A sweep.csv's column of what its counts count (e.g. "doors")."""
    return next(k for k in sweep_rows[0] if k not in ("line", "seed", "tasks", "solve_rate"))


def sweep_ratios(sweep_rows: list[dict], line: str, reference: str) -> list[tuple[float, float, float]]:
    """Per novelty count, `line`'s mean solve rate over `reference`'s with its paired 95% interval over
    the seeds (a sweep.csv's rows; NaN where the reference solves none)."""
    counted = counted_column(sweep_rows)
    rates: dict[str, dict[int, dict[int, float]]] = {}
    for row in sweep_rows:
        rates.setdefault(row["line"], {}).setdefault(int(row[counted]), {})[int(row["seed"])] = float(row["solve_rate"] or "nan")
    paired = lambda k: [np.array([by_seed[s] for s in sorted(by_seed)]) for by_seed in (rates[line][k], rates[reference][k])]
    nan = (float("nan"),) * 3
    return [stats.ratio_ci(*paired(k)) if np.mean(paired(k)[1]) > 0 else nan for k in sorted(rates[reference])]


def rerun_command(run: dict) -> str:
    """The command that made a test-seed record, as a reader reruns it today: its seeds said (an older
    record left its default out), and what the ledger keeps (--change, --chosen-on) as placeholders."""
    command = current_command(run["command"])
    command += "" if "--seeds" in command else f" --seeds {run['seeds']}"
    return command if "--change" in command else f"{command} --change CHANGE --chosen-on SEEDS"


def step_command(run: dict, step: str) -> str:
    """A step's recorded command as a reader reruns it after the record's own command: a runs folder outside
    the repository (a temporary one) shown as that bench command's default, runs/<study>."""
    command, study = current_command(run["steps"][step]["command"]), current_command(run["command"]).split()[2].split(".")[-1]
    out = re.search(r"--out (/\S+)", run["steps"].get("train", {}).get("command", ""))
    return command.replace(out.group(1), f"runs/{study}") if out else command


def attention_text(line: str) -> str:
    """eval.py --attention's line ("... per seed: 200 1.00 of 90, ...; all 0.98") in a few words."""
    per_seed, _, overall = line.partition("; all ")
    cells = [cell.split() for cell in per_seed.split(": ", 1)[1].split(", ")]  # [seed, fraction, "of", count]
    lowest = min(cells, key=lambda cell: float(cell[1]))
    return (f"at {sum(int(c[3]) for c in cells):,} bridge decisions the most attended object was the fix's in "
            f"{overall} of them; the lowest seed, {lowest[0]}: {lowest[1]} of {lowest[3]}")


def selection(env: str) -> str:
    """docs/results/selection.md's table of the selections on `env`'s test seeds (bench.studies.selection's records): test solve
    rates, what the learned selector looks at and its cost; no bar is judged (the seeds are spent for the selector)."""
    folder = RECORDS / env
    run = read_json(folder / "selection.json")
    if run is None:
        return f"_Not generated yet: `python -m bench.studies.selection --env {env}`._\n"
    by_run, last = by_approach(read_csv(folder / "selection.csv"))
    sweep_rows = read_csv(folder / "selection_sweep.csv")
    elapsed = {name: run["elapsed_s"][name] / last for name in run["approaches"]}
    reward = {name: float(by_run[name][last]["test_smooth_reward_mean"]) for name in run["approaches"]}
    ratios = sweep_ratios(sweep_rows, label("ours_learned_selection"), label("ours"))
    lowest = min((r for r in ratios if not np.isnan(r[0])), key=lambda r: r[0])
    seeds_file = folder / "selection_seeds.csv"  # per-seed values: the reward ratio's interval
    reward_ci = (stats.ratio_ci(*(seed_values(read_csv(seeds_file), a, "test_smooth_reward") for a in
                                  ("ours_learned_selection", "ours")))[1:] if seeds_file.is_file() else None)
    ratio = reward["ours_learned_selection"] / reward["ours"]
    lines = [f"Test seeds {run['seeds']}, {last} cycles; each cell: mean [95% CI] over seeds, IQM [95% CI] beside it.",
             "", *table_header(last)]
    lines += [approach_row(name, cycles, last) for name, cycles in by_run.items()]
    layout = ("one at a time" if "--workers 1" in run["steps"]["train"]["command"] else "side by side") + (
        "; timed from a restart, so lower bounds" if restarted(run["steps"]["train"]) else "")
    lines += ["", f"| approach | cycles to a mean of 0.9 | seconds per cycle (its training's wall time / cycles; trained "
              f"{layout}) |",
              "|---|---|---|"]
    lines += [f"| {label(name)} | {cycles_to(by_run[name])} | {elapsed[name]:.2f} |" for name in run["approaches"]]
    lines += ["", *distractor_bullet(by_run, last),
              f"* Smooth test reward at cycle {last}, learned selection over ours: "
              f"{stats.ci_text(ratio, reward_ci) if reward_ci else f'{ratio:.2f}'}; the paper's rule "
              f"read off the object view over ours: {reward['ours_closest_object'] / reward['ours']:.2f}.",
              f"* Generalisation sweep, learned selection's mean solve rate over ours' at each count: lowest "
              f"{stats.ci_text(lowest[0], lowest[1:])}.",
              f"* Cost (`{current_command(run['steps']['cost']['command'])}`: one timing run, no interval), a cycle of the learned "
              f"selection over one of ours: {cost_ratio(run['cost']):.2f}; "
              f"its peak memory, both measured in one process: {run['steps']['cost']['peak_rss_mib']:,.0f} MiB.",
              f"* What it looks at (test tasks, greedy; `{step_command(run, 'attention')}`): "
              f"{attention_text(run['attention'])}{over_training_text(run, last)}.",
              "", f"`{rerun_command(run)}`: {seconds_text(run)} on {machine_text(run['machine'])}, {commit_text(run)}.",
              "", f"![{ENV_TITLES[env]}, selections]({env}/selection.png)", "",
              novelty_table(env, sweep_rows, run["seeds"], step_command(run, "sweep"))]
    return "\n".join(lines)


def over_training_text(run: dict, last: int) -> str:
    """How attention on the fix's object changed over training (the records of `eval.py --attention --cycle N`
    on checkpoints kept at the table's earlier cycles), and eval.py's diagnosis of the last; empty for a
    record without them."""
    over = run.get("attention_over_training")
    if not over:
        return ""
    cycles = [f"{c} {v}" for c, v in over.items()] + [f"{last} {run['attention'].rpartition('; all ')[2]}"]
    return f". Over training, all seeds: cycle {', '.join(cycles)}. At cycle {last}, {run['attention_diagnosis']}"


def cost_ratio(line: str) -> float:
    """The ratio of bench.timings.training's line ("ours_learned_selection: 2.46x ours's steady-state ...")."""
    return float(line.split(": ", 1)[1].split("x ", 1)[0])


def distractor_bullet(by_run: dict, last: int) -> list[str]:
    """Where the run has no feature selection (a distractor env): the learned selector's test solve rate at
    `last` against the closest object's, and whether their 95% intervals overlap."""
    if "no_feature_selection" not in by_run:
        return []
    row = lambda name: by_run[name][last]
    interval = lambda name: (float(row(name)["test_solve_rate_mean_low"]), float(row(name)["test_solve_rate_mean_high"]))
    learned, closest = interval("ours_learned_selection"), interval("ours_closest_object")
    apart = learned[0] > closest[1]
    return [f"* Distractor tasks, test solve rate at cycle {last}: learned selection "
            f"{float(row('ours_learned_selection')['test_solve_rate_mean']):.2f} [{learned[0]:.2f}, {learned[1]:.2f}], "
            f"the closest object {float(row('ours_closest_object')['test_solve_rate_mean']):.2f} "
            f"[{closest[0]:.2f}, {closest[1]:.2f}], no feature selection "
            f"{float(row('no_feature_selection')['test_solve_rate_mean']):.2f}: the learned selector's interval "
            + ("lies above the closest object's." if apart else "does not lie above the closest object's.")]


BLOCKS = {**{f"headline {env}": (lambda env=env: headline(env)) for env in ENVS},
          **{f"sweep {env}": (lambda env=env: sweep_table(env)) for env in ENVS},
          **{f"plan repair {env}": (lambda env=env: plan_repair(env)) for env in ENVS + VARIANTS},
          **{f"learners {env}": (lambda env=env: learners(env)) for env in ENVS},
          **{f"selection {env}": (lambda env=env: selection(env)) for env in ENVS + DISTRACTOR_ENVS},
          "ledger": ledger_table}


