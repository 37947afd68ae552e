"""The planner: optimal plan lengths (checked against pyperplan's A* + LM-cut), the compiled tables,
and the host-callback path behind them."""
import dataclasses
import gc
import itertools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from pyperplan import search
from pyperplan.heuristics.lm_cut import LmCutHeuristic
from pyperplan.planner import search_plan

from envs_jax.doorknobs import maps as doorknobs_maps
from envs_jax.light_switch_door import env as lsd
from envs_jax.coffee.env import Coffee
from envs_jax.doorknobs.env import Doorknobs
from planner.search import NO_OPERATOR, UNREACHABLE, BitOperator, HostPlanner, PolicyEntry, optimal_policy
from planner.strips import domain_pddl, ground, problem_pddl
from planner.tables import bits_to_words, compile_task, host_lookup, register_planner, table_lookup, words_to_bits

ENV = lsd.LightSwitchDoor(max_cells=20, max_doors=4)


def astar_lmcut_length(problem, tmp_path) -> int:
    (tmp_path / "domain.pddl").write_text(domain_pddl(problem.domain))
    (tmp_path / "problem.pddl").write_text(problem_pddl(problem))
    plan = search_plan(str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl"), search.astar_search,
                       LmCutHeuristic)
    return len(plan)


def some_tasks():
    tasks = [lsd.train_task(s) for s in range(3)] + [lsd.test_tasks(s)[0] for s in range(8)]
    return tasks + [lsd.sized_task(np.random.default_rng(1), 30, 5)]


@pytest.mark.parametrize("spec", some_tasks(), ids=lambda s: s.describe())
def test_plan_lengths_equal_astar_lmcut(spec, tmp_path):
    compiled = compile_task(ENV if spec.num_cells <= 20 else lsd.LightSwitchDoor(30, 5), spec)
    assert len(compiled.plan()) == astar_lmcut_length(compiled.problem, tmp_path)


def test_plan_lengths_equal_astar_lmcut_from_other_states(tmp_path):
    spec = lsd.test_tasks(3)[0]
    compiled = compile_task(ENV, spec)
    rng = np.random.default_rng(0)
    for cell in rng.choice(spec.num_cells, 4, replace=False):
        init = frozenset({("RobotInCell", "robby", f"cell{cell}"), ("LightOff", "light")})
        problem = dataclasses.replace(compiled.problem, init=init)
        state = sum(1 << ENV.atom_index(a) for a in init)
        ours = compiled.planner.plan(state)
        assert len(ours) == astar_lmcut_length(problem, tmp_path) == (spec.num_cells - 1 - cell) + 1


def test_the_model_knows_nothing_of_doors():
    spec = lsd.test_tasks(0)[0]
    plan = [str(op) for op in compile_task(ENV, spec).plan()]
    n = spec.num_cells
    assert plan == [f"MoveRobot(robby, cell{i}, cell{i + 1})" for i in range(n - 1)] + \
        [f"TurnOnLight(robby, cell{n - 1}, light)"]
    names = list(lsd.DOMAIN.predicates) + [op.name for op in lsd.DOMAIN.operators]
    assert not any("door" in name.lower() for name in names)


def test_grounding_drops_false_static_preconditions():
    spec = lsd.LightSwitchDoorTask(6, (1,))
    ops = ground(ENV.planner_problem(spec))
    count = lambda name: sum(o.name == name for o in ops)
    assert count("MoveRobot") == 2 * (6 - 1)  # only adjacent cells
    assert count("TurnOnLight") == count("TurnOffLight") == 1  # only the light's cell
    assert count("MoveKey") == count("TurnKey") == 6


def test_dead_ends_and_goals():
    # a -> b -> goal, and a -> dead (no way out)
    ops = [BitOperator(pre=0b0001, add=0b0010, delete=0b0001), BitOperator(pre=0b0010, add=0b0100, delete=0b0010),
           BitOperator(pre=0b0001, add=0b1000, delete=0b0001)]
    policy = optimal_policy(ops, goal=0b0100, root=0b0001)
    assert policy[0b0001].op == 0 and policy[0b0001].dist == 2 and policy[0b0001].next_state == 0b0010
    assert policy[0b0100].op == NO_OPERATOR and policy[0b0100].dist == 0
    assert policy[0b1000].op == NO_OPERATOR and policy[0b1000].dist == UNREACHABLE
    assert HostPlanner(ops, 0b0100).plan(0b1000) is None


@pytest.mark.parametrize("seed", [0, 2, 7])
def test_table_and_host_callback_agree_on_every_abstract_state(seed):
    spec = lsd.test_tasks(seed)[0]
    compiled = compile_task(ENV, spec)
    table = jax.tree.map(jnp.asarray, compiled.table)
    keys = table.state_keys
    in_graph = jax.jit(jax.vmap(lambda k: table_lookup(table, k)))(keys)
    found, op, nxt = jax.jit(lambda k: host_lookup(jnp.broadcast_to(table.uid, k.shape[:1]), k,
                                                   jnp.ones(k.shape[:1], bool)))(keys)
    assert bool(jnp.all(in_graph.found)) and bool(jnp.all(found))
    assert np.array_equal(in_graph.op, op) and np.array_equal(in_graph.next_key, nxt)
    # The table covers every state the model can reach: any cell, light off or on.
    assert compiled.num_reachable == keys.shape[0] == 2 * spec.num_cells


def test_unknown_states_miss_the_table_and_the_host_solves_them():
    spec = lsd.test_tasks(1)[0]
    compiled = compile_task(ENV, spec)
    table = jax.tree.map(jnp.asarray, compiled.table)
    # The robot in cells 3 and 4 at once is no state the model can reach from its initial state.
    state = (1 << 3) | (1 << 4) | (1 << ENV.atom_index(("LightOff", "light")))
    key = jnp.asarray(bits_to_words(state, table.state_keys.shape[1]))
    assert not bool(table_lookup(table, key).found)
    found, op, nxt = host_lookup(table.uid[None], key[None], jnp.ones(1, bool))
    assert bool(found[0]) and int(op[0]) >= 0
    chosen = compiled.ground_ops[int(op[0])]
    assert chosen.name == "MoveRobot"
    expected = (state & ~sum(1 << ENV.atom_index(a) for a in chosen.delete)) | \
        sum(1 << ENV.atom_index(a) for a in chosen.add)
    assert words_to_bits(np.asarray(nxt[0])) == expected
    assert len(compiled.planner.plan(state)) == len(compiled.planner.plan(expected)) + 1


def test_grounding_prunes_by_static_preconditions_without_changing_the_operators():
    """ground() checks each static atom as soon as its variables are bound; the result must be every
    binding of the full product whose static preconditions hold, in product order."""
    def brute_force(problem):
        fluent, out = problem.domain.fluent_predicates, []
        for op in problem.domain.operators:
            variables = [v for v, _ in op.params]
            choices = [[o for o, t in problem.objects.items() if t == typ] for _, typ in op.params]
            for values in itertools.product(*choices):
                bind = dict(zip(variables, values))
                atoms = lambda atoms: frozenset((a[0],) + tuple(bind.get(x, x) for x in a[1:]) for a in atoms)
                if atoms(a for a in op.pre if a[0] not in fluent) <= problem.static:
                    out.append((op.name, tuple(values), atoms(a for a in op.pre if a[0] in fluent),
                                atoms(op.add), atoms(op.delete)))
        return out

    rng = np.random.default_rng(0)
    for env, spec in ((Doorknobs(4), doorknobs_maps.sample_task(rng, 4)), (ENV, lsd.test_tasks(1, 1)[0]),
                      (Coffee(), Coffee.test_tasks(2, 4)[3])):
        problem = env.planner_problem(spec)
        ops = [(op.name, op.args, op.pre, op.add, op.delete) for op in ground(problem)]
        assert ops == brute_force(problem) and len(ops) > 5


def test_table_shape_states_the_layout_compile_task_builds():
    """Memory estimates read table_shape; it must match a real table field for field."""
    from planner.tables import table_shape
    for env, spec in ((ENV, lsd.test_tasks(3, 1)[0]), (Doorknobs(4), doorknobs_maps.sample_task(np.random.default_rng(2), 4)),
                      (Coffee(), Coffee.test_tasks(1, 4)[3])):
        compiled = compile_task(env, spec)
        shape = table_shape(compiled.num_reachable, len(compiled.ground_ops), env.num_atoms)
        real = jax.tree.map(lambda x: (np.shape(x), np.asarray(x).dtype), compiled.table)
        assert jax.tree.map(lambda x: (x.shape, x.dtype), shape) == real


def test_light_switch_door_plan_bound_is_what_the_planner_finds():
    """eval.py refuses too large LSD tasks from plan_bound alone, before grounding: it must hold."""
    for spec in [lsd.sized_task(np.random.default_rng(s), n, d) for s, (n, d) in enumerate([(5, 1), (30, 5), (200, 3)])]:
        env = lsd.LightSwitchDoor(spec.num_cells, len(spec.door_cells))
        compiled = compile_task(env, spec)
        assert env.plan_bound(spec) == (compiled.num_reachable, len(compiled.ground_ops))


def test_a_registered_planner_answers_only_while_something_holds_it():
    """The host fallback names planners by uid without keeping them: a sweep's learned planners go with
    their batches instead of piling up for the process's life."""
    class Answering:
        def decide(self, state: int) -> PolicyEntry:
            return PolicyEntry(3, state | 1, 1)

    planner = Answering()
    uid, key, ask = jnp.asarray([register_planner(planner)], jnp.int32), jnp.zeros((1, 1), jnp.uint32), jnp.ones(1, bool)
    found, op, _ = host_lookup(uid, key, ask)
    assert bool(found[0]) and int(op[0]) == 3
    del planner
    gc.collect()
    found, op, _ = host_lookup(uid, key, ask)
    assert not bool(found[0]) and int(op[0]) == NO_OPERATOR
