"""Exact optimal planning over the abstract states a STRIPS model can reach.

States are Python ints used as bitsets over an environment's fluent-atom layout. Unit-cost optimal plans
come from a forward closure of the reachable states plus a backward breadth-first sweep from the goal
states (exact goal distances), so plan lengths equal those of A* with an admissible heuristic such as
LM-cut. The policy takes, in every state, the first ground operator (in grounding order) that moves one
step closer to the goal: a fixed tie-break, so the compiled table and the on-demand host planner always
choose the same operator.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

NO_OPERATOR = -1
UNREACHABLE = -1  # goal distance of a dead end


@dataclass(frozen=True)
class BitOperator:
    pre: int
    add: int
    delete: int


@dataclass
class PolicyEntry:
    op: int  # first operator of an optimal plan; NO_OPERATOR at a goal or dead end
    next_state: int  # the state the model predicts after `op`
    dist: int  # optimal plan length, UNREACHABLE for a dead end


def successors(ops: list[BitOperator], state: int, candidates: list[int]) -> list[tuple[int, int]]:
    """(operator index, successor) for every applicable operator that changes the state, in operator
    order, trying only `candidates` (sorted indices: every operator that can apply in `state`)."""
    out = []
    for i in candidates:
        op = ops[i]
        if state & op.pre == op.pre:
            nxt = (state & ~op.delete) | op.add
            if nxt != state:
                out.append((i, nxt))
    return out


def by_lowest_precondition(ops: list[BitOperator]) -> tuple[list[int], dict[int, list[int]]]:
    """Operators without preconditions, and the others keyed by their lowest precondition bit: an
    operator can only apply in a state holding that bit (most states hold few of the model's atoms)."""
    always, keyed = [], {}
    for i, op in enumerate(ops):
        if op.pre == 0:
            always.append(i)
        else:
            keyed.setdefault((op.pre & -op.pre).bit_length() - 1, []).append(i)
    return always, keyed


def set_bits(mask: int):
    """The indices of the set bits of `mask`, lowest first."""
    while mask:
        low = mask & -mask
        yield low.bit_length() - 1
        mask ^= low


def candidates(always: list[int], keyed: dict[int, list[int]], state: int) -> list[int]:
    """The operators that may apply in `state` (by `by_lowest_precondition`'s index), in index order."""
    return sorted(always + [i for bit in set_bits(state) for i in keyed.get(bit, ())])


def reachable(ops: list[BitOperator], root: int) -> dict[int, list[tuple[int, int]]]:
    """Every state reachable from `root` (in breadth-first order) with its outgoing edges."""
    always, keyed = by_lowest_precondition(ops)
    graph: dict[int, list[tuple[int, int]]] = {}
    queue = deque([root])
    while queue:
        s = queue.popleft()
        if s in graph:
            continue
        graph[s] = successors(ops, s, candidates(always, keyed, s))
        queue.extend(n for _, n in graph[s] if n not in graph)
    return graph


def breadth_first_distances(neighbours: dict, sources: list) -> dict:
    """{node: fewest edges from any of `sources`} over the nodes reachable along `neighbours`, in the
    order they are reached."""
    dist = {s: 0 for s in sources}
    queue = deque(dist)
    while queue:
        node = queue.popleft()
        for n in neighbours[node]:
            if n not in dist:
                dist[n] = dist[node] + 1
                queue.append(n)
    return dist


def optimal_policy(ops: list[BitOperator], goal: int, root: int) -> dict[int, PolicyEntry]:
    """The optimal policy on every state reachable from `root` (insertion order = BFS order)."""
    graph = reachable(ops, root)
    parents: dict[int, list[int]] = {s: [] for s in graph}
    for s, edges in graph.items():
        for _, n in edges:
            parents[n].append(s)
    dist = breadth_first_distances(parents, [s for s in graph if s & goal == goal])
    policy = {}
    for s, edges in graph.items():
        d = dist.get(s, UNREACHABLE)
        entry = PolicyEntry(NO_OPERATOR, s, d)
        if d > 0:
            op, nxt = next((i, n) for i, n in edges if dist.get(n) == d - 1)
            entry = PolicyEntry(op, nxt, d)
        policy[s] = entry
    return policy


@dataclass
class HostPlanner:
    """On-demand planner for one task: answers any abstract state, caching what it has solved."""

    ops: list[BitOperator]
    goal: int
    cache: dict[int, PolicyEntry] = field(default_factory=dict)
    calls: int = 0

    def decide(self, state: int) -> PolicyEntry:
        self.calls += 1
        if state not in self.cache:
            # Goal distances are a property of the state, so entries from any root agree.
            self.cache.update(optimal_policy(self.ops, self.goal, state))
        return self.cache[state]

    def plan(self, state: int) -> list[int]:
        """The whole optimal operator sequence from `state` (empty at a goal; None at a dead end)."""
        plan = []
        entry = self.decide(state)
        if entry.dist == UNREACHABLE:
            return None
        while entry.op != NO_OPERATOR:
            plan.append(entry.op)
            entry = self.decide(entry.next_state)
        return plan
