"""Heuristic forward search on the host, over planner/search.py's bitsets (`BitOperator`, states as ints).

search.py enumerates every reachable state, which is exact but explodes once a model has many
independent atoms (40 doors: 2^40 states). A* here expands only what its heuristic points at:
`h_max` (admissible, so A* returns optimal-length plans) or `h_ff` (the relaxed plan's length: not
admissible, far better informed). Both come from one unit-cost relaxed planning graph: delete effects
ignored, atoms reached layer by layer, each operator fired once all its preconditions are reached.
"""
from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

from planner.search import BitOperator, by_lowest_precondition, candidates, set_bits, successors


class Relaxation:
    """The delete relaxation of `ops`, indexed once so each evaluation costs about one pass over the
    operators' preconditions rather than one pass per layer."""

    def __init__(self, ops: list[BitOperator]):
        self.ops = ops
        self.pre_count = [op.pre.bit_count() for op in ops]
        self.free = [i for i, op in enumerate(ops) if op.pre == 0]
        self.by_pre: dict[int, list[int]] = {}
        for i, op in enumerate(ops):
            for atom in set_bits(op.pre):
                self.by_pre.setdefault(atom, []).append(i)

    def achievers(self, state: int, goal: int) -> tuple[int, dict[int, int]] | None:
        """(layers until every goal atom is reached, {atom: the lowest-index operator that first adds it}),
        or None when the relaxed goal is unreachable."""
        missing = list(self.pre_count)
        reached, frontier, ready, layer, achiever = state, state, list(self.free), 0, {}
        while reached & goal != goal:
            for atom in set_bits(frontier):  # operators whose last precondition was reached last layer
                for i in self.by_pre.get(atom, ()):
                    missing[i] -= 1
                    if missing[i] == 0:
                        ready.append(i)
            frontier = 0
            for i in sorted(ready):  # lowest index first: the achievers, so h_ff, are deterministic
                new = self.ops[i].add & ~reached & ~frontier
                for atom in set_bits(new):
                    achiever[atom] = i
                frontier |= new
            if not frontier:
                return None
            reached, ready, layer = reached | frontier, [], layer + 1
        return layer, achiever

    def h_max(self, state: int, goal: int) -> int | None:
        found = self.achievers(state, goal)
        return None if found is None else found[0]

    def relaxed_plan(self, state: int, goal: int) -> frozenset[int] | None:
        """h_ff's relaxed plan from `state`: each open atom's achiever, back from the goal; None where the
        relaxed goal is unreachable."""
        found = self.achievers(state, goal)
        if found is None:
            return None
        achiever, plan = found[1], set()
        open_atoms = list(set_bits(goal & ~state))
        while open_atoms:  # each achiever's preconditions were reached a layer earlier: this ends
            op = achiever[open_atoms.pop()]
            if op not in plan:
                plan.add(op)
                open_atoms += set_bits(self.ops[op].pre & ~state)
        return frozenset(plan)

    def h_ff(self, state: int, goal: int) -> int | None:
        plan = self.relaxed_plan(state, goal)
        return None if plan is None else len(plan)


def h_max(ops: list[BitOperator], state: int, goal: int) -> int | None:
    """The number of relaxed planning-graph layers until `goal` holds (admissible); None if never."""
    return Relaxation(ops).h_max(state, goal)


def h_ff(ops: list[BitOperator], state: int, goal: int) -> int | None:
    """The length of a relaxed plan to `goal` (FF's heuristic, not admissible); None if none exists."""
    return Relaxation(ops).h_ff(state, goal)


def _prepared(method: str):
    """(ops, goal) -> (state -> estimate), with the relaxation indexed once for a whole search."""
    def prepare(ops: list[BitOperator], goal: int):
        relaxation = Relaxation(ops)
        return lambda state: getattr(relaxation, method)(state, goal)
    return prepare


h_max.prepare, h_ff.prepare = _prepared("h_max"), _prepared("h_ff")


@dataclass(frozen=True)
class SearchResult:
    plan: list[int] | None  # operator indices from the root to a goal state; None if none exists
    expanded: int  # states whose successors were generated
    generated: int  # successor states put on the open list


def _evaluator(heuristic, ops, goal):
    """state -> estimate. h_ff and h_max index the operators once (their `prepare`); any other
    callable (ops, state, goal) -> int | None is called as it is."""
    prepare = getattr(heuristic, "prepare", None)
    return prepare(ops, goal) if prepare else (lambda s: heuristic(ops, s, goal))


def path_to(parent: dict[int, tuple[int, int]], state: int) -> list[int]:
    """The operators from the search's root to `state`, through each state's (parent, operator)."""
    plan = []
    while state in parent:
        state, op = parent[state]
        plan.append(op)
    return plan[::-1]


def astar(ops: list[BitOperator], goal: int, root: int, heuristic=h_ff) -> SearchResult:
    """A* with unit costs from `root` to a state holding every bit of `goal`.

    Ties on f go to the deeper state (larger g: on h_ff's plateaus this walks one plan instead of every
    ordering of it), then to the earlier generated one, so runs repeat exactly. A state is reopened when
    reached more cheaply, so h_max (admissible) gives optimal-length plans; states the heuristic calls
    dead ends (None: the relaxed goal is unreachable, so the real one is) are never queued."""
    evaluate = _evaluator(heuristic, ops, goal)
    always, keyed = by_lowest_precondition(ops)
    h_root = evaluate(root)
    if h_root is None:
        return SearchResult(None, 0, 0)
    order = itertools.count()
    queue = [(h_root, 0, next(order), root)]
    best_g, parent, dead, expanded = {root: 0}, {}, set(), 0
    while queue:
        _, neg_g, _, state = heapq.heappop(queue)
        g = -neg_g
        if g > best_g[state]:
            continue  # a stale entry: the state was reached more cheaply since
        if state & goal == goal:
            return SearchResult(path_to(parent, state), expanded, next(order) - 1)
        expanded += 1
        for op, nxt in successors(ops, state, candidates(always, keyed, state)):
            if g + 1 >= best_g.get(nxt, g + 2) or nxt in dead:
                continue
            h = evaluate(nxt)
            if h is None:
                dead.add(nxt)
            else:
                best_g[nxt], parent[nxt] = g + 1, (state, op)
                heapq.heappush(queue, (g + 1 + h, -(g + 1), next(order), nxt))
    return SearchResult(None, expanded, next(order) - 1)
