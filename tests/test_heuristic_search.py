"""Heuristic search on the host: A* with h_max finds plans as short as the exhaustive search's, and A*
with h_ff plans in models whose state space search.reachable could never enumerate."""
import numpy as np
import pytest

from envs_jax import BUILTIN, KNOBS, VARIANTS, WORLDS, env_class
from planner.heuristic import astar, h_ff, h_max
from planner.search import UNREACHABLE, BitOperator, optimal_policy
from planner.tables import compile_task


def run(ops, state, plan):
    """The state after `plan`, checking that each operator applies in turn."""
    for i in plan:
        assert state & ops[i].pre == ops[i].pre, f"operator {i} does not apply"
        state = (state & ~ops[i].delete) | ops[i].add
    return state


def bit_task(name):
    """(operators, goal, initial state) of the env's first training task, as compile_task builds them."""
    cls = env_class(name)
    spec = cls.train_task(0)
    compiled = compile_task(cls.for_tasks([spec]), spec)
    return compiled.planner.ops, compiled.planner.goal, compiled.init_state


def larger_doorknobs_task():
    """A sampled 5x5 Doorknobs map: a few hundred abstract states, where the training tasks have < 20."""
    from envs_jax.doorknobs import maps
    from envs_jax.doorknobs.env import Doorknobs
    compiled = compile_task(Doorknobs(5), maps.sample_task(np.random.default_rng(0), 5))
    return compiled.planner.ops, compiled.planner.goal, compiled.init_state


@pytest.mark.parametrize("name", BUILTIN + VARIANTS + KNOBS + WORLDS + ("doorknobs 5x5",))
def test_astar_with_h_max_is_optimal_on_every_builtin_model(name):
    ops, goal, init = larger_doorknobs_task() if name == "doorknobs 5x5" else bit_task(name)
    policy = optimal_policy(ops, goal, init)
    states = list(policy)
    for state in states[:: max(1, len(states) // 40)] + [init]:  # about 40 roots spread over the graph
        dist = policy[state].dist
        optimal, ff = astar(ops, goal, state, h_max), astar(ops, goal, state, h_ff)
        if dist == UNREACHABLE:
            assert optimal.plan is None and ff.plan is None
            continue
        assert len(optimal.plan) == dist and h_max(ops, state, goal) <= dist
        assert run(ops, state, optimal.plan) & goal == goal and run(ops, state, ff.plan) & goal == goal
    assert policy[init].dist > 0


def doors(n):
    """n closed doors (bits 0..n-1) to open (bits n..2n-1), in any order: 2^n reachable states."""
    ops = [BitOperator(pre=1 << i, add=1 << (n + i), delete=1 << i) for i in range(n)]
    return ops, ((1 << n) - 1) << n, (1 << n) - 1


def corridor(doors, switches):
    """A robot in cell 0 of a row of `doors` + 1 cells, a closed door before each next cell, must reach
    the last cell; `switches` light switches it may toggle anywhere multiply the states by 2^switches.
    Bits: at cell k = k, door k open = doors + 1 + k, switch j on = 2 * doors + 1 + j."""
    at = lambda k: 1 << k
    door = lambda k: 1 << (doors + 1 + k)
    switch = lambda j: 1 << (2 * doors + 1 + j)
    ops = [BitOperator(pre=at(k), add=door(k), delete=0) for k in range(doors)]
    ops += [BitOperator(pre=at(k) | door(k), add=at(k + 1), delete=at(k)) for k in range(doors)]
    ops += [BitOperator(pre=at(k + 1) | door(k), add=at(k), delete=at(k + 1)) for k in range(doors)]
    ops += [BitOperator(pre=0, add=switch(j), delete=0) for j in range(switches)]
    ops += [BitOperator(pre=switch(j), add=0, delete=switch(j)) for j in range(switches)]
    return ops, at(doors), at(0)


def test_h_ff_plans_where_the_state_space_cannot_be_enumerated():
    # search.reachable would visit all 2^40 door states here (and 41 * 2^30 * 2^40 in the corridor).
    for ops, goal, root, length in (doors(40) + (40,), corridor(30, 40) + (60,)):
        result = astar(ops, goal, root, h_ff)
        assert len(result.plan) == length and run(ops, root, result.plan) & goal == goal
        assert result.expanded <= 20 * len(result.plan)
        assert astar(ops, goal, root, h_ff) == result  # deterministic: same plan, same counts


def test_h_max_plans_are_optimal_on_small_synthetic_models():
    for ops, goal, root in (doors(6), corridor(4, 2)):
        policy = optimal_policy(ops, goal, root)
        for state, entry in policy.items():
            plan = astar(ops, goal, state, h_max).plan
            assert len(plan) == entry.dist and run(ops, state, plan) & goal == goal


def test_goals_dead_ends_and_any_heuristic():
    # a -> b -> goal, and a -> dead (no way out); as in test_planner's exhaustive search
    ops = [BitOperator(pre=0b0001, add=0b0010, delete=0b0001), BitOperator(pre=0b0010, add=0b0100, delete=0b0010),
           BitOperator(pre=0b0001, add=0b1000, delete=0b0001)]
    assert astar(ops, 0b0100, 0b0001, h_max).plan == [0, 1]
    assert astar(ops, 0b0100, 0b0100).plan == [] and astar(ops, 0b0100, 0b0100).expanded == 0
    assert h_ff(ops, 0b1000, 0b0100) is None and astar(ops, 0b0100, 0b1000).plan is None
    assert (h_max(ops, 0b0001, 0b0100), h_ff(ops, 0b0001, 0b0100)) == (2, 2)
    blind = astar(ops, 0b0100, 0b0001, heuristic=lambda ops, state, goal: 0)  # any callable works
    assert blind.plan == [0, 1] and blind.expanded == 3  # a, b, then the dead end (f 1) before the goal (f 2)


def test_h_ff_counts_a_shared_precondition_once_and_h_max_the_longest_chain():
    # goal g1 | g2; op0 makes p; op1: p -> g1; op2: p -> g2; op3: nothing -> q; op4: q -> g2
    ops = [BitOperator(0, 0b00001, 0), BitOperator(0b00001, 0b00010, 0), BitOperator(0b00001, 0b00100, 0),
           BitOperator(0, 0b01000, 0), BitOperator(0b01000, 0b00100, 0)]
    assert h_max(ops, 0, 0b00110) == 2 and h_ff(ops, 0, 0b00110) == 3  # op0, op1, op2 (op2 is first for g2)
    assert len(astar(ops, 0b00110, 0, h_max).plan) == 3
