"""Multi Novelty (issue 54): the rules of its three kinds of novelty, each fix's grounding unique by
applicability, the env contract, tasks whose held-out combinations no training task holds, and, through
the meta-policy, that every kind blocks the planner, the oracle fixes each kind alone, the test tasks and
the held-out combinations, a random bridge few, and the closest-object rule picks the wrong object at
the keycard doors; and the study page's answer to the paper's question."""
from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from oracle_vs_planning import oracle_and_pure_planning

from envs_jax import env_class, is_builtin
from envs_jax.multi_novelty.env import FETCH, FUSE, LIFT, PUSH, MultiNovelty
from envs_jax.multi_novelty.tasks import BOTH, KEYCARD, LATCHED, STIFFNESS_RANGE, MultiNoveltyTask, task_of
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.observations import closest_object
from jaxbridge.core.tasks import evaluation_specs, make_batch
from jaxbridge.run.sweep import sweep_tasks

SEEDS = tuple(range(8))  # development seeds
ENV = MultiNovelty(max_cells=10, max_doors=3)
# cells 0..9, the light in 9; a keycard door in 3 (its card in 1), a latched door in 5 (stiffness 0.4),
# a door with both locks in 7 (its card in 6, stiffness 0.6)
TASK = MultiNoveltyTask(10, (3, 5, 7), (KEYCARD, LATCHED, BOTH), (1, -1, 6), (0.0, 0.4, 0.6), True)


def fresh(x=0.5, **fields):
    return ENV.reset(ENV.task_arrays(TASK)).replace(robot_x=jnp.float32(x), **{k: jnp.asarray(v) for k, v in fields.items()})


def act(state, dx=0.0, light=0.0, fuse=0.0, grip=0.0, latch=0.0, push=0.0):
    return jax.jit(ENV.step)(state, jnp.array([dx, light, fuse, grip, latch, push], jnp.float32))


# ---- the rules ---------------------------------------------------------------------------------------------
def test_a_keycard_door_opens_for_the_robot_carrying_its_card():
    assert float(act(fresh(3.5), dx=1.0).robot_x) == 3.5  # closed: blocked
    assert float(act(fresh(3.5), dx=-1.0).robot_x) == 2.5  # a move left never is
    assert float(act(fresh(0.5), dx=5.0).robot_x) == 0.5  # nor can a long move jump it
    assert not bool(act(fresh(2.5), grip=1.0).card_held[0])  # the card lies in cell 1, not here
    picked = act(fresh(1.5), grip=1.0, dx=1.0)  # a grip reads the robot's cell before the step's move
    assert bool(picked.card_held[0]) and float(picked.robot_x) == 2.5
    assert bool(ENV.door_open(picked)[0]) and float(act(picked.replace(robot_x=jnp.float32(3.5)), dx=1.0).robot_x) == 4.5


def test_a_latched_door_needs_a_lift_then_a_push_at_its_stiffness():
    at_door = fresh(5.5, card_held=[True, False, False])
    assert not bool(act(at_door, push=0.4).released[1])  # latch down: a push does nothing
    lifted = act(at_door, latch=1.0)
    assert bool(lifted.latch_up[1]) and not bool(ENV.door_open(lifted)[1])
    for force, opens in ((0.4, True), (0.31, True), (0.49, True), (0.55, False), (0.2, False), (0.0, False)):
        assert bool(ENV.door_open(act(lifted, push=force))[1]) == opens, force
    assert not bool(act(fresh(4.5), latch=1.0).latch_up[1])  # only in the door's cell


def test_a_door_with_both_locks_opens_once_both_are_undone():
    lifted = act(fresh(7.5), latch=1.0)
    pushed = act(lifted, push=0.6)
    assert bool(pushed.released[2]) and not bool(ENV.door_open(pushed)[2])  # the card is still missing
    assert bool(ENV.door_open(pushed.replace(card_held=jnp.array([False, False, True])))[2])


def test_the_light_needs_its_fuse_replaced_first():
    assert not bool(act(fresh(9.5), light=1.0).light_on)
    replaced = act(fresh(9.5), fuse=1.0)
    assert bool(replaced.fuse_ok) and bool(act(replaced, light=1.0).light_on)
    assert not bool(act(fresh(8.5), fuse=1.0).fuse_ok)  # only at the light


def test_min_steps_is_reached_by_gripping_in_passing():
    state, steps = fresh(), 0
    script = {1: [dict(grip=1.0, dx=1.0)], 5: [dict(latch=1.0), dict(push=0.4), dict(dx=1.0)],
              6: [dict(grip=1.0, dx=1.0)], 7: [dict(latch=1.0), dict(push=0.6), dict(dx=1.0)],
              9: [dict(fuse=1.0), dict(light=1.0)]}
    while not bool(ENV.goal_reached(state)):
        for action in script.get(int(state.robot_x), [dict(dx=1.0)]):
            state, steps = act(state, **action), steps + 1
    assert steps == TASK.min_steps == 9 + 1 + 2 * 2 + 1


def test_each_fix_has_one_grounding_by_applicability():
    """FetchKey: only the cards the robot does not hold and can walk to (the card of a door further on
    lies behind a closed door); LiftLatch and PushDoor: only the closed door in the robot's cell;
    ReplaceFuse: only at the light."""
    at = lambda state, skill: [int(j) for j in range(3) if ENV.skill_initiable(state, jnp.int32(skill), jnp.int32(j))]
    assert at(fresh(3.5), FETCH) == [0] and at(fresh(3.5), LIFT) == at(fresh(3.5), PUSH) == [0]
    past_first = fresh(5.5, card_held=[True, False, False])
    assert at(past_first, FETCH) == [] and at(past_first, LIFT) == [1]  # door 2's card lies behind door 1
    past_second = fresh(7.5, card_held=[True, False, False], released=[False, True, False])
    assert at(past_second, FETCH) == [2] and at(past_second, PUSH) == [2]
    assert at(fresh(4.5), LIFT) == []  # no door here
    assert bool(ENV.skill_initiable(fresh(9.5), jnp.int32(FUSE), jnp.int32(0)))
    assert not bool(ENV.skill_initiable(fresh(8.5), jnp.int32(FUSE), jnp.int32(0)))


def test_the_features_and_the_oracle_object_follow_the_fix():
    door, key = lambda j: 2 + ENV.max_cells + j, lambda j: 2 + ENV.max_cells + ENV.max_doors + j
    cases = [(fresh(3.5), [1, 1, 0, 0, 0, 0], key(0)),
             (fresh(5.5, card_held=[True, False, False]), [1, 0, 1, 0, 0.4, 0], door(1)),
             (fresh(5.5, card_held=[True, False, False], latch_up=[False, True, False]), [1, 0, 0, 1, 0.4, 0], door(1)),
             (fresh(7.5), [1, 1, 1, 0, 0.6, 0], key(2)),
             (fresh(9.5), [0, 0, 0, 0, 0, 1], 1),
             (fresh(2.5), [0] * 6, -1)]
    for state, features, slot in cases:
        np.testing.assert_allclose(ENV.features(state, state), np.float32(features))
        assert int(ENV.oracle_object(state)) == slot


# ---- the env and its tasks ---------------------------------------------------------------------------------
def test_the_env_keeps_the_env_contract():
    from jaxbridge import check_env
    assert env_class("multi_novelty") is MultiNovelty and is_builtin("multi_novelty")
    assert check_env(MultiNovelty) is MultiNovelty  # shapes, purity, the planner's model, the oracle on seed 0's test tasks
    # another seed's tasks: shapes and purity (the oracle on every seed's tasks: the tests below)
    assert check_env(MultiNovelty, seed=3, num_test_tasks=3, oracle=False) is MultiNovelty


def test_every_training_task_shows_each_kind_and_no_held_out_combination():
    for seed in range(400):  # development seeds, the test seeds 300-331, and more
        for spec in [MultiNovelty.train_task(seed)] + MultiNovelty.train_tasks(seed, 5):
            assert sorted(spec.locks) == [KEYCARD, LATCHED] and spec.fuse_blown, spec
            assert BOTH not in spec.locks
    for seed in SEEDS:
        held_out = MultiNovelty.test_tasks(seed, 10, protocol="held_out")
        assert all(BOTH in spec.locks and spec.fuse_blown for spec in held_out)
        default = MultiNovelty.test_tasks(seed, 10)
        assert all(BOTH not in spec.locks and spec.instances > 3 for spec in default)
        assert all(spec.instances > MultiNovelty.train_task(seed).instances for spec in default + held_out)


def test_a_seeds_training_tasks_spread_the_latched_doors_stiffness_over_its_range():
    """One layout per seed, the latched door's stiffness in the j-th of n equal parts of the range at
    episode j (to the 0.01 it is rounded to): every part of the range the test doors draw from is shown
    in every cycle, whatever the seed."""
    low, high = STIFFNESS_RANGE
    for seed in range(400):
        alone = MultiNovelty.train_task(seed)
        for n in (1, 5, 8):
            specs = MultiNovelty.train_tasks(seed, n)
            assert len(specs) == n and specs == MultiNovelty.train_tasks(seed, n)
            assert {replace(spec, stiffness=()) for spec in specs} == {replace(alone, stiffness=())}  # one layout
            latched = [spec.stiffness[spec.locks.index(LATCHED)] for spec in specs]
            assert all(stiffness == 0.0 for spec in specs for lock, stiffness in zip(spec.locks, spec.stiffness)
                       if lock == KEYCARD)
            width = (high - low) / n
            assert all(low + j * width - 0.005 <= s <= low + (j + 1) * width + 0.005 for j, s in enumerate(latched)), latched
        assert low <= alone.stiffness[alone.locks.index(LATCHED)] <= high
    # so each test door's stiffness has one of its seed's training pushes within a part's width (0.12 for
    # 5 episodes) and the rounding, whatever the draws; one stiffness a seed would leave most far off
    for seed in SEEDS:
        shown = np.array([max(spec.stiffness) for spec in MultiNovelty.train_tasks(seed, 5)])
        tested = np.array([s for protocol in ("jaxbridge", "held_out")
                           for spec in MultiNovelty.test_tasks(seed, 10, protocol=protocol) for s in spec.stiffness if s])
        assert np.abs(shown[:, None] - tested[None]).min(0).max() <= 0.12 + 0.01
    one = np.array([max(MultiNovelty.train_task(seed).stiffness) for seed in SEEDS])
    assert max(np.abs(s - np.array([t for spec in MultiNovelty.test_tasks(seed, 10) for t in spec.stiffness if t])).max()
               for seed, s in zip(SEEDS, one)) > 0.3


def test_the_training_batch_runs_each_episode_on_its_own_training_task():
    from jaxbridge.core.config import TrainConfig
    from jaxbridge.learn.setup import make_setup, task_batches
    setup = make_setup(TrainConfig(env="multi_novelty", num_seeds=2, first_seed=0, episodes_per_cycle=5, num_test_tasks=2))
    train, _ = task_batches(setup)
    assert train.specs == MultiNovelty.train_tasks(0, 5) + MultiNovelty.train_tasks(1, 5)
    assert train.seeds.tolist() == [0] * 5 + [1] * 5
    stiffness = np.asarray(train.arrays.tasks.stiffness)
    assert all(len({tuple(row) for row in seed.tolist()}) == 5 for seed in stiffness.reshape(2, 5, -1))  # a door per episode


def test_cards_lie_in_their_doors_sections_and_doors_two_cells_apart():
    specs, _ = evaluation_specs(MultiNovelty, list(SEEDS), 10, "held_out")
    for spec in specs + [MultiNovelty.train_task(s) for s in SEEDS]:
        cells = (-1,) + spec.door_cells
        assert all(b - a >= 2 for a, b in zip(cells, cells[1:])) and spec.door_cells[-1] <= spec.num_cells - 2
        for previous, cell, lock, key in zip(cells, cells[1:], spec.locks, spec.key_cells):
            assert (previous < key < cell) if lock & KEYCARD else key == -1


def test_sized_tasks_and_the_sweep_count_instances():
    rng = np.random.default_rng(0)
    assert len(MultiNovelty.sized_task(rng, cells=12, doors=5).door_cells) == 5
    with pytest.raises(ValueError):
        MultiNovelty.sized_task(rng, cells=10, doors=5)  # five doors two apart need 11 cells
    specs, counts = sweep_tasks(MultiNovelty, 2, sweep_seed=3)
    assert [s.instances for s in specs] == counts.tolist() == [k for k in range(1, 13) for _ in range(2)]
    assert max(counts) >= 2 * max(s.instances for s in MultiNovelty.test_tasks(0, 10))


# ---- through the meta-policy --------------------------------------------------------------------------------
ALONE = {"keycard": (KEYCARD,), "latched": (LATCHED,), "both": (BOTH,), "fuse": ()}


def alone_tasks() -> tuple[list, list]:
    """Four tasks per kind holding one instance of it (or a door with both locks), and their kinds."""
    specs, kinds = [], []
    for kind, locks in ALONE.items():
        rng = np.random.default_rng([54, len(kinds)])
        specs += [task_of(rng, int(rng.integers(6, 12)), locks, fuse_blown=kind == "fuse") for _ in range(4)]
        kinds += [kind] * 4
    return specs, kinds


@pytest.fixture(scope="module")
def episodes():
    """The default and held-out test tasks of the development seeds, every kind alone and the sweep's
    tasks in one batch: the oracle and pure planning in one rollout, a random bridge in another."""
    groups = {}
    specs = []
    for name, protocol in (("test", None), ("held_out", "held_out")):
        more, _ = evaluation_specs(MultiNovelty, list(SEEDS), 10, protocol)
        groups[name] = np.arange(len(specs), len(specs) + len(more))
        specs += more
    alone, kinds = alone_tasks()
    groups["alone"] = np.arange(len(specs), len(specs) + len(alone))
    specs += alone
    sweep, _ = sweep_tasks(MultiNovelty, 2, sweep_seed=3)
    groups["sweep"] = np.arange(len(specs), len(specs) + len(sweep))
    specs += sweep
    batch = make_batch(MultiNovelty, specs, [0] * len(specs))
    result = oracle_and_pure_planning(batch)
    random, _ = rollout(MetaPolicy(batch.env, make_bridge("random", batch.env)), batch.arrays,
                        jax.random.split(jax.random.key(1), batch.size), batch.max_steps)
    result["random"] = jax.tree.map(np.asarray, random)
    result.update(groups=groups, kinds=np.array(kinds), h=np.array([s.shortest_solution for s in specs]))
    return result


@pytest.mark.parametrize("kind", ALONE)
def test_each_kind_alone_blocks_the_planner_and_the_oracle_fixes_it(episodes, kind):
    mine = episodes["groups"]["alone"][episodes["kinds"] == kind]
    oracle, none = episodes["oracle"], episodes["none"]
    assert len(mine) == 4 and not none.success[mine].any()
    assert oracle.success[mine].all() and (oracle.steps[mine] == episodes["h"][mine]).all()
    assert (oracle.stuck_events[mine] == {"keycard": 1, "latched": 1, "both": 2, "fuse": 1}[kind]).all()


@pytest.mark.parametrize("group", ["test", "held_out", "sweep"])
def test_the_oracle_solves_the_tasks_pure_planning_none_and_a_random_bridge_few(episodes, group):
    mine = episodes["groups"][group]
    oracle, none, random = episodes["oracle"], episodes["none"], episodes["random"]
    solved = oracle.success[mine]
    print(f"{group}: {len(mine)} tasks solved by the oracle {solved.mean():.3f}, pure planning "
          f"{none.success[mine].mean():.3f}, a random bridge {random.success[mine].mean():.3f}")
    assert solved.mean() >= 0.95 and (oracle.steps[mine][solved] == episodes["h"][mine][solved]).all()
    assert not none.success[mine].any()
    if group != "sweep":
        assert random.success[mine].mean() <= 0.2


def test_the_closest_object_rule_picks_the_door_where_the_fix_fetches_its_card():
    """At every state where the planner got stuck at a closed keycard door whose card the robot lacks,
    the fix acts on the card (`oracle_object`), which lies cells away, while the paper's rule picks the
    closest interactable object: the door itself, in the robot's cell."""
    specs, _ = evaluation_specs(MultiNovelty, list(SEEDS[:4]), 10)
    held_out, _ = evaluation_specs(MultiNovelty, list(SEEDS[:4]), 10, "held_out")
    batch = make_batch(MultiNovelty, specs + held_out, [0] * (len(specs) + len(held_out)))
    env = batch.env
    _, records = rollout(MetaPolicy(env, make_bridge("oracle", env)), batch.arrays,
                         jax.random.split(jax.random.key(2), batch.size), batch.max_steps, record=True)
    states = jax.tree.map(lambda x: x[np.asarray(records.stuck & records.live)], records.env_state)
    features = np.asarray(jax.vmap(lambda s: env.features(s, s))(states))
    at_card_door = features[:, 1] > 0.5  # a closed door here whose card the robot lacks
    chosen, _ = jax.vmap(lambda s: closest_object(env.objects(s)))(states)
    oracle = np.asarray(jax.vmap(env.oracle_object)(states))
    keys = oracle[at_card_door] - (2 + env.max_cells + env.max_doors)
    assert at_card_door.sum() >= 50 and ((keys >= 0) & (keys < env.max_doors)).all()  # the oracle's object is a card
    disagree = (np.asarray(chosen)[at_card_door] != oracle[at_card_door]).mean()
    assert disagree >= 0.25
    print(f"closest-object rule vs oracle_object at keycard stalls: {disagree:.2f} of {at_card_door.sum()}")


def test_an_oracle_episode_draws_with_its_doors_opened_by_the_bridge_and_the_skills_objects_placed():
    from jaxbridge.viz.animate import render_gif
    from jaxbridge.viz.render import render_episode, trace_episodes
    spec = MultiNovelty.test_tasks(0, 10, protocol="held_out")[0]
    batch = make_batch(MultiNovelty, [spec], [0])
    trace = trace_episodes(batch, make_bridge("oracle", batch.env), None, [0], seed=0)[0]
    assert trace.success and trace.opened_by_bridge[: len(spec.door_cells)].all()
    assert render_episode(batch.env, trace, "oracle bridge")[:8] == b"\x89PNG\r\n\x1a\n"
    assert render_gif(batch.env, trace, "oracle bridge", max_frames=8)[:3] == b"GIF"
    drawer, keycard = batch.env.drawer(), spec.locks.index(BOTH)
    assert drawer.object_xy(batch.env, trace, "door", keycard, 5)[0] == spec.door_cells[keycard] + 0.5
    assert drawer.object_xy(batch.env, trace, "key", keycard, 5)[0] == spec.key_cells[keycard] + 0.5
    assert drawer.object_xy(batch.env, trace, "light", 0, 5)[0] == spec.num_cells - 0.5


# ---- the study's page --------------------------------------------------------------------------------------
def test_the_page_answers_whether_one_bridge_suffices_on_each_set():
    """bench.pages.multi_novelty: one bridge meets a bar, only a per-signature bridge does, or none does;
    the kind alone each approach named solves least; an approach whose seeds are spent is judged in nothing."""
    from bench.pages.multi_novelty import answer

    def cells(**by_name):
        return {name: {"test": (t, (t - 0.1, t + 0.05)), "held_out": (h, (h - 0.1, h + 0.05))}
                for name, (t, h) in by_name.items()}
    kinds = [{"approach": name, "kind": kind, "mean": str(mean), "low": "0", "high": "1"}
             for name, means in (("ours", (1.0, 0.7)), ("ours_learned_selection", (0.9, 0.4)), ("ours_per_signature", (0.6, 0.8)))
             for kind, mean in zip(("keycard", "both"), means)]
    text = answer(cells(ours=(0.6, 0.3), ours_learned_selection=(0.94, 0.2), ours_per_signature=(0.5, 0.85)), kinds, set())
    assert text.startswith("On the test tasks, one bridge for every kind suffices: ours, learned selection 0.94")
    assert ("On the held-out combinations, one bridge does not suffice (ours 0.30 [0.20, 0.35]); ours, a bridge per "
            "signature 0.85 [0.75, 0.90] meets the bar of 0.8.") in text
    assert text.endswith("ours, both (0.70); ours, learned selection, both (0.40); ours, a bridge per signature, keycard (0.60).")
    none = answer(cells(ours=(0.6, 0.3), ours_learned_selection=(0.7, 0.2), ours_per_signature=(0.5, 0.1)), kinds, set())
    assert "On the test tasks, no approach reaches the bar of 0.9: the best is ours, learned selection 0.70" in none
    spent = answer(cells(ours=(0.6, 0.3), ours_learned_selection=(0.94, 0.2), ours_per_signature=(0.5, 0.85)), kinds,
                   {"ours_learned_selection"})
    assert spent.startswith("ours, learned selection is not judged here: these seeds are spent for it.")
    assert "On the test tasks, no approach reaches the bar of 0.9: the best is ours 0.60" in spent
    assert "learned selection, both" not in spent  # nor among the kinds each one-bridge approach solves least
