"""Statistics over seeds that hold across machines: mean and interquartile mean (IQM) with 95% bootstrap
confidence intervals, the protocol of Agarwal et al. 2021 ("Deep RL at the edge of the statistical
precipice").

A table's cell summarises one approach on one env, so the stratified bootstrap (resampling runs within
each task) is the plain bootstrap over seeds: each replicate draws the seeds with replacement and
recomputes the statistic; the interval is the replicates' 2.5th and 97.5th percentiles. The resampling
uses a fixed generator, so the same metrics give the same intervals on every machine.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

CONFIDENCE = 0.95
REPS = 2_000  # bootstrap replicates per interval, as rliable's curves (its endpoints move by ~0.01 at 32 seeds)


def mean(scores: np.ndarray, axis: int = 0) -> np.ndarray:
    return np.mean(scores, axis=axis)


def iqm(scores: np.ndarray, axis: int = 0) -> np.ndarray:
    """Interquartile mean: the mean of what is left after cutting int(n/4) runs from each end (of n along
    `axis`), i.e. scipy.stats.trim_mean(scores, 0.25)."""
    ordered = np.sort(scores, axis=axis)
    n = ordered.shape[axis]
    cut = int(0.25 * n)
    return np.take(ordered, np.arange(cut, n - cut), axis=axis).mean(axis=axis)


STATISTICS: dict[str, Callable[[np.ndarray, int], np.ndarray]] = {"mean": mean, "iqm": iqm}


def bootstrap_ci(scores: np.ndarray, statistic: Callable[[np.ndarray, int], np.ndarray] = mean, reps: int = REPS,
                 confidence: float = CONFIDENCE, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of the percentile bootstrap interval of `statistic` over the runs of `scores` [runs, ...]
    (every trailing entry, e.g. each cycle, gets its interval from the same resampled runs)."""
    scores = np.asarray(scores, np.float64)
    runs = scores.shape[0]
    draws = np.random.default_rng(seed).integers(0, runs, size=(reps, runs))
    replicates = statistic(scores[draws], 1)  # [reps, ...]
    tail = 100 * (1 - confidence) / 2
    low, high = np.percentile(replicates, [tail, 100 - tail], axis=0)
    return low, high


def ratio_ci(numerator: np.ndarray, denominator: np.ndarray, reps: int = REPS, confidence: float = CONFIDENCE,
             seed: int = 0) -> tuple[float, float, float]:
    """The ratio of two means over the same seeds, (ratio, low, high): its percentile bootstrap interval
    resamples the seeds once for both (paired), so what the seeds share cancels."""
    a, b = np.asarray(numerator, np.float64), np.asarray(denominator, np.float64)
    draws = np.random.default_rng(seed).integers(0, len(a), size=(reps, len(a)))
    with np.errstate(divide="ignore", invalid="ignore"):
        replicates = a[draws].mean(1) / b[draws].mean(1)
    tail = 100 * (1 - confidence) / 2
    low, high = np.nanpercentile(replicates, [tail, 100 - tail])
    return float(a.mean() / b.mean()), float(low), float(high)


def verdict(value: float, interval: tuple[float, float] | None, bar: float, at_least: bool = True) -> str:
    """A bar judged by one rule: "clearly met" when the whole 95% interval clears it, "met" when the
    point estimate does, else "missed" (`at_least`: the bar is a floor; else a ceiling)."""
    clears = (lambda x: x >= bar) if at_least else (lambda x: x <= bar)
    if interval is not None and clears(interval[0] if at_least else interval[1]):
        return "clearly met"
    return "met" if clears(value) else "missed"


def describe(scores: np.ndarray, reps: int = REPS) -> dict[str, np.ndarray]:
    """Every statistic of the tables for `scores` [runs, ...]: mean and IQM, each with its 95% interval
    (`mean_low`, `mean_high`, ...), and the lowest and highest run."""
    scores = np.asarray(scores, np.float64)
    out = {}
    for name, statistic in STATISTICS.items():
        out[name] = statistic(scores, 0)
        out[f"{name}_low"], out[f"{name}_high"] = bootstrap_ci(scores, statistic, reps)
    out["min"], out["max"] = scores.min(0), scores.max(0)
    return out


def drop_from_best(curve: np.ndarray) -> np.ndarray:
    """curve[..., c] minus the highest of curve[..., :c] (0 at the first cycle): how far a curve stands
    below its best so far (negative), or above it (positive)."""
    best_before = np.maximum.accumulate(curve, axis=-1)
    return curve - np.concatenate([curve[..., :1], best_before[..., :-1]], axis=-1)


def describe_drop(scores: np.ndarray, reps: int = REPS) -> dict[str, np.ndarray]:
    """`describe`'s keys for the fall below the best so far, per cycle (scores [runs, cycles]): for mean
    and IQM, the statistic's curve at cycle c minus its highest value before c, with the bootstrap
    interval of that difference (each replicate resamples the seeds once for every cycle); min and max:
    the seeds' own falls (each seed's rate minus its best before)."""
    scores = np.asarray(scores, np.float64)
    out = {}
    for name, statistic in STATISTICS.items():
        fall = lambda runs, axis, statistic=statistic: drop_from_best(statistic(runs, axis))
        out[name] = fall(scores, 0)
        out[f"{name}_low"], out[f"{name}_high"] = bootstrap_ci(scores, fall, reps)
    per_seed = drop_from_best(scores)
    out["min"], out["max"] = per_seed.min(0), per_seed.max(0)
    return out


def ci_text(value: float, interval, signed: bool = False) -> str:
    """"0.85 [0.70, 0.95]": a statistic and its interval (the value alone where the interval rounds to one
    point); `signed`: every number with its sign ("-0.02 [-0.05, +0.01]", for differences)."""
    f = ("{:+.2f}" if signed else "{:.2f}").format
    point, low, high = f(value), f(interval[0]), f(interval[1])
    return point if low == high else f"{point} [{low}, {high}]"


def cell_text(cell: dict, statistic: str = "mean", signed: bool = False) -> str:
    """A table cell ({statistic: value, f"{statistic}_ci": [low, high], ...}) as ci_text."""
    return ci_text(cell[statistic], cell[f"{statistic}_ci"], signed)


def seed_range(seeds: list[int]) -> str:
    """The seeds in words: "100-131", "0-3, 7"."""
    seeds = sorted(seeds)
    spans, start = [], None
    for i, s in enumerate(seeds):
        start = s if start is None else start
        if i + 1 == len(seeds) or seeds[i + 1] != s + 1:
            spans.append(f"{start}" if start == s else f"{start}-{s}")
            start = None
    return ", ".join(spans)
