"""The planner/bridge meta-policy (Algorithm 1): stuck detection, hand-over, CallPlanner, batching."""
from functools import partial

import chex
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax import BridgeObs
from envs_jax.light_switch_door import env as lsd
from envs_jax.light_switch_door.env import LightSwitchDoor
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.meta_policy import (ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, Controls, hashed_choice,
                                       MetaPolicy, rollout, same_state)
from jaxbridge.core.tasks import make_batch, evaluation_batch
from planner.tables import compile_task, stack_tables

SEEDS = list(range(8))


@pytest.fixture(scope="module")
def batch():
    return evaluation_batch(LightSwitchDoor, SEEDS)


def run(batch, bridge_name, seed=0, record=False, tables=None, controls=Controls()):
    bridge = make_bridge(bridge_name, batch.env)
    arrays = batch.arrays if tables is None else batch.arrays.replace(tables=tables)
    result, records = rollout(MetaPolicy(batch.env, bridge, None, controls), arrays,
                              jax.random.split(jax.random.key(seed), batch.size), batch.max_steps, record=record)
    return jax.tree.map(np.asarray, result), (None if records is None else jax.tree.map(np.asarray, records))


def test_oracle_bridge_solves_every_test_task_of_seeds_0_to_7_in_the_fewest_steps(batch):
    result, _ = run(batch, "oracle")
    assert result.success.all()
    shortest = np.array([s.shortest_solution for s in batch.specs])
    assert np.array_equal(result.steps, shortest)  # blocked move + MoveKey + TurnKey + CallPlanner per door
    doors = np.array([len(s.door_cells) for s in batch.specs])
    assert (result.steps <= np.asarray(batch.horizons)).all()
    assert np.array_equal(result.planner_calls, 1 + doors) and np.array_equal(result.stuck_events, doors)
    assert result.table_misses.sum() == 0


def test_pure_planning_solves_none(batch):
    result, _ = run(batch, "none")
    assert not result.success.any()
    assert np.array_equal(result.steps, np.asarray(batch.horizons))
    assert (result.stuck_events >= 1).all() and (result.planner_calls > 1).all()  # it keeps re-planning


def test_random_bridge_only_takes_applicable_actions(batch):
    _, rec = run(batch, "random", seed=3, record=True)
    decided = rec.decided & rec.live
    call_planner = decided & (rec.skill == batch.env.num_skills)
    assert call_planner.any() and rec.can_plan[call_planner].all()  # CallPlanner only once applicable
    stuck = rec.stuck & rec.live
    assert not rec.can_plan[stuck].any()  # ... never at the state where the bridge takes over
    # Every skill the bridge ran had a ground instance at the robot's position: MoveRobot goes to an
    # adjacent cell, MoveKey/TurnKey act on the robot's own cell.
    robot_cell = np.floor(rec.env_state.robot_x).astype(int)
    started = decided & ~call_planner
    move = started & (rec.skill == batch.env.skill_index("MoveRobot"))
    assert (np.abs(rec.slot[move] - robot_cell[move]) == 1).all()
    keys = started & np.isin(rec.skill, [batch.env.skill_index("MoveKey"), batch.env.skill_index("TurnKey")])
    assert (rec.slot[keys] == robot_cell[keys]).all()


def guarded_repeats(batch, rec) -> tuple[int, int]:
    """Walk every episode's bridge decisions with the loop guard's rule written out: (decisions that
    chose a skill the rule leaves out, decisions whose recorded applicable skills differ from the rule's)."""
    env = batch.env
    vecs = np.asarray(jax.vmap(jax.vmap(env.state_vector))(rec.env_state))
    chosen_no_op = wrong_counts = 0
    for episode in range(batch.size):
        last_vec, last_skill, no_ops = None, -1, set()
        for t in np.flatnonzero(rec.decided[:, episode] & rec.live[:, episode]):
            vec, skill, counts = vecs[t, episode], rec.skill[t, episode], rec.num_ground[t, episode]
            unchanged = last_vec is not None and bool(same_state(vec, last_vec))
            no_ops = (no_ops | ({last_skill} - {env.num_skills})) if unchanged else set()
            expected = counts.copy()
            expected[list(no_ops)] = 0
            if not expected.any():  # nothing would be left: the guard stands aside
                no_ops, expected = set(), counts
            wrong_counts += not np.array_equal(counts, expected)
            chosen_no_op += skill in no_ops
            last_vec, last_skill = vec, skill
    return chosen_no_op, wrong_counts


def test_loop_guard_never_repeats_a_skill_that_left_the_state_unchanged(batch):
    # The random bridge often moves the robot into the closed door (a blocked move changes nothing) and
    # then, unguarded, draws the same move again at the same state.
    _, unguarded = run(batch, "random", seed=1, record=True)
    repeats, differ = guarded_repeats(batch, unguarded)
    assert repeats > 20 and differ > 20
    # Guarded, what is left out is exactly the rule's: the recorded applicable counts carry it (the
    # learner's TD targets see them), and the bridge never picks a left-out skill.
    _, guarded = run(batch, "random", seed=1, record=True, controls=Controls(loop_guard=True))
    assert guarded_repeats(batch, guarded) == (0, 0)


def test_stuck_hand_over_and_call_planner_step_by_step():
    spec = lsd.LightSwitchDoorTask(5, (2,))
    b = make_batch(LightSwitchDoor, [spec], [0])
    result, rec = run(b, "oracle", record=True)
    env, x = b.env, rec.env_state.robot_x[:, 0]
    actors = rec.actor[:, 0][: result.steps[0]].tolist()
    # 0,1: planner moves to cell 2; 2: its move out of the door cell is blocked; 3: the repeated state
    # is detected (no step spent on it) and the bridge turns both keys; 5: CallPlanner; then the plan.
    assert actors == [ACTOR_PLANNER] * 3 + [ACTOR_BRIDGE] * 2 + [ACTOR_CALL_PLANNER] + [ACTOR_PLANNER] * 3
    assert x[:4].tolist() == [0.5, 1.5, 2.5, 2.5] and rec.stuck[:, 0].tolist().index(True) == 3
    assert rec.skill[3:5, 0].tolist() == [env.skill_index("MoveKey"), env.skill_index("TurnKey")]
    assert not rec.can_plan[3, 0] and rec.can_plan[5, 0]
    before, after = rec.env_state.keys[5, 0], rec.env_state.keys[6, 0]  # CallPlanner's step is a no-op
    assert x[5] == x[6] and all(jax.tree.leaves(jax.tree.map(np.array_equal, before, after)))
    assert result.success[0] and result.steps[0] == spec.shortest_solution == 9


def test_expected_atoms_that_fail_make_the_planner_stuck():
    # Corrupt the model's predictions: after its first move the planner expects an impossible state.
    spec = lsd.LightSwitchDoorTask(6, (4,))
    b = make_batch(LightSwitchDoor, [spec], [0])
    broken = b.arrays.tables.replace(next_keys=jnp.full_like(b.arrays.tables.next_keys, 0xFFFFFFFF))
    _, rec = run(b, "none", record=True, tables=broken)
    first_stuck = rec.stuck[:, 0].tolist().index(True)
    assert first_stuck == 1 and rec.env_state.robot_x[1, 0] == 1.5  # the move worked, the check did not


def test_the_host_planner_covers_states_missing_from_the_table(batch):
    truncated = [compile_task(batch.env, spec, max_states=3) for spec in batch.specs]
    result, _ = run(batch, "oracle", tables=stack_tables(truncated))
    full, _ = run(batch, "oracle")
    assert result.success.all() and np.array_equal(result.steps, full.steps)
    assert (result.table_misses > 0).all()
    assert sum(t.planner.calls for t in truncated) == result.table_misses.sum()


def test_an_episode_runs_the_same_alone_and_in_a_batch(batch):
    full, full_rec = run(batch, "oracle", record=True)
    for i in (0, 41, 79):
        alone = make_batch(LightSwitchDoor, [batch.specs[i]], [0], env=batch.env)
        one, one_rec = run(alone, "oracle", record=True)
        assert one.steps[0] == full.steps[i] and one.planner_calls[0] == full.planner_calls[i]
        steps = one.steps[0]
        assert np.array_equal(one_rec.actor[:steps, 0], full_rec.actor[:steps, i])


def test_rollouts_are_deterministic_per_key(batch):
    a, _ = run(batch, "random", seed=5)
    b, _ = run(batch, "random", seed=5)
    c, _ = run(batch, "random", seed=6)
    chex.assert_trees_all_equal(a, b)
    assert not np.array_equal(a.bridge_decisions, c.bridge_decisions)


def test_hashed_choice_is_uniform_over_set_entries():
    mask = jnp.zeros(40, bool).at[jnp.array([3, 7, 8, 20, 39])].set(True)
    bits = jax.random.bits(jax.random.key(0), (20000,), jnp.uint32)
    picks = np.asarray(jax.vmap(lambda b: hashed_choice(mask, b))(bits))
    values, counts = np.unique(picks, return_counts=True)
    assert values.tolist() == [3, 7, 8, 20, 39]
    assert np.all(np.abs(counts / len(picks) - 0.2) < 0.02)
    assert int(hashed_choice(jnp.zeros(40, bool), bits[0])) == 0


def test_equal_bridges_are_one_static_argument_and_compile_once(batch):
    """Bridges are frozen dataclasses: a new but equal bridge (or env) reuses the compiled program."""
    from dataclasses import replace

    from jaxbridge.core.bridges import RandomBridge

    @partial(jax.jit, static_argnames="bridge")
    @chex.assert_max_traces(n=1)
    def decide(bridge, obs, key):
        return bridge(None, obs, key)

    obs = BridgeObs(features=jnp.zeros(batch.env.num_features), num_ground=jnp.ones(batch.env.num_skills + 1, jnp.int32))
    chex.clear_trace_counter()
    first = decide(RandomBridge(batch.env), obs, jax.random.key(0))
    again = decide(RandomBridge(replace(batch.env)), obs, jax.random.key(0))  # equal, not the same objects
    chex.assert_trees_all_equal(first, again)
    with pytest.raises(AssertionError, match="is traced > 1 times"):  # a bridge of another env does compile
        decide(RandomBridge(replace(batch.env, max_cells=batch.env.max_cells + 1)), obs, jax.random.key(0))
