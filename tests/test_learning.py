"""The learner: epsilon schedule, double-DQN targets, replay buffer, transitions, seeding, checkpoints."""

import jaxbridge
from dataclasses import replace

import chex
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax.base import BridgeObs
from envs_jax.light_switch_door import env as lsd
from envs_jax.light_switch_door.env import LightSwitchDoor
from jaxbridge.run import checkpoint
from jaxbridge.utils import compile_cache
from jaxbridge.learn import dqn
from jaxbridge.core.bridges import RandomBridge, make_bridge
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import SeedMesh
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.dqn import init_learner, learn, make_dqn, minibatch_indices, td_targets
from jaxbridge.learn.learner import epsilon
from jaxbridge.core.meta_policy import Controls, MetaPolicy, rollout
from jaxbridge.core.observations import FULL_STATE
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import make_setup
from jaxbridge.utils.smoothing import smooth
from jaxbridge.learn.q_bridge import (SPLIT_FROM_FEATURES, QNetwork, SplitInput, best_candidate, candidate_skills,
                                candidates_input, encode, input_size, sample_candidates, task_state_split)
from jaxbridge.learn.replay import add, init_buffer, sample_indices
from jaxbridge.core.tasks import evaluation_batch, make_batch
from jaxbridge.learn.transitions import Transition, episode_transitions, for_buffer, successor_features

ENV = LightSwitchDoor(5, 1)
TINY = TrainConfig(num_seeds=2, cycles=3, updates_per_cycle=20, num_test_tasks=3, n_sample=10)


def test_epsilon_anneals_linearly_per_decision_to_its_floor():
    cfg = TrainConfig()
    assert float(epsilon(cfg, jnp.int32(0))) == 1.0
    assert float(epsilon(cfg, jnp.int32(10000))) == pytest.approx(1.0 - 0.38)
    assert float(epsilon(cfg, jnp.int32(25000))) == pytest.approx(0.05, abs=1e-6)
    assert float(epsilon(cfg, jnp.int32(10 ** 6))) == pytest.approx(0.05, abs=1e-6)
    values = np.asarray(epsilon(cfg, jnp.arange(0, 30000, 1000)))
    assert np.all(np.diff(values) <= 0)


def test_double_dqn_target_on_a_hand_built_batch():
    cfg = TrainConfig()
    net = QNetwork(cfg.learner.hidden_sizes)
    x0 = jnp.zeros((1, input_size(ENV, ENV.num_features)))
    # Random output layers (the default starts them at 0) so that the two nets disagree.
    def random_net(key):
        params = net.init(key, x0)
        out = params["params"]["UniformDense_2"]
        out = {"kernel": jax.random.normal(key, out["kernel"].shape), "bias": out["bias"]}
        return {"params": {**params["params"], "UniformDense_2": out}}
    online, target = random_net(jax.random.key(1)), random_net(jax.random.key(2))
    move, light, call_planner = ENV.skill_index("MoveRobot"), ENV.skill_index("TurnOnLight"), ENV.num_skills
    features = jnp.array([[1.0, 0.2, 0.5, 0.3, 0.75], [0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.5, 0.5, 0.8, 0.75]])
    # Only constant-parameter skills are applicable next, so the candidates are known exactly.
    ground = jnp.array([[1, 1, 0, 0, 0, 1], [2, 0, 0, 0, 0, 0], [1, 1, 0, 0, 0, 0]], jnp.int32)
    batch = Transition(features=features, skill=jnp.array([3, 0, 5]), param=jnp.array([0.1, 0.0, 0.0]),
                       reward=jnp.array([0.0, 0.0, 1.0]), done=jnp.array([False, False, True]),
                       next_features=features[::-1], next_num_ground=ground)
    y = np.asarray(td_targets(make_dqn(cfg, ENV, ENV.num_features), Hyper.of(cfg), online, target, batch, jax.random.key(0)))

    def q(params, f, skill, param):
        return float(net.apply(params, encode(ENV, f, jnp.int32(skill), jnp.float32(param))))

    candidates = {move: 0.0, light: 0.75, call_planner: 0.0}
    for i in range(2):
        allowed = [k for k in candidates if ground[i, k] > 0]
        chosen = max(allowed, key=lambda k: q(online, batch.next_features[i], k, candidates[k]))
        expected = 0.0 + cfg.learner.gamma * q(target, batch.next_features[i], chosen, candidates[chosen])
        assert y[i] == pytest.approx(expected, abs=1e-5)
    assert y[2] == 1.0  # terminal: no bootstrapping


def test_bootstrapped_values_are_clipped_to_the_achievable_range_only_when_asked():
    """A target net that says Q = 5 everywhere (output bias 5): the bootstrap is clipped to 1 + bonus."""
    net = QNetwork()
    params = net.init(jax.random.key(0), jnp.zeros((1, input_size(ENV, ENV.num_features))))
    out = params["params"]["UniformDense_2"]
    high = {"params": {**params["params"], "UniformDense_2": {"kernel": out["kernel"], "bias": out["bias"] + 5.0}}}
    f = jnp.zeros((2, ENV.num_features))
    batch = Transition(features=f, skill=jnp.array([0, 0]), param=jnp.zeros(2), reward=jnp.array([0.0, 1.5]),
                       done=jnp.array([False, True]), next_features=f,
                       next_num_ground=jnp.ones((2, ENV.num_skills + 1), jnp.int32))
    for clip, expected in ((False, 0.8 * 5.0), (True, 0.8 * 1.5)):
        cfg = TrainConfig(call_planner_bonus=0.5, clip_bootstrap=clip)
        y = np.asarray(td_targets(make_dqn(cfg, ENV, ENV.num_features), Hyper.of(cfg), high, high, batch, jax.random.key(1)))
        assert y[0] == pytest.approx(expected) and y[1] == 1.5  # terminal rewards are never clipped


def test_a_step_discount_discounts_each_target_by_the_steps_its_transition_spans():
    """With step_gamma the goal's reward and the bootstrapped value of a transition of k env steps are
    step_gamma^k of what they are without it (a target net saying Q = 5 everywhere)."""
    net = QNetwork()
    params = net.init(jax.random.key(0), jnp.zeros((1, input_size(ENV, ENV.num_features))))
    out = params["params"]["UniformDense_2"]
    five = {"params": {**params["params"], "UniformDense_2": {"kernel": out["kernel"], "bias": out["bias"] + 5.0}}}
    f = jnp.zeros((3, ENV.num_features))
    batch = Transition(features=f, skill=jnp.array([0, 0, 5]), param=jnp.zeros(3), reward=jnp.array([0.0, 0.0, 1.0]),
                       done=jnp.array([False, False, True]), next_features=f,
                       next_num_ground=jnp.ones((3, ENV.num_skills + 1), jnp.int32), steps=jnp.array([1, 4, 30]))
    y = np.asarray(td_targets(make_dqn(TrainConfig(step_gamma=0.9), ENV, ENV.num_features), Hyper.of(TrainConfig()), five, five, batch,
                              jax.random.key(1)))
    np.testing.assert_allclose(y, [0.8 * 5.0 * 0.9, 0.8 * 5.0 * 0.9 ** 4, 0.9 ** 30], rtol=1e-5)
    plain = np.asarray(td_targets(make_dqn(TrainConfig(), ENV, ENV.num_features), Hyper.of(TrainConfig()), five, five,
                                  batch.replace(steps=None), jax.random.key(1)))
    np.testing.assert_allclose(plain, [4.0, 4.0, 1.0], rtol=1e-6)


def test_transitions_count_the_env_steps_from_their_decision_to_the_next():
    """Coffee's oracle: MoveToTwistJug, TwistJug (one wrist step, then one up) and CallPlanner,
    which runs the plan to the goal; the three spans add up to the episode after the first decision."""
    from envs_jax.coffee.env import Coffee
    batch = evaluation_batch(Coffee, [0], 1, protocol="jaxbridge")
    result, rec = rollout(MetaPolicy(batch.env, make_bridge("oracle", batch.env)), batch.arrays,
                          jax.random.split(jax.random.key(0), 1), batch.max_steps, record=True)
    records = jax.tree.map(lambda x: x[:, 0], rec)
    transitions, valid = episode_transitions(records, result.success[0], batch.env.num_skills, 0.0, True)
    t = np.flatnonzero(np.asarray(valid))
    steps = np.asarray(transitions.steps)[t]
    assert bool(result.success[0]) and np.asarray(transitions.skill)[t].tolist() == [0, 1, batch.env.num_skills]
    assert steps[1] == 2 and steps[0] >= 1
    assert steps.sum() == int(result.steps[0]) - t[0]
    assert episode_transitions(records, result.success[0], batch.env.num_skills)[0].steps is None


def test_an_ensemble_is_the_minimum_of_independent_members_all_fitted_to_the_targets():
    x = jax.random.normal(jax.random.key(0), (64, input_size(ENV, ENV.num_features)))
    single = QNetwork((32, 32)).init(jax.random.key(1), x)
    assert set(single["params"]) == {"UniformDense_0", "UniformDense_1", "UniformDense_2"}  # old checkpoints load
    pair = QNetwork((32, 32), ensemble=2)
    cfg = TrainConfig(q_ensemble=2, updates_per_cycle=300, n_target_sample=2, buffer_capacity=64, batch_size=64)
    learner = init_learner(make_dqn(cfg, ENV, ENV.num_features), jax.random.key(2))
    kernels = jax.tree.leaves(learner.params)
    assert all(k.shape[0] == 2 for k in kernels) and not np.allclose(kernels[1][0], kernels[1][1])
    # A buffer of terminal transitions with reward 1 for skill 0 and 0 otherwise: both members must learn it.
    f = jax.random.uniform(jax.random.key(3), (64, ENV.num_features))
    skill = jnp.arange(64) % 2
    batch = Transition(features=f, skill=skill, param=jnp.zeros(64), reward=(skill == 0).astype(jnp.float32),
                       done=jnp.ones(64, bool), next_features=f, next_num_ground=jnp.ones((64, ENV.num_skills + 1), jnp.int32))
    learner = learner.replace(buffer=add(learner.buffer, for_buffer(batch), jnp.ones(64, bool)))
    learner, loss, _ = jax.jit(lambda l: learn(make_dqn(cfg, ENV, ENV.num_features), Hyper.of(cfg), l, jnp.int32(64)))(learner)
    members = pair.apply(learner.params, encode(ENV, f, skill, jnp.zeros(64)), members=True)
    assert members.shape == (2, 64) and np.abs(np.asarray(members) - np.asarray(batch.reward)).max() < 0.2
    value = pair.apply(learner.params, encode(ENV, f, skill, jnp.zeros(64)))
    assert np.array_equal(np.asarray(value), np.asarray(members).min(0))


@pytest.mark.parametrize("seed", [0, 1])
def test_feature_noise_fits_the_neighbourhood_of_a_stored_state_not_only_the_point(seed):
    """Every stored transition has the same features f0 and target 1 (skill 0) or 0 (skill 1). Fitted
    without noise, Q is exact at f0 and drifts around it; fitted with feature noise (a fresh draw per
    update), it holds the value around f0 too."""
    n = 64
    f0 = jax.random.uniform(jax.random.key(10 + seed), (ENV.num_features,))
    f = jnp.broadcast_to(f0, (n, ENV.num_features))
    skill = jnp.arange(n) % 2
    batch = Transition(features=f, skill=skill, param=jnp.zeros(n), reward=(skill == 0).astype(jnp.float32),
                       done=jnp.ones(n, bool), next_features=f, next_num_ground=jnp.ones((n, ENV.num_skills + 1), jnp.int32))
    nearby = f0 + 0.2 * jax.random.normal(jax.random.key(99), (256, ENV.num_features))
    error = {}
    for noise in (0.0, 0.2):
        cfg = TrainConfig(updates_per_cycle=300, buffer_capacity=n, batch_size=n, feature_noise=noise)
        learning = make_dqn(cfg, ENV, ENV.num_features)
        learner = init_learner(learning, jax.random.key(seed))
        learner = learner.replace(buffer=add(learner.buffer, for_buffer(batch), jnp.ones(n, bool)))
        learner, _, _ = jax.jit(lambda l: learn(learning, Hyper.of(learning.config), l, jnp.int32(n)))(learner)
        assert float(learning.net.apply(learner.online, encode(ENV, f0, jnp.int32(0), jnp.float32(0)))) == pytest.approx(1.0, abs=0.05)
        q = learning.net.apply(learner.online, encode(ENV, nearby, jnp.int32(0), jnp.float32(0)))
        error[noise] = float(jnp.abs(q - 1.0).mean())
    assert error[0.2] < 0.5 * error[0.0], error


def test_ensembles_traced_in_worker_threads_share_one_scanned_member_class():
    """Approaches train in threads; flax builds a scanned class from its member's dataclass fields, which
    raced when two programs traced an ensemble at once. The class is built once per (member, length)."""
    from concurrent.futures import ThreadPoolExecutor
    from jaxbridge.learn.object_q import ObjectQMember
    from jaxbridge.learn.q_bridge import _Member, members_scan
    with ThreadPoolExecutor(4) as pool:
        built = list(pool.map(lambda i: members_scan((_Member, ObjectQMember)[i % 2], 2), range(8)))
    assert len({id(c) for c in built[0::2]}) == 1 and len({id(c) for c in built[1::2]}) == 1
    assert built[0] is not built[1] and members_scan(_Member, 3) is not built[0]


@pytest.mark.parametrize("ensemble", [1, 2])
def test_a_wide_observation_is_split_off_the_candidates_without_changing_q_or_the_choice(ensemble):
    """Full-state observations (>= SPLIT_FROM_FEATURES values) go in as a SplitInput: the same parameters,
    the same Q up to rounding, the same greedy candidate; narrow ones keep the concatenated input."""
    width = SPLIT_FROM_FEATURES + 19
    net = QNetwork((32, 32), ensemble)
    params = net.init(jax.random.key(0), jnp.zeros((1, width + ENV.num_skills + 2)))
    params = jax.tree.map(lambda p: p + 0.3 * jax.random.normal(jax.random.key(1), p.shape), params)  # nonzero output
    features = jax.random.normal(jax.random.key(2), (width,))
    skills = candidate_skills(ENV, 10)
    param = jax.random.uniform(jax.random.key(3), skills.shape)
    split = candidates_input(ENV, features, jnp.asarray(skills), param)
    assert isinstance(split, SplitInput)
    assert isinstance(candidates_input(ENV, features[:5], jnp.asarray(skills), param), jax.Array)
    whole = np.asarray(net.apply(params, encode(ENV, features, jnp.asarray(skills), param)))
    np.testing.assert_allclose(np.asarray(net.apply(params, split)), whole, atol=1e-5)
    ground = jnp.ones(ENV.num_skills + 1, jnp.int32)
    action, best = best_candidate(ENV, net, params, BridgeObs(features, ground), skills, jax.random.key(4))
    drawn = sample_candidates(ENV, skills, jax.random.key(4))  # best_candidate's own parameter draws
    whole = np.asarray(net.apply(params, encode(ENV, features, jnp.asarray(skills), drawn)))
    chosen = int(np.argmax(whole))
    assert int(action.skill) == skills[chosen] and float(action.param) == float(drawn[chosen])
    assert float(best) == pytest.approx(whole[chosen], abs=1e-5)


def test_replay_buffer_masked_insert_wraps_fifo_and_samples_stored_items():
    buffer = init_buffer(jnp.float32(0), capacity=4)
    buffer = add(buffer, jnp.arange(1.0, 6.0), jnp.array([True, False, True, True, False]))
    assert int(buffer.size) == 3 and np.asarray(buffer.data).tolist() == [1.0, 3.0, 4.0, 0.0]
    buffer = add(buffer, jnp.array([10.0, 11.0, 12.0]), jnp.array([True, True, True]))
    assert int(buffer.size) == 4 and np.asarray(buffer.data).tolist() == [11.0, 12.0, 4.0, 10.0]
    assert int(buffer.insert_at) == 2
    drawn = np.asarray(buffer.data)[np.asarray(sample_indices(buffer, jax.random.key(0), 200))]
    assert set(drawn.tolist()) == {4.0, 10.0, 11.0, 12.0}


def test_minibatches_drawn_up_front_are_the_draws_of_one_split_per_update():
    """`learn` draws all its minibatch slots before the updates; they must be the stream an update
    loop splitting the key once per update would draw (the documented runs were made with that loop)."""
    config = TrainConfig(updates_per_cycle=30, batch_size=16)
    learner = init_learner(make_dqn(config, ENV, ENV.num_features), jax.random.key(3))
    learner = learner.replace(buffer=learner.buffer.replace(size=jnp.int32(77)))
    key, indices = minibatch_indices(config, learner)

    def one_per_update(key, _):
        key, k_sample = jax.random.split(key)
        return key, sample_indices(learner.buffer, k_sample, config.learner.batch_size)

    expected_key, expected = jax.lax.scan(one_per_update, learner.key, None, length=config.learner.updates_per_cycle)
    assert indices.shape == (30, 16) and np.array_equal(indices, expected)
    assert np.array_equal(jax.random.key_data(key), jax.random.key_data(expected_key))
    assert 0 <= int(indices.min()) and int(indices.max()) < 77 and len(np.unique(indices)) > 60


def test_one_transition_per_decision_and_call_planner_spans_the_plan():
    spec = lsd.LightSwitchDoorTask(5, (1,))
    batch = make_batch(LightSwitchDoor, [spec], [0], horizons=[100], env=ENV)
    result, rec = rollout(MetaPolicy(ENV, make_bridge("oracle", ENV)), batch.arrays,
                          jax.random.split(jax.random.key(0), 1), 100, record=True)
    records = jax.tree.map(lambda x: x[:, 0], rec)
    transitions, valid = episode_transitions(records, result.success[0], ENV.num_skills, 0.5)
    t = np.nonzero(np.asarray(valid))[0]
    assert len(t) == 3  # MoveKey, TurnKey, CallPlanner
    assert np.asarray(transitions.skill)[t].tolist() == [ENV.skill_index("MoveKey"), ENV.skill_index("TurnKey"),
                                                         ENV.num_skills]
    assert np.asarray(transitions.reward)[t].tolist() == [0.0, 0.0, 1.5]  # with the CallPlanner bonus
    assert np.asarray(transitions.done)[t].tolist() == [False, False, True]
    assert np.allclose(transitions.next_features[t[0]], records.features[t[1]])
    assert int(result.steps[0]) == spec.shortest_solution  # CallPlanner's transition ran the plan to the goal


def test_the_buffer_reads_next_features_back_from_the_following_slot_across_wrap_arounds(monkeypatch):
    """The buffer drops next_features (for_buffer); successor_features restores them and relabel's targets
    are those of a buffer that keeps them, bit for bit: random-bridge episodes added three at a time (as
    a cycle adds its episodes) into a buffer that wraps several times, relabelled in chunks of 8 (the
    last one padded)."""
    chunk = 8
    monkeypatch.setattr(dqn, "RELABEL_CHUNK", chunk)
    batch = evaluation_batch(LightSwitchDoor, [0, 1], 4)
    controls = Controls(observation=FULL_STATE)  # the full state: every decision's observation differs
    result, rec = rollout(MetaPolicy(batch.env, RandomBridge(batch.env), None, controls), batch.arrays,
                          jax.random.split(jax.random.key(0), batch.size), batch.max_steps, record=True)
    transitions, valid = jax.vmap(episode_transitions, in_axes=(1, 0, None, None))(
        rec, result.success, batch.env.num_skills, 0.0)
    capacity = 23
    config = TrainConfig(approach="no_feature_selection", buffer_capacity=capacity, n_target_sample=3)
    learning = make_dqn(config, batch.env, batch.env.full_state_size)
    learner = init_learner(learning, jax.random.key(3))
    noisy = lambda params, key: jax.tree.map(lambda p: p + 0.3 * jax.random.normal(key, p.shape), params)
    learner = learner.replace(params=noisy(learner.params, jax.random.key(1)),
                              target_params=noisy(learner.params, jax.random.key(2)))
    full = init_buffer(jax.tree.map(lambda x: x[0, 0], transitions), capacity)
    assert learner.buffer.data.next_features is None
    flat = lambda x: x.reshape((-1,) + x.shape[2:])
    checked = differ = 0
    for first in range(0, batch.size, 3):
        items, mask = jax.tree.map(lambda x: flat(x[first:first + 3]), transitions), flat(valid[first:first + 3])
        full = add(full, items, mask)
        learner = learner.replace(buffer=add(learner.buffer, for_buffer(items), mask))
        slots = np.arange(int(learner.buffer.size))
        live = slots[~np.asarray(full.data.done)[slots]]
        restored = np.asarray(successor_features(learner.buffer.data.features, jnp.asarray(live)))
        np.testing.assert_array_equal(restored, np.asarray(full.data.next_features)[live])
        checked += len(live)
        differ += int(np.any(restored != np.asarray(learner.buffer.data.features)[live], axis=1).sum())

        key = jax.random.key(first)
        targets = np.asarray(dqn.relabel(learning, Hyper.of(learning.config), learner, key))
        chunks = -(-capacity // chunk)
        pad = lambda x: jnp.pad(x, [(0, chunks * chunk - capacity)] + [(0, 0)] * (x.ndim - 1))
        padded = jax.tree.map(pad, full.data)
        expected = np.concatenate([np.asarray(td_targets(
            learning, Hyper.of(learning.config), learner.params, learner.target_params,
            jax.tree.map(lambda x: x[i * chunk:(i + 1) * chunk], padded), jax.random.fold_in(key, i)))
            for i in range(chunks)])
        assert np.array_equal(targets[slots], expected[slots])
    assert int(valid.sum()) > 2 * capacity and checked > 2 * capacity and differ > capacity


def test_a_cycle_whose_episodes_could_overflow_the_buffer_in_one_insert_is_refused():
    fits = TrainConfig(num_seeds=1, num_test_tasks=2, buffer_capacity=5 * 100)
    Cycle(make_setup(fits))
    with pytest.raises(ValueError, match=r"5 episodes x 100 steps per cycle must fit the replay buffer \(499"):
        Cycle(make_setup(replace(fits, buffer_capacity=499)))


def test_different_seeds_get_different_networks_and_the_same_seed_the_same():
    learning = make_dqn(TINY, ENV, ENV.num_features)
    a, b, c = (init_learner(learning, jax.random.key(k)) for k in (0, 1, 0))
    kernel = lambda learner: np.asarray(learner.params["params"]["UniformDense_0"]["kernel"])
    assert not np.array_equal(kernel(a), kernel(b))
    chex.assert_trees_all_equal(jax.random.key_data(a.key), jax.random.key_data(c.key))
    chex.assert_trees_all_equal(a.replace(key=None), c.replace(key=None))  # the whole learner, bit for bit


@pytest.fixture(scope="module")
def tiny_twice():
    """TINY trained twice from scratch with one compiled cycle on one device (compiling is most of a short
    run's time; identity across processes is checked by the resume tests of test_reliability.py), with
    the programs traced and compiled during each cycle (jax.monitoring, jaxbridge.utils.compile_cache)."""
    setup = make_setup(TINY)
    seeds = SeedMesh(TINY.num_seeds)  # one device: where XLA once handed back replicated leaves
    cycle = Cycle(setup, seeds)
    runs, compiled = [], []
    for _ in range(2):
        learners, history = seeds.place(setup.init_learners()), []
        for _ in range(TINY.cycles):
            with compile_cache.record() as record:
                learners, metrics = cycle(learners)
                jax.block_until_ready((learners, metrics))
            compiled.append(record)
            history.append(jax.tree.map(np.asarray, metrics))
        runs.append((learners, history))
    return setup, seeds, cycle, runs, compiled


def test_the_cycle_compiles_once_for_every_cycle_and_run(tiny_twice):
    """No recompilation (nor loading from the persistent cache) between cycles, the cycle without the
    host planner serves every cycle of these tasks (their tables hold every state they meet), and the
    learners keep their seed layout."""
    _, seeds, cycle, runs, compiled = tiny_twice
    assert compiled[0].compiles >= 1
    assert all(r.compiles == 0 and r.traces == 0 for r in compiled[1:]), [r.compiles for r in compiled]
    assert cycle._tables_only._cache_size() == 1 and cycle._with_host is None  # one dispatch entry
    assert all(x.sharding.is_equivalent_to(seeds.sharding, x.ndim) for x in jax.tree.leaves(runs[-1][0]))


def test_a_cycle_meeting_a_state_missing_from_a_table_runs_again_with_the_host_planner(tiny_twice):
    """Tables whose every row is marked missing: the cycle without the host planner reports misses, so the
    cycle runs again from the same learners with it, and gives what the tables gave (the host plans as
    the tables do)."""
    import dataclasses
    setup, seeds, _, ((_, history), _), _ = tiny_twice
    cut = lambda batch: dataclasses.replace(batch, arrays=batch.arrays.replace(
        tables=batch.arrays.tables.replace(state_valid=jnp.zeros_like(batch.arrays.tables.state_valid))))
    truncated = dataclasses.replace(setup)
    truncated.__dict__.update(train=cut(setup.train), test=cut(setup.test))  # Setup's cached task batches
    cycle = Cycle(truncated, seeds)
    learners, metrics = cycle(seeds.place(setup.init_learners()))
    metrics = jax.tree.map(np.asarray, metrics)
    assert cycle._with_host is not None and (metrics.table_misses > 0).all()
    for field in ("test_solve_rate", "train_success_rate", "train_env_steps", "test_env_steps", "train_decisions"):
        np.testing.assert_array_equal(getattr(metrics, field), getattr(history[0], field))
    np.testing.assert_allclose(metrics.loss, history[0].loss, rtol=1e-4)


def test_the_same_seeds_give_identical_metrics_twice(tiny_twice):
    _, _, _, ((la, ha), (lb, hb)), _ = tiny_twice
    for ma, mb in zip(ha, hb):
        assert all(np.array_equal(x, y) for x, y in zip(jax.tree.leaves(ma), jax.tree.leaves(mb)))
    assert all(np.array_equal(x, y) for x, y in zip(jax.tree.leaves(la.params), jax.tree.leaves(lb.params)))
    assert not np.array_equal(ha[-1].loss[0], ha[-1].loss[1])  # the two seeds learn differently


def test_checkpoint_round_trip_restores_identical_greedy_actions(tiny_twice, tmp_path):
    setup, seeds, _, ((learners, _), _), _ = tiny_twice
    learners = seeds.unpad(learners)
    checkpoint.save(tmp_path / "ckpt", 3, learners, {"cycle": 3})
    fresh = setup.init_learners()
    restored, record, step = checkpoint.restore(tmp_path / "ckpt", fresh)
    assert step == 3 and record == {"cycle": 3}
    as_data = lambda tree: jax.tree.leaves(tree.replace(key=jax.random.key_data(tree.key)))
    assert all(np.array_equal(x, y) for x, y in zip(as_data(learners), as_data(restored)))
    net, skills = setup.learner.net, candidate_skills(ENV, 10)
    features = jax.random.uniform(jax.random.key(5), (32, ENV.num_features))
    ground = jnp.ones((32, ENV.num_skills + 1), jnp.int32)
    keys = jax.random.split(jax.random.key(6), 32)

    def greedy(params):
        action, _ = jax.vmap(lambda o, k: best_candidate(ENV, net, params, o, skills, k))(BridgeObs(features, ground), keys)
        return np.asarray(action.skill), np.asarray(action.param)
    for seed in range(TINY.num_seeds):
        before = greedy(jax.tree.map(lambda x: x[seed], learners.params))
        after = greedy(jax.tree.map(lambda x: x[seed], restored.params))
        assert all(np.array_equal(x, y) for x, y in zip(before, after))


def test_a_checkpoint_whose_buffer_still_holds_next_features_restores(tiny_twice, tmp_path):
    """Checkpoints written before the buffer dropped next_features (it stored them per transition) load
    into today's learner: the extra field is left out, everything else comes back exactly."""
    setup, seeds, _, ((learners, _), _), _ = tiny_twice
    learners = seeds.unpad(learners)
    data = learners.buffer.data
    old_layout = learners.replace(buffer=learners.buffer.replace(data=data.replace(
        next_features=jnp.roll(data.features, -1, axis=1))))
    checkpoint.save(tmp_path / "old", 3, old_layout, {"cycle": 3})
    restored, _, _ = checkpoint.restore(tmp_path / "old", setup.init_learners())
    assert restored.buffer.data.next_features is None
    as_data = lambda tree: jax.tree.leaves(tree.replace(key=jax.random.key_data(tree.key)))
    assert all(np.array_equal(x, y) for x, y in zip(as_data(learners), as_data(restored)))


def test_smooth_reward_is_the_papers_trailing_window():
    # Value at cycle c (1-based) = sum of the rates of cycles c-25 .. c-1, / 25.
    s = smooth(np.ones((1, 30)))
    assert s[0, 0] == 0.0 and s[0, 1] == pytest.approx(1 / 25) and s[0, 25] == 1.0 and s[0, 29] == 1.0
    rates = np.zeros((1, 40))
    rates[0, 5] = 1.0  # cycle 6
    s = smooth(rates)
    assert s[0, 5] == 0.0 and s[0, 6] == pytest.approx(1 / 25) and s[0, 30] == pytest.approx(1 / 25)
    assert s[0, 31] == 0.0


@pytest.mark.parametrize("env_name, ensemble", [("light_switch_door", 1), ("coffee", 1), ("doorknobs", 2)])
def test_the_task_constant_split_is_the_whole_network_in_values_and_gradients(env_name, ensemble):
    """Each env's full state as varying entries plus its task's constants (multiplied once per task, then
    gathered by task index) gives the unsplit network's Q and parameter gradients, to float tolerance."""
    from jaxbridge.learn.q_bridge import TaskPart, encode_action, task_state_split
    from envs_jax.registry import env_class
    batch = evaluation_batch(env_class(env_name), [0], 3)
    env, split = batch.env, task_state_split(batch.env)
    assert split is not None and len(split.constant) > 0
    varying, constant = np.array(split.varying), np.array(split.constant)
    start = jax.vmap(lambda task: env.full_state(env.reset(task)))(batch.arrays.tasks)  # [B, S]
    b = np.repeat(np.arange(batch.size), 12)  # 12 observations per task: its constants, random varying values
    observations = start[b].at[:, varying].set(jax.random.normal(jax.random.key(7), (len(b), len(varying))))
    skills = jax.random.randint(jax.random.key(1), b.shape, 0, env.num_skills + 1)
    params_in = jax.random.uniform(jax.random.key(2), b.shape)
    net = QNetwork((32, 32), ensemble)
    params = net.init(jax.random.key(0), jnp.zeros((1, input_size(env, env.full_state_size))))
    params = jax.tree.map(lambda p: p + 0.3 * jax.random.normal(jax.random.key(3), p.shape), params)
    task = TaskPart(values=start[:, constant], index=jnp.asarray(b), split=split)
    whole = lambda p: net.apply(p, encode(env, observations, skills, params_in), members=True)
    parts = lambda p: net.apply(p, SplitInput(observations[:, varying], encode_action(env, skills, params_in), task),
                                members=True)
    chex.assert_trees_all_close(parts(params), whole(params), atol=1e-4, rtol=1e-4)
    weights = jax.random.normal(jax.random.key(4), whole(params).shape)
    grad = lambda f: jax.grad(lambda p: jnp.sum(f(p) * weights))(params)
    chex.assert_trees_all_close(grad(parts), grad(whole), atol=1e-4, rtol=1e-4)


def test_a_split_learner_relabels_and_updates_as_the_unsplit_one():
    """Through the learner: the same transitions stored split (varying entries and a task index) or whole
    give the same TD targets and the same parameters after an update, to float tolerance."""
    batch = evaluation_batch(LightSwitchDoor, [0], 3)
    result, rec = rollout(MetaPolicy(batch.env, RandomBridge(batch.env)), batch.arrays,
                          jax.random.split(jax.random.key(0), batch.size), 40, record=True)
    full = jax.vmap(jax.vmap(batch.env.full_state))(rec.env_state)  # every step's full state, [T, B, S]
    config = TrainConfig(approach="no_feature_selection", buffer_capacity=256, n_target_sample=3, batch_size=32)
    whole_dqn = make_dqn(config, batch.env, batch.env.full_state_size)
    split_dqn = make_dqn(config, batch.env, batch.env.full_state_size, task_state_split(batch.env))
    transitions, valid = jax.vmap(episode_transitions, in_axes=(1, 0, None, None))(
        rec.replace(features=full), result.success, batch.env.num_skills, 0.0)
    flat = lambda x: x.reshape((-1,) + x.shape[2:])
    learners = []
    for learning in (whole_dqn, split_dqn):
        learner = init_learner(learning, jax.random.key(5))
        learner = learner.replace(target_params=jax.tree.map(lambda p: p + 0.1, learner.params))
        items = jax.tree.map(flat, dqn.stored_transitions(learning, transitions))
        learners.append(learner.replace(buffer=add(learner.buffer, items, flat(valid))))
    whole, split = learners
    assert split.buffer.data.features.shape[-1] == len(split_dqn.split.varying) < whole.buffer.data.features.shape[-1]
    task = split_dqn.task_part(batch.arrays.tasks)
    key = jax.random.key(6)
    hyper = Hyper.of(whole_dqn.config)
    targets, stored = dqn.relabel(whole_dqn, hyper, whole, key), int(whole.buffer.size)  # empty slots differ, unread
    chex.assert_trees_all_close(dqn.relabel(split_dqn, hyper, split, key, task)[:stored], targets[:stored], atol=1e-4)
    index = jnp.arange(32) % stored
    updated = [dqn.update_step(whole_dqn, hyper, whole, targets, index)[0].params,
               dqn.update_step(split_dqn, hyper, split, targets, index, task)[0].params]
    chex.assert_trees_all_close(updated[1], updated[0], atol=1e-5)


def test_a_cycles_fit_perturbs_each_update_by_that_updates_own_noise():
    """A cycle's fit draws its minibatch feature noise for all its updates at once: it fits as the same
    updates made one at a time, each drawing its own noise (`update_step` without `noise`), to float
    tolerance, and the noise reaches the fit (without it the parameters differ)."""
    config = jaxbridge.make_config("light_switch_door", num_seeds=1, feature_noise=0.1, updates_per_cycle=6,
                                 batch_size=16)
    learning = make_setup(config).learner
    item = dqn.empty_transition(learning)
    n, k_features, k_targets = 40, *jax.random.split(jax.random.key(7))
    items = jax.tree.map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), item)
    items = items.replace(features=jax.random.normal(k_features, items.features.shape))
    learner = init_learner(learning, jax.random.key(8))
    learner = learner.replace(buffer=add(learner.buffer, items, jnp.ones(n, bool)), updates=jnp.int32(11))
    targets = jax.random.uniform(k_targets, (learner.buffer.capacity,))
    hyper = Hyper.of(config)
    fitted = jax.jit(lambda l: dqn.fixed_updates(learning, hyper, l, targets, None)[0].params)
    one_by_one = learner
    for index in minibatch_indices(config, learner)[1]:
        one_by_one = dqn.update_step(learning, hyper, one_by_one, targets, index)[0]
    chex.assert_trees_all_close(fitted(learner), one_by_one.params, atol=1e-6)
    quiet = replace(learning, config=replace(config, feature_noise=0.0))
    unperturbed = dqn.fixed_updates(quiet, hyper, learner, targets, None)[0].params
    assert not np.allclose(jax.tree.leaves(unperturbed)[0], jax.tree.leaves(one_by_one.params)[0], atol=1e-6)


@pytest.mark.parametrize("preset", ["jaxbridge", "authors"])  # the authors': input scaling, a new Adam, early stopping
def test_a_fit_leaves_out_the_weights_of_the_inputs_its_training_tasks_never_fill(preset):
    """Doorknobs trains on 2x2 maps and its full state has room for 5x5 ones: a fit trains only the weights
    of the inputs a training task can fill (DQN.fit_rows). It fits as the learner whose split keeps the
    rest (as task constants, zero) does, to float tolerance, and leaves the rest's weights, their Adam
    moments, input scaling and target rows exactly as they were: no gradient reaches them."""
    from envs_jax.doorknobs.env import Doorknobs
    config = jaxbridge.make_config("doorknobs", preset=preset, approach="maple_q", num_seeds=1, updates_per_cycle=20,
                                 **({"fit_patience": 5} if preset == "authors" else {}))
    cut = make_setup(config).learner
    split = cut.split
    every = replace(cut, split=replace(split, constant=tuple(sorted(split.constant + split.unfilled)), unfilled=()))
    assert every.fit_rows is None and len(cut.fit_rows) < cut.num_features / 4
    rng, n = np.random.default_rng(0), 300
    items = Transition(features=rng.normal(size=(n, len(split.varying))).astype(np.float32),
                       skill=rng.integers(0, 3, n).astype(np.int32), param=rng.uniform(-1, 1, n).astype(np.float32),
                       reward=(rng.uniform(size=n) < 0.3).astype(np.float32), done=rng.uniform(size=n) < 0.3,
                       next_features=None, next_num_ground=np.ones((n, 4), np.int32), task=np.zeros(n, np.int32))
    learner = init_learner(cut, jax.random.key(3))
    learner = learner.replace(buffer=add(learner.buffer, items, jnp.ones(n, bool)))
    task = cut.env.task_arrays(Doorknobs.train_task(0))
    tasks = jax.tree.map(lambda x: jnp.stack([x] * config.episodes_per_cycle), task)
    fit = lambda learning: jax.jit(lambda l: learn(learning, Hyper.of(config), l, jnp.int32(3), tasks))(learner)
    (after, loss, _), (reference, reference_loss, _) = fit(cut), fit(every)
    np.testing.assert_allclose(loss, reference_loss, rtol=1e-4)
    chex.assert_trees_all_close(after.params, reference.params, atol=1e-4)
    unfilled = np.array(split.unfilled)

    def unfilled_inputs(state):  # the first layer's kernels (weights, target, Adam's moments), the input scaling
        return {jax.tree_util.keystr(path): leaf[..., unfilled, :] if path[-1].key == "kernel" else leaf[..., unfilled]
                for path, leaf in jax.tree_util.tree_leaves_with_path(state)
                if jax.tree_util.keystr(path).endswith(("['UniformDense_0']['kernel']", "['x_shift']", "['x_scale']"))}
    before = unfilled_inputs(dqn.track_target(config, learner, jnp.int32(3)))  # the authors' target moves first
    assert len(before) == (6 if preset == "authors" else 4)
    chex.assert_trees_all_equal(unfilled_inputs(after), before)
    first = lambda state: next(leaf for path, leaf in jax.tree_util.tree_leaves_with_path(state.params)
                               if jax.tree_util.keystr(path).endswith("['UniformDense_0']['kernel']"))
    assert not np.allclose(first(after)[..., cut.fit_rows, :], first(learner)[..., cut.fit_rows, :])  # the rest trained


def test_rollouts_take_one_shared_network_as_they_take_a_copy_per_episode():
    """A MetaPolicy with shared_params gives every episode the one network and exploration rate it is passed:
    exploring at epsilon 1 (choices from the keys alone), the episodes are exactly those of per-episode copies."""
    from jaxbridge.learn.q_bridge import QBridge, QBridgeParams
    batch = evaluation_batch(LightSwitchDoor, [0, 1], 3)
    net = QNetwork((32, 32))
    params = net.init(jax.random.key(0), jnp.zeros((1, input_size(batch.env, batch.env.full_state_size))))
    bridge, keys, n = QBridge(batch.env, net, 10), jax.random.split(jax.random.key(1), batch.size), batch.size
    controls = Controls(observation=FULL_STATE)
    copies = QBridgeParams(q=jax.tree.map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), params), epsilon=jnp.ones(n))
    each, _ = rollout(MetaPolicy(batch.env, bridge, copies, controls), batch.arrays, keys, batch.max_steps)
    one = QBridgeParams(q=params, epsilon=jnp.float32(1.0))
    shared, _ = rollout(MetaPolicy(batch.env, bridge, one, controls, shared_params=True), batch.arrays, keys,
                        batch.max_steps)
    chex.assert_trees_all_equal(shared, each)
    assert int(each.bridge_decisions.sum()) > 0
