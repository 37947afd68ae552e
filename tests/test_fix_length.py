"""Light Switch Sequence, the fix-length knob: the lock's rules, k as a class attribute that train.py,
eval.py and the sweep reach, the oracle fixing every length in k + 1 decisions while pure planning fixes
none, a random bridge's chance falling with k, and features that tell the steps of a fix apart."""
import pickle

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from oracle_vs_planning import oracle_and_pure_planning

from envs_jax import env_class, is_builtin
from envs_jax.base import BridgeObs, SkillCall
from envs_jax.light_switch_door import sequence as lss
from envs_jax.light_switch_door.sequence import LightSwitchSequence, LightSwitchSequenceTask, dial_target
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import make_batch
from jaxbridge.run.sweep import sweep_tasks

LENGTHS = (1, 2, 4, 8, 12)
SEEDS = (0, 1, 2)  # development seeds
ENV = LightSwitchSequence(max_cells=8, max_dials=4)
TASK = LightSwitchSequenceTask(num_cells=6, door_cell=2, dials=4)
SET_DIAL = ENV.skill_index("SetDial")


def fresh(x=2.5, dials_set=0, task=TASK):
    return ENV.reset(ENV.task_arrays(task)).replace(robot_x=jnp.float32(x), dials_set=jnp.int32(dials_set))


def act(state, dx=0.0, dlight=0.0, dial=0.0, press=0.0):
    return jax.jit(ENV.step)(state, jnp.array([dx, dlight, dial, press], jnp.float32))


def enter(state, value):
    return act(state, dial=value, press=1.0)


# ---- the lock's rules ------------------------------------------------------------------------------------
def test_a_right_value_sets_the_next_dial_and_a_wrong_one_starts_the_lock_again():
    targets = dial_target(np.arange(4))
    state = fresh()
    for i in range(3):
        state = enter(state, targets[i] + (0.05 if i % 2 else -0.05))  # inside the +-0.1 window
        assert int(state.dials_set) == i + 1
    wrong = enter(state, targets[3] + 0.15)
    assert int(wrong.dials_set) == 0 and float(wrong.dialled) == pytest.approx(targets[3] + 0.15)
    assert int(enter(fresh(), targets[0] - 0.15).dials_set) == 0
    assert int(enter(fresh(), targets[1]).dials_set) == 0  # the right value for another dial is wrong here


def test_only_a_press_at_the_lock_enters_a_value_and_an_open_lock_stays_open():
    target = dial_target(0)
    assert int(act(fresh(), dial=target, press=0.4).dials_set) == 0  # no press: the planner's actions
    assert int(enter(fresh(x=3.5), target).dials_set) == 0  # not at the lock
    assert float(enter(fresh(x=3.5), target).dialled) == 0.0
    opened = fresh(dials_set=4)
    assert bool(ENV.door_open(opened)[0]) and not bool(ENV.door_open(fresh(dials_set=3))[0])
    after = enter(opened, 0.0)
    assert int(after.dials_set) == 4 and float(after.dialled) == 0.0


def test_the_closed_door_blocks_only_leaving_its_cell_to_the_right():
    assert float(act(fresh(), dx=1.0).robot_x) == 2.5
    assert float(act(fresh(), dx=-1.0).robot_x) == 1.5
    assert float(act(fresh(x=1.5), dx=1.0).robot_x) == 2.5
    assert float(act(fresh(dials_set=4), dx=1.0).robot_x) == 3.5
    # The step that sets the last dial reads the closed door: it does not also move.
    last = act(fresh(dials_set=3), dx=1.0, dial=dial_target(3), press=1.0)
    assert float(last.robot_x) == 2.5 and bool(ENV.door_open(last)[0])


def test_min_steps_is_reached_and_the_horizon_grows_with_k():
    state, steps = fresh(x=0.5), 0
    for cell in range(TASK.num_cells - 1):
        if cell == TASK.door_cell:
            for i in range(TASK.dials):
                state, steps = enter(state, dial_target(i)), steps + 1
        state, steps = act(state, dx=1.0), steps + 1
    state, steps = act(state, dlight=0.75), steps + 1
    assert bool(ENV.goal_reached(state)) and steps == TASK.min_steps == 5 + 1 + 4
    horizons = [LightSwitchSequenceTask(20, 3, k).horizon for k in (1, 8, 16)]
    assert horizons == [max(30, 20 + k + 2 + 5) for k in (1, 8, 16)] and horizons[0] < horizons[1] < horizons[2]


# ---- what the bridge sees and chooses ------------------------------------------------------------------
def test_the_features_tell_the_steps_of_the_fix_apart():
    state, seen = fresh(), []
    for i in range(TASK.dials):
        seen.append(np.asarray(ENV.features(state, state)))
        np.testing.assert_array_equal(seen[-1], np.float32([1.0, i / TASK.dials, dial_target(i)]))
        state = enter(state, dial_target(i))
    seen.append(np.asarray(ENV.features(state, state)))
    assert seen[-1].tolist() == [1.0, 1.0, 0.0]  # open: nothing left to set
    assert len({tuple(f) for f in seen}) == TASK.dials + 1  # every step of the fix looks different
    wrong = enter(fresh(dials_set=2), 0.0 if dial_target(2) > 0.2 else 1.0)
    np.testing.assert_array_equal(ENV.features(wrong, wrong), seen[0])  # a miss looks like the start again
    assert not np.asarray(ENV.features(fresh(x=3.5), state)).any()  # away from the lock: nothing


def test_setdial_has_one_grounding_so_each_decision_is_the_bridges_own():
    """In any cell exactly one SetDial is applicable (the robot's cell): the meta-policy's uniform
    grounding draws nothing, and the bridge's skill and parameter are the whole choice."""
    from jaxbridge.core.meta_policy import applicable_ops, count_by_skill
    from planner.tables import compile_task, pack_atoms
    table = compile_task(ENV, TASK).table
    for x in (0.5, 2.5, 5.5):
        state = fresh(x=x)
        ops = applicable_ops(ENV, table, pack_atoms(ENV.abstract(state)), state)
        assert int(count_by_skill(ENV, table, ops)[SET_DIAL]) == 1


@pytest.mark.parametrize("x", [2.5, 4.5])
def test_the_object_view_holds_the_door_the_features_select(x):
    state = fresh(x, dials_set=1)
    objects = jax.tree.map(np.asarray, ENV.objects(state))
    door = 2 + ENV.max_cells
    assert list(np.flatnonzero(objects.interactable)) == list(ENV.candidate_slots) == [1, door]
    assert int(ENV.oracle_object(state)) == (door if x == 2.5 else -1)
    at_lock = state.replace(robot_x=jnp.float32(2.5))  # the door's features are the lock's, wherever the robot is
    np.testing.assert_array_equal(objects.features[door], np.asarray(ENV.features(at_lock, state))[1:])


def test_at_k_1_the_fix_is_the_oracles_one_setdial():
    """At the stuck state of a one-dial task the oracle chooses SetDial with the dial's target, and that
    one skill opens the door; then it calls the planner."""
    task = LightSwitchSequenceTask(num_cells=6, door_cell=2, dials=1)
    state = fresh(task=task)
    observe = lambda s: BridgeObs(features=ENV.features(s, state), num_ground=jnp.ones(ENV.num_skills + 1, jnp.int32))
    choice = ENV.oracle_bridge(None, observe(state), None)
    assert int(choice.skill) == SET_DIAL and float(choice.param) == dial_target(0)
    call = SkillCall(choice.skill, jnp.int32(2), choice.param, jnp.bool_(True), jnp.int32(0))
    opened = ENV.step(state, ENV.skill_action(state, call))
    assert bool(ENV.door_open(opened)[0])
    after = ENV.oracle_bridge(None, observe(opened), None)
    assert int(after.skill) == ENV.num_skills  # CallPlanner


# ---- k: the class attribute, and how the tools reach it --------------------------------------------------
def test_k_is_a_class_attribute_that_the_command_line_names():
    from jaxbridge.api.envs import env_name
    k8 = env_class("envs_jax.light_switch_door.sequence:LightSwitchSequence_k8")
    assert k8 is LightSwitchSequence.of_length(8) and k8.fix_length == 8 and k8.name == "light_switch_sequence_k8"
    assert env_name(k8) == "envs_jax.light_switch_door.sequence:LightSwitchSequence_k8"  # what config.json records
    assert LightSwitchSequence.of_length(lss.DEFAULT_LENGTH) is LightSwitchSequence is env_class("light_switch_sequence")
    assert is_builtin("light_switch_sequence") and env_name(LightSwitchSequence) == "light_switch_sequence"
    assert k8.train_task(3).dials == 8 and {t.dials for t in k8.test_tasks(3)} == {8}
    # The draws do not depend on k: the same rows and doors, a longer lock.
    assert [(t.num_cells, t.door_cell) for t in k8.test_tasks(3)] \
        == [(t.num_cells, t.door_cell) for t in LightSwitchSequence.test_tasks(3)]
    assert k8.train_task(3).door_cell == LightSwitchSequence.train_task(3).door_cell
    instance = k8.for_tasks(k8.test_tasks(0))
    assert isinstance(instance, k8) and pickle.loads(pickle.dumps(instance)) == instance
    assert instance != LightSwitchSequence(**{f: getattr(instance, f) for f in ("max_cells", "max_doors", "max_dials")})
    for bad in (0, -1, 2.0, True):
        with pytest.raises(ValueError):
            LightSwitchSequence.of_length(bad)
    for missing in ("LightSwitchSequence_k0", "LightSwitchSequence_k08", "LightSwitchSequence_kx", "Other"):
        with pytest.raises(AttributeError):
            getattr(lss, missing)


def test_sized_tasks_and_the_sweep_count_dials():
    rng = np.random.default_rng(0)
    assert LightSwitchSequence.sized_task(rng, cells=12, dials=5).dials == 5
    assert LightSwitchSequence.of_length(7).sized_task(rng, cells=12).dials == 7  # default: the env's k
    assert 10 <= LightSwitchSequence.sized_task(rng, dials=3).num_cells <= 20
    for cells, dials in ((1, 1), (5, 0)):
        with pytest.raises(ValueError):
            LightSwitchSequence.sized_task(rng, cells=cells, dials=dials)
    specs, counts = sweep_tasks(LightSwitchSequence, 2, sweep_seed=3)
    assert [s.dials for s in specs] == counts.tolist() == [k for k in range(1, 17) for _ in range(2)]


def test_the_env_keeps_the_env_contract():
    from jaxbridge import check_env
    assert check_env(LightSwitchSequence) is LightSwitchSequence  # its oracle solves its test tasks too


# ---- the oracle, pure planning and a random bridge over k -----------------------------------------------
@pytest.fixture(scope="module")
def episodes():
    """Every length's test tasks of the development seeds and the sweep's tasks in one batch: the oracle
    and pure planning in one rollout, a random bridge in another (two compilations for the whole file)."""
    specs, owners = [], []
    for k in LENGTHS:
        for seed in SEEDS:
            tasks = LightSwitchSequence.of_length(k).test_tasks(seed)
            specs, owners = specs + tasks, owners + [seed] * len(tasks)
    sweep, _ = sweep_tasks(LightSwitchSequence, 2, sweep_seed=3)
    batch = make_batch(LightSwitchSequence, specs + sweep, owners + [0] * len(sweep))
    result = oracle_and_pure_planning(batch)
    random, _ = rollout(MetaPolicy(batch.env, make_bridge("random", batch.env)), batch.arrays,
                        jax.random.split(jax.random.key(1), batch.size), batch.max_steps)
    result["random"] = jax.tree.map(np.asarray, random)
    result["dials"] = np.array([s.dials for s in batch.specs])
    result["h"] = np.array([s.shortest_solution for s in batch.specs])
    result["sweep"] = np.arange(batch.size) >= len(specs)
    return result


@pytest.mark.parametrize("k", LENGTHS)
def test_the_oracle_fixes_every_length_in_k_plus_one_decisions_and_pure_planning_none(episodes, k):
    mine = (episodes["dials"] == k) & ~episodes["sweep"]
    oracle, none = episodes["oracle"], episodes["none"]
    assert mine.sum() == 10 * len(SEEDS)
    assert oracle.success[mine].all() and (oracle.steps[mine] == episodes["h"][mine]).all()
    assert (oracle.bridge_decisions[mine] == k + 1).all() and (oracle.stuck_events[mine] == 1).all()
    assert not none.success[mine].any()


def test_the_oracle_solves_the_sweep_and_pure_planning_none_of_it(episodes):
    sweep = episodes["sweep"]
    assert set(episodes["dials"][sweep]) == set(range(1, 17))
    assert episodes["oracle"].success[sweep].all() and not episodes["none"].success[sweep].any()


def test_a_random_bridge_solves_short_fixes_and_no_long_ones(episodes):
    """A random SetDial is right with chance 0.2 (the window's share of [0, 1]); the other skills neither set
    nor reset the lock; a miss starts it again. So k right entries in a row have chance 0.2^k: on
    these tasks about half the one-dial tasks are solved, one or none of the four-dial ones, none from
    eight on (0.2^8 = 3e-6 per run of entries). The bounds are loose: k = 1 at 50% falls below 25% of
    30 tasks with chance 0.3%; k = 4 at about 1% exceeds 10% with less."""
    tests, solved = ~episodes["sweep"], episodes["random"].success
    rate = {k: solved[tests & (episodes["dials"] == k)].mean() for k in LENGTHS}
    assert rate[1] >= 0.25 and rate[4] <= 0.1
    assert rate[8] == rate[12] == 0.0


# ---- bench.studies.fix_length's figures --------------------------------------------------------------------------

def test_the_bench_finds_the_first_cycle_at_0_9_and_the_longest_k_solved_with_every_shorter_one():
    from bench.studies.fix_length import first_cycle, longest_solved, summary

    solve = np.array([[0.0, 0.8, 1.0, 1.0], [0.0, 1.0, 0.9, 1.0]])  # the mean reaches 0.9 at cycle 2
    assert int(first_cycle(solve)) == 2 and int(first_cycle(solve[:, :1])) == 2  # never: one past the run
    row = summary(solve)
    assert (row["final"], row["final_ci"], row["first"]) == (1.0, [1.0, 1.0], 2) and row["first_ci"][0] == 2
    rows = {k: {"final": final} for k, final in [(1, 1.0), (2, 0.95), (4, 0.5), (6, 0.95)]}
    assert longest_solved(rows) == 2 and longest_solved({1: {"final": 0.2}}) is None


@pytest.mark.parametrize("argv", [["--seeds", "300-331", "--gamma-lengths", "0", "--paper-envs", "none"],
                                  ["--seeds", "0-3", "--lengths", "1,2", "--gamma-lengths", "2", "--bonus", "0.2"]])
def test_the_command_a_record_shows_parses_back_to_the_same_run(argv):
    import shlex

    from bench.studies.fix_length import STUDY

    args = STUDY.parse(argv)
    shown = shlex.split(args.command)[3:]  # past "python -m bench.studies.fix_length"
    assert vars(STUDY.parse(shown)) == vars(args)
    assert STUDY.stem(args) == ("fix_length-300-331" if args.seed_list[0] == 300 else "fix_length")
