"""Doorknobs: geometry, the dynamics rules of envs.md §3.4, predicates, features, task generation, the
precomputed motion, and the meta-policy with the oracle bridge and with pure planning."""
from collections import deque
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.doorknobs import maps
from envs_jax import geometry
from envs_jax.base import SkillCall
from envs_jax.doorknobs.env import Doorknobs
from jaxbridge.core.tasks import make_batch

from oracle_vs_planning import oracle_and_pure_planning

ENV = Doorknobs(map_size=2)
SPEC = Doorknobs.train_task(0)  # rooms (0,1), (1,0), (1,1); doors (0,1) bottom, (1,1) left
MOVE_TO, OPEN, THROUGH = (ENV.skill_index(n) for n in ("MoveToDoor", "OpenDoor", "MoveThroughDoor"))
BOTTOM_DOOR = ENV.object_slot("door-0-1-bottom")  # between (0,1) above and (1,1) below, at y = 1
LEFT_DOOR = ENV.object_slot("door-1-1-left")  # between (1,1) and (1,0), at x = 1


def fresh(robot=None, rot=None, opened=()):
    state = ENV.reset(jax.tree.map(jnp.asarray, ENV.task_arrays(SPEC)))
    if robot is not None:
        state = state.replace(robot=jnp.array(robot, jnp.float32))
    if rot is not None:
        state = state.replace(knob_rot=state.knob_rot.at[BOTTOM_DOOR].set(rot))
    return state.replace(door_open=state.door_open.at[jnp.array(opened, int)].set(True))


step = jax.jit(ENV.step)
abstract, features, full_state = jax.jit(ENV.abstract), jax.jit(ENV.features), jax.jit(ENV.full_state)
skill_action, skill_done = jax.jit(ENV.skill_action), jax.jit(ENV.skill_done)


def act(state, dx=0.0, dy=0.0, drot=0.0):
    return step(state, jnp.array([dx, dy, drot], jnp.float32))


def call(skill, slot, param=0.0):
    return SkillCall(jnp.int32(skill), jnp.int32(slot), jnp.float32(param), jnp.bool_(True), jnp.int32(0))


# ---- geometry ------------------------------------------------------------------------------------
def test_circle_rectangle_collision_axis_aligned_and_rotated():
    box = geometry.rect(0.0, 0.0, 1.0, 0.2)
    hits = lambda p, r: bool(geometry.circle_hits_rect(jnp.array(p), 0.05, r))
    assert hits((0.5, 0.1), box) and hits((0.5, 0.25), box) and hits((1.03, 0.23), box)
    assert not hits((0.5, 0.26), box) and not hits((1.04, 0.24), box)
    # Rotated a quarter turn counter-clockwise about its anchor, the box covers x in [-0.2, 0], y in [0, 1].
    upright = geometry.rect(0.0, 0.0, 1.0, 0.2, np.pi / 2)
    assert hits((-0.1, 0.5), upright) and hits((0.04, 0.5), upright)
    assert not hits((0.06, 0.5), upright) and not hits((0.5, 0.1), upright)
    # A diamond (45 degrees): the corner (0, 0) is the anchor, the far corner is at (0, 0.2 * sqrt 2).
    diamond = geometry.rect(0.0, 0.0, 0.2, 0.2, np.pi / 4)
    assert hits((0.0, 0.3), diamond) and not hits((0.0, 0.34), diamond) and not hits((0.12, 0.0), diamond)
    np.testing.assert_allclose(geometry.corners(diamond)[2], [0.0, 0.2 * np.sqrt(2)], atol=1e-6)


def test_segment_rectangle_distance_and_overlap():
    box = geometry.rect(0.0, 0.0, 1.0, 1.0)

    def gap(a, b, r=box):  # the segment's distance to r, as the clearance test sees it
        clears = lambda g: bool(geometry.segment_clears_rect(jnp.array(a), jnp.array(b), r, g))
        return lambda d: clears(d - 1e-3) and not clears(d + 1e-3) and not clears(d + 0.1)

    assert not geometry.segment_clears_rect(jnp.array([-1.0, 0.5]), jnp.array([2.0, 0.5]), box, 0.0)  # through
    assert not geometry.segment_clears_rect(jnp.array([0.5, 0.5]), jnp.array([0.6, 0.6]), box, 0.0)  # inside
    assert gap((-1.0, 1.3), (2.0, 1.3))(0.3)  # passing above
    assert gap((1.5, -1.0), (1.5, 2.0))(0.5)  # passing beside
    assert gap((1.2, 1.2), (2.0, 2.0))(0.2 * np.sqrt(2))  # nearest to a corner
    assert gap((2.5, 0.0), (0.0, 2.5))(0.5 / np.sqrt(2))  # cutting past a corner
    assert gap((1.1, 1.1), (1.1, 1.1))(0.1 * np.sqrt(2))  # a point
    diamond = geometry.rect(0.0, 0.0, 0.2, 0.2, np.pi / 4)  # its top corner is (0, 0.2 sqrt 2)
    assert gap((-1.0, 0.4), (1.0, 0.4), diamond)(0.4 - 0.2 * np.sqrt(2))
    tilted = geometry.rect(1.2, 0.5, 0.3, 0.3, np.pi / 4)  # its left corner reaches x = 1.2 - 0.3 / sqrt 2
    assert bool(geometry.rects_overlap(box, tilted))
    assert not bool(geometry.rects_overlap(box, geometry.rect(1.5, 0.5, 0.3, 0.3, np.pi / 4)))


def test_doorway_rectangles_and_positions():
    task = ENV.task_arrays(SPEC)
    # The bottom door of room (0,1) (lower-left corner (1, 1)) spans x in [1.38, 1.63] on the line y = 1.
    np.testing.assert_allclose(task.door_rect[BOTTOM_DOOR], [1.38, 0.995, 0.25, 0.01, 0.0], atol=1e-6)
    np.testing.assert_allclose(task.doorway[BOTTOM_DOOR], [1.38, 0.944, 0.25, 0.112, 0.0], atol=1e-6)
    np.testing.assert_allclose(task.door_point[BOTTOM_DOOR], [[1.505, 1.056], [1.505, 0.944]], atol=1e-6)
    # The left door of room (1,1) stands upright on x = 1 (theta = pi/2 about its anchor).
    np.testing.assert_allclose(task.door_rect[LEFT_DOOR], [1.005, 0.38, 0.25, 0.01, np.pi / 2], atol=1e-6)
    np.testing.assert_allclose(task.doorway[LEFT_DOOR], [0.944, 0.38, 0.112, 0.25, 0.0], atol=1e-6)
    cases = [(BOTTOM_DOOR, 0, "room-0-1", "door-0-1-bottom"), (BOTTOM_DOOR, 1, "room-1-1", "door-0-1-bottom"),
             (LEFT_DOOR, 0, "room-1-1", "door-1-1-left"), (LEFT_DOOR, 1, "room-1-0", "door-1-1-left")]
    for door, side, room, name in cases:  # the position in the doorway on each side of each door
        atoms = np.asarray(abstract(fresh(robot=task.door_point[door, side])))
        assert atoms[ENV.atom_index(("InDoorway", "robby", name))] and atoms[ENV.atom_index(("InRoom", "robby", room))]
        assert not atoms[ENV.atom_index(("InMainRoom", "robby", room))] and atoms.sum() == 2


# ---- dynamics ------------------------------------------------------------------------------------
def test_a_colliding_move_is_cancelled_and_moves_are_clipped():
    near_wall = fresh(robot=(1.5, 0.06))  # 0.055 above the outer bottom wall's top face (y = 0.005)
    assert np.allclose(act(near_wall, dy=-0.02).robot, [1.5, 0.06])  # would touch: cancelled, no sliding
    assert np.allclose(act(near_wall, dx=0.02, dy=-0.02).robot, [1.5, 0.06])
    assert np.allclose(act(near_wall, dy=-0.004).robot, [1.5, 0.056])
    assert np.allclose(act(near_wall, dx=0.3, dy=0.3).robot, [1.55, 0.11])  # clipped to +-0.05
    under_door = fresh(robot=(1.505, 0.944))
    assert np.allclose(act(under_door, dy=0.05).robot, [1.505, 0.944])  # the closed door blocks
    assert np.allclose(act(fresh(robot=(1.505, 0.944), opened=[BOTTOM_DOOR]), dy=0.05).robot, [1.505, 0.994])
    clutter = np.asarray(ENV.task_arrays(SPEC).clutter[3, 0])  # in room (1,1), rotated
    centre = geometry.corners(jnp.asarray(clutter)).mean(0)
    beside = centre + jnp.array([0.0, 0.3])
    assert not bool(ENV.collides(fresh().task, fresh().door_open, beside))
    assert bool(ENV.collides(fresh().task, fresh().door_open, centre))


def test_knobs_turn_incrementally_and_clip_only_while_touching_a_closed_door():
    at_door = fresh(robot=(1.505, 0.944))
    s = act(act(at_door, drot=0.3), drot=0.3)
    assert float(s.knob_rot[BOTTOM_DOOR]) == pytest.approx(0.6) and not bool(s.door_open[BOTTOM_DOOR])
    assert float(act(at_door, drot=2.0).knob_rot[BOTTOM_DOOR]) == 1.0
    assert float(act(fresh(robot=(1.505, 0.944), rot=0.2), drot=-0.9).knob_rot[BOTTOM_DOOR]) == 0.0
    away = act(fresh(robot=(1.5, 0.5)), drot=0.75)
    assert not np.asarray(away.knob_rot).any() and not np.asarray(away.door_open).any()
    # The knob reads the pre-step state: stepping away while turning still turns it.
    leaving = act(at_door, dy=-0.05, drot=0.75)
    assert bool(leaving.door_open[BOTTOM_DOOR]) and float(leaving.robot[1]) == pytest.approx(0.894)


@pytest.mark.parametrize("rot,opens", [(0.64, False), (0.66, True), (0.75, True), (0.84, True), (0.86, False),
                                       (0.0, False), (1.0, False)])
def test_door_opens_within_strict_tolerance_of_its_target_and_stays_open(rot, opens):
    s = act(fresh(robot=(1.505, 0.944)), drot=rot)
    assert bool(s.door_open[BOTTOM_DOOR]) == opens and not bool(s.door_open[LEFT_DOOR])
    if opens:
        again = act(s, drot=-1.0)
        assert bool(again.door_open[BOTTOM_DOOR]) and float(again.knob_rot[BOTTOM_DOOR]) == pytest.approx(rot)


def test_a_knob_next_to_its_bounds_opens_as_the_authors_float64_test():
    """The authors test |rot - 0.75| < 0.1 in float64: float32(0.65) = 0.64999998 stays shut, the next
    float32 up opens; float32(0.85) = 0.85000002 stays shut, the one below opens."""
    for bound in (0.65, 0.85):
        rot = np.float32(bound)
        for _ in range(3):
            rot = np.nextafter(rot, np.float32(0))
        for _ in range(7):
            authors = abs(np.float64(rot) - maps.KNOB_TARGET) < maps.OPEN_TOLERANCE
            s = act(fresh(robot=(1.505, 0.944)), drot=rot)
            assert float(s.knob_rot[BOTTOM_DOOR]) == rot and bool(s.door_open[BOTTOM_DOOR]) == authors
            rot = np.nextafter(rot, np.float32(1))
    assert not bool(act(fresh(robot=(1.505, 0.944)), drot=np.float32(0.65)).door_open[BOTTOM_DOOR])


def test_move_through_door_is_blocked_while_closed_and_crosses_once_open():
    def through(state, steps=6):
        for _ in range(steps):
            nxt = act(state, *np.asarray(skill_action(state, call(THROUGH, BOTTOM_DOOR))))
            if bool(skill_done(state, nxt, call(THROUGH, BOTTOM_DOOR))):
                return nxt
            state = nxt
        raise AssertionError("MoveThroughDoor did not finish")

    below = fresh(robot=(1.505, 0.9))
    blocked = through(below)
    assert np.allclose(blocked.robot, below.robot)  # no progress ends the skill
    opened = act(below, drot=0.75)
    crossed = through(opened)
    assert bool(ENV.in_room(crossed)[ENV.object_slot("room-0-1")]) and bool(ENV.goal_reached(crossed))
    assert bool(ENV.in_doorway(crossed)[BOTTOM_DOOR])  # the planner model's expected atoms hold


# ---- predicates, features, full state ----------------------------------------------------------
def test_predicates_and_goal():
    atoms = np.asarray(abstract(fresh()))
    assert atoms.shape == (ENV.num_atoms,) and atoms.sum() == 2
    assert atoms[ENV.atom_index(("InRoom", "robby", "room-1-1"))]
    assert atoms[ENV.atom_index(("InMainRoom", "robby", "room-1-1"))]
    assert not bool(ENV.goal_reached(fresh())) and bool(ENV.goal_reached(fresh(robot=(1.5, 1.5))))
    # Rooms are half-open: a centre on the shared edge y = 1 is in the upper room only.
    assert np.nonzero(np.asarray(ENV.in_room(fresh(robot=(1.505, 1.0)))))[0].tolist() == [ENV.object_slot("room-0-1")]


def test_features_see_the_nearest_knob_of_the_robots_room_and_the_displacement():
    stuck = fresh(robot=(1.505, 0.9), rot=0.3)
    f = np.asarray(features(stuck, stuck))
    np.testing.assert_allclose(f, [0.125, 0.095, 0.3, 0.75, 0.0, 0.0, 0.0], atol=1e-6)
    moved = stuck.replace(robot=jnp.array([1.1, 0.45]))  # now nearest to the left door's anchor (1.005, 0.38)
    f = np.asarray(features(moved, stuck))
    # Offsets and displacement come larger first, whatever the door's orientation (|dy| > |dx| here).
    np.testing.assert_allclose(f, [0.095, 0.07, 0.0, 0.75, 0.0, 0.45, 0.405], atol=1e-6)
    assert f.shape == (ENV.num_features,)
    # The authors' order (the `raw_offsets` quirk): (|dx|, |dy|) as they are.
    raw = ENV.with_quirks(("raw_offsets",))
    np.testing.assert_allclose(raw.features(moved, stuck), [0.095, 0.07, 0.0, 0.75, 0.0, 0.405, 0.45], atol=1e-6)
    np.testing.assert_allclose(raw.features(moved.replace(robot=jnp.array([1.03, 0.45])), stuck),
                               [0.025, 0.07, 0.0, 0.75, 0.0, 0.475, 0.45], atol=1e-6)


def test_full_state_is_capacity_independent():
    big = Doorknobs()
    small_state = fresh(robot=(1.2, 0.7), rot=0.4, opened=[LEFT_DOOR])
    big_task = jax.tree.map(jnp.asarray, big.task_arrays(SPEC))
    big_state = big.reset(big_task).replace(robot=small_state.robot)
    big_state = big_state.replace(knob_rot=big_state.knob_rot.at[big.object_slot("door-0-1-bottom")].set(0.4),
                                  door_open=big_state.door_open.at[big.object_slot("door-1-1-left")].set(True))
    a, b = np.asarray(full_state(small_state)), np.asarray(jax.jit(big.full_state)(big_state))
    assert a.shape == b.shape == (Doorknobs.full_state_size,) == (2027,)
    np.testing.assert_array_equal(a, b)
    assert a[:2].tolist() == pytest.approx([1.2, 0.7]) and np.count_nonzero(a) > 100


def test_a_2x2_map_fills_only_its_rooms_slots_of_the_full_state():
    """full_state_filled: the robot and a 2x2 map's 4 room slots of the 5x5 layout (326 of its 2027 entries;
    a 5x5 map fills them all), and a 2x2 map's state, a knob turned and a door open, sets nothing else."""
    assert len(ENV.full_state_filled) == 326 and np.array_equal(Doorknobs().full_state_filled, np.arange(2027))
    state = fresh(robot=(1.2, 0.7), rot=0.4, opened=[LEFT_DOOR])
    set_entries = np.flatnonzero(np.asarray(full_state(state)))
    assert len(set_entries) > 100 and np.isin(set_entries, ENV.full_state_filled).all()


# ---- task generation -------------------------------------------------------------------------------
def connected(spec) -> bool:
    seen, queue = {spec.rooms[0]}, deque([spec.rooms[0]])
    while queue:
        room = queue.popleft()
        for door in spec.doors:
            a, b = maps.door_rooms(door)
            for x, y in ((a, b), (b, a)):
                if x == room and y not in seen:
                    seen.add(y)
                    queue.append(y)
    return seen == set(spec.rooms)


def check_task(spec):
    rooms = set(spec.rooms)
    adjacent = {(r, c, side) for r, c in rooms for side, n in ((0, (r + 1, c)), (1, (r, c - 1))) if n in rooms}
    assert set(spec.doors) == adjacent  # a door on every shared wall, nowhere else
    assert connected(spec) and spec.goal_room != spec.start_room and spec.goal_room in rooms
    assert all(len(c) <= 3 for c in spec.clutter) and len(spec.clutter) == len(rooms)
    for placed in spec.clutter:
        for i in range(len(placed)):
            for j in range(i):
                assert not bool(maps._overlaps(np.float32(placed[i]), np.float32(placed[j])))
    task = jax.tree.map(jnp.asarray, maps.task_arrays(spec, spec.size))
    assert not bool(COLLIDES[spec.size](task, jnp.zeros_like(task.door_mask), jnp.array(spec.robot)))


COLLIDES = {size: jax.jit(Doorknobs(size).collides) for size in (2, 5)}


@pytest.mark.parametrize("seed", range(20))
def test_train_maps_are_three_rooms_in_an_l_with_two_doors(seed):
    spec = Doorknobs.train_task(seed)
    assert spec.size == 2 and len(spec.rooms) == 3 and len(spec.doors) == 2 and 1 <= spec.doors_to_goal <= 2
    check_task(spec)


def test_test_maps_have_6_to_20_connected_rooms_on_5x5_and_replay_the_seed():
    specs = [t for seed in range(8) for t in Doorknobs.test_tasks(seed)]
    assert all(s.size == 5 and 6 <= len(s.rooms) <= 20 for s in specs)
    assert len({len(s.rooms) for s in specs}) > 5 and max(s.doors_to_goal for s in specs) >= 4
    for spec in specs[:20]:
        check_task(spec)
    assert Doorknobs.test_tasks(3) == Doorknobs.test_tasks(3) and Doorknobs.test_tasks(3) != Doorknobs.test_tasks(4)


# ---- precomputed motion ------------------------------------------------------------------------------
def motion_cases(env, specs):
    """Per task: (start position, target door) for MoveToDoor from the robot's start to every door of its
    room, and from each doorway position to every other door of that room."""
    cases = []
    door_rooms, room_doors = maps.layout(env.map_size)
    for spec in specs:
        task, mine = env.task_arrays(spec), []
        start_room = spec.start_room[0] * env.map_size + spec.start_room[1]
        mine += [(task.robot_start, d) for d in room_doors[start_room] if d >= 0 and task.door_mask[d]]
        for d in np.nonzero(task.door_mask)[0]:
            for side, room in enumerate(door_rooms[d]):
                others = [e for e in room_doors[room] if e >= 0 and e != d and task.door_mask[e]]
                mine += [(task.door_point[d, side], e) for e in others]
        cases.append(mine)
    width = max(len(c) for c in cases)
    start = np.zeros((len(specs), width, 2), np.float32)
    door, valid = np.zeros((len(specs), width), np.int32), np.zeros((len(specs), width), bool)
    for i, mine in enumerate(cases):
        for j, (p, d) in enumerate(mine):
            start[i, j], door[i, j], valid[i, j] = p, d, True
    return start, door, valid


@partial(jax.jit, static_argnums=0)
def drive(env, tasks, start, door):
    """MoveToDoor from `start` (all doors closed) until it ends, then open the door and MoveThroughDoor.
    Returns per case: steps, any step longer than 0.05, any cancelled step, in the doorway at the end,
    crossed into the far room."""
    def one(task, p, d):
        state = env.reset(task).replace(robot=p)

        def go(skill, carry, _):
            state, done, long_step, cancelled, steps = carry
            action = env.skill_action(state, call(skill, d))
            nxt = env.step(state, action)
            moved = ~jnp.all(nxt.robot == state.robot)
            cancelled |= ~done & ~moved & jnp.any(action[:2] != 0) & (skill == MOVE_TO)
            long_step |= ~done & (jnp.linalg.norm(action[:2]) > 0.05 + 1e-6)
            ended = env.skill_done(state, nxt, call(skill, d))
            state = jax.tree.map(lambda a, b: jnp.where(done, a, b), state, nxt)
            return (state, done | ended, long_step, cancelled, steps + ~done), None

        false = jnp.bool_(False)
        (state, _, long_step, cancelled, steps), _ = jax.lax.scan(partial(go, MOVE_TO),
                                                                 (state, false, false, false, jnp.int32(0)), None, 36)
        arrived = env.in_doorway(state)[d]
        far = env._far_room(state, d)
        state = state.replace(door_open=state.door_open.at[d].set(True))
        (state, *_), _ = jax.lax.scan(partial(go, THROUGH), (state, false, false, false, jnp.int32(0)), None, 6)
        return steps, long_step, cancelled, arrived, env.in_room(state)[far]

    return jax.vmap(jax.vmap(one, (None, 0, 0)))(tasks, start, door)


def test_every_motion_path_is_collision_free_with_short_steps_and_ends_in_the_doorway():
    specs = [Doorknobs.train_task(s) for s in range(8)] + [t for seed in range(2) for t in Doorknobs.test_tasks(seed)]
    env = Doorknobs.for_tasks(specs)
    start, door, valid = motion_cases(env, specs)
    steps, long_step, cancelled, arrived, crossed = jax.tree.map(
        np.asarray, drive(env, env.stack_tasks(specs), jnp.asarray(start), jnp.asarray(door)))
    assert valid[:8].sum() > 20 and valid[8:].sum() > 300
    assert not long_step[valid].any() and not cancelled[valid].any()
    assert arrived[valid].all() and crossed[valid].all()
    assert steps[valid].max() <= 30  # about 0.05 per step across a 1x1 room, around clutter


# ---- the meta-policy: oracle bridge vs pure planning ---------------------------------------------
TEST_SEEDS = list(range(8))


@pytest.fixture(scope="module")
def batch():
    """Every test task of seeds 0-7, then every seed's training task: one batch, one compilation."""
    specs = [t for seed in TEST_SEEDS for t in Doorknobs.test_tasks(seed)]
    specs += [Doorknobs.train_task(seed) for seed in TEST_SEEDS]
    return make_batch(Doorknobs, specs, [seed for seed in TEST_SEEDS for _ in range(10)] + TEST_SEEDS)


@pytest.fixture(scope="module")
def results(batch):
    return oracle_and_pure_planning(batch)


def test_the_planner_model_plans_through_the_closed_doors(batch):
    for spec, compiled in list(zip(batch.specs, batch.compiled))[::8]:
        plan = [op.name for op in compiled.plan()]
        assert plan[0] == "MoveToDoorFromMainRoom" and "OpenDoor" not in plan
        assert plan.count("MoveThroughDoor") == spec.doors_to_goal == len(plan) // 2


def test_oracle_bridge_solves_every_test_task_of_seeds_0_to_7_and_every_training_task(batch, results):
    result = results["oracle"]
    assert batch.size == 88 and result.success.all() and (result.steps <= 200).all()
    assert (result.steps[80:] <= 40).all()  # the 2x2 training maps
    doors = np.array([s.doors_to_goal for s in batch.specs])
    # Stuck once at each closed door on the way: OpenDoor, then CallPlanner.
    assert np.array_equal(result.stuck_events, doors) and np.array_equal(result.planner_calls, 1 + doors)
    assert np.array_equal(result.bridge_decisions, 2 * doors) and result.table_misses.sum() == 0
    # min_steps (train.py refuses shorter training horizons) is a lower bound, and not a vacuous one.
    bound = np.array([s.min_steps for s in batch.specs])
    assert (bound <= result.steps).all() and (bound >= 0.3 * result.steps).all()


def test_pure_planning_solves_none(results):
    result = results["none"]
    assert not result.success.any() and (result.steps == 200).all() and (result.stuck_events > 1).all()


def test_skill_initiability():
    at_door = fresh(robot=(1.505, 0.9))
    initiable = jax.jit(ENV.skill_initiable)
    skills = jnp.array([MOVE_TO, MOVE_TO, THROUGH, THROUGH, OPEN])
    slots = jnp.array([BOTTOM_DOOR, LEFT_DOOR, BOTTOM_DOOR, LEFT_DOOR, 0])
    assert np.asarray(initiable(at_door, skills, slots)).tolist() == [True, True, True, False, True]
    in_other_room = fresh(robot=(0.25, 0.25))  # room (1,0): only the left door is one of its doors
    assert np.asarray(initiable(in_other_room, skills, slots)).tolist() == [False, True, False, False, True]


def test_the_env_keeps_the_env_contract():
    from envs_jax import Doorknobs
    from jaxbridge import check_env

    assert check_env(Doorknobs) is Doorknobs  # shapes, dtypes, purity, the planner's model, the oracle on its test tasks
