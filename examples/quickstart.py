"""The Python API in one page: train ours on Light Switch Door, plot its curve, load the trained policy and
evaluate it on rows twice as long as any it was tested on (docs/API.md walks through each call).

    python examples/quickstart.py                      # 4 seeds x 20 cycles, about a minute on a laptop CPU
    python examples/quickstart.py --cycles 5 --out /tmp/quick
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt  # noqa: E402

import jaxbridge  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=4, help="seeds 0..N-1 (default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=20, help="learning cycles (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=Path("runs"), help="where the run and the plot go (default: %(default)s)")
    args = parser.parse_args()

    # 1. Train: the experiment directory out/quickstart, and every metric as a [seeds, cycles] array.
    experiment = jaxbridge.train("light_switch_door", approaches="ours", seeds=args.seeds, cycles=args.cycles,
                                 out=args.out, name="quickstart")
    rates = experiment.metrics["ours"]["test_solve_rate"]
    print(f"test solve rate at cycle {args.cycles}: {rates[:, -1].mean():.2f} (seeds: {rates[:, -1].round(2).tolist()})")

    # 2. Plot the mean test solve rate per cycle, with every seed's curve behind it.
    cycles = range(1, args.cycles + 1)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(cycles, rates.T, color="tab:blue", alpha=0.25, lw=1)
    ax.plot(cycles, experiment.curve("ours"), color="tab:blue", lw=2, label=f"ours, mean of {args.seeds} seeds")
    ax.set(xlabel="cycle", ylabel="test solve rate", ylim=(-0.05, 1.05), title="Light Switch Door")
    ax.legend(loc="lower right")
    fig.savefig(args.out / "quickstart.png", dpi=120, bbox_inches="tight")
    print(f"plot: {args.out / 'quickstart.png'}")

    # 3. Load the trained policy and evaluate it on 40-cell rows with 3 doors (training: 5 cells, 1 door).
    policy = jaxbridge.load(experiment.run_dir)
    episodes = policy.evaluate(task_size={"cells": 40, "doors": 3}, num_tasks=10)
    print(f"40-cell tasks, 3 doors: solve rate {episodes.solve_rate:.2f} over {episodes.success.size} episodes; "
          f"per seed {episodes.per_seed()}")


if __name__ == "__main__":
    main()
