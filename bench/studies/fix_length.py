"""Where epsilon-greedy stops finding a fix of k decisions, and whether the count bonus keeps finding it
(issue 56; docs/design/envs.md, "Light Switch Sequence"; docs/design/learning.md, "Exploration").

    python -m bench.studies.fix_length --seeds 0-7                  # development seeds: look
    python -m bench.studies.fix_length --seeds 300-331 --gamma-lengths 0 --paper-envs none \
        --change "first run" --chosen-on "development seeds 0-7"   # the figure on its test seeds, with their ledger row

Ours at its default settings is trained on Light Switch Sequence at every fix length k of --lengths
(`LightSwitchSequence.of_length(k)`), once with epsilon-greedy alone and once with the count bonus
(`count_bonus`, --bonus), each through `jaxbridge.make_train` (one jitted run per k and method; compiled,
then timed: the CPU seconds per cycle of the two, measured in one process, give the cost ratio); at --gamma-lengths the
discount per decision is swept too (--gammas, epsilon-greedy), to tell an exploration failure from a
discounting one; the oracle bridge on every k's test tasks; and each of the paper's envs (--paper-envs)
trained with and without the bonus, to show what it does where the fixes are short. Per k and method: the test solve rate at
the last cycle and the first cycle whose mean over seeds reaches 0.9, each with its 95% bootstrap
interval over the seeds (jaxbridge/utils/stats.py).

It writes fix_length.json (commit, command, seeds, every figure, times, memory, machine), fix_length.csv
(one row per method, k and seed) and fix_length.png into docs/results/light_switch_sequence/, each named
fix_length-FIRST-LAST.* on a test-seed set so that the development seeds' records stay beside it; uncommitted
code is refused (--allow-dirty: a local try, records under RUNS/records). A finished step is kept in the
runs folder and not run again, so a stopped command continues where it left off.
"""
from __future__ import annotations

import csv
import dataclasses
import io
import json
import time
from pathlib import Path

import jax
import numpy as np

import jaxbridge
from bench.records import ENVS
from bench.study import Steps, Study, run_study
from jaxbridge.utils import stats
from jaxbridge.utils.files import write_atomic

ENV = "light_switch_sequence"
LENGTHS = (1, 2, 3, 4, 6, 8, 10, 12)
GAMMAS = (0.9, 0.95, 0.99)  # beside the default's 0.8
GAMMA_LENGTHS = (4, 8)
BONUS = 0.1  # count_bonus of the exploration rows
SOLVED = 0.9  # "reaches" a solve rate of this


def env_spec(k: int) -> str:
    return f"envs_jax.light_switch_door.sequence:LightSwitchSequence_k{k}"


def config(k: int | str, seeds: list[int], cycles: int, settings: list[str]):
    """Ours' config at fix length k (or on the env named k)."""
    return jaxbridge.make_config(env_spec(k) if isinstance(k, int) else k, seeds=seeds, cycles=cycles, settings=settings)


def timed_run(train, *args) -> tuple[object, float, float, float]:
    """(output, compile seconds, run seconds, run CPU seconds) of jit(train)(*args). The CPU seconds are this
    process's (every thread's), which other processes on a shared machine move less than the wall time."""
    start = time.perf_counter()
    compiled = jax.jit(train).lower(*args).compile()
    compiled_at, cpu_at = time.perf_counter(), time.process_time()
    out = jax.block_until_ready(compiled(*args))
    return out, compiled_at - start, time.perf_counter() - compiled_at, time.process_time() - cpu_at


def train_step(k: int | str, seeds: list[int], cycles: int, settings: list[str]) -> dict:
    """Ours at fix length k (or on the env named k) with `settings`: every seed's test solve rate per cycle, the seconds, the learner
    state's bytes per seed and the plan-table misses (0: the run is train.py's)."""
    out, compile_s, run_s, cpu_s = timed_run(jaxbridge.make_train(config(k, seeds, cycles, settings)))
    state_bytes = sum(x.nbytes for x in jax.tree.leaves(out.learners)) // len(seeds)
    return {"solve": np.round(np.asarray(out.metrics.test_solve_rate), 4).tolist(), "compile_s": round(compile_s, 1),
            "run_s": round(run_s, 1), "s_per_cycle": round(run_s / cycles, 3), "cpu_s_per_cycle": round(cpu_s / cycles, 3),
            "state_bytes_per_seed": state_bytes,
            "table_misses": int(np.asarray(out.metrics.table_misses).sum())}


def gamma_step(k: int, seeds: list[int], cycles: int, gammas: list[float]) -> dict:
    """Ours at fix length k at each discount (one program, the runs one after another): {gamma: solve}."""
    base = config(k, seeds, cycles, [])
    hypers = jax.tree.map(lambda *v: np.stack(v), *[jaxbridge.Hyper.of(dataclasses.replace(base, gamma=g)) for g in gammas])
    out, compile_s, run_s, _ = timed_run(jax.vmap(jaxbridge.make_train(base), in_axes=(None, 0)), None, hypers)
    solve = np.round(np.asarray(out.metrics.test_solve_rate), 4)
    return {"solve": {str(g): solve[i].tolist() for i, g in enumerate(gammas)}, "compile_s": round(compile_s, 1),
            "run_s": round(run_s, 1), "table_misses": int(np.asarray(out.metrics.table_misses).sum())}


def oracle_step(k: int, seeds: list[int]) -> dict:
    episodes = jaxbridge.hand_made(env_spec(k), "oracle").evaluate(seeds=seeds)
    return {"solve": [episodes.per_seed()[s] for s in seeds]}


def first_cycle(solve: np.ndarray, axis: int = 0) -> np.ndarray:
    """The first cycle (1-based) at which the mean over seeds (`axis`) reaches SOLVED; cycles + 1 if none."""
    reached = np.mean(solve, axis=axis) >= SOLVED
    return np.where(reached.any(-1), reached.argmax(-1) + 1, reached.shape[-1] + 1)


def summary(solve: list) -> dict:
    """A method's figures at one k: its test solve rate at the last cycle and the first cycle reaching SOLVED,
    means over seeds with 95% bootstrap intervals (a first cycle past the run: cycles + 1, "never"); the
    highest mean over seeds of any cycle, and that cycle (a fall after it shows as a last below it)."""
    solve = np.asarray(solve, np.float64)
    last = solve[:, -1]
    low, high = stats.bootstrap_ci(last)
    first_low, first_high = stats.bootstrap_ci(solve, first_cycle)
    curve = solve.mean(0)
    return {"final": round(float(last.mean()), 4), "final_ci": [round(float(low), 4), round(float(high), 4)],
            "first": int(first_cycle(solve)), "first_ci": [int(first_low), int(first_high)],
            "best": round(float(curve.max()), 4), "best_cycle": int(curve.argmax()) + 1}


def longest_solved(rows: dict[int, dict]) -> int | None:
    """The longest k whose mean at the last cycle is at least SOLVED, with every shorter k's too."""
    best = None
    for k in sorted(rows):
        if rows[k]["final"] < SOLVED:
            break
        best = k
    return best


def csv_rows(methods: dict[str, dict[int, list]], seeds: list[int]) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["method", "k", "seed", "final_solve_rate", "first_cycle_reaching"])
    for method, by_k in methods.items():
        for k, solve in by_k.items():
            solve = np.asarray(solve)
            for i, seed in enumerate(seeds):
                first = np.argmax(solve[i] >= SOLVED) + 1 if (solve[i] >= SOLVED).any() else ""
                writer.writerow([method, k, seed, f"{solve[i, -1]:.4f}", first])
    return out.getvalue()


def figure(path: Path, table: dict[str, dict[int, dict]], oracle: dict[int, float], cycles: int, seeds: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for (method, rows), marker in zip(table.items(), ("o", "s")):  # the markers tell coinciding points apart
        ks = sorted(rows)
        ax.plot(ks, [rows[k]["final"] for k in ks], marker=marker, markerfacecolor="none", label=method)
        ax.fill_between(ks, [rows[k]["final_ci"][0] for k in ks], [rows[k]["final_ci"][1] for k in ks], alpha=0.2)
    ax.plot(sorted(oracle), [oracle[k] for k in sorted(oracle)], "k:", label="oracle bridge")
    ax.set_xticks(sorted(oracle))
    ax.set(xlabel="fix length k (bridge decisions the fix takes)", ylabel=f"test solve rate at cycle {cycles}",
           title=f"Light Switch Sequence: ours, seeds {seeds}", ylim=(-0.03, 1.03))
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def ints(text: str) -> list[int]:
    return [int(v) for v in text.split(",")]


def env_list(text: str) -> list[str]:
    return [] if text == "none" else text.split(",")


def run_steps(args, methods: dict[str, list[str]], steps: Steps) -> dict:
    """Every step's figures (a finished one read back): {"runs": {method: {k: ...}}, "oracle": {k: ...},
    "gammas": {k: ...}, "paper": {env: {method: ...}}, "steps": {step: {"commit": the code it ran at}}}."""
    seeds, cycles = args.seed_list, args.cycles
    args.runs.mkdir(parents=True, exist_ok=True)
    steps, commits = Steps(args.runs / f"steps-{args.seeds}-{cycles}.json"), {}

    def step(name: str, work) -> dict:
        commits[name] = (figures := steps.run(name, work))["commit"]
        return figures

    runs = {name: {} for name in methods}
    for k in args.lengths:
        for name, settings in methods.items():
            runs[name][k] = step(f"{name} k={k}", lambda: train_step(k, seeds, cycles, settings))
            print(f"k={k} {name}: {runs[name][k]['run_s']} s ({runs[name][k]['compile_s']} s compiling)", flush=True)
    return {"runs": runs,
            "oracle": {k: step(f"oracle k={k}", lambda: oracle_step(k, seeds)) for k in args.lengths},
            "gammas": {k: step(f"gammas k={k}", lambda: gamma_step(k, seeds, cycles, args.gammas))
                       for k in args.gamma_lengths},
            "paper": {env: {name: step(f"{name} {env}", lambda: train_step(env, seeds, cycles, settings))
                            for name, settings in methods.items()} for env in args.paper_envs},
            "steps": {name: {"commit": commit} for name, commit in commits.items()}}


def record_fields(args, methods: dict[str, list[str]], done: dict) -> dict:
    """The record of the steps' figures: each method's summary per k and on the paper's envs, the longest k
    solved, the oracle, the discount sweep, the cost and the memory."""
    runs, eps, bonus = done["runs"], *methods
    table = {name: {k: summary(run["solve"]) for k, run in by_k.items()} for name, by_k in runs.items()}
    discount = {k: {"0.8": table[eps][k], **{g: summary(solve) for g, solve in step["solve"].items()}}
                for k, step in done["gammas"].items()}
    trainings = [r for by_k in runs.values() for r in by_k.values()] + list(done["gammas"].values()) + [
        r for by_method in done["paper"].values() for r in by_method.values()]
    return {"methods": methods, "solved": SOLVED,
            "table": {n: {str(k): row for k, row in rows.items()} for n, rows in table.items()},
            "longest_solved": {n: longest_solved(rows) for n, rows in table.items()},
            "oracle": {str(k): round(float(np.mean(step["solve"])), 4) for k, step in done["oracle"].items()},
            "discount": {str(k): rows for k, rows in discount.items()},
            "cost_ratio": {str(k): round(runs[bonus][k]["cpu_s_per_cycle"] / runs[eps][k]["cpu_s_per_cycle"], 3)
                           for k in args.lengths},
            "paper_envs": {env: {name: {**summary(run["solve"]), "cpu_s_per_cycle": run["cpu_s_per_cycle"]}
                                 for name, run in by_method.items()} for env, by_method in done["paper"].items()},
            "seconds": {n: {str(k): {f: r[f] for f in ("compile_s", "run_s", "s_per_cycle", "cpu_s_per_cycle")}
                            for k, r in by_k.items()} for n, by_k in runs.items()},
            "state_bytes_per_seed": {n: by_k[args.lengths[0]]["state_bytes_per_seed"] for n, by_k in runs.items()},
            "table_misses": sum(r["table_misses"] for r in trainings),
            "training_s": round(sum(r["compile_s"] + r["run_s"] for r in trainings), 1), "steps": done["steps"]}


def report(record: dict) -> None:
    print(json.dumps({k: record[k] for k in ("longest_solved", "oracle", "cost_ratio", "state_bytes_per_seed")}))
    for name, rows in record["table"].items():
        print(name + ": " + "; ".join(f"k={k} {stats.ci_text(r['final'], r['final_ci'])}, first {r['first']}"
                                      for k, r in rows.items()))
    for k, rows in record["discount"].items():
        print(f"discount at k={k}: " + "; ".join(f"{g}: {stats.ci_text(r['final'], r['final_ci'])}" for g, r in rows.items()))
    for env, rows in record["paper_envs"].items():
        print(f"{env}: " + "; ".join(f"{m} {stats.ci_text(r['final'], r['final_ci'])}" for m, r in rows.items()))


class FixLength(Study):
    name, doc, page = "fix_length", __doc__, "docs/results/fix_length.md"
    envs, seeds, stem_by_seeds = (ENV,), "0-7", True
    regenerate = (("--seeds", "300-331", "--gamma-lengths", "0", "--paper-envs", "none"), ("--seeds", "0-7"))

    def flags(self, parser) -> None:
        parser.add_argument("--lengths", type=ints, default=list(LENGTHS), help="fix lengths k (default: 1,2,3,4,6,8,10,12)")
        parser.add_argument("--gamma-lengths", type=lambda text: [] if text == "none" else [k for k in ints(text) if k > 0],
                            default=list(GAMMA_LENGTHS), help="the k at which the discount is swept (default: 4,8; none or 0: none)")
        parser.add_argument("--gammas", type=lambda t: [float(v) for v in t.split(",")], default=list(GAMMAS),
                            help="discounts swept beside the default 0.8 (default: 0.9,0.95,0.99)")
        parser.add_argument("--paper-envs", type=env_list, default=list(ENVS),
                            help="the paper's envs, each trained with and without the bonus (default: all three; none)")
        parser.add_argument("--bonus", type=float, default=BONUS, help="count_bonus of the exploration rows (default: %(default)s)")

    def check(self, parser, args) -> None:
        if not set(args.gamma_lengths) <= set(args.lengths):
            parser.error("--gamma-lengths must be among --lengths (their default discount's runs are those)")

    def methods(self, args) -> dict[str, list[str]]:
        return {"epsilon-greedy": [], f"count bonus {args.bonus:g}": [f"count_bonus={args.bonus}"]}

    def steps(self, args, steps: Steps) -> dict:
        return run_steps(args, self.methods(args), steps)

    def write(self, args, done: dict, out: Path) -> dict:
        fields, stem = record_fields(args, self.methods(args), done), self.stem(args)
        solve = {name: {k: run["solve"] for k, run in by_k.items()} for name, by_k in done["runs"].items()}
        write_atomic(out / f"{stem}.csv", csv_rows(solve, args.seed_list))
        table = {n: {int(k): row for k, row in rows.items()} for n, rows in fields["table"].items()}
        figure(out / f"{stem}.png", table, {int(k): v for k, v in fields["oracle"].items()}, args.cycles, args.seeds)
        report(fields)
        return fields


STUDY = FixLength()

if __name__ == "__main__":
    run_study(STUDY)
