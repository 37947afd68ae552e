"""The paper's selection rule read off the object view, and the distractor envs where it picks the wrong
object (issues 37 and 55): the rule chooses in the stuck state and reads in the current one; in Coffee
Distractor the cup past the handle, not the jug, is the closest object wherever the planner gets stuck,
and in Doorknobs Distractor the closet beside the doorway, not the door blocking it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax import Coffee, CoffeeDistractor, Doorknobs, DoorknobsDistractor, LightSwitchDoor
from envs_jax.coffee.distractor import with_decoy
from envs_jax.doorknobs import maps
from envs_jax.doorknobs.distractor import CLOSET_KNOB_OUT
from envs_jax.light_switch_door.env import LightSwitchDoorTask
from jaxbridge.core.observations import closest_object, closest_object_features, closest_object_width
from jaxbridge.core.bridges import RandomBridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import evaluation_batch, make_batch


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


def _stuck_picks(batch):
    """The oracle's episodes of a batch: (solved per task, the rule's choice and oracle_object at each
    stuck state, whether the robot then touches that real door's doorway)."""
    env = batch.env
    result, records = rollout(MetaPolicy(env, env.oracle_bridge), batch.arrays,
                              jax.random.split(jax.random.key(0), batch.size), batch.max_steps, record=True)
    stuck = np.asarray(records.stuck & records.live)
    per_state = jax.vmap(jax.vmap(lambda s: (closest_object(env.objects(s))[0], env.oracle_object(s),
                                             env.in_doorway(s))))
    chosen, oracle, doorways = (np.asarray(x)[stuck] for x in per_state(records.env_state))
    door = oracle - 1 - env.map_size ** 2
    in_it = (door >= 0) & doorways[np.arange(len(door)), np.maximum(door, 0)]
    return np.asarray(result.success), chosen, oracle, in_it


@pytest.mark.parametrize("cls", [Doorknobs, DoorknobsDistractor])
def test_where_the_planner_gets_stuck_in_a_doorway_the_closest_object_is_its_knob_unless_a_closet_stands_beside(cls):
    """The oracle's episodes on seeds 0-7's training tasks: every one solved; at each stuck state the robot
    is in the doorway of the door oracle_object names (a real one), and the paper's rule picks that door's
    knob in Doorknobs, its closet (door slot d + 2R) in Doorknobs Distractor."""
    batch = make_batch(cls, [cls.train_task(s) for s in range(8)], list(range(8)), [cls.train_steps] * 8)
    solved, chosen, oracle, in_doorway = _stuck_picks(batch)
    closet = 2 * batch.env.map_size ** 2 if cls is DoorknobsDistractor else 0
    assert solved.all() and len(chosen) >= 8 and in_doorway.all()
    assert (chosen == oracle + closet).all()


def test_on_test_tasks_the_oracle_solves_and_the_rule_picks_a_closet_at_most_stuck_states():
    """Seeds 0-1's test tasks (5x5 maps): the closets change nothing the oracle reads, and at half the stuck
    states at least the rule picks the closet beside the real door the robot stands in, which the fix
    turns (docs/design/selection.md gives the fraction on seeds 0-7)."""
    solved, chosen, oracle, in_doorway = _stuck_picks(evaluation_batch(DoorknobsDistractor, [0, 1], 10))
    rooms = DoorknobsDistractor().map_size ** 2
    assert solved.mean() >= 0.95 and len(chosen) >= 20 and in_doorway.all()
    assert (chosen == oracle + 2 * rooms).mean() >= 0.5


@pytest.mark.parametrize("seed", [0, 3])
def test_each_door_has_a_closet_beside_its_knob_in_the_wall_of_the_room_nearer_the_start(seed):
    spec = DoorknobsDistractor.test_tasks(seed, 1)[0]
    env = DoorknobsDistractor.for_tasks([spec])
    task, m = env.task_arrays(spec), env.map_size
    distance = maps.door_distances(spec.rooms, spec.doors, spec.start_room)
    assert task.closet_mask.sum() == len(spec.doors) and (task.closet_mask == task.door_mask).all()
    for row, col, side in spec.doors:
        d = 2 * (row * m + col) + side
        knob, (near, far) = task.closet_knob[d], task.closet_door[d]
        rect, doorway, centre, normal = maps.door_geometry(spec.size, row, col, side)
        owner, other = maps.door_rooms((row, col, side))
        facing = normal if distance[owner] < distance[other] else -normal
        # off the wall line into the room nearer the start, level with the edge of the doorway at the knob
        assert (knob - centre) @ facing == pytest.approx(CLOSET_KNOB_OUT, abs=1e-6)
        assert np.linalg.norm(knob - rect[:2]) == pytest.approx(CLOSET_KNOB_OUT, abs=0.0051)
        # its door runs along the wall away from the doorway, never across it
        along = np.array([np.cos(rect[4]), np.sin(rect[4])])
        assert (near - centre) @ along == pytest.approx(-maps.HALLWAY_WIDTH / 2, abs=1e-6)
        assert (far - centre) @ along < (near - centre) @ along - 0.2


def test_the_closets_are_objects_of_the_door_type_that_nothing_else_sees():
    """Same type and unturned features as a real door, candidates for the selector; the planner's problem,
    the hand features and every episode (random bridges on the training tasks) are Doorknobs'."""
    specs = [Doorknobs.train_task(s) for s in range(4)]
    env, plain = DoorknobsDistractor.for_tasks(specs), Doorknobs.for_tasks(specs)
    rooms = env.map_size ** 2
    objects = jax.jit(env.objects)(env.reset(jax.tree.map(jnp.asarray, env.task_arrays(specs[0]))))
    real = np.flatnonzero(np.asarray(objects.mask))
    closets = real[real > 3 * rooms]  # after the robot, the rooms and the door slots
    assert env.num_objects == plain.num_objects + 2 * rooms == len(objects.mask) and len(closets) == 2
    assert (np.asarray(objects.type_id)[closets] == 2).all() and np.asarray(objects.interactable)[closets].all()
    np.testing.assert_allclose(np.asarray(objects.features)[closets], [[0.0, 0.75, 0.0]] * 2)
    assert set(closets) <= set(env.candidate_slots) and set(plain.candidate_slots) < set(env.candidate_slots)
    assert all(env.planner_problem(s) == plain.planner_problem(s) for s in specs)
    episodes = []
    for e in (env, plain):
        batch = make_batch(type(e), specs, list(range(4)), [e.train_steps] * 4)
        _, records = rollout(MetaPolicy(batch.env, RandomBridge(batch.env)), batch.arrays,
                             jax.random.split(jax.random.key(1), 4), batch.max_steps, record=True)
        episodes.append((np.asarray(records.env_state.robot), np.asarray(records.env_state.knob_rot)))
    np.testing.assert_array_equal(episodes[0][0], episodes[1][0])
    np.testing.assert_array_equal(episodes[0][1], episodes[1][1])


def test_doorknobs_distractor_keeps_the_env_contract():
    from jaxbridge import check_env

    # the full state with the closets, the object view; the oracle on test tasks: the test above
    assert check_env(DoorknobsDistractor, oracle=False) is DoorknobsDistractor
