"""Light Switch Door: every dynamics rule of envs.md §2.3, the predicates, task generation, jit/vmap."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.light_switch_door import env as lsd
from envs_jax.light_switch_door.env import LightSwitchDoor, LightSwitchDoorTask
from envs_jax.precision import ExactKey

ENV = LightSwitchDoor(max_cells=12, max_doors=3)
TASK = LightSwitchDoorTask(num_cells=10, door_cells=(2, 5))  # robot starts in cell 0


def fresh(x=0.5, move=(0.0, 0.0), turn=(0.0, 0.0)):
    state = ENV.reset(ENV.task_arrays(TASK))
    door_keys = np.array([[move[0], turn[0]], [move[1], turn[1]], [0.0, 0.0]], np.float32)  # [D, (move, turn)]
    return state.replace(robot_x=jnp.float32(x), keys=ExactKey.of(door_keys))


def keys(state):
    """The float32 move keys and turn keys (each [D]) the observations show."""
    return tuple(np.asarray(state.keys.to_float32()).T)


def act(state, dx=0.0, dlight=0.0, dmove=0.0, dturn=0.0):
    return jax.jit(ENV.step)(state, jnp.array([dx, dlight, dmove, dturn], jnp.float32))


def test_min_steps_is_reached_by_setting_both_keys_in_one_step():
    """train.py refuses training horizons below a task's min_steps; the bound is tight."""
    spec = LightSwitchDoorTask(6, (0, 3))
    state, steps = ENV.reset(ENV.task_arrays(spec)), 0
    for cell in range(spec.num_cells - 1):
        if cell in spec.door_cells:
            state, steps = act(state, dmove=lsd.MOVE_TARGET, dturn=lsd.TURN_TARGET), steps + 1
        state, steps = act(state, dx=1.0), steps + 1
    state, steps = act(state, dlight=lsd.LIGHT_SWITCH_VALUE), steps + 1
    assert ENV.goal_reached(state) and steps == spec.min_steps == 5 + 1 + 2


def test_closed_door_blocks_only_leaving_its_cell_to_the_right():
    assert float(act(fresh(x=2.5), dx=1.0).robot_x) == 2.5  # blocked in the door cell
    assert float(act(fresh(x=2.5), dx=-1.0).robot_x) == 1.5  # left is always allowed
    assert float(act(fresh(x=1.5), dx=1.0).robot_x) == 2.5  # entering a door cell is allowed
    assert float(act(fresh(x=3.5), dx=1.0).robot_x) == 4.5  # other cells are free
    open_first = fresh(x=2.5, move=(0.5, 0.0), turn=(0.75, 0.0))
    assert float(act(open_first, dx=1.0).robot_x) == 3.5  # an open door lets the robot through


def test_opening_step_does_not_also_move():
    # The move test reads the pre-step keys: the step that opens the door leaves the robot in place.
    s = act(fresh(x=2.5, move=(0.5, 0.0), turn=(0.0, 0.0)), dx=1.0, dturn=0.75)
    assert float(s.robot_x) == 2.5 and bool(ENV.door_open(s)[0])


def test_keys_accumulate_and_clip_only_in_the_door_cell():
    s = act(act(fresh(x=2.5), dmove=0.3), dmove=0.3)
    assert keys(s)[0][0] == pytest.approx(0.6)
    assert keys(act(fresh(x=2.5, move=(0.8, 0)), dmove=0.7))[0][0] == 1.0
    assert keys(act(fresh(x=2.5, turn=(0.2, 0)), dturn=-0.9))[1][0] == 0.0
    assert keys(act(fresh(x=2.5, turn=(0.2, 0)), dturn=-1e30))[1][0] == 0.0  # the authors' box is unbounded
    assert np.all(np.concatenate(keys(act(fresh(x=3.5), dmove=0.5, dturn=0.5))) == 0)
    assert keys(act(fresh(x=5.5), dmove=0.2))[0][1] == pytest.approx(0.2)  # the second door


def authors_door_open(move_key, turn_key):
    """The authors' test: float64 keys against float64 target +- 0.1, bounds included (elementwise)."""
    move, turn = np.float64(move_key), np.float64(turn_key)
    return ((lsd.MOVE_TARGET - 0.1 <= move) & (move <= lsd.MOVE_TARGET + 0.1)
            & (lsd.TURN_TARGET - 0.1 <= turn) & (turn <= lsd.TURN_TARGET + 0.1))


@pytest.mark.parametrize("move,turn,is_open", [
    (0.5, 0.75, True), (0.4, 0.75, True), (0.5, 0.84, True), (0.0, 0.0, False), (0.39, 0.75, False),
    (0.6, 0.75, False),  # float32(0.6) = 0.60000002 > 0.6
    (0.5, 0.85, False),  # float32(0.85) = 0.85000002 > 0.85
    (0.5, 0.65, False)])  # float32(0.65) = 0.64999998 < 0.65
def test_door_opens_as_the_authors_float64_test_at_the_bounds(move, turn, is_open):
    move32, turn32 = np.float32(move), np.float32(turn)
    assert authors_door_open(move32, turn32) == is_open  # the cases above are the authors' verdicts
    assert bool(ENV.door_open(fresh(move=(move32, 0), turn=(turn32, 0)))[0]) == is_open


def test_every_float32_key_next_to_a_bound_gets_the_authors_verdict():
    for bound in (0.4, 0.6):
        for key in bounds_neighbourhood(bound):
            assert bool(ENV.door_open(fresh(move=(key, 0), turn=(0.75, 0)))[0]) == authors_door_open(key, 0.75)
    for bound in (0.65, 0.85):
        for key in bounds_neighbourhood(bound):
            assert bool(ENV.door_open(fresh(move=(0.5, 0), turn=(key, 0)))[0]) == authors_door_open(0.5, key)


def bounds_neighbourhood(bound: float, ulps: int = 3) -> list[np.float32]:
    """The float32 values within a few ulps of float32(bound)."""
    keys = [np.float32(bound)]
    for _ in range(ulps):
        keys = [np.nextafter(keys[0], np.float32(-1))] + keys + [np.nextafter(keys[-1], np.float32(2))]
    return keys


TARGETS = {"move": lsd.MOVE_TARGET, "turn": lsd.TURN_TARGET}
STEPS = 7  # per action sequence


def sums_next_to(end: float, rng: np.random.Generator) -> list[list[np.float32]]:
    """float32 actions for one key whose float64 sum ends next to a window end: decimals that sum to it
    (0.25 + 0.4 - 0.05 = 0.6), random steps then one landing on the end or one float32 ulp either side of
    it, and the float32 neighbours of the end, as one action and as two."""
    end32 = np.float32(end)
    aims = [end, end32, np.nextafter(end32, np.float32(-1)), np.nextafter(end32, np.float32(2))]
    sequences = []
    for _ in range(40):
        decimals = rng.integers(-40, 80, int(rng.integers(1, STEPS - 2))) / 100
        sequences.append([*np.float32(decimals), np.float32(round(end - decimals.sum(), 2))])
        steps = np.float32(rng.uniform(-0.6, 1.0, int(rng.integers(1, STEPS - 2))))
        key = 0.0
        for step in steps:
            key = np.clip(key + np.float64(step), 0.0, 1.0)  # the authors' float64 key
        sequences += [[*steps, np.float32(aim - key)] for aim in aims]
    for value in bounds_neighbourhood(end):
        sequences.append([value])
        sequences += [[x, np.float32(np.float64(value) - x)] for x in np.float32(rng.uniform(0.0, 1.0, 5))]
    return sequences


def edge_actions(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(dmove, dturn) float32[sequences, STEPS]: one key's sums next to each of its window's ends; the
    other key is set to its target before them (the door opens as soon as the sum enters the window) or
    after them (the last sum decides)."""
    dmove, dturn = [], []
    for key, other, ends in (("move", "turn", (0.4, 0.6)), ("turn", "move", (0.65, 0.85))):
        for i, terms in enumerate(t for end in ends for t in sums_next_to(end, rng)):
            sequence = {key: np.zeros(STEPS, np.float32), other: np.zeros(STEPS, np.float32)}
            other_first = i % 2 == 0
            sequence[key][int(other_first): int(other_first) + len(terms)] = terms
            sequence[other][0 if other_first else -1] = TARGETS[other]
            dmove.append(sequence["move"]), dturn.append(sequence["turn"])
    return np.array(dmove), np.array(dturn)


def authors_doors(dmove, dturn, here) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The authors' float64 keys and open doors [sequences, STEPS, doors] after every step: a closed door
    in the robot's cell adds the float32 actions to its keys and clips them to [0, 1]."""
    move, turn = np.zeros(here.shape), np.zeros(here.shape)
    moves, turns, opens = [], [], []
    for t in range(dmove.shape[1]):
        closed_here = here & ~authors_door_open(move, turn)
        move = np.where(closed_here, np.clip(move + np.float64(dmove[:, t, None]), 0.0, 1.0), move)
        turn = np.where(closed_here, np.clip(turn + np.float64(dturn[:, t, None]), 0.0, 1.0), turn)
        moves.append(move), turns.append(turn), opens.append(authors_door_open(move, turn))
    return np.stack(moves, 1), np.stack(turns, 1), np.stack(opens, 1)


def test_every_door_opens_at_the_step_the_authors_float64_sums_open_it():
    """Keys are sums of float32 actions; the authors sum them in float64. Random walks and sums built to
    straddle every window end, in either door's cell: every door's verdict after every step is theirs,
    and the bridge sees each key as the float32 nearest their float64 key."""
    rng = np.random.default_rng(39)
    edge_move, edge_turn = edge_actions(rng)
    walks = np.float32(rng.uniform(-1.0, 1.0, (2, 1000, STEPS)) * rng.choice([1.0, 0.3], (2, 1000, 1)))
    dmove, dturn = np.concatenate([edge_move, walks[0]]), np.concatenate([edge_turn, walks[1]])
    door_cells = np.array(TASK.door_cells)
    robot_cell = rng.choice(door_cells, len(dmove))
    move64, turn64, authors_open = authors_doors(dmove, dturn, robot_cell[:, None] == door_cells)

    tasks = ENV.stack_tasks([TASK] * len(dmove))
    state = jax.vmap(ENV.reset)(tasks).replace(robot_x=jnp.asarray(robot_cell + 0.5, jnp.float32))
    step, door_open = jax.jit(jax.vmap(ENV.step)), jax.jit(jax.vmap(ENV.door_open))
    features = jax.jit(jax.vmap(lambda s: ENV.features(s, s)))
    here = np.arange(len(dmove)), np.searchsorted(door_cells, robot_cell)  # the door in the robot's cell
    actions = np.stack([np.zeros_like(dmove), np.zeros_like(dmove), dmove, dturn], -1)  # robot and light still
    wrong_verdicts = wrong_keys = 0
    for t in range(STEPS):
        state = step(state, jnp.asarray(actions[:, t]))
        ours = np.asarray(door_open(state))[:, : len(door_cells)]
        wrong_verdicts += int(np.sum(ours != authors_open[:, t]))
        seen = np.asarray(features(state))[:, [1, 3]]
        expected = np.float32(np.stack([move64[:, t][here], turn64[:, t][here]], 1))
        wrong_keys += int(np.sum(seen != expected))
    assert np.any(authors_open[:, -1]) and not np.all(authors_open[:, -1])
    assert (wrong_verdicts, wrong_keys) == (0, 0)


def test_the_bridge_sees_the_float32_nearest_each_exact_key():
    """ExactKey.to_float32 is numpy's float32 of the float64 key: random keys, and ties between two
    float32 neighbours and a 2^-53 either side of one, for keys of every magnitude."""
    rng = np.random.default_rng(0)
    anywhere = rng.integers(0, 2 ** 53, 5000, dtype=np.int64) >> rng.integers(0, 53, 5000)  # in 2^-53 units
    shift = rng.integers(1, 30, 5000)
    ties = (2 * rng.integers(2 ** 23, 2 ** 24, 5000, dtype=np.int64) + 1) << (shift - 1)
    units = np.concatenate([anywhere, ties - 1, ties, ties + 1, [0, 1, 2 ** 31 - 1, 2 ** 31, 2 ** 53]])
    coarse, fine = units >> 29, units & (2 ** 29 - 1)
    key = ExactKey(jnp.asarray(coarse, jnp.int32), jnp.asarray(fine, jnp.int32))
    expected = np.float32(np.float64(units) * 2.0 ** -53)
    assert np.array_equal(np.asarray(jax.jit(ExactKey.to_float32)(key)), expected)


def test_open_doors_stay_open():
    s = act(fresh(x=2.5, move=(0.5, 0), turn=(0.75, 0)), dmove=0.9, dturn=-0.9)
    assert keys(s)[0][0] == 0.5 and keys(s)[1][0] == 0.75 and bool(ENV.door_open(s)[0])


@pytest.mark.parametrize("dlight,on", [(0.75, True), (0.74, False), (0.76, False), (1.0, False), (-0.75, False)])
def test_light_switches_on_only_at_exactly_075_in_its_cell(dlight, on):
    assert bool(ENV.goal_reached(act(fresh(x=9.5), dlight=dlight))) == on
    assert not bool(ENV.goal_reached(act(fresh(x=8.5), dlight=0.75)))  # not in the light's cell


def test_light_cannot_be_switched_off():
    on = act(fresh(x=9.5), dlight=0.75)
    assert bool(ENV.goal_reached(act(on, dlight=0.75))) and bool(ENV.goal_reached(act(on, dlight=-0.75)))


def test_moves_clip_to_the_row():
    assert float(act(fresh(x=0.5), dx=-1.0).robot_x) == 0.0


def test_predicates():
    atoms = np.asarray(ENV.abstract(fresh(x=3.5)))
    assert atoms.shape == (ENV.num_atoms,)
    assert atoms[:12].tolist() == [i == 3 for i in range(12)]  # RobotInCell; padded cells never hold
    assert atoms[ENV.atom_index(("LightOff", "light"))] and not atoms[ENV.atom_index(("LightOn", "light"))]
    lit = np.asarray(ENV.abstract(act(fresh(x=9.5), dlight=0.75)))
    assert lit[ENV.atom_index(("LightOn", "light"))] and not lit[ENV.atom_index(("LightOff", "light"))]
    assert not np.asarray(ENV.abstract(fresh(x=10.5)))[:12].any()  # beyond the row: no cell


def test_features_see_the_door_in_the_robots_cell_only():
    s = fresh(x=2.5, move=(0.3, 0.0), turn=(0.1, 0.0))
    assert np.allclose(ENV.features(s, s), [1.0, 0.3, 0.5, 0.1, 0.75])
    assert np.allclose(ENV.features(fresh(x=3.5), s), 0.0)


def test_skill_actions_follow_their_spec():
    from envs_jax.base import SkillCall
    s = fresh(x=2.5)

    def action(name, slot, param):
        return np.asarray(ENV.skill_action(s, SkillCall(jnp.int32(ENV.skill_index(name)), jnp.int32(slot),
                                                        jnp.float32(param), jnp.bool_(True), jnp.int32(0))))
    assert action("MoveRobot", 3, 0.0).tolist() == [1.0, 0, 0, 0]
    assert action("MoveRobot", 1, 0.0).tolist() == [-1.0, 0, 0, 0]
    assert action("TurnOnLight", 2, 0.75).tolist() == [0, 0.75, 0, 0]
    assert np.allclose(action("MoveKey", 2, 0.4), [0, 0, 0.4, 0])
    assert np.allclose(action("TurnKey", 2, -0.2), [0, 0, 0, -0.2])


@pytest.mark.parametrize("seed", range(50))
def test_task_generation_ranges(seed):
    train = lsd.train_task(seed)
    assert train.num_cells == 5 and len(train.door_cells) == 1 and train.door_cells[0] in (0, 1, 2)
    tests = lsd.test_tasks(seed)
    assert len(tests) == 10
    assert len({(t.num_cells, len(t.door_cells)) for t in tests}) == 1  # N and K drawn once per seed
    for t in tests:
        assert 10 <= t.num_cells <= 20 and 2 <= len(t.door_cells) <= 4
        assert len(set(t.door_cells)) == len(t.door_cells) and all(0 <= c <= 8 for c in t.door_cells)
        assert t.horizon == max(30, (t.num_cells - 1) + 1 + 4 * len(t.door_cells) + 5)


def test_test_sizes_replay_the_authors_rng():
    # envs.md §2.2 lists (N, K, h) per seed, computed by replaying the authors' test RNG.
    expected = {0: (11, 3, 23), 1: (14, 4, 30), 2: (20, 3, 32), 3: (13, 4, 29), 4: (14, 4, 30),
                5: (13, 2, 21), 6: (13, 2, 21), 7: (11, 4, 27)}
    for seed, (n, k, h) in expected.items():
        t = lsd.test_tasks(seed)[0]
        assert (t.num_cells, len(t.door_cells), t.shortest_solution) == (n, k, h)


def test_reset_and_step_jit_and_vmap_over_seeds_and_tasks():
    specs = [t for seed in range(8) for t in lsd.test_tasks(seed)]
    env = LightSwitchDoor.for_tasks(specs)
    tasks = env.stack_tasks(specs)
    states = jax.jit(jax.vmap(env.reset))(tasks)
    assert states.robot_x.shape == (80,) and states.keys.coarse.shape == (80, env.max_doors, 2)
    actions = jnp.tile(jnp.array([1.0, 0.0, 0.2, 0.0], jnp.float32), (80, 1))
    batched = jax.jit(jax.vmap(env.step))(states, actions)
    for i in (0, 37, 79):
        one = env.step(jax.tree.map(lambda x: x[i], states), actions[i])
        assert float(one.robot_x) == float(batched.robot_x[i])
        assert all(jax.tree.leaves(jax.tree.map(np.array_equal, one.keys, batched.keys[i])))
    # Each task's first door decides whether the robot could leave cell 0.
    blocked = np.array([0 in s.door_cells for s in specs])
    assert np.array_equal(np.asarray(batched.robot_x) == 0.5, blocked)


def test_the_env_keeps_the_env_contract():
    from envs_jax import LightSwitchDoor
    from jaxbridge import check_env

    assert check_env(LightSwitchDoor) is LightSwitchDoor  # shapes, dtypes, purity, the planner's model, the oracle on its test tasks


@pytest.mark.parametrize("x", [2.5, 5.5])
def test_the_object_view_holds_the_door_the_features_select(x):
    """In a door's cell, the interactable object closest to the robot (the paper's selection over the
    object view) is that door, with the features the bridge sees; doors and the light are the candidates."""
    state = fresh(x, move=(0.3, 0.6), turn=(0.1, 0.2))
    objects = jax.tree.map(np.asarray, ENV.objects(state))
    assert ENV.num_objects == 2 + 12 + 3 and objects.mask.sum() == 2 + 10 + 2
    assert list(np.flatnonzero(objects.interactable)) == [1, 14, 15]  # the light, door 0, door 1
    distance = np.where(objects.interactable, np.abs(objects.position[:, 0] - x), np.inf)
    closest = np.argmin(distance)
    assert closest == int(ENV.oracle_object(state))  # the door the oracle's fix acts on
    np.testing.assert_array_equal(objects.features[closest][1:], np.asarray(ENV.features(state, state))[1:])
    assert objects.features[closest][0] == 0.0  # the door is in its keys' cell (offset 0)
