"""Samplers: a learned operator's continuous parameter as a linear function of its acted-on object's
features (the slot object's, or the object whose literals its effects change, found among the ground
operator's objects through the relations its preconditions state to the slot object), fitted by least squares on the quickest of the calls that had the operator's effect (a push's
force follows the door's stiffness; a twist that turns a jug in one wrist step leaves more of the horizon
than one that takes two); a skill whose bounds are equal keeps its constant."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jaxbridge.learn.model.predicates import Before, SamePlace
from jaxbridge.learn.model.segments import Segment, View


@dataclass(frozen=True)
class Sampler:
    weights: tuple[float, ...]  # per feature of the input object, then the intercept
    low: float
    high: float
    input_type: str | None = None  # the input object's type, where it is not the slot object
    links: tuple[tuple[SamePlace | Before, bool], ...] = ()  # relations tying it to the slot object (slot first?)

    def input_object(self, view: View, slot_object: str | None, args: tuple[str, ...]) -> str | None:
        """The object the parameter follows: the slot object, or the first of the input type that every
        link ties to it (a key's door at the cell the skill's slot names) among the ground operator's `args`
        (with no link every object of the type is tied: the door a robot opens is its operator's, not the
        view's first)."""
        if self.input_type is None:
            return slot_object
        at = lambda name: view.position[view.names.index(name)][None]
        tied = lambda name: all(slot_object in view.names and
                                rel.holds(*((at(slot_object), at(name)) if first else (at(name), at(slot_object))))[0, 0]
                                for rel, first in self.links)
        return next((n for n, t in zip(view.names, view.types)
                     if n in args and t == self.input_type and tied(n)), None)

    def __call__(self, view: View, slot_object: str | None, args: tuple[str, ...]) -> float:
        inputs = _inputs(view, self.input_object(view, slot_object, args))
        return float(np.clip(np.dot(inputs, self.weights), self.low, self.high))


def _inputs(view: View, name: str | None) -> np.ndarray:
    row = view.names.index(name) if name in view.names else None
    features = view.features[row] if row is not None else np.zeros(view.features.shape[1], np.float32)
    return np.append(features, 1.0)


def fit_sampler(calls: list[tuple[Segment, str | None]], low: float, high: float, input_type: str | None = None,
                links: tuple = ()) -> Sampler:
    """The least-squares fit of the parameters of the calls that took the fewest env steps (all calls
    where fewer than two did) on their slot objects' features (the minimum-norm one where features repeat
    or never vary); `calls` pairs each call with its input object."""
    fewest = min(segment.steps for segment, _ in calls)
    quickest = [c for c in calls if c[0].steps == fewest]
    calls = quickest if len(quickest) >= 2 else calls
    inputs = np.stack([_inputs(segment.before, name) for segment, name in calls])
    params = np.array([segment.param for segment, _ in calls])
    weights, *_ = np.linalg.lstsq(inputs.astype(np.float64), params, rcond=None)
    return Sampler(tuple(float(w) for w in weights), low, high, input_type, links)
