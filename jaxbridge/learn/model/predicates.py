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

`given_grammar` is the same structure over the env's declared novelty predicates instead of the literals
read off the data (the *given* setting: what a perception system would report).
"""
from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass

import numpy as np

from envs_jax.base import NoveltyPredicate
from jaxbridge.learn.model.segments import Segment, View
from planner.strips import Atom

PLACE_TOLERANCE = 1e-3  # positions this close are one place
MANY_VALUES = 4  # a feature with more distinct values gets quartile thresholds


def _token(x: float) -> str:
    return f"{x:.3g}".replace("-", "m").replace(".", "p")


Measure = tuple[str, int, "int | None"]  # (type, feature, other feature): a feature, or a band's distance


def measure_values(features: np.ndarray, feature: int, other: int | None) -> np.ndarray:
    """float[n] for rows float32[n, W]: the feature, or its distance to the other feature (a band)."""
    return features[:, feature] if other is None else np.abs(features[:, feature] - features[:, other])


@dataclass(frozen=True)
class Literal:
    type: str
    feature: int
    feature_name: str
    threshold: float
    above: bool
    binary: bool  # the feature takes two values: the name needs no threshold
    other: int | None = None  # a band: the feature's distance to this other feature of the object
    other_name: str = ""

    @property
    def name(self) -> str:
        if self.other is not None:
            side = "beyond" if self.above else "within"
            return f"{self.type}_{self.feature_name}_{side}_{_token(self.threshold)}_of_{self.other_name}"
        if self.binary:
            return f"{self.type}_{'' if self.above else 'not_'}{self.feature_name}"
        return f"{self.type}_{self.feature_name}_{'above' if self.above else 'below'}_{_token(self.threshold)}"

    @property
    def measure(self) -> Measure:
        return self.type, self.feature, self.other

    def holds(self, features: np.ndarray) -> np.ndarray:
        """bool[n] for rows float32[n, W] of this type."""
        above = measure_values(features, self.feature, self.other) > self.threshold
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

    def cuts(self, chosen: set[str]) -> dict[Measure, set[float]]:
        """The thresholds of the literals the predicates named in `chosen` read (quantified or paired)."""
        out: dict[Measure, set[float]] = {}
        for p in self.unary + self.all_at:
            if p.name in chosen:
                unary = p.unary if isinstance(p, AllAt) else p
                for lit in (unary.guard, unary.literal) if isinstance(unary, Either) else (unary,):
                    out.setdefault(lit.measure, set()).add(lit.threshold)
        return out

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

    def relation(self, name: str) -> SamePlace | Before | None:
        return self._relations.get(name)

    @functools.cached_property
    def _relations(self) -> dict[str, SamePlace | Before]:
        return {p.name: p for p in self.relations}

    def is_literal(self, name: str) -> bool:
        return name in self._literals

    def complement(self, name: str) -> str | None:
        """The literal of the same feature and threshold with the other sign (None: not a literal)."""
        found = self._literals.get(name)
        return dataclasses.replace(found, above=not found.above).name if found else None

    def reads(self, name: str) -> set[int]:
        """The features the literal `name` reads (none: not a literal)."""
        found = self._literals.get(name)
        return {f for f in (found.feature, found.other) if f is not None} if found else set()

    def static_literal(self, name: str) -> bool:
        """Whether `name` is a literal on features no segment changes."""
        found = self._literals.get(name)
        return found is not None and all((found.type, f) in self.static for f in (found.feature, found.other) if f is not None)

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


@dataclass(frozen=True)
class Data:
    """What the segments show: each measure's values on every object of its type in every view, the
    features no segment changes, and the type pairs with two objects at one place somewhere."""

    object_types: dict[str, tuple[str, ...]]
    values: dict[Measure, np.ndarray]
    static: frozenset[tuple[str, int]]
    shared: frozenset[tuple[str, str]]

    @functools.cached_property
    def distinct(self) -> dict[Measure, np.ndarray]:
        """Each measure's distinct values, sorted."""
        return {m: np.unique(v) for m, v in self.values.items()}


def read_data(segments: list[Segment], object_types: dict[str, tuple[str, ...]]) -> Data:
    """The measures of the segments' views: every feature, and a band from each changing feature with
    many values to each feature of its object that no segment changes (a key near its target)."""
    views = [s.before for s in segments] + [s.after for s in segments]
    values, static = {}, set()
    for t, feature_names in object_types.items():
        rows = np.concatenate([v.features[[i for i, ty in enumerate(v.types) if ty == t and v.names[i]]] for v in views])
        for f in range(len(feature_names)):
            values[t, f, None] = rows[:, f]
            if not any(not np.array_equal(_column(s.before, t, f), _column(s.after, t, f)) for s in segments):
                static.add((t, f))
        for f, g in itertools.permutations(range(len(feature_names)), 2):
            if (t, f) not in static and (t, g) in static and len(np.unique(rows[:, f])) > MANY_VALUES:
                values[t, f, g] = measure_values(rows, f, g)
    placed = [t for t in list(object_types)[1:]]  # the robot (the first type) takes part in no relation
    shared = set().union(*(_sharing(v, placed) for v in views))
    return Data(object_types, values, frozenset(static), frozenset(shared))


def _thresholds(values: np.ndarray) -> list[float]:
    """A threshold between each two of a few distinct values, the quartiles of many."""
    distinct = np.unique(values)
    if len(distinct) <= MANY_VALUES:
        return list((distinct[1:] + distinct[:-1]) / 2)
    return list(np.unique(np.quantile(values, [0.25, 0.5, 0.75])))


def make_grammar(data: Data, cuts: dict[Measure, set[float]] | None = None) -> Grammar:
    """The grammar's predicates over the measures `data` shows: literals at each feature's thresholds and
    at `cuts` (a band's only thresholds), guards on the features no segment changes, relations and
    quantified atoms between the types that share a place somewhere."""
    cuts, literals = cuts or {}, []
    for (t, f, g), values in data.values.items():
        names = data.object_types[t]
        seen = _thresholds(values) if g is None else []
        every = sorted(set(seen) | set(cuts.get((t, f, g), ())))
        binary = len(seen) == 1 and len(every) == 1
        literals += [Literal(t, f, names[f], float(c), above, binary, g, names[g] if g is not None else "")
                     for c in every for above in (True, False)]
    guards = [g for g in literals if g.other is None and (g.type, g.feature) in data.static and g.binary and not g.above]
    either = [Either(g, lit) for g in guards for lit in literals
              if lit.type == g.type and (lit.type, lit.feature) not in data.static]
    return _structure(data, tuple(literals + either))


def given_grammar(data: Data, declared: tuple[NoveltyPredicate, ...]) -> Grammar:
    """The grammar whose unary predicates are the env's declared ones (`NoveltyPredicate`s: what a
    perception system would report), each literal with its other side (a door open, and not), with the
    relations and quantified atoms `make_grammar` builds over them: nothing read off thresholds."""
    return _structure(data, tuple(p for d in declared for p in _declared(d, data)))


def _declared(declared: NoveltyPredicate, data: Data) -> tuple[Literal | Either, ...]:
    """A `NoveltyPredicate` in the grammar's terms: its literal and that literal's other side, or its
    `Either` when it is implied by a flag."""
    names = data.object_types[declared.type]
    feature, other = names.index(declared.feature), names.index(declared.other) if declared.other else None
    # a flag (every value seen 0 or 1) is named without its threshold: door_open, door_not_open
    seen = data.distinct.get((declared.type, feature, None), np.zeros(0))
    flag = other is None and 0 < declared.threshold < 1 and bool(np.isin(seen, (0, 1)).all())
    literal = Literal(declared.type, feature, declared.feature, float(declared.threshold), declared.above, flag, other,
                      declared.other or "")
    if declared.when is None:
        return literal, dataclasses.replace(literal, above=not literal.above)
    guard = Literal(declared.type, names.index(declared.when), declared.when, 0.5, False, True)
    return (Either(guard, literal),)


def _structure(data: Data, unary: tuple[Literal | Either, ...]) -> Grammar:
    """The grammar over `unary`: relations and quantified atoms between the types that share a place."""
    placed = [t for t in list(data.object_types)[1:]]
    pairs = list(itertools.permutations(placed, 2)) + [(t, t) for t in placed]
    relations = tuple(r for a, b in pairs for r in (SamePlace((a, b)), Before((a, b))))
    all_at = tuple(AllAt(a, u) for a, b in sorted(data.shared) for u in unary if u.type == b)
    return Grammar(unary, relations, all_at, next(iter(data.object_types)), data.static)


def stall_cuts(calls: list[tuple[View, dict[str, str], bool]], grammar: Grammar, data: Data) -> dict[Measure, set[float]]:
    """The thresholds an operator's stalls ask for, from its calls (state before, variable -> object,
    whether its effects followed): for the successes (all, or those where a relation between its objects
    holds, or those where it does not: the sides of `repair`'s case split) and each measure on one of its
    objects, or over the objects at one's place, the midpoint between the successes' largest value and
    the next value seen above it (and between their smallest and the one below), where a stall lies
    beyond it. Quartiles rarely fall where an effect starts (a key within 0.1 of its target)."""
    table = [(_extremes(view, binding, grammar, data), _relations(view, binding, grammar), worked)
             for view, binding, worked in calls]
    pos, neg = [t for t in table if t[2]], [t for t in table if not t[2]]
    relations = set().union(set(), *(t[1] for t in pos))
    subsets = [pos] + [[t for t in pos if (r in t[1]) == side] for r in sorted(relations) for side in (True, False)]
    cuts: dict[Measure, set[float]] = {}
    for subset in (s for s in subsets if s):
        for key in set().union(*(t[0] for t in subset)):
            low = min(t[0][key][0] for t in subset if key in t[0])
            high = max(t[0][key][1] for t in subset if key in t[0])
            values, measure = data.distinct[key[1]], key[1]
            above, below = values[values > high], values[values < low]
            if above.size and any(key in t[0] and t[0][key][1] > (high + above[0]) / 2 for t in neg):
                cuts.setdefault(measure, set()).add(float((high + above[0]) / 2))
            if below.size and any(key in t[0] and t[0][key][0] < (low + below[-1]) / 2 for t in neg):
                cuts.setdefault(measure, set()).add(float((low + below[-1]) / 2))
    return cuts


def _extremes(view: View, binding: dict[str, str], grammar: Grammar, data: Data) -> dict:
    """{(variable, measure): (smallest, largest) value} of each measure on the variable's object, and
    {((variable, "at"), measure): ...} over the objects at its place (where a type shares places)."""
    rows, out = _rows_by_type(view), {}
    for v, o in binding.items():
        if o not in view.names:
            continue
        i = view.names.index(o)
        t, here = view.types[i], view.position[i][None]
        for measure in data.distinct:
            if measure[0] == t:
                x = measure_values(view.features[i][None], measure[1], measure[2])[0]
                out[v, measure] = (x, x)
            elif (t, measure[0]) in data.shared and measure[0] in rows:
                _, features, pos = rows[measure[0]]
                x = measure_values(features[SamePlace((t, t)).holds(here, pos)[0]], measure[1], measure[2])
                if x.size:
                    out[(v, "at"), measure] = (x.min(), x.max())
    return out


def _relations(view: View, binding: dict[str, str], grammar: Grammar) -> frozenset[Atom]:
    """The grammar's relations between the binding's objects that hold in `view`, over its variables."""
    index = {v: view.names.index(o) for v, o in binding.items() if o in view.names}
    out = []
    for (a, i), (b, j) in itertools.permutations(index.items(), 2):
        for p in grammar.relations:
            if p.types == (view.types[i], view.types[j]) and view.names[i] != view.names[j] and \
                    p.holds(view.position[i][None], view.position[j][None])[0, 0]:
                out.append((p.name, a, b))
    return frozenset(out)


def _column(view: View, t: str, f: int) -> np.ndarray:
    return view.features[[i for i, ty in enumerate(view.types) if ty == t and view.names[i]], f]


def _sharing(view: View, types: list[str]) -> set[tuple[str, str]]:
    """The type pairs with two objects at one place in `view`."""
    rows = _rows_by_type(view)
    return {(a, b) for a, b in itertools.permutations(types, 2)
            if a in rows and b in rows and SamePlace((a, b)).holds(rows[a][2], rows[b][2]).any()}
