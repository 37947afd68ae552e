"""Invented predicates: one grammar over any env's object view, its thresholds and pairs read off the data.

* `Literal`: one feature of one type against a threshold (`door_card_held`, `door_not_card_held`); a
  feature with few values seen gets a threshold between each two, one with many its quartiles.
* `Either`: "not X or Y", that is X implies Y: X a two-valued feature that no segment changes (what
  kind of object it is), Y a literal on one that changes ("a keycard door has its card held").
* `SamePlace`, `Before`: two objects at one position, or the first's x below the second's.
* `AllAt`: every object of a type at the place of the argument satisfies a unary predicate ("a cell
  with no closed keycard door"): the universally quantified atom a blocked move needs.
* `Span`: every object of a type from the first argument's place up to the second's (excluded)
  satisfies a unary predicate that a repaired precondition quantifies with `AllAt` ("no closed door on
  the way"): what a skill that walks needs of the cells it crosses.

The robot takes part in no relation: where it is, is the planner model's own (each model tracks it).
"""
from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass

import numpy as np

from jaxbridge.learn.model.segments import Segment, View
from planner.strips import Atom

PLACE_TOLERANCE = 1e-3  # positions this close are one place
MANY_VALUES = 4  # a feature with more distinct values gets quartile thresholds


def _token(x: float) -> str:
    return f"{x:.3g}".replace("-", "m").replace(".", "p")


@dataclass(frozen=True)
class Literal:
    type: str
    feature: int
    feature_name: str
    threshold: float
    above: bool
    binary: bool  # the feature takes two values: the name needs no threshold

    @property
    def name(self) -> str:
        if self.binary:
            return f"{self.type}_{'' if self.above else 'not_'}{self.feature_name}"
        return f"{self.type}_{self.feature_name}_{'above' if self.above else 'below'}_{_token(self.threshold)}"

    def holds(self, features: np.ndarray) -> np.ndarray:
        """bool[n] for rows float32[n, W] of this type."""
        above = features[:, self.feature] > self.threshold
        return above if self.above else ~above


@dataclass(frozen=True)
class Either:
    guard: Literal  # "not X" on a feature no segment changes
    literal: Literal

    type = property(lambda self: self.guard.type)
    name = property(lambda self: f"{self.guard.name}_or_{self.literal.name.removeprefix(self.type + '_')}")

    def holds(self, features: np.ndarray) -> np.ndarray:
        return self.guard.holds(features) | self.literal.holds(features)


@dataclass(frozen=True)
class SamePlace:
    types: tuple[str, str]
    name = property(lambda self: f"same_place_{self.types[0]}_{self.types[1]}")

    def holds(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """bool[n, m] for positions float32[n, 3], float32[m, 3]."""
        return np.abs(a[:, None, :] - b[None, :, :]).max(-1) < PLACE_TOLERANCE


@dataclass(frozen=True)
class Before:
    types: tuple[str, str]
    name = property(lambda self: f"before_{self.types[0]}_{self.types[1]}")

    def holds(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return a[:, None, 0] < b[None, :, 0] - PLACE_TOLERANCE


@dataclass(frozen=True)
class AllAt:
    place_type: str
    unary: Literal | Either
    name = property(lambda self: f"{self.place_type}_all_{self.unary.name}")


@dataclass(frozen=True)
class Span:
    place_type: str
    unary: Literal | Either
    name = property(lambda self: f"{self.place_type}_span_all_{self.unary.name}")

    def holds(self, places: np.ndarray, at: np.ndarray, fails: np.ndarray) -> np.ndarray:
        """bool[n, n] for place positions float32[n, 3], the unary's objects' positions float32[m, 3] and
        where it fails bool[m]: along x, place i before place j and no failing object in [i, j)."""
        x, z = places[:, 0], at[:, 0]
        inside = (z[None, None, :] >= x[:, None, None] - PLACE_TOLERANCE) & (z[None, None, :] < x[None, :, None] - PLACE_TOLERANCE)
        return (x[:, None] < x[None, :] - PLACE_TOLERANCE) & ~(inside & fails).any(-1)


@dataclass(frozen=True)
class Grammar:
    """The candidate predicates for one env's data."""

    unary: tuple[Literal | Either, ...]
    relations: tuple[SamePlace | Before, ...]
    all_at: tuple[AllAt, ...]
    robot: str  # the robot's type
    static: frozenset[tuple[str, int]]  # (type, feature): what no segment changes, what kind of object it is
    spans: tuple[Span, ...] = ()  # added once repairs chose their quantified atoms (`with_spans`)

    def with_spans(self, chosen: set[str]) -> "Grammar":
        """The grammar with a `Span` for the unary predicate of each `AllAt` named in `chosen`."""
        spans = tuple(dict.fromkeys(Span(p.place_type, p.unary) for p in self.all_at if p.name in chosen))
        return dataclasses.replace(self, spans=spans)

    @functools.cached_property
    def _kinds(self) -> dict[str, int]:
        composite = {p.name: 1 + isinstance(p, Either) for p in self.unary} | {p.name: 1 for p in self.relations}
        return composite | {p.name: 2 + isinstance(p.unary, Either) for p in self.all_at + self.spans}

    @functools.cached_property
    def _literals(self) -> dict[str, Literal]:
        return {p.name: p for p in self.unary if isinstance(p, Literal)}

    def kind(self, name: str) -> int:
        """How composite the predicate `name` is: 0 the planner model's, 1 a literal or relation, 2 a pair
        of literals or a quantified literal, 3 a quantified pair (the learner prefers the simplest)."""
        return self._kinds.get(name, 0)

    def is_literal(self, name: str) -> bool:
        return name in self._literals

    def complement(self, name: str) -> str | None:
        """The literal of the same feature and threshold with the other sign (None: not a literal)."""
        found = self._literals.get(name)
        return dataclasses.replace(found, above=not found.above).name if found else None

    def static_literal(self, name: str) -> bool:
        """Whether `name` is a literal on a feature no segment changes."""
        found = self._literals.get(name)
        return found is not None and (found.type, found.feature) in self.static

    @property
    def signatures(self) -> dict[str, tuple[str, ...]]:
        """{predicate name: argument types}, every predicate of the grammar."""
        out = {p.name: (p.type,) for p in self.unary}
        out |= {p.name: p.types for p in self.relations} | {p.name: (p.place_type,) * 2 for p in self.spans}
        return out | {p.name: (p.place_type,) for p in self.all_at}

    def atoms(self, view: View) -> frozenset[Atom]:
        """The grammar's atoms that hold in `view`, over the task's objects."""
        rows = _rows_by_type(view)
        out: list[Atom] = []
        for p in self.unary:
            names, features, _ = rows.get(p.type, ((), None, None))
            if names:
                out += [(p.name, n) for n, ok in zip(names, p.holds(features)) if ok]
        for p in self.relations:
            (na, _, pa), (nb, _, pb) = rows.get(p.types[0], ((), None, None)), rows.get(p.types[1], ((), None, None))
            if na and nb:
                ok = p.holds(pa, pb)
                out += [(p.name, na[i], nb[j]) for i, j in zip(*np.nonzero(ok)) if na[i] != nb[j]]
        for p in self.all_at:
            if found := _quantified(rows, p):
                places, at, pos, fails = found
                here = SamePlace((p.place_type, p.unary.type)).holds(at, pos)
                out += [(p.name, places[i]) for i in range(len(places)) if not (here[i] & fails).any()]
        return frozenset(out) | self._span_atoms(rows)

    def span_atoms(self, view: View) -> frozenset[Atom]:
        """The atoms of the grammar's spans alone that hold in `view`."""
        return self._span_atoms(_rows_by_type(view))

    def _span_atoms(self, rows) -> frozenset[Atom]:
        out = []
        for p in self.spans:
            if found := _quantified(rows, p):
                places, at, pos, fails = found
                out += [(p.name, places[i], places[j]) for i, j in zip(*np.nonzero(p.holds(at, pos, fails)))]
        return frozenset(out)


def _quantified(rows, p: "AllAt | Span"):
    """(place names, their positions, the unary's objects' positions, where the unary fails) for a
    quantified predicate over `rows` (`_rows_by_type`), None without places; no objects: nothing fails."""
    (places, _, at), (names, features, pos) = rows.get(p.place_type, ((), None, None)), rows.get(p.unary.type, ((), None, None))
    if not places:
        return None
    return (places, at, pos, ~p.unary.holds(features)) if names else (places, at, np.zeros((0, 3)), np.zeros(0, bool))


def _rows_by_type(view: View) -> dict[str, tuple[tuple[str, ...], np.ndarray, np.ndarray]]:
    """{type: (names, features, positions)} of the task's objects."""
    out: dict = {}
    for t in dict.fromkeys(view.types):
        rows = [i for i, (n, ty) in enumerate(zip(view.names, view.types)) if n is not None and ty == t]
        if rows:
            out[t] = (tuple(view.names[i] for i in rows), view.features[rows], view.position[rows])
    return out


def _thresholds(values: np.ndarray) -> list[float]:
    distinct = np.unique(values)
    if len(distinct) <= MANY_VALUES:
        return list((distinct[1:] + distinct[:-1]) / 2)
    return list(np.unique(np.quantile(values, [0.25, 0.5, 0.75])))


def make_grammar(segments: list[Segment], object_types: dict[str, tuple[str, ...]]) -> Grammar:
    """The grammar's predicates over the types and feature values the segments show: literals with their
    thresholds, guards on the features no segment changes, relations and quantified atoms between the
    types that share a place somewhere."""
    views = [s.before for s in segments] + [s.after for s in segments]
    robot = next(iter(object_types))
    literals, static = [], set()
    for t, feature_names in object_types.items():
        for f, fname in enumerate(feature_names):
            values = np.concatenate([v.features[[i for i, ty in enumerate(v.types) if ty == t and v.names[i]], f] for v in views])
            changed = any(not np.array_equal(_column(s.before, t, f), _column(s.after, t, f)) for s in segments)
            cuts = _thresholds(values) if values.size else []
            if not changed:
                static.add((t, f))
            literals += [Literal(t, f, fname, float(c), above, len(cuts) == 1) for c in cuts for above in (True, False)]
    guards = [g for g in literals if (g.type, g.feature) in static and g.binary and not g.above]
    either = [Either(g, lit) for g in guards for lit in literals
              if lit.type == g.type and (lit.type, lit.feature) not in static]
    unary = tuple(literals + either)
    placed = [t for t in object_types if t != robot]
    shared = set().union(*(_sharing(v, placed) for v in views))
    pairs = list(itertools.permutations(placed, 2)) + [(t, t) for t in placed]
    relations = tuple(r for a, b in pairs for r in (SamePlace((a, b)), Before((a, b))))
    all_at = tuple(AllAt(a, u) for a, b in sorted(shared) for u in unary if u.type == b)
    return Grammar(unary, relations, all_at, robot, frozenset(static))


def _column(view: View, t: str, f: int) -> np.ndarray:
    return view.features[[i for i, ty in enumerate(view.types) if ty == t and view.names[i]], f]


def _sharing(view: View, types: list[str]) -> set[tuple[str, str]]:
    """The type pairs with two objects at one place in `view`."""
    rows = _rows_by_type(view)
    return {(a, b) for a, b in itertools.permutations(types, 2)
            if a in rows and b in rows and SamePlace((a, b)).holds(rows[a][2], rows[b][2]).any()}
