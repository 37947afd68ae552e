"""Planning with a learned model (jaxbridge/learn/model/search.py, planning.py): the helpful-action search
finds valid plans where noise operators flood plain A*, and a planner keeps its grounding between plans."""
from __future__ import annotations

import numpy as np

from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.planning import ModelPlanner
from jaxbridge.learn.model.predicates import Grammar
from jaxbridge.learn.model.search import find_plan
from jaxbridge.learn.model.segments import View
from planner.heuristic import astar
from planner.search import BitOperator
from planner.strips import Domain, LiftedOperator


def _corridor(cells: int, switches: int) -> tuple[list[BitOperator], int, int]:
    """A row of cells, a closed door between each two (opened where the robot stands before it), and
    switches anywhere that toggle atoms no goal needs: (ops, goal, root) as bits. Bits: at cell i (i),
    door i open (cells + i), switch j on (2 cells + j)."""
    at, door, switch = (lambda i: 1 << i), (lambda i: 1 << cells + i), (lambda j: 1 << 2 * cells + j)
    ops = []
    for i in range(cells - 1):
        ops.append(BitOperator(at(i), door(i), 0))  # open door i from cell i
        ops.append(BitOperator(at(i) | door(i), at(i + 1), at(i)))  # through it
        ops.append(BitOperator(at(i + 1) | door(i), at(i), at(i + 1)))  # and back
    for j in range(switches):
        ops.append(BitOperator(0, switch(j), 0))
        ops.append(BitOperator(switch(j), 0, switch(j)))
    return ops, at(cells - 1), at(0)


def _valid(ops: list[BitOperator], plan: list[int], root: int, goal: int) -> bool:
    state = root
    for i in plan:
        if state & ops[i].pre != ops[i].pre:
            return False
        state = (state & ~ops[i].delete) | ops[i].add
    return state & goal == goal


def test_the_helpful_action_search_finds_an_optimal_plan_among_switches_no_goal_needs():
    ops, goal, root = _corridor(cells=8, switches=12)
    found = find_plan(ops, goal, root)
    assert found is not None and _valid(ops, found, root, goal) and len(found) == 2 * 7
    small, goal, root = _corridor(cells=4, switches=3)  # small enough for A* over every operator
    assert len(find_plan(small, goal, root)) == len(astar(small, goal, root).plan)


def test_no_plan_where_the_goal_cannot_be_reached():
    ops, goal, root = _corridor(cells=4, switches=2)
    assert find_plan([op for op in ops if op.add != 1 << 3], goal, root) is None  # no way into the last cell


def test_a_model_planner_grounds_once_for_every_plan_from_one_tasks_states():
    move = LiftedOperator("Move", (("?r", "robot"), ("?a", "cell"), ("?b", "cell")),
                          (("Adjacent", "?a", "?b"), ("At", "?r", "?a")), (("At", "?r", "?b"),), (("At", "?r", "?a"),), "Move", "?b")
    domain = Domain("row", ("robot", "cell"), {"At": ("robot", "cell"), "Adjacent": ("cell", "cell")}, (move,))
    model = LearnedModel(domain, Grammar((), (), (), "robot", frozenset()), {})
    names = ("robby", "c0", "c1", "c2")
    adjacent = {("Adjacent", f"c{i}", f"c{j}") for i in range(3) for j in range(3) if abs(i - j) == 1}
    view = lambda cell: View(names, ("robot", "cell", "cell", "cell"), np.zeros((4, 1), np.float32), np.zeros((4, 3), np.float32),
                             frozenset(adjacent | {("At", "robby", f"c{cell}")}))
    planner, goal = ModelPlanner(model), frozenset({("At", "robby", "c2")})
    assert [str(op) for op in planner.plan(view(0), goal)] == ["Move(robby, c0, c1)", "Move(robby, c1, c2)"]
    assert [str(op) for op in planner.plan(view(1), goal)] == ["Move(robby, c1, c2)"]
    assert len(planner.groundings) == 1
