"""Each baseline and ablation differs from our method exactly by its defining difference
(the authors' code), checked on the rollouts it produces and on the program it compiles to."""
import jaxbridge
from collections import Counter
from dataclasses import replace
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.light_switch_door.env import LightSwitchDoor
from envs_jax.precision import ExactKey
from jaxbridge.core.bridges import PurePlanningBridge, RandomBridge
from jaxbridge.core.episode import observation
from jaxbridge.learn.approaches import (APPROACHES, KNOWN, LOW_LEVEL, MODEL_REPAIR, PLAN_REPAIR, SELECTION, SIGNATURE, BridgeKind,
                                       get_approach)
from jaxbridge.learn.q_bridge import QBridge, encode
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.meta_policy import ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, Controls, MetaPolicy, rollout
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import make_setup
from jaxbridge.core.tasks import evaluation_batch

ROOT = Path(__file__).resolve().parents[1]
TINY = TrainConfig(num_seeds=1, episodes_per_cycle=2, num_test_tasks=2, updates_per_cycle=2, buffer_capacity=512)


@pytest.fixture(scope="module")
def tests_batch():
    return evaluation_batch(LightSwitchDoor, [0, 1, 2], 4)


def random_rollout(batch, controls, seed=0):
    """The random bridge picks CallPlanner whenever it is applicable, so it shows what `controls` allow."""
    keys = jax.random.split(jax.random.key(seed), batch.size)
    result, records = rollout(MetaPolicy(batch.env, RandomBridge(batch.env), None, controls), batch.arrays, keys,
                              batch.max_steps, record=True)
    return jax.tree.map(np.asarray, result), jax.tree.map(np.asarray, records)


def primitives(closed_jaxpr) -> Counter:
    """Every primitive in a traced program, nested jaxprs (jit, scan, cond branches) included."""
    counts = Counter()

    def walk(jaxpr):
        for eqn in jaxpr.eqns:
            counts[eqn.primitive.name] += 1
            for value in eqn.params.values():
                for sub in value if isinstance(value, (list, tuple)) else [value]:
                    if hasattr(sub, "eqns"):
                        walk(sub)
                    elif hasattr(sub, "jaxpr") and hasattr(sub.jaxpr, "eqns"):
                        walk(sub.jaxpr)

    walk(closed_jaxpr.jaxpr)
    return counts


def cycle_program(approach: str, host_planner: bool = True) -> Counter:
    setup = make_setup(replace(TINY, approach=approach))
    cycle = Cycle(setup)
    return primitives(jax.make_jaxpr(lambda learners: cycle.run(learners, host_planner))(setup.init_learners()))


def test_approach_names_are_unique_and_each_resolves_to_itself():
    """A name or label given twice would silently replace an approach (the registries are dicts merged
    into KNOWN) or merge two runs' lines in the figures and tables, which tell approaches apart by label."""
    entries = [(key, a) for group in (APPROACHES, LOW_LEVEL, PLAN_REPAIR, SELECTION, SIGNATURE, MODEL_REPAIR)
               for key, a in group.items()]
    assert len(KNOWN) == len(entries) and all(key == a.name for key, a in entries)
    assert len({a.label for _, a in entries}) == len(entries)
    assert all(get_approach(name) is approach for name, approach in KNOWN.items())
    with pytest.raises(ValueError, match="unknown approach 'clever'; choose from ours, "):
        get_approach("clever")


@pytest.mark.parametrize("name", list(KNOWN))
def test_each_approach_builds_its_bridge_and_a_network_as_wide_as_what_its_bridge_sees(name):
    """The network is sized by `observation_size`, the bridge fed by `observation`: the two must agree for
    every approach's controls, and its bridge is the kind it declares."""
    approach = get_approach(name)
    setup = make_setup(replace(TINY, approach=name))
    env, controls = setup.train_env, setup.controls
    state = env.reset(env.task_arrays(LightSwitchDoor.train_task(0)))
    seen = observation(env, controls, state, state)
    assert seen.shape == (approach.observation_size(env),) == (setup.learner.num_features,)
    assert controls.planner or not controls.call_planner  # CallPlanner hands control to a planner
    assert controls.low_level == approach.low_level == (approach.algorithm in ("ppo", "sac"))
    if approach.low_level:
        return  # brax's policies (tests/test_low_level.py)
    expected = {BridgeKind.Q: QBridge, BridgeKind.RANDOM: RandomBridge, BridgeKind.NONE: PurePlanningBridge}
    assert type(setup.bridge(env)) is expected[approach.bridge]

    def q_of_what_it_sees(key):  # a fresh network's Q of (this observation, the first skill, param 0.5)
        learner = setup.learner
        return learner.net.apply(learner.greedy(learner.init(key)),
                                 encode(env, seen[None], jnp.int32(0), jnp.float32(0.5)))

    q = jax.eval_shape(q_of_what_it_sees, jax.random.key(0))  # traced only: a width mismatch fails here
    assert q.shape[0] == 1 and q.dtype == jnp.float32


def test_the_command_line_and_every_env_name_only_registered_approaches():
    """train.py's --approaches: `all` is the env's (the paper's six, then what its default adds), every
    registered name is accepted alone and all together, a name given twice or unknown is refused; each env's
    default figure names registered ones, the paper's envs only the six."""
    import argparse

    import jaxbridge
    from envs_jax import BUILTIN, KNOBS, VARIANTS, WORLDS, env_class
    from jaxbridge.utils.cli import names_from
    from jaxbridge.api.training import all_approaches, default_approaches
    assert list(jaxbridge.ALL_APPROACHES) == list(KNOWN)
    approach_list = names_from(jaxbridge.ALL_APPROACHES, "approach")  # train.py --approaches' type
    assert approach_list("all") == "all" and len(APPROACHES) == 6 and "ours" in APPROACHES
    assert all(approach_list(name) == [name] for name in KNOWN)
    assert approach_list(" , ".join(KNOWN)) == list(KNOWN)
    for text, message in (("ours,ours", "listed twice"), ("ours,clever", "unknown approach clever")):
        with pytest.raises(argparse.ArgumentTypeError, match=message):
            approach_list(text)
    for env in BUILTIN + VARIANTS + KNOBS + WORLDS:
        defaults, every = default_approaches(env_class(env)), all_approaches(env_class(env))
        assert set(defaults) <= set(every) <= set(KNOWN) and every[:6] == list(APPROACHES), env
        assert every == list(APPROACHES) or env in WORLDS, env
    assert all_approaches(env_class("multi_novelty"))[6:] == ["ours_learned_selection", *SIGNATURE]


def test_no_callplanner_never_hands_control_back(tests_batch):
    result, records = random_rollout(tests_batch, get_approach("no_callplanner").controls)
    live_decisions = records.decided & records.live
    assert live_decisions.any()
    assert not (records.actor == ACTOR_CALL_PLANNER).any()
    assert (records.num_ground[..., -1][live_decisions] == 0).all()  # CallPlanner never offered
    assert (result.planner_calls == 1).all() and (result.stuck_events <= 1).all()
    # After the first stuck state the planner never acts again.
    first_bridge = np.argmax(records.actor == ACTOR_BRIDGE, axis=0)
    for episode in np.nonzero((records.actor == ACTOR_BRIDGE).any(0))[0]:
        after = records.actor[first_bridge[episode]:, episode][records.live[first_bridge[episode]:, episode]]
        assert (after == ACTOR_BRIDGE).all()
    # The same bridge under our method's controls does hand back, so the check above can fail.
    _, ours = random_rollout(tests_batch, Controls())
    assert (ours.actor == ACTOR_CALL_PLANNER).any()


def test_maple_q_never_plans(tests_batch):
    result, records = random_rollout(tests_batch, get_approach("maple_q").controls)
    live = records.live
    assert not np.isin(records.actor[live], [ACTOR_PLANNER, ACTOR_CALL_PLANNER]).any()
    assert (records.decided & live)[0].all()  # the bridge acts from the very first step
    assert (result.planner_calls == 0).all() and (result.table_misses == 0).all()
    assert records.features.shape[-1] == LightSwitchDoor.full_state_size
    # The host planner is not even part of Maple Q's program; it is part of ours.
    assert cycle_program("maple_q")["pure_callback"] == 0
    assert cycle_program("ours")["pure_callback"] > 0
    assert cycle_program("ours", host_planner=False)["pure_callback"] == 0  # the program the cache keeps


@pytest.mark.parametrize("approach", ["pure_planning", "random"])
def test_non_learning_approaches_never_evaluate_a_q_network(approach):
    # The only matrix products in a cycle are the Q-network's (the envs' dynamics have none).
    assert cycle_program(approach)["dot_general"] == 0
    assert cycle_program("ours")["dot_general"] > 0


def test_pure_planning_replans_whenever_stuck_and_solves_nothing(tests_batch):
    from jaxbridge.core.bridges import PurePlanningBridge
    keys = jax.random.split(jax.random.key(0), tests_batch.size)
    result, records = rollout(MetaPolicy(tests_batch.env, PurePlanningBridge(tests_batch.env)), tests_batch.arrays,
                              keys, tests_batch.max_steps, record=True)
    result, records = jax.tree.map(np.asarray, (result, records))
    assert not result.success.any()
    decided = records.decided & records.live
    assert (records.skill[decided] == tests_batch.env.num_skills).all()  # every decision is a re-plan
    assert (result.planner_calls == 1 + result.bridge_decisions).all() and (result.planner_calls > 2).all()


def test_no_feature_selection_sees_the_padded_full_state(tests_batch):
    approach = get_approach("no_feature_selection")
    setup = make_setup(replace(TINY, approach=approach.name))
    kernel = setup.init_learners().params["params"]["UniformDense_0"]["kernel"]
    env = setup.test_env
    assert kernel.shape[1] == LightSwitchDoor.full_state_size + env.num_skills + 1 + 1  # [seeds, inputs, 32]
    ours = make_setup(TINY).init_learners().params["params"]["UniformDense_0"]["kernel"]
    assert ours.shape[1] == LightSwitchDoor.num_features + env.num_skills + 1 + 1

    # The full state is the same size for the 5-cell training env and the 20-cell test env, and it
    # carries what the object-centric features leave out (robot position, light, every door).
    train_env = setup.train.env
    assert train_env.max_cells < env.max_cells
    task = jax.tree.map(lambda x: x[0], tests_batch.tasks)
    state = tests_batch.env.reset(task)
    full = tests_batch.env.full_state(state)
    assert full.shape == (LightSwitchDoor.full_state_size,)
    keys = ExactKey.of(state.keys.to_float32().at[1, 0].set(0.4))  # door 1's move key
    moved = tests_batch.env.full_state(state.replace(robot_x=jnp.float32(3.5), keys=keys))
    changed = np.nonzero(np.asarray(moved != full))[0]
    first_door = 1 + 3 + LightSwitchDoor.max_task_cells
    assert changed.tolist() == [0, first_door + 5 + 1]  # robot x; door 1's move key
    with pytest.raises(ValueError, match="at most 20 cells"):
        LightSwitchDoor(max_cells=25).full_state(LightSwitchDoor(max_cells=25).reset(
            LightSwitchDoor(max_cells=25).task_arrays(LightSwitchDoor.test_tasks(0, 1)[0])))


def test_approaches_of_one_experiment_share_its_tasks_and_other_seeds_get_their_own():
    ours, ablation = make_setup(TINY), make_setup(replace(TINY, approach="maple_q"))
    assert ours.train is ablation.train and ours.test is ablation.test  # built once, not per approach
    other = make_setup(replace(TINY, first_seed=1))
    assert other.test is not ours.test and other.test.seeds.tolist() == [1, 1]
    assert ours.test.seeds.tolist() == [0, 0]


def test_random_and_pure_planning_leave_the_network_untouched():
    for name in ("random", "pure_planning"):
        setup = make_setup(replace(TINY, approach=name))
        learners = setup.init_learners()
        after, metrics = Cycle(setup)(learners)
        assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(learners.params),
                                                        jax.tree.leaves(after.params)))
        assert float(metrics.loss[0]) == 0.0 and int(metrics.buffer_size[0]) == 0


def test_env_defaults_sit_between_the_paper_defaults_and_explicit_overrides():
    assert jaxbridge.make_config("light_switch_door") == TrainConfig()
    doorknobs = jaxbridge.make_config("doorknobs")
    assert doorknobs.env == "doorknobs" and doorknobs.call_planner_bonus == 0.5
    assert jaxbridge.make_config("doorknobs", call_planner_bonus=0.0).call_planner_bonus == 0.0
    coffee = jaxbridge.make_config("coffee")
    assert coffee.learner.updates_per_cycle == 250 and coffee.call_planner_bonus == 0.0
    assert jaxbridge.make_config("coffee", updates_per_cycle=1000).learner.updates_per_cycle == 1000
    with pytest.raises(ValueError, match="unknown env"):
        jaxbridge.make_config("nowhere")


@pytest.mark.parametrize("env,message", [
    ("doorknobs", "holds maps up to 5x5; this env's maps are 7x7"),
    ("coffee", "holds at most 4 cups; this env has 6"),
])
def test_a_full_state_too_small_for_the_env_is_refused(env, message):
    """The full-state ablations' input is sized to the test tasks; a larger env must not be cut to fit
    (Doorknobs once dropped a 7x7 map's extra objects without a word)."""
    from envs_jax import env_class
    big = env_class(env)(map_size=7) if env == "doorknobs" else env_class(env)(max_cups=6)
    assert not big.full_state_fits
    with pytest.raises(ValueError, match=message):
        big.full_state(None)  # refused before the state is read
