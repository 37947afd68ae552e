"""The figures of numbers (the run's and the experiment's curves, the generalisation sweep), beside the
pictures of episodes: each approach keeps one colour in every figure, its place among the registered
approaches, so a line is recognised across figures."""
from __future__ import annotations

import io

import numpy as np

from jaxbridge.learn.approaches import KNOWN
from jaxbridge.utils import stats

PANELS = (("test_solve_rate", "test solve rate per cycle", "fraction of the 10 test tasks solved"),
          ("test_smooth_reward", "test smooth reward", "smooth reward (25-cycle window / 25)"),
          ("train_smooth_reward", "training smooth reward", None))


def colour(label: str) -> str:
    """An approach's colour, by its name or label (a run's label may add to it: "ours, PQN"); others get
    the palette's colours after the approaches', by a stable hash of the label."""
    import matplotlib

    palette = [matplotlib.colormaps["tab20"](i) for i in range(20)]
    names = list(KNOWN)
    for i, (name, approach) in enumerate(KNOWN.items()):
        if label in (name, approach.label):
            return matplotlib.colors.to_hex(palette[i % 20])
    return matplotlib.colors.to_hex(palette[(len(names) + sum(map(ord, label))) % 20])


def same_as(lines: dict[str, np.ndarray]) -> dict[str, str]:
    """Each line that coincides with an earlier one (equal means, NaNs alike), and which: drawn dashed over
    it and named in the legend, so that a hidden line is not taken for a missing one."""
    earlier: dict[str, np.ndarray] = {}
    found = {}
    for label, values in lines.items():
        twin = next((other for other, seen in earlier.items() if np.array_equal(seen, values, equal_nan=True)), None)
        if twin is not None:
            found[label] = twin
        earlier[label] = values
    return found


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def plot_curves(curves: dict[str, dict[str, dict[str, np.ndarray]]], title: str) -> bytes:
    """PNG of the paper's figure and the tables' quantity: the per-cycle test solve rate (what the tables
    report), and the test and training smooth reward vs cycle (the paper's curves); one line per approach
    (mean over seeds), its 95% bootstrap interval as a band and the lowest to highest seed as a lighter
    one; the legend beside the panels, clear of the lines, naming lines that coincide (same_as).
    curves: {label: curve_statistics(...)}."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 4))
    axes = fig.subplots(1, len(PANELS), sharey=True)
    twins = same_as({label: np.stack([described[key]["mean"] for key, _, _ in PANELS]) for label, described in curves.items()})
    for ax, (key, name, ylabel) in zip(axes, PANELS):
        for label, described in curves.items():
            values = described[key]
            x = np.arange(1, len(values["mean"]) + 1)
            shown = f"{label} (on {twins[label]}'s line)" if label in twins else label
            line, = ax.plot(x, values["mean"], label=shown, color=colour(label), ls="--" if label in twins else "-")
            ax.fill_between(x, values["mean_low"], values["mean_high"], color=line.get_color(), alpha=0.3, lw=0)
            ax.fill_between(x, values["min"], values["max"], color=line.get_color(), alpha=0.08, lw=0)
        ax.set_xlabel("online learning cycle")
        ax.set_title(name)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
        if ylabel:
            ax.set_ylabel(ylabel)
            ax.yaxis.set_tick_params(labelleft=True)
    axes[-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False, fontsize=9)
    fig.suptitle(title + "; mean, 95% CI (dark band), min-max (light band)", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def plot_sweep(result, title: str) -> bytes:
    """PNG of a generalisation sweep (run/sweep.SweepResult): solve rate vs count, one line per label
    (mean over seeds) with its 95% bootstrap interval as a band and the lowest to the highest seed as a
    lighter one."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4.2))
    ax = fig.add_subplot()
    x = np.asarray(result.counts)
    twins = same_as({label: rate.mean(0) for label, rate in result.solve_rate.items() if not np.isnan(rate).all()})
    for label, rate in result.solve_rate.items():
        if np.isnan(rate).all():  # listed, so that a missing line is explained
            ax.plot([], [], " ", label=f"{label}: n/a (its full-state input is too small)")
            continue
        on = f", on {twins[label]}'s line" if label in twins else ""
        line, = ax.plot(x, rate.mean(0), marker="o", markersize=3, label=f"{label} ({rate.shape[0]} seeds{on})",
                        color=colour(label), ls="--" if label in twins else "-")
        low, high = stats.bootstrap_ci(rate)  # NaN at counts the approach cannot see: nothing drawn there
        ax.fill_between(x, low, high, color=line.get_color(), alpha=0.3, lw=0)
        ax.fill_between(x, rate.min(0), rate.max(0), color=line.get_color(), alpha=0.08, lw=0)
    ax.set_xlabel(f"number of {result.counted} ({result.setting})")
    ax.set_ylabel(f"test solve rate ({result.tasks_per_count} tasks per point and seed)")
    ax.set_xticks(x)
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)  # clear of the lines
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    return _png(fig)
