"""docs/results/fix_length.md's block, rendered from bench.studies.fix_length's records
(docs/results/light_switch_sequence/fix_length.json): solve rate per fix length k with epsilon-greedy and
with the count bonus, the longest k each solves, the discount sweep, the cost and the memory."""
from __future__ import annotations

from pathlib import Path

from bench.records import RECORDS, current_command
from bench.pages.results import ENV_TITLES, commit_text, machine_text, read_json
from jaxbridge.utils import stats

FOLDER = RECORDS / "light_switch_sequence"


def first_text(row: dict, cycles: int) -> str:
    """The first cycle whose mean reaches the bar, with its interval; past the run: "not reached"."""
    shown = lambda c: f"> {cycles}" if c > cycles else str(c)
    if row["first"] > cycles:
        return "not reached" + ("" if row["first_ci"][0] > cycles else f" [{shown(row['first_ci'][0])}, > {cycles}]")
    low, high = row["first_ci"]
    return row["first"].__str__() + ("" if low == high else f" [{shown(low)}, {shown(high)}]")


def final_text(row: dict) -> str:
    return stats.ci_text(row["final"], row["final_ci"])


def length_table(run: dict) -> list[str]:
    methods, cycles = list(run["table"]), run["cycles"]
    head = ["k", "oracle"] + [f"{m}: cycle {cycles} | first cycle at {run['solved']} | highest (its cycle)" for m in methods]
    lines = ["| " + " | ".join(head) + " | CPU seconds per cycle, bonus / epsilon-greedy |",
             "|---" * (2 + 3 * len(methods) + 1) + "|"]
    for k in run["table"][methods[0]]:
        cells = [k, f"{run['oracle'][k]:.2f}"]
        cells += [f"{final_text(row)} | {first_text(row, cycles)} | {row['best']:.2f} ({row['best_cycle']})"
                  for row in (run["table"][m][k] for m in methods)]
        lines.append("| " + " | ".join(cells) + f" | {run['cost_ratio'][k]:.2f} |")
    return lines


def longest_text(run: dict) -> str:
    """The longest k each method solves, and whether the bonus extends epsilon-greedy's by 2 or more."""
    best, ks = run["longest_solved"], [int(k) for k in run["oracle"]]

    def where_it_stops(method: str, longest: int | None) -> str:
        """The longest k with its mean [CI], and the next k's."""
        mean_at = lambda k: f"{final_text(run['table'][method][str(k)])} at k = {k}"
        shown = [mean_at(longest)] if longest else []
        shown += [mean_at(k) for k in ks if k > (longest or 0)][:1]
        return f"{method}: {f'k = {longest}' if longest else 'none'} ({'; '.join(shown)})"

    said = "; ".join(where_it_stops(m, k) for m, k in best.items())
    plain, bonus = best.get("epsilon-greedy") or 0, [k or 0 for m, k in best.items() if m != "epsilon-greedy"][0]
    verdict = (f"the count bonus extends it by {bonus - plain}" if bonus - plain >= 2 else
               f"the count bonus does not extend it by 2 or more (by {bonus - plain})")
    note = f" (the longest k run: {max(ks)}; the bonus may go further)" if bonus == max(ks) else ""
    return (f"The longest k at which ours' mean test solve rate at cycle {run['cycles']} is at least {run['solved']}, "
            f"with every shorter k's too: {said}; {verdict}{note}.")


def discount_table(run: dict) -> list[str]:
    if not run["discount"]:
        return []
    ks = list(run["discount"])
    lines = ["Epsilon-greedy at other discounts per decision (`gamma`; the default 0.8), test solve rate at cycle "
             f"{run['cycles']}:", "", "| gamma | " + " | ".join(f"k = {k}" for k in ks) + " |", "|---" * (len(ks) + 1) + "|"]
    for gamma in run["discount"][ks[0]]:
        lines.append(f"| {gamma} | " + " | ".join(final_text(run["discount"][k][gamma]) for k in ks) + " |")
    return lines + [""]


def paper_table(run: dict) -> list[str]:
    """The paper's envs, ours with and without the bonus: test solve rate at the last cycle, the first cycle at
    the bar, the cost."""
    envs = run.get("paper_envs") or {}
    if not envs:
        return []
    methods = list(next(iter(envs.values())))
    lines = [f"The paper's envs, where every fix is short: ours at its default settings with and without the bonus "
             f"(same seeds, {run['cycles']} cycles).", "",
             "| env | " + " | ".join(f"{m}: cycle {run['cycles']} | {m}: first cycle at {run['solved']}" for m in methods)
             + " | CPU seconds per cycle, bonus / epsilon-greedy |", "|---" * (2 * len(methods) + 2) + "|"]
    for env, rows in envs.items():
        ratio = rows[methods[1]]["cpu_s_per_cycle"] / rows[methods[0]]["cpu_s_per_cycle"]
        lines.append(f"| {ENV_TITLES[env]} | " + " | ".join(f"{final_text(rows[m])} | {first_text(rows[m], run['cycles'])}"
                                                          for m in methods) + f" | {ratio:.2f} |")
    return lines + [""]


def commits_text(run: dict) -> str:
    """The record's commit, and how many of its steps ran at each other commit (a continued command's)."""
    others = {}
    for step in run["steps"].values():
        if step["commit"] != run["commit"]:
            others[step["commit"]] = others.get(step["commit"], 0) + 1
    shown = "; ".join(f"{n} at {commit_text({'commit': c})[len('commit '):]}" for c, n in others.items())
    return commit_text({"commit": run["commit"]}) + (f" (of its {len(run['steps'])} steps, {shown})" if shown else "")


def record_lines(run: dict, folder: Path, stem: str) -> list[str]:
    """One record's tables, cost, memory, command and figure."""
    state = run["state_bytes_per_seed"]
    memory = ", ".join(f"{m} {b / 2**10:,.0f} KiB" for m, b in state.items())
    return [f"Seeds {run['seeds']}, {run['cycles']} cycles, ours at its default settings; each cell: the mean over "
            "seeds [95% bootstrap CI]. The oracle: the mean test solve rate of the hand-written bridge on the same tasks.",
            "", *length_table(run), "", longest_text(run), "", *discount_table(run), *paper_table(run),
            f"Memory: the learner state per seed, {memory}. "
            "The cost: each run's compiled program timed alone, the two methods one after another in one process, "
            "in the process's CPU seconds (on a shared machine, other processes move them less than the wall time).", "",
            f"`{current_command(run['command'])}`: its trainings {run['training_s']:,.0f} s (compiling included) on "
            f"{machine_text(run['machine'])}, {commits_text(run)}.", "",
            f"![Light Switch Sequence, solve rate vs fix length, seeds {run['seeds']}]({folder.name}/{stem}.png)", ""]


def block(folder: Path = FOLDER) -> str:
    """The test seeds' record (the figure's) first, where it exists, then the development seeds' (the discount
    sweep and the paper's envs)."""
    test = sorted(folder.glob("fix_length-*.json"))
    dev = read_json(folder / "fix_length.json")
    if dev is None and not test:
        return "_Not generated yet: `python -m bench.studies.fix_length --seeds 0-7`._\n"
    lines = []
    for path in test:
        lines += [f"**Test seeds {path.stem[len('fix_length-'):]}.**", "", *record_lines(read_json(path), folder, path.stem)]
    if dev is not None:
        heading = ["**Development seeds.**", ""] if test else []  # alone, the block is the development seeds'
        lines += heading + record_lines(dev, folder, "fix_length")
    return "\n".join(lines)
