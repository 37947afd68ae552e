"""Samplers: a learned operator's continuous parameter as a linear function of its acted-on object's
features, fitted by least squares on the calls that had the operator's effect (a push's force follows
the door's stiffness); a skill whose bounds are equal keeps its constant."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jaxbridge.learn.model.segments import Segment, View


@dataclass(frozen=True)
class Sampler:
    weights: tuple[float, ...]  # per feature of the slot object, then the intercept
    low: float
    high: float

    def __call__(self, view: View, slot_object: str | None) -> float:
        return float(np.clip(np.dot(_inputs(view, slot_object), self.weights), self.low, self.high))


def _inputs(view: View, slot_object: str | None) -> np.ndarray:
    row = view.names.index(slot_object) if slot_object in view.names else None
    features = view.features[row] if row is not None else np.zeros(view.features.shape[1], np.float32)
    return np.append(features, 1.0)


def fit_sampler(calls: list[tuple[Segment, str | None]], low: float, high: float) -> Sampler:
    """The least-squares fit of the calls' parameters on their slot objects' features (the minimum-norm
    one where features repeat or never vary)."""
    inputs = np.stack([_inputs(segment.before, slot_object) for segment, slot_object in calls])
    params = np.array([segment.param for segment, _ in calls])
    weights, *_ = np.linalg.lstsq(inputs.astype(np.float64), params, rcond=None)
    return Sampler(tuple(float(w) for w in weights), low, high)
