"""The plan-repair baselines (issue 38) on a hand-made Light Switch Door row: the bridge's reward fires
exactly when the abstract state reaches a later state of the plan it got stuck in, and the test-time
meta-policy then resumes that plan at the right step (or replans); and the variant built to test
commitment to the plan, Light Switch Panel."""
import csv
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from run_helpers import trained_whole_and_resumed

from envs_jax import env_class
from envs_jax.base import BridgeAction
from envs_jax.light_switch_door import LightSwitchDoor, LightSwitchDoorTask, LightSwitchPanel
from jaxbridge import check_env
from jaxbridge.core.check_env import OracleBridge
from jaxbridge.core.meta_policy import ACTOR_BRIDGE, ACTOR_PLANNER, MetaPolicy, rollout
from jaxbridge.core.tasks import make_batch
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.setup import make_setup
from jaxbridge.run.evaluate import evaluate_run
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
        result, rec = rollout(MetaPolicy(env, KeysThenMove(env), None, get_approach(name).controls), batch.arrays,
                              jax.random.split(jax.random.key(3), 4), batch.max_steps, record=True)
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


# ---- the variant: Light Switch Panel, each door's keys one cell before it ------------------------------
PANEL_TASK = LightSwitchDoorTask(num_cells=6, door_cells=(2,), panel_offset=1)  # stuck in cell 2, keys in cell 1


def test_the_panel_variant_keeps_the_env_contract_and_its_keys_turn_only_on_the_panel():
    assert check_env(LightSwitchPanel) is LightSwitchPanel  # the oracle solves its test tasks, among the rest
    env = LightSwitchPanel.for_tasks([PANEL_TASK])
    state = env.reset(env.task_arrays(PANEL_TASK))
    step = jax.jit(env.step)
    set_keys = jnp.array([0.0, 0.0, 0.5, 0.75], jnp.float32)
    at_door = step(state.replace(robot_x=jnp.float32(2.5)), set_keys)
    assert not env.door_open(at_door)[0] and float(step(at_door, jnp.array([1.0, 0, 0, 0])).robot_x) == 2.5
    on_panel = step(state.replace(robot_x=jnp.float32(1.5)), set_keys)
    assert env.door_open(on_panel)[0]
    through = step(step(on_panel, jnp.array([1.0, 0, 0, 0])), jnp.array([1.0, 0, 0, 0]))
    assert float(through.robot_x) == 3.5
    for name, cls in (("light_switch_panel", LightSwitchPanel), ("light_switch_door", LightSwitchDoor)):
        doors = [t.door_cells for seed in range(8) for t in env_class(name).test_tasks(seed, 4)]
        adjacent = [d for d in doors if np.any(np.diff(sorted(d)) < 2)]
        assert (not adjacent) == (cls.panel_offset == 1)  # no panel shares a cell with a door; cell 0 holds none
        assert (min(min(d) for d in doors) >= 1) == (cls.panel_offset == 1)


def test_on_the_panel_variant_plan_progress_hands_back_past_the_door_and_ours_at_the_panel():
    batch = make_batch(LightSwitchPanel, [PANEL_TASK] * 4, [0] * 4)
    env, keys = batch.env, jax.random.split(jax.random.key(5), 4)
    runs = {name: jax.tree.map(np.asarray, rollout(MetaPolicy(env, bridge, None, get_approach(name).controls),
                                                   batch.arrays, keys, batch.max_steps, record=True))
            for name, bridge in (("plan_progress", KeysThenMove(env)), ("ours", OracleBridge(env)))}
    result, rec = runs["ours"]
    assert result.success.all() and not rec.progressed.any()
    for b in range(4):  # ours hands back on the panel: cell 1, a state the plan had already passed
        back = np.flatnonzero(rec.live[:, b] & (rec.actor[:, b] != ACTOR_PLANNER)).max() + 1
        assert np.floor(rec.env_state.robot_x[back, b]) == 1 and rec.actor[back, b] == ACTOR_PLANNER
    # plan_progress hands back only past the door (cell 3), after a walk whose direction it does not choose
    result, rec = runs["plan_progress"]
    handed_back = rec.progressed.any(axis=0)
    assert handed_back.any() and (handed_back == result.success).all()
    assert (np.floor(rec.env_state.robot_x[rec.progressed]) == 3).all()


def test_a_plan_repair_run_resumes_to_the_same_metrics_and_its_evaluation_finds_its_test_rate(tmp_path):
    config = TrainConfig(approach="plan_progress", num_seeds=1, cycles=2, updates_per_cycle=10, episodes_per_cycle=2,
                         checkpoint_every=1, num_test_tasks=2)
    setup = make_setup(config)
    trained_whole_and_resumed(setup, tmp_path, crash_at=2)
    whole = (tmp_path / "whole" / "metrics.csv").read_bytes()
    assert (tmp_path / "crashed" / "metrics.csv").read_bytes() == whole and whole.count(b"\n") == 3
    # evaluation (eval.py's) rebuilds the approach's meta-policy, resuming the stuck plan, and finds the last test rate
    _, step, _, result, (_, _, controls) = evaluate_run(tmp_path / "crashed")
    assert step == 2 and controls == setup.controls and controls.plan_progress and controls.resume_plan
    last = list(csv.DictReader((tmp_path / "whole" / "metrics.csv").open()))[-1]
    assert np.mean(result.success) == float(last["test_solve_rate"]) and (np.asarray(result.planner_calls) == 1).all()
