"""The run directory: metrics CSV, summary JSON, config JSON and the learning-curve figure.

Every file is written atomically (jaxbridge/utils/files.py).
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.smoothing import smooth

METRIC_FIELDS = ("test_solve_rate", "train_success_rate", "train_env_steps", "train_decisions", "test_env_steps",
                 "epsilon", "loss", "q_abs_max", "buffer_size", "table_misses")
REPORT_CYCLES = (10, 25, 50, 100)




def history_arrays(history: list) -> dict[str, np.ndarray]:
    """Per-cycle CycleMetrics (numpy) -> {field: float[seeds, cycles]}."""
    return {f: np.stack([np.asarray(getattr(m, f), np.float64) for m in history], axis=-1) for f in METRIC_FIELDS}


def metrics_csv(history: list, seeds: list[int]) -> str:
    arrays = history_arrays(history)
    test_smooth, train_smooth = smooth(arrays["test_solve_rate"]), smooth(arrays["train_success_rate"])
    out = io.StringIO()
    writer = csv.writer(out)
    writer.writerow(["seed", "cycle", *METRIC_FIELDS, "test_smooth_reward", "train_smooth_reward"])
    for i, seed in enumerate(seeds):
        for c in range(len(history)):
            writer.writerow([seed, c + 1, *(f"{arrays[f][i, c]:.6g}" for f in METRIC_FIELDS),
                             f"{test_smooth[i, c]:.6g}", f"{train_smooth[i, c]:.6g}"])
    return out.getvalue()


def summary(history: list, seeds: list[int], elapsed_s: float, devices: str | None = None) -> dict:
    """Headline numbers: the tables of reference/results.md, for this run (`devices`: what ran it, e.g.
    "2 cpu"; informational, the numbers do not depend on it)."""
    arrays = history_arrays(history)
    rates = arrays["test_solve_rate"]
    test_smooth = smooth(rates)
    cycles = rates.shape[1]

    def at(c):
        return {"mean": float(rates[:, c - 1].mean()), "min": float(rates[:, c - 1].min()),
                "max": float(rates[:, c - 1].max())}

    return {
        "seeds": seeds, "cycles": cycles, "elapsed_s": round(elapsed_s, 2),
        **({"devices": devices} if devices else {}),
        "test_solve_rate_at": {str(c): at(c) for c in REPORT_CYCLES if c <= cycles},
        "smooth_reward_final": {"mean": float(test_smooth[:, -1].mean()),
                                "per_seed": [round(float(x), 4) for x in test_smooth[:, -1]]},
        "mean_test_solve_rate_per_cycle": [round(float(x), 4) for x in rates.mean(0)],
        "train_success_rate_final": float(arrays["train_success_rate"][:, -1].mean()),
        "train_env_steps_total": int(arrays["train_env_steps"].sum()),
        "bridge_decisions_total": int(arrays["train_decisions"].sum()),
        "table_misses_total": int(arrays["table_misses"].sum()),
    }


def plot_curves(curves: dict[str, dict[str, np.ndarray]], title: str) -> bytes:
    """PNG of test and training smooth reward vs cycle: one line per approach (mean over seeds) with a
    band from the lowest to the highest seed. curves: {label: {"test": [seeds, cycles], "train": ...}}."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, key, name in zip(axes, ("test", "train"), ("test", "training")):
        for label, data in curves.items():
            values = smooth(data[key])
            x = np.arange(1, values.shape[1] + 1)
            line, = ax.plot(x, values.mean(0), label=label)
            ax.fill_between(x, values.min(0), values.max(0), color=line.get_color(), alpha=0.2)
        ax.set_xlabel("online learning cycle")
        ax.set_title(f"{name} smooth reward")
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("smooth reward (25-cycle window / 25)")
    axes[0].legend(loc="lower right")
    fig.suptitle(title)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def write_run_files(run_dir: Path, config_dict: dict, history: list, seeds: list[int], elapsed_s: float,
                    label: str = "ours", devices: str | None = None) -> dict:
    arrays = history_arrays(history)
    info = summary(history, seeds, elapsed_s, devices)
    write_atomic(run_dir / "metrics.csv", metrics_csv(history, seeds))
    write_atomic(run_dir / "summary.json", json.dumps(info, indent=2) + "\n")
    curves = {label: {"test": arrays["test_solve_rate"], "train": arrays["train_success_rate"]}}
    write_atomic(run_dir / "curves.png", plot_curves(curves, f"{config_dict['env']}, {len(seeds)} seeds"))
    return info
