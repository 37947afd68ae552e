"""docs/results/model_repair.md's block, rendered from bench.studies.model_repair's records (docs/results/E/
model_repair*): per env the test solve rate, the early-learning mean, the bridge decisions per test task
and the learned operators, the repaired planner alone, the held-out combinations or the oracle, the
issue's bars, the cost, sentences on what composed, and one seed's learned operators as PDDL."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from bench.pages.multi_novelty import COST_BAR, cell, cost_lines
from bench.pages.results import (ENV_TITLES, approach_row, bar_text, by_approach, commit_text, label, machine_text,
                                  read_csv, read_json, seconds_text, seeds_label, table_header)
from bench.records import RECORDS, current_command
from bench.studies.model_repair import ENVS, REPAIR
from jaxbridge.utils import stats

SOURCE = "issue 76"
EARLY = 20  # the early-learning window: cycles 1-20
BARS = {"held_out": 0.8, "test": 0.9, "alone": 0.9, "oracle": 0.95}
INVENTED = REPAIR[0]


def per_seed(cycles: list[dict], approach: str, column: str, last: int) -> np.ndarray:
    """float[seeds, cycles 1..last] of a column of the per-cycle records."""
    rows = [r for r in cycles if r["approach"] == approach and int(r["cycle"]) <= last]
    seeds = sorted({int(r["seed"]) for r in rows})
    out = np.full((len(seeds), last), np.nan)
    for r in rows:
        out[seeds.index(int(r["seed"])), int(r["cycle"]) - 1] = float(r[column]) if r[column] != "" else np.nan
    return out


def mean_cell(values: np.ndarray) -> tuple[float, tuple[float, float]]:
    described = stats.describe(values)
    return float(described["mean"]), (float(described["mean_low"]), float(described["mean_high"]))


def cycles_table(cycles: list[dict], names: list[str], last: int) -> tuple[list[str], dict]:
    """Per approach: the mean test solve rate over cycles 1-EARLY (per seed, then over seeds), bridge
    decisions per test task at cycles 1, EARLY and the last, and (repair) the learned operators at the last."""
    early = {name: mean_cell(np.nanmean(per_seed(cycles, name, "test_solve_rate", EARLY), axis=1)) for name in names}
    lines = [f"| approach | mean test solve rate, cycles 1-{EARLY} | bridge decisions per test task, cycle 1 / {EARLY} / "
             f"{last} | learned operators at cycle {last} (mean over seeds) |", "|---|---|---|---|"]
    for name in names:
        decisions = per_seed(cycles, name, "test_decisions", last).mean(axis=0)
        learned = per_seed(cycles, name, "learned_operators", last)[:, -1]
        lines.append(f"| {label(name)} | {stats.ci_text(*early[name])} | "
                     + " / ".join(f"{decisions[c - 1]:.1f}" for c in (1, min(EARLY, last), last))
                     + f" | {'' if np.isnan(learned).all() else f'{np.nanmean(learned):.1f}'} |")
    return lines, early


def bar_lines(env: str, test: dict, last: int, early: dict, extra: dict) -> list[str]:
    """Issue 76's bars on this env, for the repair approach with invented predicates (and given, where the
    bar is Multi Novelty's)."""
    final = lambda name: (float(test[name][last]["test_solve_rate_mean"]), (float(test[name][last]["test_solve_rate_mean_low"]),
                                                                          float(test[name][last]["test_solve_rate_mean_high"])))
    if env == "multi_novelty":
        return [f"* {label(name)}, cycle {last}: held-out combinations {bar_text(*cell(extra['held_out'][name]), BARS['held_out'], SOURCE)}; "
                f"test tasks {bar_text(*final(name), BARS['test'], SOURCE)}" for name in REPAIR]
    ours_low = final("ours")[1][0]
    lines = [f"* cycle {last}, within ours' interval or above: {label(INVENTED)} "
             + bar_text(final(INVENTED)[0], final(INVENTED)[1], ours_low, f"{SOURCE}: ours' lower bound"),
             f"* mean over cycles 1-{EARLY}, intervals apart: {label(INVENTED)} {stats.ci_text(*early[INVENTED])} against ours "
             f"{stats.ci_text(*early['ours'])}: " + ("met" if early[INVENTED][1][0] > early["ours"][1][1] else "missed")]
    if "largest" in extra:
        lines.append(f"* the repaired planner alone at the sweep's largest size ({extra['largest']['tasks']}): "
                     + bar_text(*cell(extra["largest"]), BARS["alone"], SOURCE))
    if "oracle" in extra:
        ratio = final(INVENTED)[0] / extra["oracle"]
        lines.append(f"* against the fastest fix (the oracle bridge, {extra['oracle']:.2f} on the same tasks): "
                     + bar_text(ratio, None, BARS["oracle"], SOURCE) + " (a ratio)")
    return lines


def composed(env: str, test: dict, last: int, alone: list[dict], extra: dict) -> str:
    """What composed and what did not, in sentences from the numbers."""
    rate = lambda name: float(test[name][last]["test_solve_rate_mean"])
    sentences = [f"At cycle {last}, {label(name)} solves {rate(name):.2f} of the test tasks against ours' {rate('ours'):.2f}."
                 for name in REPAIR]
    if env == "multi_novelty":
        held = {name: cell(row)[0] for name, row in extra["held_out"].items()}
        best_other = max((n for n in held if n not in REPAIR), key=held.get)
        alone_held = next(float(r["mean"]) for r in alone if r["approach"] == INVENTED and r["tasks"] == "held_out")
        sentences.append(f"On the held-out combinations (both locks on one door; no training task holds one), {label(INVENTED)} "
                         f"solves {held[INVENTED]:.2f} and the best bridge-only approach ({label(best_other)}) {held[best_other]:.2f}; "
                         f"its planner alone, with no bridge, solves {alone_held:.2f}"
                         + (": its plans put the learned operators of both locks together." if alone_held >= BARS["held_out"]
                            else ": its learned operators did not compose into plans for most of them."))
    invented = [r for r in alone if r["approach"] == INVENTED]
    failed = [r["tasks"] for r in invented if float(r["mean"]) < BARS["alone"]]
    sentences.append(f"The repaired planner alone (no bridge) solves {BARS['alone']:g} or more on "
                     + (f"every task set it met ({task_sets_text([r['tasks'] for r in invented])})." if not failed
                        else f"{len(invented) - len(failed)} of {len(invented)} task sets; below it on {task_sets_text(failed)}."))
    return " ".join(sentences)


def task_sets_text(names: list[str]) -> str:
    """Task sets in words, a sweep's sizes together ("sweep: 1 doors", ..., "sweep: 10 doors": "the sweep at 1
    to 10 doors"; sizes with gaps listed: "the sweep at 6, 8 and 12 doors")."""
    sizes = [name.removeprefix("sweep: ").split(" ", 1) for name in names if name.startswith("sweep: ")]
    others = [name for name in names if not name.startswith("sweep: ")]
    counts = sorted(int(count) for count, _ in sizes)
    if not counts:
        return ", ".join(others)
    if len(counts) > 2 and counts == list(range(counts[0], counts[-1] + 1)):
        at = f"{counts[0]} to {counts[-1]}"
    else:
        at = " and ".join(filter(None, [", ".join(map(str, counts[:-1])), str(counts[-1])]))
    return ", ".join(others + [f"the sweep at {at} {sizes[0][1]}"])


# The timing's ratios in the order it prints them: cycles 2 on (ours' one compilation left out, the repair
# approach's second, for its learned tables, kept), then every cycle (each approach's every compilation in).
COST_MEASURES = ("the median cycle", "the mean cycle after the first", "the mean cycle after the first without building programs",
                 "the mean over every cycle")


def cost_bullets(run: dict) -> list[str]:
    """The repair approach's seconds per cycle over ours', at the median cycle after the first, on average
    after the first (relearning and the compilation for the learned tables are in the means alone) and, where
    the timing measured them, that average without building programs and the average over every cycle, each
    against the bar; then the training's idle cores."""
    line = next(line for line in run["cost"] if line.startswith(INVENTED))
    ratios = [float(part.split("x ")[0]) for part in line.split(": ", 1)[1].split(", ")]
    return [f"* {label(INVENTED)}, {measure}: {bar_text(ratio, None, COST_BAR, SOURCE, at_least=False)}"
            for measure, ratio in zip(COST_MEASURES, ratios)] + [
        line.replace("issue 54", SOURCE) for line in cost_lines(run)[len(run["cost"]):]]


def alone_table(alone: list[dict]) -> list[str]:
    """The planner-alone rows as a table: a task set per row, a repair approach per column."""
    names = list(dict.fromkeys(r["approach"] for r in alone))
    cells = {(r["tasks"], r["approach"]): stats.ci_text(*cell(r)) for r in alone}
    return (["| tasks | " + " | ".join(label(n) for n in names) + " |", "|---|" + "---|" * len(names)]
            + [f"| {tasks} | " + " | ".join(cells[tasks, n] for n in names) + " |" for tasks in dict.fromkeys(r["tasks"] for r in alone)])


def pddl_lines(path: Path) -> list[str]:
    """The learned operators (the `(:action` blocks of a learned-only domain file) in a code block."""
    text = path.read_text()
    return ["```pddl", text[text.index("  (:action"):].rstrip().removesuffix(")"), "```"] if "(:action" in text else ["(none)"]


def record_lines(env: str, run: dict, folder: Path, stem: str) -> list[str]:
    test, last = by_approach(read_csv(folder / f"{stem}.csv"))
    cycles, alone = read_csv(folder / f"{stem}_cycles.csv"), read_csv(folder / f"{stem}_alone.csv")
    extra: dict = {}
    if (folder / f"{stem}_held_out.csv").is_file():
        extra["held_out"] = {r["approach"]: r for r in read_csv(folder / f"{stem}_held_out.csv")}
    if (folder / f"{stem}_oracle.csv").is_file():
        extra["oracle"] = float(np.mean([float(r["solve_rate"]) for r in read_csv(folder / f"{stem}_oracle.csv")]))
    swept = [r for r in alone if r["approach"] == INVENTED and r["tasks"].startswith("sweep")]
    if swept and env in ("light_switch_door", "doorknobs"):
        extra["largest"] = swept[-1]
    lines = [f"**{ENV_TITLES.get(env, env)}**, {seeds_label(run['seeds'])}, {last} cycles; each cell: mean [95% CI] over "
             "seeds, IQM [95% CI] beside it.", "", *table_header(last)]
    lines += [approach_row(name, by_cycle, last) for name, by_cycle in test.items()]
    table, early = cycles_table(cycles, list(test), last)
    lines += ["", *table, "", "The repaired planner alone (no bridge: a stall is a failure), the final models:", "",
              *alone_table(alone)]
    if "held_out" in extra:
        lines += ["", "Held-out combinations (`--test-protocol held_out`), the final policies:", "",
                  "| approach | held-out combinations |", "|---|---|",
                  *(f"| {label(n)} | {stats.ci_text(*cell(r))} |" for n, r in extra["held_out"].items())]
    lines += ["", f"The bars ({SOURCE}):", "", *bar_lines(env, test, last, early, extra), "", composed(env, test, last, alone, extra)]
    lines += ["", f"Cost per cycle against ours' ({SOURCE}'s bar: 3x at most; the training's idle cores: its wall at most "
              f"1.1x its approaches' summed seconds per core), one timing run (`{current_command(run['steps']['cost']['command'])}`):",
              *cost_bullets(run)]
    for name in REPAIR:
        lines += ["", f"Seed {run['seeds'].split('-')[0]}'s learned operators, {label(name)} (the whole domain: the run's "
                  "`models/seedN.pddl`):", "", *pddl_lines(folder / f"{stem}_{name}.pddl")]
    lines += ["", f"`{current_command(run['command'])}`: {seconds_text(run)} on {machine_text(run['machine'])}, {commit_text(run)}.",
              "", f"![{ENV_TITLES.get(env, env)}, {seeds_label(run['seeds'])}]({folder.name}/{stem}.png)"]
    return lines


def block(records: Path = RECORDS) -> str:
    """Each env's test-seed records first, where they exist, then its development seeds'."""
    lines = []
    for env in ENVS:
        folder = records / env
        for path in sorted(folder.glob("model_repair-*.json")) + sorted(folder.glob("model_repair.json")):
            lines += [f"### {ENV_TITLES.get(env, env)}: {'test' if path.stem != 'model_repair' else 'development'} seeds",
                      "", *record_lines(env, read_json(path), folder, path.stem), ""]
    return "\n".join(lines) if lines else "_Not generated yet: `python -m bench.studies.model_repair --env multi_novelty`._\n"
