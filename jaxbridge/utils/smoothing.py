"""The paper's smooth reward (the paper's results section), the statistic of its figures and tables."""
from __future__ import annotations

import numpy as np


def smooth(rates: np.ndarray, window: int = 25) -> np.ndarray:
    """The paper's smooth reward (the paper's results section): the value at cycle c (1-based) is the sum of
    the rates of cycles c-25 .. c-1 divided by 25, so it ramps up from 0 over the first 25 cycles and
    excludes cycle c itself. rates: [..., cycles] -> [..., cycles]."""
    cumulative = np.concatenate([np.zeros(rates.shape[:-1] + (1,)), np.cumsum(rates, axis=-1)], axis=-1)
    before = np.arange(rates.shape[-1])  # cycles completed before cycle c = c - 1
    return (cumulative[..., before] - cumulative[..., np.maximum(before - window, 0)]) / window
