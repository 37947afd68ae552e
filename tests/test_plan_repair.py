"""The plan-repair baselines (issue 38) on a hand-made Light Switch Door row: the bridge's reward fires
exactly when the abstract state reaches a later state of the plan it got stuck in, and the test-time
meta-policy then resumes that plan at the right step (or replans)."""
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.base import BridgeAction
from envs_jax.light_switch_door.env import LightSwitchDoor, LightSwitchDoorTask
from jaxbridge.core.meta_policy import ACTOR_BRIDGE, ACTOR_PLANNER, rollout
from jaxbridge.core.tasks import make_batch
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.transitions import PROGRESS_STEP_COST, episode_transitions

TASK = LightSwitchDoorTask(num_cells=6, door_cells=(1,))  # the plan: cells 0 -> 5, then the light


@dataclass(frozen=True)
class KeysThenMove:
    """Sets the door's keys (the oracle's choices), then moves the robot: no CallPlanner."""

    env: LightSwitchDoor

    def __call__(self, params, obs, key):
        oracle = self.env.oracle_bridge(params, obs, key)
        move = oracle.skill == self.env.num_skills
        return BridgeAction(skill=jnp.where(move, self.env.skill_index("MoveRobot"), oracle.skill).astype(jnp.int32),
                            param=jnp.where(move, 0.5, oracle.param).astype(jnp.float32))


@pytest.fixture(scope="module")
def episodes():
    """Each approach's episode of TASK, for several rollout keys (MoveRobot's grounding, left or right, is random)."""
    batch = make_batch(LightSwitchDoor, [TASK] * 4, [0] * 4)
    env = batch.env
    out = {}
    for name in ("plan_progress", "plan_progress_replan"):
        result, rec = rollout(env, KeysThenMove(env), None, batch.arrays, jax.random.split(jax.random.key(3), 4),
                              batch.max_steps, record=True, controls=get_approach(name).controls)
        out[name] = jax.tree.map(np.asarray, (result, rec))
    return env, out


@pytest.mark.parametrize("name", ["plan_progress", "plan_progress_replan"])
def test_the_hand_back_fires_exactly_when_the_robot_reaches_the_plans_next_cell_and_the_plan_goes_on_there(episodes, name):
    env, runs = episodes
    result, rec = runs[name]
    assert result.success.all() and (result.stuck_events == 1).all()
    cell = np.floor(rec.env_state.robot_x).astype(int)  # [T, B]: the robot's cell before each step
    for b in range(result.success.shape[0]):
        live = rec.live[:, b]
        first_in_2 = np.argmax(cell[:, b] == 2)
        # stuck in cell 1 heading for cell 2; the bridge acts until the robot is in cell 2, and no longer
        assert np.flatnonzero(rec.progressed[:, b]).tolist() == [first_in_2]
        bridge = np.flatnonzero(live & (rec.actor[:, b] == ACTOR_BRIDGE))
        assert bridge.max() == first_in_2 - 1 and (cell[bridge, b] <= 1).all()
        after = np.flatnonzero(live)[first_in_2:]
        assert (rec.actor[after, b] == ACTOR_PLANNER).all()  # the plan's moves to cells 3-5 and the light
        assert cell[after, b].tolist() == [2, 3, 4, 5] and rec.skill[after[-1], b] == env.skill_index("TurnOnLight")
    # resuming follows the recorded plan; replanning makes a second plan at the hand-back
    assert (result.planner_calls == (1 if name == "plan_progress" else 2)).all()


def test_the_reward_is_a_cost_per_step_until_the_decision_that_reaches_the_plan_which_ends_its_problem(episodes):
    env, runs = episodes
    result, rec = runs["plan_progress"]
    one = jax.tree.map(lambda x: x[:, 0], rec)
    transitions, valid = episode_transitions(one, result.success[0], env.num_skills, plan_progress=True)
    decided = np.flatnonzero(valid)
    reward, done = np.asarray(transitions.reward)[decided], np.asarray(transitions.done)[decided]
    assert reward[-1] == 1.0 and done[-1] and not done[:-1].any()  # the last decision moved it into cell 2
    spans = np.diff(decided)  # each earlier decision's skill takes its steps until the next decision
    np.testing.assert_allclose(reward[:-1], -PROGRESS_STEP_COST * spans)
