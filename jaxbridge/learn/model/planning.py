"""Plans with a learned model: A* with h_ff over the repaired grounding of a state's view."""
from __future__ import annotations

from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.operators import typed_objects
from jaxbridge.learn.model.segments import View
from planner.heuristic import astar
from planner.search import BitOperator
from planner.strips import Atom, GroundOperator, Problem, ground


def plan(model: LearnedModel, view: View, goal: frozenset[Atom]) -> list[GroundOperator] | None:
    """A plan from `view` to `goal` in the learned model (A*, h_ff), None if it has none."""
    atoms, fluent = model.atoms(view), model.domain.fluent_predicates
    problem = Problem(model.domain, typed_objects(view, model.domain), frozenset(a for a in atoms if a[0] not in fluent),
                      frozenset(a for a in atoms if a[0] in fluent), goal)
    ops = ground(problem)
    index: dict[Atom, int] = {}
    bits = lambda atoms: sum(1 << index.setdefault(a, len(index)) for a in sorted(atoms))
    bit_ops = [BitOperator(bits(o.pre), bits(o.add), bits(o.delete)) for o in ops]
    found = astar(bit_ops, bits(goal), bits(problem.init)).plan
    return None if found is None else [ops[i] for i in found]
