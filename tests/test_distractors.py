"""The paper's selection rule read off the object view, and the distractor env where it picks the wrong
object (issue 37): the rule chooses in the stuck state and reads in the current one; in Coffee
Distractor the cup past the handle, not the jug, is the closest object wherever the planner gets stuck."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax import Coffee, CoffeeDistractor, LightSwitchDoor
from envs_jax.coffee.distractor import with_decoy
from envs_jax.light_switch_door.env import LightSwitchDoorTask
from jaxbridge.core.observations import closest_object, closest_object_features, closest_object_width
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import make_batch


def test_the_closest_object_is_chosen_where_the_robot_got_stuck_and_read_where_it_is():
    spec = LightSwitchDoorTask(6, (1, 3))
    env = LightSwitchDoor.for_tasks([spec])
    start = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))
    stuck, now = start.replace(robot_x=jnp.float32(3.5)), start.replace(robot_x=jnp.float32(4.5))
    door = 2 + env.max_cells + 1  # the door whose keys are in cell 3
    assert int(closest_object(env.objects(stuck))[0]) == door
    features = np.asarray(closest_object_features(env, now, stuck))
    width = env.object_width
    assert features.shape == (closest_object_width(env),) and features[0] == 1.0
    np.testing.assert_array_equal(features[1:1 + width], np.asarray(env.objects(now).features[door]))
    assert features[1 + width] == pytest.approx(-0.5)  # the door one cell back now: -1 / (1 + 1)
    assert features[-3] == pytest.approx(0.5) and not features[-2:].any()  # the robot moved one cell right


def test_the_decoy_cup_lies_past_the_handle_clear_of_the_jug_and_the_other_cups_stay():
    task = Coffee.test_tasks(0, 1, protocol="authors")[0]
    decoy = with_decoy(task)
    assert len(decoy.cups) == len(task.cups) and decoy.cups[1:] == task.cups[1:]
    assert decoy.cups[0][2] == task.cups[0][2] and decoy.jug[0] <= 8.3
    gap = np.hypot(decoy.cups[0][0] - decoy.jug[0], decoy.cups[0][1] - decoy.jug[1])
    assert gap == pytest.approx(0.72, abs=1e-6)  # the cup (0.24) clears the jug (0.4)


@pytest.mark.parametrize("cls, closest", [(Coffee, "the jug"), (CoffeeDistractor, "the first cup")])
def test_where_the_planner_gets_stuck_the_closest_object_is_the_jug_unless_a_cup_lies_past_its_handle(cls, closest):
    """The oracle's episodes on seeds 0-7's training tasks: every one solved, and at each stuck state the
    paper's rule picks the jug in Coffee, the decoy cup in Coffee Distractor."""
    batch = make_batch(cls, [cls.train_task(s) for s in range(8)], list(range(8)), [cls.train_steps] * 8)
    env = batch.env
    result, records = rollout(MetaPolicy(env, env.oracle_bridge), batch.arrays,
                              jax.random.split(jax.random.key(0), 8), batch.max_steps, record=True)
    assert np.asarray(result.success).all()
    stuck = np.asarray(records.stuck & records.live)
    chosen = np.asarray(jax.vmap(jax.vmap(lambda s: closest_object(env.objects(s))[0]))(records.env_state))[stuck]
    assert stuck.sum() >= 8 and (chosen == {"the jug": 1, "the first cup": 3}[closest]).all()
