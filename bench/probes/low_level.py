"""The low-level baselines against ours and Maple Q (issue 22): test solve rate against training steps on a
log axis, one panel per env, and its table, from finished experiment directories.

    python -m bench.probes.low_level runs/ll/lsd_16 runs/ll/lsd_sac_4 ... --figure runs/ll/low_level.png

Every run of the given experiments is one line: its approach, with its budget where it is not the
paper's. x: training steps per seed so far (the mean over seeds of the summed `train_env_steps`: env
steps for ours and Maple Q, agent steps for the low-level agents, each at least one env step).
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

import jaxbridge
from bench.command import CommandParser
from jaxbridge.utils import stats

ENVS = ("light_switch_door", "doorknobs", "coffee")


def load_run(run_dir: Path) -> dict:
    """A finished run: its env, label, seeds, and per seed and cycle its solve rate and training steps."""
    config = json.loads((run_dir / "config.json").read_text())
    rows = list(csv.DictReader((run_dir / "metrics.csv").open()))
    seeds = sorted({int(r["seed"]) for r in rows}, key=int)
    per_seed = lambda field: np.array([[float(r[field]) for r in rows if int(r["seed"]) == s] for s in seeds])
    approach = config["approach"]
    budget = config.get("low_level_budget", 1)
    low_level = approach in jaxbridge.LOW_LEVEL
    label = jaxbridge.run_labels([approach])[approach] + (f", {budget}x budget" if low_level and budget != 1 else "")
    return {"env": config["env"], "label": label, "approach": approach, "budget": budget, "seeds": seeds,
            "rates": per_seed("test_solve_rate"), "steps": np.cumsum(per_seed("train_env_steps"), axis=1)}


def summary_row(run: dict) -> list[str]:
    """seeds, training steps per seed, the solve rate at the last cycle and over the last 25 cycles (mean
    and 95% bootstrap CI over seeds), the fraction of seeds that ever solved a test task."""
    rates = run["rates"]
    last, late = rates[:, -1], rates[:, -25:].mean(axis=1)
    cell = lambda x: stats.ci_text(float(x.mean()), [float(v) for v in stats.bootstrap_ci(x)])
    return [run["label"], stats.seed_range(run["seeds"]), f"{run['steps'][:, -1].mean():,.0f}", cell(last), cell(late),
            f"{int((rates.max(axis=1) > 0).sum())}/{len(run['seeds'])}"]


def plot(runs: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = [e for e in ENVS if any(r["env"] == e for r in runs)]
    names = list(dict.fromkeys(r["approach"] for r in runs))  # one colour per approach, in every panel
    colour = {name: f"C{i}" for i, name in enumerate(names)}
    fig, axes = plt.subplots(1, len(envs), figsize=(5.2 * len(envs), 4.2), sharey=True, squeeze=False)
    for ax, env in zip(axes[0], envs):
        for run in (r for r in runs if r["env"] == env):
            x, rates = run["steps"].mean(axis=0), run["rates"]
            low, high = stats.bootstrap_ci(rates)
            ax.plot(x, rates.mean(axis=0), color=colour[run["approach"]], ls="-" if run["budget"] == 1 else "--",
                    label=f"{run['label']} ({len(run['seeds'])} seeds)")
            ax.fill_between(x, low, high, color=colour[run["approach"]], alpha=0.15, lw=0)
        ax.set_xscale("log")
        ax.set_title(env)
        ax.set_xlabel("training steps per seed (log)")
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[0][0].set_ylabel("test solve rate (mean, 95% CI)")
    fig.suptitle("Low-level RL from the stuck state against ours and Maple Q, evaluation seeds", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> None:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("experiments", type=Path, nargs="+", help="finished experiment directories (train.py --out/--name)")
    parser.add_argument("--figure", type=Path, default=None, help="write the figure here (PNG) (default: none)")
    args = parser.parse_args(argv)
    runs = [load_run(d) for e in args.experiments for d in sorted(e.iterdir()) if (d / "metrics.csv").is_file()]
    for env in ENVS:
        chosen = [r for r in runs if r["env"] == env]
        if not chosen:
            continue
        print(f"\n{env}\n")
        print("| approach | seeds | training steps per seed | test solve rate, last cycle | last 25 cycles | seeds that ever solved a test task |")
        print("|---|---|---|---|---|---|")
        for run in chosen:
            print("| " + " | ".join(summary_row(run)) + " |")
    if args.figure:
        plot(runs, args.figure)
        print(f"\nfigure: {args.figure}")


if __name__ == "__main__":
    main()
