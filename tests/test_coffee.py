"""Coffee: every dynamics branch of envs.md §4.4 and their priority, the predicates, each skill reaching
its operator's effects, pouring into several cups, task generation, features, jit/vmap, and the
meta-policy with the oracle bridge and with pure planning, and the authors' shared repeated-state flag."""
import jaxbridge
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.coffee import skills
from envs_jax.coffee import world
from envs_jax.base import SkillCall
from envs_jax.coffee.env import CUP_ATOMS, SINGLE_ATOMS, Coffee
from envs_jax.coffee.world import CoffeeTask
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import evaluation_batch, make_batch
from planner.strips import ground

from oracle_vs_planning import oracle_and_pure_planning

ENV = Coffee()  # 4 cup slots
# Three cups far apart (pouring positions at x + 0.96, y + 0.24), the jug on the table.
# Targets 0.825, 0.975, 0.675: no multiple of the 0.15 pour lands on one (float32 ties).
SPEC = CoffeeTask(cups=((1.5, 3.0, 1.1), (4.0, 3.0, 1.3), (6.0, 4.4, 0.9)), jug=(8.5, 3.5))
HANDLE_AT_ROT_0 = np.array([8.5, 3.08, 1.125])  # the jug's handle points to -y when rot = 0

step = jax.jit(ENV.step)
abstract = jax.jit(ENV.abstract)


def fresh(robot=None, rot=None, jug=None, held=False, filled=False, on=False, liquid=None):
    state = ENV.reset(jax.tree.map(jnp.asarray, ENV.task_arrays(SPEC)))
    pose = np.array(world.ROBOT_INIT if robot is None else robot, np.float32)
    return state.replace(
        robot=jnp.asarray(pose), jug_rot=jnp.float32(world.JUG_INIT_ROT if rot is None else rot),
        jug_xy=jnp.asarray(np.float32(SPEC.jug if jug is None else jug)), jug_held=jnp.bool_(held),
        jug_filled=jnp.bool_(filled), machine_on=jnp.bool_(on),
        cup_liquid=jnp.zeros(4, jnp.float32) if liquid is None else jnp.asarray(np.float32(liquid)))


def act(state, dx=0.0, dy=0.0, dz=0.0, dtilt=0.0, dwrist=0.0, dfingers=0.0):
    return step(state, jnp.array([dx, dy, dz, dtilt, dwrist, dfingers], jnp.float32))


ATOM_NAMES = list(SINGLE_ATOMS) + [f"{a}(cup{c})" for a in CUP_ATOMS for c in range(ENV.max_cups)]


def atoms(state) -> set:
    """The true fluent atoms, by name (cup atoms name their cup)."""
    return {ATOM_NAMES[i] for i in np.flatnonzero(np.asarray(abstract(state)))}


def same(a, b) -> bool:
    return all(np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)))


def pose(x, y, z, tilt=0.0, wrist=0.0, fingers=0.4):
    return (x, y, z, tilt, wrist, fingers)


POUR_0 = np.array([1.5 + 0.96, 3.0 + 0.24])  # cup0's pouring (x, y) for the jug
AT_POUR_0 = {"robot": pose(POUR_0[0], POUR_0[1] - 0.42, world.POUR_Z + 1.125, fingers=0.1), "jug": POUR_0,
             "rot": 0.0, "held": True, "filled": True}


# ---- dynamics ---------------------------------------------------------------------------------------
def test_actions_are_scaled_and_the_pose_clipped_to_its_ranges():
    s = act(fresh(robot=pose(5, 5, 5, wrist=-6.0)), dx=1.0, dy=-0.5, dz=2.0, dtilt=0.5, dwrist=-1.0, dfingers=-0.1)
    np.testing.assert_allclose(s.robot, [7.5, 3.75, 7.5, np.pi / 8, -2 * np.pi, 0.3], atol=1e-6)
    s = act(fresh(robot=pose(9.0, 0.5, 1.0, tilt=0.1)), dx=1.0, dy=-1.0, dz=-1.0, dtilt=-1.0, dfingers=1.0)
    np.testing.assert_allclose(s.robot, [10.0, 0.0, 0.0, 0.0, 0.0, 0.4], atol=1e-6)


def test_button_turns_the_machine_on_and_snaps_the_robot_and_beats_holding():
    near = fresh(robot=pose(9.3, 7.6, 2.9, tilt=0.3, wrist=1.0))  # squared distance 0.11 < 0.2
    s = act(near, dwrist=0.5)
    assert bool(s.machine_on)
    np.testing.assert_allclose(s.robot, [9.0, 7.5, 3.0, 0.0, 0.0, 0.4], atol=1e-6)
    assert not bool(act(fresh(robot=pose(9.0, 7.0, 3.0)), dy=0.0).machine_on)  # squared distance 0.25
    again = act(near.replace(machine_on=jnp.bool_(True)), dwrist=0.5)  # already on: a plain move
    np.testing.assert_allclose(again.robot[:5], [9.3, 7.6, 2.9, 0.3, 1.0 + np.pi / 8], atol=1e-6)
    held = act(fresh(robot=pose(9.3, 7.6, 2.9, fingers=0.1), jug=(9.3, 8.02), rot=0.0, held=True), dfingers=1.0)
    assert bool(held.machine_on) and bool(held.jug_held)  # no drop: the button branch took the step
    np.testing.assert_allclose(held.jug_xy, [9.3, 8.02], atol=1e-6)


def test_held_jug_drops_when_the_fingers_open_before_anything_else():
    s = act(fresh(**AT_POUR_0), dtilt=1.0, dfingers=1.0)  # opening wins over tilting to pour
    assert not bool(s.jug_held) and float(s.cup_liquid[0]) == 0.0
    assert float(s.robot[world.FINGERS]) == pytest.approx(0.4)
    assert bool(act(fresh(**AT_POUR_0), dfingers=0.28).jug_held)  # 0.38: not within 0.01 of open


def test_pouring_fills_the_nearest_cup_in_reach_and_keeps_the_robot_in_place():
    start = fresh(**AT_POUR_0)
    s = act(start, dx=0.5, dtilt=1.0)
    assert float(s.cup_liquid[0]) == pytest.approx(0.15) and not np.asarray(s.cup_liquid[1:]).any()
    np.testing.assert_allclose(s.robot[:3], start.robot[:3])  # the position resets to the pre-step one
    assert float(s.robot[world.TILT]) == pytest.approx(np.pi / 4) and bool(s.jug_held)
    np.testing.assert_allclose(s.jug_xy, start.jug_xy)
    s = act(s, dtilt=1.0)
    assert float(s.cup_liquid[0]) == pytest.approx(0.3)
    # Within 0.1 of pi/4 counts as pouring.
    assert float(act(fresh(**{**AT_POUR_0, "robot": pose(*AT_POUR_0["robot"][:3], tilt=0.7, fingers=0.1)}))
                 .cup_liquid[0]) > 0
    # Two cups 1.5 apart: the jug between their pouring positions reaches both, the nearer one gets it.
    close = fresh(**AT_POUR_0)
    close = close.replace(task=close.task.replace(cup_xy=close.task.cup_xy.at[1].set(jnp.array([3.0, 3.0]))))
    for shift, cup in ((0.7, 0), (0.8, 1)):
        poured = act(close.replace(jug_xy=close.jug_xy + jnp.array([shift, 0.0])), dtilt=1.0)
        assert np.flatnonzero(np.asarray(poured.cup_liquid)).tolist() == [cup]


def test_pour_no_ops_freeze_the_whole_state():
    nowhere = fresh(**{**AT_POUR_0, "jug": POUR_0 + (1.2, 0.0)})  # no pouring position within reach
    assert same(act(nowhere, dx=0.5, dz=-0.3, dtilt=1.0, dwrist=0.5, dfingers=-0.1), nowhere)
    full = fresh(**AT_POUR_0, liquid=(1.0, 0.0, 0.0, 0.0))  # 1.0 + 0.15 > capacity 1.1
    assert same(act(full, dx=0.5, dtilt=1.0, dwrist=1.0), full)
    fits = fresh(**AT_POUR_0, liquid=(0.94, 0.0, 0.0, 0.0))  # up to the capacity: pours
    assert float(act(fits, dtilt=1.0).cup_liquid[0]) == pytest.approx(1.09)


def test_carrying_moves_the_jug_by_the_clipped_move_levels_the_wrist_and_keeps_the_fingers_closed():
    start = fresh(robot=pose(9.5, 3.08, 5.0, tilt=0.3, wrist=1.0, fingers=0.1), rot=0.0, held=True)
    s = act(start, dx=1.0, dy=0.4, dz=-0.2, dtilt=-0.2, dwrist=0.6, dfingers=0.2)
    np.testing.assert_allclose(s.robot, [10.0, 4.08, 4.5, 0.0, 0.0, 0.1], atol=1e-6)  # x clipped at 10
    np.testing.assert_allclose(s.jug_xy, [9.0, 4.5], atol=1e-6)  # moved by (0.5, 1.0), not (2.5, 1.0)
    assert bool(s.jug_held) and float(s.jug_rot) == 0.0


def test_twisting_turns_the_jug_by_the_wrist_motion_and_beats_the_grasp():
    top = pose(8.5, 3.5, 1.5, fingers=0.1)  # the jug top: within grasping distance of the handle too
    s = act(fresh(robot=top), dwrist=-1.0)
    assert float(s.jug_rot) == pytest.approx(1.5 - np.pi / 4) and float(s.robot[world.WRIST]) == pytest.approx(-np.pi / 4)
    held = act(fresh(robot=top, rot=0.0))  # fingers closed, |rot| < pi/3, no wrist motion: still no grasp
    assert not bool(held.jug_held) and float(held.jug_rot) == 0.0
    carried = act(fresh(robot=top, rot=0.0, held=True), dwrist=0.5)  # holding comes first: a carry
    assert float(carried.jug_rot) == 0.0 and float(carried.robot[world.WRIST]) == 0.0
    moved = act(fresh(robot=pose(8.5, 3.5, 1.9)), dz=0.2, dwrist=0.4)  # twisting reads the pre-step pose
    assert float(moved.jug_rot) == pytest.approx(1.5 + 0.4 * np.pi / 4)
    assert float(act(fresh(robot=pose(8.5, 3.5, 4.0)), dwrist=0.4).jug_rot) == 1.5  # out of reach


@pytest.mark.parametrize("rot,dwrist,fingers,offset,grasps", [
    (0.0, 0.0, 0.1, (0.0, -0.6, 0.0), True),
    (1.0, 0.0, 0.1, (0.0, -0.6, 0.0), True),  # |rot| < pi/3 = 1.047
    (-1.1, 0.0, 0.1, (0.0, -0.6, 0.0), False),  # the novelty
    (0.0, 0.1, 0.1, (0.0, -0.6, 0.0), False),  # the wrist moved
    (0.0, 0.0, 0.12, (0.0, -0.6, 0.0), False),  # fingers not within 0.01 of closed
    (0.0, 0.0, 0.1, (0.0, -0.72, 0.0), False),  # squared distance 0.52
])
def test_grasp_needs_closed_fingers_the_handle_in_reach_a_small_rotation_and_a_still_wrist(
        rot, dwrist, fingers, offset, grasps):
    handle = np.array([8.5 + 0.42 * np.cos(rot - np.pi / 2), 3.5 + 0.42 * np.sin(rot - np.pi / 2), 1.125])
    s = act(fresh(robot=pose(*(handle + offset), tilt=0.2, wrist=0.5, fingers=fingers), rot=rot), dwrist=dwrist)
    assert bool(s.jug_held) == grasps
    if grasps:
        np.testing.assert_allclose(s.robot, [*handle, 0.0, 0.0, 0.1], atol=1e-5)


def test_a_wrist_pushed_against_its_limit_does_not_move_and_so_does_not_stop_the_grasp():
    at_handle = pose(*HANDLE_AT_ROT_0, wrist=2 * np.pi, fingers=0.1)
    assert bool(act(fresh(robot=at_handle, rot=0.0), dwrist=1.0).jug_held)


def test_the_jug_fills_in_the_machine_once_the_machine_is_on():
    in_machine = {"robot": pose(9.3, 7.6, 2.9), "jug": (9.0, 7.06), "rot": 0.0}
    s = act(fresh(**in_machine))
    assert bool(s.machine_on) and bool(s.jug_filled)  # the press and the fill in the same step
    assert not bool(act(fresh(**{**in_machine, "jug": (8.5, 3.5)})).jug_filled)
    assert bool(act(fresh(robot=pose(5, 5, 10), jug=(9.0, 7.06), on=True)).jug_filled)  # already on


# ---- predicates -----------------------------------------------------------------------------------
def test_predicates():
    assert atoms(fresh()) == {"OnTable", "HandEmpty", "NotAboveCup"}
    at_top = fresh(robot=pose(8.5, 3.5, 1.5))
    assert atoms(at_top) == {"OnTable", "Twisting", "NotAboveCup"}
    assert "Twisting" in atoms(fresh(robot=pose(8.5, 3.5, 2.1)))  # squared distance 0.36 < 0.5
    assert "Twisting" not in atoms(fresh(robot=pose(8.5, 3.5, 2.3)))  # 0.64
    assert "Twisting" not in atoms(fresh(robot=pose(*HANDLE_AT_ROT_0), rot=0.0))  # nearer to the handle
    assert atoms(fresh(robot=pose(9.0, 7.5, 3.0), jug=(9.0, 7.06), on=True, filled=True)) == {
        "JugInMachine", "MachineOn", "HandEmpty", "JugFilled", "PressingButton", "NotAboveCup"}
    assert "JugInMachine" in atoms(fresh(jug=(9.6, 7.8)))  # squared distance 0.9076 < 1
    assert "OnTable" in atoms(fresh(jug=(9.8, 7.8)))
    holding = atoms(fresh(robot=pose(9.0, 6.64, 1.125), jug=(9.0, 7.06), rot=0.0, held=True))
    assert holding == {"Holding", "NotAboveCup"}  # a held jug is in no machine and on no table
    above = atoms(fresh(**AT_POUR_0, liquid=(0.9, 0.96, 0.0, 0.0)))
    assert above == {"Holding", "JugFilled", "JugAboveCup(cup0)", "RobotAboveCup(cup0)", "CupFilled(cup0)"}
    # CupFilled: more than the target, 0.975 (0.75 x 1.3) for cup1.
    assert "CupFilled(cup1)" not in atoms(fresh(liquid=(0.0, 0.97, 0.0, 0.0)))
    assert "CupFilled(cup1)" in atoms(fresh(liquid=(0.0, 0.98, 0.0, 0.0)))


def test_goal_needs_every_real_cup_filled_and_ignores_the_padding():
    assert not bool(ENV.goal_reached(fresh(liquid=(0.9, 0.98, 0.0, 0.0))))
    assert bool(ENV.goal_reached(fresh(liquid=(0.9, 0.98, 0.7, 0.0))))  # slot 3 is padding


# ---- skills ---------------------------------------------------------------------------------------
@jax.jit
def run_skill(state, call):
    """Execute one skill from `state` until it finishes (at most 60 steps): (final state, steps)."""
    def body(carry):
        state, _, steps = carry
        nxt = ENV.step(state, ENV.skill_action(state, call))
        return nxt, ENV.skill_done(state, nxt, call), steps + 1

    state, _, steps = jax.lax.while_loop(lambda c: ~c[1] & (c[2] < 60), body,
                                            (state, jnp.bool_(False), jnp.int32(0)))
    return state, steps


GROUND = {str(op): op for op in ground(ENV.planner_problem(SPEC))}


def execute(state, op_name, param=0.0):
    """Run a ground operator's skill; check the model's predicted abstract state holds afterwards."""
    op = GROUND[op_name]
    before = atoms(state)
    name = lambda atom: atom[0] if atom[0] not in ("CupFilled", "JugAboveCup", "RobotAboveCup") else \
        f"{atom[0]}({atom[-1]})"
    assert {name(a) for a in op.pre} <= before, f"{op_name}: preconditions do not hold"
    call = SkillCall(jnp.int32(ENV.skill_index(op.skill)), jnp.int32(ENV.object_slot(op.slot_object or "")),
                     jnp.float32(param), jnp.bool_(True), jnp.int32(0))
    after, steps = run_skill(state, call)
    predicted = (before - {name(a) for a in op.delete}) | {name(a) for a in op.add}
    assert predicted <= atoms(after), f"{op_name}: missing {predicted - atoms(after)}"
    return after, int(steps)


def test_the_planners_skills_reach_their_operators_effects_and_pour_into_several_cups():
    s, steps = execute(fresh(rot=0.0), "PickJugFromTable(robby, juggy)")
    assert steps == 8 and float(s.robot[world.FINGERS]) == pytest.approx(0.1)  # fly 2, down 4, onto it, grasp
    s, _ = execute(s, "PlaceJugInMachine(robby, juggy, coffee_machine)")
    s, _ = execute(s, "TurnMachineOn(robby, juggy, coffee_machine)")
    s, _ = execute(s, "PickJugFromMachine(robby, juggy, coffee_machine)")
    s, _ = execute(s, "PourFromNowhere(robby, juggy, cup1)")
    s, _ = execute(s, "PourFromOtherCup(robby, juggy, cup0, cup1)")
    s, _ = execute(s, "PourFromOtherCup(robby, juggy, cup2, cup0)")
    assert bool(ENV.goal_reached(s))
    # Each pour stops with the first 0.15 that passes the cup's target; the padding slot stays empty.
    np.testing.assert_allclose(s.cup_liquid, [0.9, 1.05, 0.75, 0.0], atol=1e-5)


@pytest.mark.parametrize("p", [0.0, 0.4, -0.45, 0.9])
def test_move_to_twist_jug_then_twist_jug_sets_the_asked_rotation_and_frees_the_hand(p):
    stuck = fresh(robot=pose(8.5 + 0.419, 3.5 - 0.03, 1.125, fingers=0.1))
    top, steps = execute(stuck, "MoveToTwistJug(robby, juggy)")
    assert steps <= 3 and atoms(top) == {"OnTable", "Twisting", "NotAboveCup"}
    twisted, steps = execute(top, "TwistJug(robby, juggy)", p)
    assert abs(float(twisted.jug_rot) - p * 2 * np.pi / 3) < 0.1
    assert steps == int(np.ceil(max(abs(1.5 - p * 2 * np.pi / 3) - 0.1, 0) / (np.pi / 4))) + 1  # twists, 1 up


def test_pick_jug_at_the_rotated_jug_closes_the_fingers_at_the_handle_and_stops_without_progress():
    call = SkillCall(jnp.int32(skills.PICK_JUG), jnp.int32(0), jnp.float32(0.0), jnp.bool_(True), jnp.int32(0))
    stuck, steps = run_skill(fresh(), call)
    assert int(steps) == 9 and not bool(stuck.jug_held)  # 7 to the handle, close, then one unchanged step
    handle = np.asarray(world.handle(stuck))
    np.testing.assert_allclose(handle - [8.5, 3.5, 1.125], [0.419, -0.0297, 0.0], atol=1e-3)
    np.testing.assert_allclose(stuck.robot, [*handle, 0.0, 0.0, 0.1], atol=1e-5)
    np.testing.assert_allclose(ENV.features(stuck, stuck), [0.419, 0.0297, 1.5, 0.0, 0.0], atol=1e-3)


def test_a_pour_that_cannot_pour_stops_at_once():
    call = SkillCall(jnp.int32(skills.POUR), jnp.int32(0), jnp.float32(0.0), jnp.bool_(True), jnp.int32(0))
    full = fresh(**AT_POUR_0, liquid=(1.0, 0.0, 0.0, 0.0)).replace(robot=jnp.asarray(
        np.float32(pose(*AT_POUR_0["robot"][:3], tilt=np.pi / 4, fingers=0.1))))
    after, steps = run_skill(full, call)
    assert int(steps) == 1 and same(after, full)


# ---- tasks, features, full state, jit/vmap --------------------------------------------------------
def test_task_generation():
    train = [Coffee.train_task(s) for s in range(20)]
    assert all(len(t.cups) == 1 for t in train) and len(set(train)) == 20
    tests = [t for s in range(8) for t in Coffee.test_tasks(s)]
    assert {len(t.cups) for t in tests} == {1, 2, 3, 4} and Coffee.test_tasks(3) == Coffee.test_tasks(3)
    for t in train + tests:
        assert 8.0 <= t.jug[0] <= 9.0 and 2.4 <= t.jug[1] <= 4.6
        for i, (x, y, capacity) in enumerate(t.cups):
            assert 0.74 <= x <= 6.76 and 2.4 <= y <= 4.6 and 0.75 <= capacity <= 1.5
            assert all(np.hypot(x - u, y - v) > 1.48 for u, v, _ in t.cups[:i])
    arrays = ENV.task_arrays(tests[0])
    n = len(tests[0].cups)
    assert arrays.cup_mask.tolist() == [i < n for i in range(4)]
    np.testing.assert_allclose(arrays.cup_target, 0.75 * arrays.cup_capacity)


def test_full_state_is_padded_to_four_cups_whatever_the_capacity():
    one = Coffee(max_cups=1)
    spec = Coffee.train_task(0)
    a = one.full_state(one.reset(jax.tree.map(jnp.asarray, one.task_arrays(spec))))
    b = ENV.full_state(ENV.reset(jax.tree.map(jnp.asarray, ENV.task_arrays(spec))))
    assert a.shape == b.shape == (Coffee.full_state_size,) == (32,)
    np.testing.assert_array_equal(a, b)
    x, y, capacity = spec.cups[0]
    np.testing.assert_allclose(a[:17], [5, 5, 10, 0, 0, 0.4, *spec.jug, 1.5, 0, 0, 0, x, y, capacity,
                                        0.75 * capacity, 0], atol=1e-6)
    assert not np.asarray(a[17:]).any()


def test_reset_and_step_jit_and_vmap_over_seeds_and_tasks():
    specs = [t for seed in range(8) for t in Coffee.test_tasks(seed)]
    env = Coffee.for_tasks(specs)
    states = jax.jit(jax.vmap(env.reset))(env.stack_tasks(specs))
    assert states.robot.shape == (80, 6) and states.cup_liquid.shape == (80, 4)
    actions = jax.random.uniform(jax.random.key(0), (80, 6), minval=-1.0, maxval=1.0)
    batched = jax.jit(jax.vmap(env.step))(states, actions)
    single = jax.jit(env.step)
    for i in (0, 41, 79):
        row = lambda tree, i=i: jax.tree.map(lambda x: x[i], tree)
        assert same(single(row(states), actions[i]), row(batched))
    np.testing.assert_allclose(batched.jug_xy, np.array([s.jug for s in specs]), atol=1e-6)  # nothing held


# ---- the meta-policy: oracle bridge vs pure planning ---------------------------------------------
TEST_SEEDS = list(range(8))


@pytest.fixture(scope="module")
def batch():
    """Every test task of seeds 0-7 of the 1-4-cup variant (`Coffee.test_tasks`' own default, protocol
    "jaxbridge"), then every seed's training task (with the training steps)."""
    specs = [t for seed in TEST_SEEDS for t in Coffee.test_tasks(seed)] + [Coffee.train_task(s) for s in TEST_SEEDS]
    horizons = [Coffee.test_tasks(0)[0].horizon] * 80 + [Coffee.train_steps] * 8
    return make_batch(Coffee, specs, [s for s in TEST_SEEDS for _ in range(10)] + TEST_SEEDS, horizons)


@pytest.fixture(scope="module")
def results(batch):
    return oracle_and_pure_planning(batch)


def test_the_planner_model_never_twists(batch):
    for spec, compiled in zip(batch.specs, batch.compiled):
        plan = [op.name for op in compiled.plan()]
        assert plan[:4] == ["PickJugFromTable", "PlaceJugInMachine", "TurnMachineOn", "PickJugFromMachine"]
        assert plan[4:] == ["PourFromNowhere"] + ["PourFromOtherCup"] * (len(spec.cups) - 1)


def test_oracle_bridge_solves_every_variant_test_task_of_seeds_0_to_7_within_its_horizon(batch, results):
    result = results["oracle"]
    assert batch.size == 88 and result.success.all() and result.table_misses.sum() == 0
    # Stuck once at the rotated jug: MoveToTwistJug, TwistJug, CallPlanner.
    assert (result.stuck_events == 1).all() and (result.bridge_decisions == 3).all()
    assert (result.planner_calls == 2).all()
    # The variant's horizon leaves the longest test episode at most 10 steps to spare.
    horizon = Coffee.test_tasks(0)[0].horizon
    assert horizon - 10 <= result.steps[:80].max() <= horizon and result.steps[80:].max() <= Coffee.train_steps
    # min_steps (train.py refuses shorter training horizons) is a lower bound.
    assert all(spec.min_steps <= steps for spec, steps in zip(batch.specs, result.steps))


@dataclass(frozen=True)
class FixedTwistOracle:
    """The oracle, but twisting with the episode's own fixed parameter where that is not nan."""

    env: Coffee

    def __call__(self, fixed, obs, key):
        oracle = self.env.oracle_bridge(None, obs, key)
        use_fixed = (oracle.skill == skills.TWIST_JUG) & ~jnp.isnan(fixed)
        return oracle.replace(param=jnp.where(use_fixed, fixed, oracle.param))


FIXED_TWISTS = (0.0, 0.2, 0.3, 0.4, 0.45)  # p = 0: the oracle's twist until it took the fewest steps


def test_the_oracle_twists_in_fewer_wrist_steps_than_any_fixed_twist_and_solves_all_they_solve():
    """Seeds 0-3's default test tasks (4 cups, horizon 100), the oracle and each fixed twist on the same
    tasks in one rollout: the oracle's twist takes one wrist step (p = 0 and 0.2 take two), its episodes
    are never longer, and it solves every task any of them solves (more than p = 0)."""
    batch = evaluation_batch(Coffee, [0, 1, 2, 3], protocol="authors")
    runs = 1 + len(FIXED_TWISTS)
    fixed = jnp.repeat(jnp.array((jnp.nan,) + FIXED_TWISTS, jnp.float32), batch.size)
    arrays = jax.tree.map(lambda x: jnp.concatenate([x] * runs), batch.arrays)
    result, rec = rollout(MetaPolicy(batch.env, FixedTwistOracle(batch.env), fixed), arrays,
                          jax.random.split(jax.random.key(0), runs * batch.size), batch.max_steps, record=True)
    rot, live = np.asarray(rec.env_state.jug_rot), np.asarray(rec.live)
    wrist_steps = ((rot[1:] != rot[:-1]) & live[:-1]).sum(0).reshape(runs, batch.size)
    success = np.asarray(result.success).reshape(runs, batch.size)
    steps = np.asarray(result.steps).reshape(runs, batch.size)
    ours, grid = (wrist_steps[0], success[0], steps[0]), (wrist_steps[1:], success[1:], steps[1:])
    assert (ours[0] == 1).all() and (grid[0][:2] == 2).all() and (grid[0] >= ours[0]).all()
    assert not (grid[1] & ~ours[1]).any() and ours[1].sum() > grid[1][0].sum()
    assert (ours[2] <= grid[2]).all()


@pytest.mark.parametrize("rot", [1.5, -1.5, 1.1, 2.0, 3.0])
def test_the_oracles_twist_parameter_makes_the_jug_graspable_in_the_fewest_wrist_steps(rot):
    """TwistJug from the jug's top with every parameter on a grid of 0.01: none makes the jug graspable
    in fewer wrist steps than the oracle's (`skills.fewest_steps_twist`), whose twist leaves it graspable."""
    top = fresh(robot=pose(8.5, 3.5, 1.5, fingers=0.1), rot=rot)
    params = jnp.concatenate([jnp.linspace(-1.0, 1.0, 201), skills.fewest_steps_twist(jnp.float32(rot))[None]])
    n = params.shape[0]
    calls = SkillCall(jnp.full(n, skills.TWIST_JUG, jnp.int32), jnp.zeros(n, jnp.int32), params, jnp.ones(n, bool),
                      jnp.zeros(n, jnp.int32))
    after, steps = jax.vmap(run_skill, in_axes=(None, 0))(top, calls)
    graspable = np.abs(np.asarray(after.jug_rot)) < world.PICK_JUG_ROT_TOL
    wrist_steps = np.asarray(steps) - 1  # the last step rises off the jug
    assert graspable[-1] and wrist_steps[-1] == wrist_steps[:-1][graspable[:-1]].min()


def test_pure_planning_solves_none(results):
    result = results["none"]
    assert not result.success.any() and (result.stuck_events > 10).all()


def test_the_env_keeps_the_env_contract():
    from envs_jax import Coffee
    from jaxbridge import check_env

    assert check_env(Coffee) is Coffee  # shapes, dtypes, purity, the planner's model, the oracle on its test tasks


# ---- the authors' shared repeated-state flag (quirk "shared_repeat_flag", envs.md §4.6) ---------------
@dataclass(frozen=True)
class HesitantOracle:
    """The oracle, except that where it would move to the jug's top it first tries PickJug on a coin flip."""

    env: Coffee

    def __call__(self, params, obs, key):
        oracle = self.env.oracle_bridge(params, obs, key)
        pick = (oracle.skill == skills.MOVE_TO_TWIST_JUG) & jax.random.bernoulli(key)
        return oracle.replace(skill=jnp.where(pick, skills.PICK_JUG, oracle.skill))


@pytest.fixture(scope="module")
def training_batch():
    return make_batch(Coffee, [Coffee.train_task(s) for s in range(8)], list(range(8)), [Coffee.train_steps] * 8)


def hesitant_rollout(batch, quirk: bool, groups):
    env = batch.env.with_quirks(("shared_repeat_flag",) if quirk else ())
    result, rec = rollout(MetaPolicy(env, HesitantOracle(env)), batch.arrays,
                          jax.random.split(jax.random.key(1), batch.size), batch.max_steps, record=True,
                          groups=groups)
    decided = np.asarray(rec.decided & rec.live)
    first = np.array([np.asarray(rec.skill)[decided[:, i], i][0] for i in range(batch.size)])
    return jax.tree.map(np.asarray, result), first == skills.PICK_JUG, np.asarray(rec.env_state.memory.repeated[-1])


def test_pick_jug_at_the_stuck_state_sets_the_authors_flag_which_fails_the_planners_pick_later(training_batch):
    """The planner's PickJug last acted in the stuck state, so the bridge's PickJug there repeats it: the
    flag is set, and after the twist the planner's PickJug ends after one step without the jug, again
    and again. Without the quirk every episode recovers; an episode that never tried PickJug first
    is unaffected unless it shares the flag with one that did."""
    result, picked_first, _ = hesitant_rollout(training_batch, False, None)
    assert result.success.all() and 0 < picked_first.sum() < training_batch.size
    own = jnp.arange(training_batch.size)
    result, picked, flagged = hesitant_rollout(training_batch, True, own)
    assert np.array_equal(picked, picked_first) and np.array_equal(flagged, picked)
    assert np.array_equal(result.success, ~picked)
    assert (result.stuck_events[picked] > 1).all() and (result.stuck_events[~picked] == 1).all()
    result, _, flagged = hesitant_rollout(training_batch, True, None)  # one seed's episodes: one flag
    assert flagged.all() and not result.success.any()


def test_the_quirk_is_named_by_the_authors_preset_and_unknown_quirks_are_refused():
    from jaxbridge.core.config import TrainConfig
    from jaxbridge.learn.setup import make_setup
    setup = make_setup(jaxbridge.make_config("coffee", preset="authors", num_seeds=1))
    assert setup.train_env.shared_repeat_flag and setup.test_env.shared_repeat_flag
    assert not make_setup(jaxbridge.make_config("coffee", num_seeds=1)).train_env.shared_repeat_flag
    with pytest.raises(ValueError, match="has no quirk 'shared_repeat_flag'"):
        make_setup(jaxbridge.make_config("doorknobs", num_seeds=1, env_quirks=("shared_repeat_flag",)))
    config = jaxbridge.make_config("coffee", preset="authors")
    assert TrainConfig.from_dict(config.to_dict()) == config and config.to_dict()["env_quirks"] == ["shared_repeat_flag"]
