"""docs/results/multi_novelty.md's block, rendered from bench.multi_novelty's records
(docs/results/multi_novelty/): test solve rate per approach on the test tasks and on the held-out
combinations, which kinds each approach solves alone, the novelty sweep, the cost, and the issue's bars
with the answer to the paper's question."""
from __future__ import annotations

from pathlib import Path

from bench.performance_blocks import busy_text
from bench.records import RECORDS
from bench.results_blocks import (approach_row, bar_text, by_approach, commit_text, cost_ratio, label, machine_text,
                                  novelty_table, read_csv, read_json, seeds_label, step_command, table_header)

ENV = "multi_novelty"
FOLDER = RECORDS / ENV
BARS = {"test": 0.9, "held_out": 0.8}  # issue 54: the mean test solve rate at the last cycle, per protocol
COST_BAR = 3.0  # issue 54: no approach of the default over 3x ours per cycle
IDLE_BAR = 1.1  # issue 54: the training's wall over the approaches' summed seconds per core
ONE_BRIDGE = ("ours", "ours_learned_selection")  # one bridge for every kind


def cell(row: dict) -> tuple[float, tuple[float, float]]:
    """A summary row's mean and 95% CI (bench.multi_novelty.summary_row)."""
    return float(row["mean"]), (float(row["low"]), float(row["high"]))


def bars_lines(test: dict, held_out: list[dict], last: int) -> list[str]:
    """Each learned approach's last-cycle solve rate on the test tasks and the held-out combinations against
    their bars, and which meet both."""
    held = {row["approach"]: row for row in held_out if int(row["cycle"]) == last}
    learned = [n for n in test if n not in ("random", "pure_planning")]
    lines = [f"| approach | test tasks, cycle {last} | held-out combinations, cycle {last} |", "|---|---|---|"]
    meets = []
    for name in learned:
        row = test[name][last]
        t, t_ci = float(row["test_solve_rate_mean"]), (float(row["test_solve_rate_mean_low"]),
                                                        float(row["test_solve_rate_mean_high"]))
        h, h_ci = cell(held[name])
        lines.append(f"| {label(name)} | {bar_text(t, t_ci, BARS['test'], 'issue 54')} | "
                     f"{bar_text(h, h_ci, BARS['held_out'], 'issue 54')} |")
        if t >= BARS["test"] and h >= BARS["held_out"]:
            meets.append(name)
    one = [n for n in meets if n in ONE_BRIDGE]
    answer = ("Both bars are met by " + ", ".join(label(n) for n in meets) + ": "
              + ("one bridge suffices here (" + ", ".join(label(n) for n in one) + ")." if one else
                 "not by one bridge for every kind; the bridges keyed by failure signature meet them.")
              if meets else "No approach meets both bars (0.9 on the test tasks, 0.8 on the held-out combinations).")
    return lines + ["", answer]


def summary_table(rows: list[dict], column: str, heading: str = "{}") -> list[str]:
    """Summary rows (bench.multi_novelty.summary_row) as a table: an approach per row, a value of `column`
    per column (headed by `heading` formatted with it), mean [95% CI] over seeds in each cell."""
    values = list(dict.fromkeys(r[column] for r in rows))
    cells: dict[str, dict[str, str]] = {}
    for r in rows:
        mean, (low, high) = cell(r)
        cells.setdefault(r["approach"], {})[r[column]] = f"{mean:.2f} [{low:.2f}, {high:.2f}]"
    return (["| approach | " + " | ".join(heading.format(v) for v in values) + " |", "|---|" + "---|" * len(values)]
            + [f"| {label(name)} | " + " | ".join(by[v] for v in values) + " |" for name, by in cells.items()])


def cost_lines(run: dict) -> list[str]:
    """bench.training's ratios to ours, each against the bar; then the training's idle cores."""
    busy = run["schedule"]["busy_s"]
    idle = run["schedule"]["wall_s"] / (sum(busy.values()) / len(busy))
    return [f"* {line.split(':')[0]}: {bar_text(cost_ratio(line), None, COST_BAR, 'issue 54', at_least=False)}"
            for line in run["cost"]] + [
        f"* the training's wall time over its approaches' summed seconds per core (each core busy: {busy_text(run)}): "
        + bar_text(idle, None, IDLE_BAR, "issue 54", at_least=False)]


def record_lines(run: dict, folder: Path, stem: str) -> list[str]:
    test, last = by_approach(read_csv(folder / f"{stem}.csv"))
    held_out = read_csv(folder / f"{stem}_held_out.csv")
    lines = [f"{seeds_label(run['seeds']).capitalize()}, {last} cycles; each cell: mean [95% CI] over seeds, IQM "
             "[95% CI] beside it.", "", "Test tasks:", "", *table_header(last)]
    lines += [approach_row(name, cycles, last) for name, cycles in test.items()]
    lines += ["", "Held-out combinations (each seed's `--test-protocol held_out` tasks: kinds mixed as no training task "
              "mixes them), met by the run's bridges at each cycle (`eval.py RUN --test-protocol held_out --cycle N`):",
              "", *summary_table(held_out, "cycle", "cycle {}")]
    lines += ["", f"The bars, at cycle {last}:", "", *bars_lines(test, held_out, last)]
    lines += ["", "Each kind alone (tasks holding one kind, the same for every seed; the final bridges):", "",
              *summary_table(read_csv(folder / f"{stem}_kinds.csv"), "kind")]
    lines += ["", f"Cost per cycle against ours', one timing run in one process (`{run['steps']['cost']['command']}`):",
              *cost_lines(run)]
    lines += ["", f"`{run['command']}`: {run['wall_s']:,.0f} s on {machine_text(run['machine'])}, {commit_text(run)}.",
              "", f"![Multi Novelty, {seeds_label(run['seeds'])}]({folder.name}/{stem}.png)", "",
              novelty_table(ENV, read_csv(folder / f"{stem}_sweep.csv"), run["seeds"], step_command(run, "sweep"))]
    return lines


def block(folder: Path = FOLDER) -> str:
    """The test seeds' records first, where they exist, then the development seeds'."""
    test = sorted(folder.glob(f"{ENV}-*.json"))
    dev = folder / f"{ENV}.json"
    if not test and not dev.is_file():
        return "_Not generated yet: `python -m bench.multi_novelty`._\n"
    lines = []
    for path in test + ([dev] if dev.is_file() else []):
        heading = "Test seeds" if path != dev else "Development seeds"
        lines += [f"**{heading}.**", "", *record_lines(read_json(path), folder, path.stem)]
    return "\n".join(lines)
