"""Plan search in a learned model's bit operators: A* with h_ff over FF's helpful actions, then, where that
finds nothing, over every operator; each within a budget of heuristic evaluations.

Why not planner.heuristic.astar over every operator first: a learned model makes many atoms fluent that the
env's model left out (every door's state on Doorknobs), and most operators change atoms no plan needs (a
door off the way opened, a knob turned back and forth). Each such change is a new state at the same
h_ff, so A* can flood a plateau with their combinations. Helpful actions (Hoffmann and Nebel's FF: the
applicable operators that add an atom the state's relaxed plan needs) leave those changes out. Pruning
to them can lose every plan, hence the later searches. On Doorknobs' 7x7 maps with 10 doors to the goal
(seed 0's model from its exploration, about 1,600 ground operators) every one of them finds the 30-step
plan (3 operators a door) in under a second.
"""
from __future__ import annotations

import heapq
import itertools

from planner.heuristic import Relaxation, path_to
from planner.search import BitOperator, by_lowest_precondition, candidates, successors

# The searches find_plan tries in turn: (helpful actions only, h_ff's weight); weight 2 finds a plan from fewer
# evaluations where weight 1 runs out of them, a longer one as a rule.
SEARCHES = ((True, 1), (True, 2), (False, 1))
EVALUATIONS = 5000  # heuristic evaluations per search: then no plan


def astar(relaxation: Relaxation, goal: int, root: int, helpful_only: bool, weight: int = 1,
          budget: int = EVALUATIONS) -> list[int] | None:
    """Weighted A* (unit costs, f = g + weight h_ff) from `root` to a state holding `goal`: operator indices, or None when
    the search space (helpful actions only, if asked) holds no plan or `budget` evaluations found none.
    Ties as planner.heuristic.astar's: the deeper state, then the earlier generated one, so runs repeat."""
    ops = relaxation.ops
    always, keyed = by_lowest_precondition(ops)
    estimate = {root: relaxation.relaxed_plan(root, goal)}
    if estimate[root] is None:
        return None
    order = itertools.count()
    queue = [(weight * len(estimate[root]), 0, next(order), root)]
    best_g, parent = {root: 0}, {}
    while queue:
        _, neg_g, _, state = heapq.heappop(queue)
        g = -neg_g
        if g > best_g[state]:
            continue  # reached more cheaply since
        if state & goal == goal:
            return path_to(parent, state)
        helpful = estimate[state]
        for op, nxt in successors(ops, state, candidates(always, keyed, state)):
            if helpful_only and op not in helpful or g + 1 >= best_g.get(nxt, g + 2):
                continue
            if nxt not in estimate:
                if len(estimate) > budget:
                    return None
                estimate[nxt] = relaxation.relaxed_plan(nxt, goal)
            if estimate[nxt] is not None:  # None: a dead end, the relaxed goal unreachable
                best_g[nxt], parent[nxt] = g + 1, (state, op)
                heapq.heappush(queue, (g + 1 + weight * len(estimate[nxt]), -(g + 1), next(order), nxt))
    return None


def find_plan(ops: list[BitOperator], goal: int, root: int, relaxation: Relaxation | None = None) -> list[int] | None:
    """A plan's operator indices from `root` to `goal`: the first that `SEARCHES` finds, None if none does.
    `relaxation`: `ops`' own, where a caller keeps it between searches."""
    relaxation = relaxation or Relaxation(ops)
    for helpful_only, weight in SEARCHES:
        found = astar(relaxation, goal, root, helpful_only, weight)
        if found is not None:
            return found
    return None
