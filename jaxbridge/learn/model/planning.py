"""Plans with a learned model: the model grounded on a state's objects and static atoms, searched by A*
with h_ff over helpful actions (search.py).

A `ModelPlanner` serves one episode: the objects and the atoms no operator changes rarely change within
one, so each grounding (0.1-0.4 s on a 7x7 Doorknobs map, about 1,600 ground operators) is built once per set of
static atoms and kept for every replan.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.operators import typed_objects
from jaxbridge.learn.model.search import find_plan
from jaxbridge.learn.model.segments import View
from planner.heuristic import Relaxation
from planner.search import BitOperator
from planner.strips import Atom, GroundOperator, Problem, ground


@dataclass
class Grounding:
    """The model's ground operators for one set of objects and static atoms, as bit operators over an
    index of atoms (grown by atoms no operator names, e.g. a goal's) and their delete relaxation."""

    ops: list[GroundOperator]
    index: dict[Atom, int] = field(default_factory=dict)

    def __post_init__(self):
        self.bit_ops = [BitOperator(self.bits(o.pre), self.bits(o.add), self.bits(o.delete)) for o in self.ops]
        self.relaxation = Relaxation(self.bit_ops)

    def bits(self, atoms) -> int:
        return sum(1 << self.index.setdefault(a, len(self.index)) for a in sorted(atoms))


class ModelPlanner:
    """Plans with `model` from any state, its groundings kept (see the module)."""

    def __init__(self, model: LearnedModel):
        self.model = model
        self.groundings: dict[tuple, Grounding] = {}

    def split(self, view: View) -> tuple[frozenset[Atom], frozenset[Atom]]:
        """(static, fluent): the model's atoms that hold in `view`, those no operator changes and the others."""
        atoms, fluent = self.model.atoms(view), self.model.domain.fluent_predicates
        return frozenset(a for a in atoms if a[0] not in fluent), frozenset(a for a in atoms if a[0] in fluent)

    def plan(self, view: View, goal: frozenset[Atom]) -> list[GroundOperator] | None:
        """A plan from `view` to `goal` in the learned model, None if the search finds none."""
        static, fluent = self.split(view)
        # sorted: the grounding's order, so its plans, must not follow the hash order of a set
        objects = dict(sorted(typed_objects(view, self.model.domain).items()))
        key = (tuple(objects.items()), static)
        if key not in self.groundings:
            self.groundings[key] = Grounding(ground(Problem(self.model.domain, objects, static, frozenset(), frozenset())))
        grounding = self.groundings[key]
        found = find_plan(grounding.bit_ops, grounding.bits(goal), grounding.bits(fluent), grounding.relaxation)
        return None if found is None else [grounding.ops[i] for i in found]


def plan(model: LearnedModel, view: View, goal: frozenset[Atom]) -> list[GroundOperator] | None:
    """A plan from `view` to `goal` in the learned model (A*, h_ff), None if it has none."""
    return ModelPlanner(model).plan(view, goal)
