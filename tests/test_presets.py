"""`--preset`: every value a preset sets reaches the config the learner uses, and its test tasks; the
authors' learner options do what they say."""
import jaxbridge
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax import env_class
from envs_jax.base import BridgeObs
from jaxbridge.core.bridges import RandomBridge
from jaxbridge.api import make_config
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.presets import AUTHORS, preset_values
from jaxbridge.learn.dqn import learn
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.q_bridge import QNetwork
from jaxbridge.learn.setup import make_setup
from jaxbridge.utils.errors import InputError

ENVS = ("light_switch_door", "doorknobs", "coffee")
# the authors' code: n_sample per env in the authors' logged runs (Coffee: configuration A).
AUTHORS_N_SAMPLE = {"light_switch_door": 100, "doorknobs": 10, "coffee": 10}


@pytest.mark.parametrize("env", ENVS)
def test_the_authors_preset_reaches_the_learner_and_its_bridge(env):
    config = make_config(env=env, preset="authors", num_seeds=1)
    setup = make_setup(config)
    learner_config = setup.learner.config  # what the updates, targets and polyak steps read
    expected = {**AUTHORS, "n_sample": AUTHORS_N_SAMPLE[env], "preset": "authors"}
    assert setup.learner.net.normalise and setup.init_learners().norm is not None  # min-max scaling
    read = lambda k: getattr(learner_config.learner if hasattr(learner_config.learner, k) else learner_config, k)
    assert {k: read(k) for k in expected} == expected
    assert setup.bridge(setup.test_env).n_sample == AUTHORS_N_SAMPLE[env] and not setup.bridge(setup.test_env).stratified
    assert set(setup.train_env.quirks) == set(config.env_quirks)  # every env-level quirk it has, switched on
    assert all(getattr(setup.train_env, q) and getattr(setup.test_env, q) for q in config.env_quirks)
    assert setup.learner.net.ensemble == 1 and not setup.controls.loop_guard
    assert config.to_dict()["preset"] == "authors"  # config.json records it with every resolved value


@pytest.mark.parametrize("loop_guard", [True, False])
def test_the_loop_guard_reaches_every_rollout_of_the_cycle(monkeypatch, loop_guard):
    """Every env's default has the guard (runs saved before it, none); the config's value is what the
    cycle's rollouts run with."""
    from jaxbridge.learn import online

    assert all(jaxbridge.make_config(env).loop_guard for env in ENVS)
    nested = TrainConfig().to_dict()  # a version-6 config was flat, without the learner's name
    old_run = {**{k: v for k, v in nested.items() if k not in ("loop_guard", "learner")},
               **{k: v for k, v in nested["learner"].items() if k != "name"}}
    assert not TrainConfig.from_dict({**old_run, "config_version": 6}).loop_guard
    seen = []

    original_rollout = online.rollout

    def recording_rollout(policy, *args, **kwargs):
        seen.append(policy.controls)
        return original_rollout(policy, *args, **kwargs)

    monkeypatch.setattr(online, "rollout", recording_rollout)
    setup = make_setup(jaxbridge.make_config("doorknobs", num_seeds=1, loop_guard=loop_guard))
    learner = jax.tree.map(lambda x: x[0], setup.init_learners())
    one = lambda batch: jax.tree.map(lambda x: x[: len(x) // setup.config.num_seeds], batch.arrays)
    jax.eval_shape(online.make_seed_cycle(setup), learner, one(setup.train), one(setup.test), Hyper.of(setup.config))
    assert len(seen) == 2 and all(c.loop_guard == loop_guard for c in seen)  # training and test episodes
    # eval.py, its sweeps and renders run a saved run's greedy policy with the same controls
    from jaxbridge.run.evaluate import TrainedPolicy
    assert TrainedPolicy(setup, 0, setup.init_learners()).on(setup.test)[2] == setup.controls == seen[-1]


def test_the_authors_test_tasks_light_switch_door_fixed_horizon_30():
    """The authors' code's fixed horizon 30: seed 2's 20 cells and 3 doors need 32 steps (unsolvable);
    the tasks themselves are the same draws as ours."""
    config = make_config(env="light_switch_door", preset="authors", num_seeds=3)
    ours = make_setup(dataclasses.replace(config, test_protocol="jaxbridge")).test
    theirs = make_setup(config).test
    assert [(s.num_cells, s.door_cells) for s in theirs.specs] == [(s.num_cells, s.door_cells) for s in ours.specs]
    assert set(theirs.arrays.horizons.tolist()) == {30}
    assert max(s.shortest_solution for s in theirs.specs) == 32  # seed 2
    assert min(ours.arrays.horizons.tolist()) == 30 and max(ours.arrays.horizons.tolist()) == 37


def test_the_authors_test_tasks_coffee_four_cups_horizon_100_are_both_presets_default():
    for preset in ("authors", "jaxbridge"):
        config = make_config(env="coffee", preset=preset, num_seeds=2)
        test = make_setup(config).test
        assert {len(s.cups) for s in test.specs} == {4} and set(test.arrays.horizons.tolist()) == {100}
    variant = make_setup(jaxbridge.make_config("coffee", num_seeds=2, test_protocol="jaxbridge")).test
    assert {len(s.cups) for s in variant.specs} == {1, 2, 3, 4} and set(variant.arrays.horizons.tolist()) == {110}


@pytest.mark.parametrize("env", ENVS)
def test_the_jaxbridge_preset_is_the_default_config(env):
    assert make_config(env=env) == jaxbridge.make_config(env) == jaxbridge.make_config(env, preset="jaxbridge")
    assert make_config(env=env).preset == "jaxbridge"


def test_flags_override_the_preset_and_bad_names_are_refused():
    config = make_config(env="doorknobs", preset="authors", batch_size=128, test_protocol="jaxbridge")
    assert config.learner.batch_size == 128 and config.learner.n_target_sample == 1 and config.test_protocol == "jaxbridge"
    with pytest.raises(InputError, match="has no|has jaxbridge"):
        make_config(env="doorknobs", test_protocol="authors")  # Doorknobs' authors' tasks are ours
    with pytest.raises(ValueError, match="unknown preset"):
        preset_values("theirs", env_class("coffee"))
    assert make_config(env="coffee", preset="authors", env_quirks=()).env_quirks == ()  # --env-quirks none
    assert make_config(env="doorknobs", env_quirks=("raw_offsets",)).env_quirks == ("raw_offsets",)
    with pytest.raises(InputError, match=r"has no quirk .shared_repeat_flag. \(its quirks: raw_offsets"):
        make_config(env="doorknobs", env_quirks=("shared_repeat_flag",))


# ---- the authors' learner options do what they say ------------------------------------------------

def test_the_authors_preset_builds_their_network_exploration_and_target():
    config = make_config(env="light_switch_door", preset="authors", num_seeds=1)
    setup = make_setup(config)
    assert setup.learner.net.activation == "relu" and setup.bridge(setup.test_env).explore_ground_operators
    assert (config.learner.target_init, config.learner.reset_optimizer) == ("apart", True)


@pytest.mark.parametrize("activation, hidden", [("relu", lambda h: np.maximum(h, 0.0)),
                                                ("leaky_relu", lambda h: np.where(h >= 0, h, 0.01 * h))])
def test_hidden_units_are_the_named_activation(activation, hidden):
    x = np.asarray(jax.random.normal(jax.random.key(0), (64, 9)))
    net = QNetwork((8, 8), 1, activation)
    params = net.init(jax.random.key(1), x)
    params = jax.tree.map(lambda p: p + 0.3 * jax.random.normal(jax.random.key(2), p.shape), params)  # output != 0
    layers = [params["params"][name] for name in sorted(params["params"])]  # UniformDense_0, _1, _2
    h = x
    for layer in layers[:-1]:
        h = hidden(h @ np.asarray(layer["kernel"]) + np.asarray(layer["bias"]))
    expected = (h @ np.asarray(layers[-1]["kernel"]) + np.asarray(layers[-1]["bias"]))[:, 0]
    np.testing.assert_allclose(net.apply(params, x), expected, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("ensemble", [1, 2])
def test_the_output_layer_starts_at_zero_or_uniform_as_pytorch(ensemble):
    x = np.asarray(jax.random.normal(jax.random.key(0), (16, 9)))
    zero = QNetwork((8, 8), ensemble, "relu", "zero")
    uniform = QNetwork((8, 8), ensemble, "relu", "uniform")
    assert not np.asarray(zero.apply(zero.init(jax.random.key(1), x), x)).any()
    params = uniform.init(jax.random.key(1), x)
    output = jax.tree.leaves(params["params"])[-2:]  # the last layer's bias and kernel: fan-in 8
    values = np.concatenate([np.ravel(v) for v in output])
    assert np.all(np.abs(values) <= 1 / np.sqrt(8)) and np.abs(values).max() > 0.5 / np.sqrt(8)
    assert np.asarray(uniform.apply(params, x)).std() > 0
    assert jaxbridge.make_config("coffee", preset="authors").learner.output_init == "uniform" == make_config(
        env="coffee", preset="authors").learner.output_init and TrainConfig().learner.output_init == "zero"


def test_the_target_starts_as_a_copy_or_apart():
    def learner(target_init):
        config = jaxbridge.make_config("light_switch_door", num_seeds=1, target_init=target_init)
        return make_setup(config).init_learners()

    copy, apart = learner("copy"), learner("apart")
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(copy.params), jax.tree.leaves(apart.params)))
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(copy.params), jax.tree.leaves(copy.target_params)))
    hidden = lambda params: params["params"]["UniformDense_0"]["kernel"]
    assert not np.allclose(hidden(apart.params), hidden(apart.target_params))


@pytest.mark.parametrize("reset", [False, True])
def test_the_optimizer_is_new_for_each_cycles_fit_only_when_asked(reset):
    """Adam's step count after a cycle: carried on from the last cycle, or counted from 0 again."""
    config = jaxbridge.make_config("light_switch_door", num_seeds=1, updates_per_cycle=3, reset_optimizer=reset)
    setup = make_setup(config)
    learner = jax.tree.map(lambda x: x[0], setup.init_learners())
    clip, (adam, scale) = learner.opt_state
    learner = learner.replace(opt_state=(clip, (adam._replace(count=jnp.int32(57)), scale)))
    after, _, _ = jax.jit(lambda l: learn(setup.learner, Hyper.of(setup.config), l, jnp.int32(0)))(learner)  # empty buffer: no update
    assert int(after.opt_state[1][0].count) == (0 if reset else 57)


@pytest.mark.parametrize("ground_operators, expected", [(False, [1 / 3, 1 / 3, 0, 0, 0, 1 / 3]),
                                                        (True, [3 / 5, 1 / 5, 0, 0, 0, 1 / 5])])
def test_random_draws_over_skills_or_over_ground_operators(ground_operators, expected):
    """3 applicable MoveRobot groundings, 1 TurnOnLight, CallPlanner: per skill, or per ground operator."""
    env = env_class("light_switch_door")()
    obs = BridgeObs(features=jnp.zeros(env.num_features), num_ground=jnp.array([3, 1, 0, 0, 0, 1], jnp.int32))
    bridge = RandomBridge(env, ground_operators)
    skills = jax.vmap(lambda k: bridge(None, obs, k).skill)(jax.random.split(jax.random.key(0), 6000))
    np.testing.assert_allclose(np.bincount(np.asarray(skills), minlength=6) / 6000, expected, atol=0.025)


def test_minmax_scaling_is_fitted_to_the_stored_inputs_and_targets_and_scales_the_network():
    """The authors' normalisation: per input column (features, skill one-hot, param) and for the targets,
    shift = min and scale = max(range, 1) over the stored transitions only; the network sees the scaled
    input and its output is scaled back."""
    from jaxbridge.learn.dqn import fit_scaling
    from jaxbridge.learn.q_bridge import encode
    config = jaxbridge.make_config("light_switch_door", preset="authors", num_seeds=1)
    setup = make_setup(config)
    dqn, learner = setup.learner, jax.tree.map(lambda x: x[0], setup.init_learners())
    empty = fit_scaling(dqn, learner.buffer, jnp.zeros(config.learner.buffer_capacity), None)
    assert not np.asarray(empty["x_shift"]).any() and (np.asarray(empty["x_scale"]) == 1).all()
    rng = np.random.default_rng(0)
    n, data = 40, learner.buffer.data
    features = rng.uniform(-3, 5, (n, dqn.num_features)).astype(np.float32)
    features[:, 0] = rng.uniform(0.2, 0.4, n)  # a narrow column: range below 1, scale 1
    skill, param = rng.integers(0, 3, n).astype(np.int32), rng.uniform(-1, 1, n).astype(np.float32)
    data = data.replace(features=data.features.at[:n].set(features).at[n:].set(100.0),  # unstored rows ignored
                        skill=data.skill.at[:n].set(skill), param=data.param.at[:n].set(param))
    buffer = learner.buffer.replace(data=data, size=jnp.int32(n))
    targets = jnp.full(config.learner.buffer_capacity, 9.0).at[:n].set(rng.uniform(0, 1.5, n))
    norm = fit_scaling(dqn, buffer, targets, None)
    x = np.asarray(encode(dqn.env, features, skill, param))
    np.testing.assert_allclose(norm["x_shift"], x.min(0))
    np.testing.assert_allclose(norm["x_scale"], np.maximum(x.max(0) - x.min(0), 1.0))
    assert norm["x_scale"][0] == 1.0 and norm["x_scale"][1] > 1.0
    np.testing.assert_allclose(norm["y_shift"], targets[:n].min())
    np.testing.assert_allclose(norm["y_scale"], max(float(targets[:n].max() - targets[:n].min()), 1.0))
    scaled = {**learner.params, "norm": norm}
    plain = QNetwork(config.learner.hidden_sizes, 1, config.learner.activation, config.learner.output_init)
    expected = plain.apply({"params": learner.params["params"]["net"]}, (x - norm["x_shift"]) / norm["x_scale"])
    np.testing.assert_allclose(dqn.net.apply(scaled, x), expected * norm["y_scale"] + norm["y_shift"], rtol=1e-5)


def test_minmax_scaling_of_a_split_full_state_equals_scaling_the_whole_input():
    """Maple Q's split input (varying entries, the task's constants, the action) is scaled part by part as
    the whole input would be; the entries its 2x2 training maps leave unfilled are zero, and so is their
    shift (fit_scaling's), so the split leaves them out."""
    from jaxbridge.learn.q_bridge import SplitInput, TaskPart, encode, encode_action
    config = jaxbridge.make_config("doorknobs", preset="authors", num_seeds=1, approach="maple_q")
    setup = make_setup(config)
    dqn, learner = setup.learner, jax.tree.map(lambda x: x[0], setup.init_learners())
    split, width = dqn.split, dqn.num_features + dqn.env.num_skills + 2
    rng = np.random.default_rng(1)
    norm = {"x_shift": jnp.asarray(rng.uniform(-1, 1, width), jnp.float32),
            "x_scale": jnp.asarray(rng.uniform(1, 3, width), jnp.float32),
            "y_shift": jnp.float32(0.25), "y_scale": jnp.float32(1.5)}
    unfilled = np.array(split.unfilled)
    norm["x_shift"] = norm["x_shift"].at[unfilled].set(0.0)
    params = jax.tree.map(lambda p: p + 0.1 * jax.random.normal(jax.random.key(2), p.shape), learner.params)
    full = jnp.asarray(rng.normal(size=(3, dqn.num_features)), jnp.float32).at[:, unfilled].set(0.0)
    skill, param = jnp.array([0, 1, 3], jnp.int32), jnp.array([0.5, -0.2, 0.0], jnp.float32)
    task = TaskPart(values=full[:1, np.array(split.constant)], index=jnp.zeros(3, jnp.int32), split=split)
    whole = jnp.concatenate([full.at[:, np.array(split.constant)].set(full[0, np.array(split.constant)]),
                             encode_action(dqn.env, skill, param)], -1)
    parts = SplitInput(full[:, np.array(split.varying)], encode_action(dqn.env, skill, param), task)
    variables = {**params, "norm": norm}
    np.testing.assert_allclose(dqn.net.apply(variables, parts), dqn.net.apply(variables, whole), rtol=2e-4, atol=1e-5)
    assert whole.shape[-1] == width and encode(dqn.env, full, skill, param).shape == whole.shape
    from jaxbridge.learn.dqn import fit_scaling  # the task's constants: shifted to 0, scale 1
    buffer = learner.buffer.replace(size=jnp.int32(3), data=learner.buffer.data.replace(
        features=learner.buffer.data.features.at[:3].set(full[:, np.array(split.varying)])))
    fitted = fit_scaling(dqn, buffer, jnp.zeros(buffer.capacity), task)
    np.testing.assert_array_equal(fitted["x_shift"][np.array(split.constant)], task.values[0])
    np.testing.assert_array_equal(fitted["x_scale"][np.array(split.constant)], 1.0)
    np.testing.assert_array_equal(fitted["x_shift"][unfilled], 0.0)
    np.testing.assert_array_equal(fitted["x_scale"][unfilled], 1.0)
    np.testing.assert_allclose(fitted["x_shift"][np.array(split.varying)], full[:, np.array(split.varying)].min(0))


def test_the_authors_fit_stops_after_patience_updates_without_a_lower_loss_and_restores_the_best_weights():
    """fit_until_no_better against the same rule written out: updates until `fit_patience` in a row found
    no lower minibatch loss (at most updates_per_cycle), then the weights that scored the lowest loss."""
    from jaxbridge.learn.dqn import fit_until_no_better, relabel, update_step
    from jaxbridge.learn.online import Cycle
    from jaxbridge.learn.replay import sample_indices
    config = jaxbridge.make_config("light_switch_door", preset="authors", num_seeds=1, fit_patience=20, updates_per_cycle=400)
    setup = make_setup(config)
    cycle = Cycle(setup)
    learners, _ = cycle(cycle.seeds.place(setup.init_learners()))  # one cycle: a filled buffer
    learner = jax.tree.map(lambda x: x[0], cycle.seeds.unpad(learners))
    assert learner.buffer.size > 0 and config.learner.fit_patience < int(learner.updates) <= config.learner.updates_per_cycle
    dqn, hyper = setup.learner, Hyper.of(setup.config)
    targets = relabel(dqn, hyper, learner, jax.random.key(3), None)
    fitted, _, _ = jax.jit(lambda l: fit_until_no_better(dqn, hyper, l, targets, None))(learner)

    step = jax.jit(lambda l, index: update_step(dqn, hyper, l, targets, index, None))
    current, best, best_loss, since_best, done = learner, learner.params, np.inf, 0, 0
    while done < config.learner.updates_per_cycle and since_best < config.learner.fit_patience:
        key, k_sample = jax.random.split(current.key)
        updated, (loss, _) = step(current.replace(key=key), sample_indices(current.buffer, k_sample, config.learner.batch_size))
        if float(loss) < best_loss:
            best, best_loss, since_best = current.params, float(loss), 0
        else:
            since_best += 1
        current, done = updated, done + 1
    assert int(fitted.updates - learner.updates) == done and config.learner.fit_patience <= done < config.learner.updates_per_cycle
    for restored, expected, last in zip(jax.tree.leaves(fitted.params), jax.tree.leaves(best),
                                        jax.tree.leaves(current.params)):
        np.testing.assert_allclose(restored, expected, rtol=1e-4, atol=1e-6)
    assert not all(np.allclose(a, b) for a, b in zip(jax.tree.leaves(fitted.params), jax.tree.leaves(current.params)))
    capped = dataclasses.replace(config, fit_patience=10**6, updates_per_cycle=37)
    dqn_capped = make_setup(capped).learner
    fitted, _, _ = jax.jit(lambda l: fit_until_no_better(dqn_capped, hyper, l, targets, None))(learner)
    assert int(fitted.updates - learner.updates) == 37


@pytest.mark.parametrize("stratified", [True, False])
def test_parameter_samples_are_stratified_or_independent(stratified):
    """Ours: the j-th of a skill's n samples lies in the j-th n-quantile of its range; the authors': n
    independent uniforms (which leave some quantiles empty)."""
    from jaxbridge.learn.q_bridge import candidate_skills, sample_candidates
    env = env_class("light_switch_door")()
    skills = candidate_skills(env, 100)
    params = np.asarray(sample_candidates(env, skills, jax.random.key(0), stratified))
    for k, spec in enumerate(env.skills):
        if spec.param_low == spec.param_high:
            continue
        u = (params[skills == k] - spec.param_low) / (spec.param_high - spec.param_low)
        strata = np.floor(u * len(u)).astype(int)
        assert np.array_equal(strata, np.arange(len(u))) == stratified
        assert ((0 <= u) & (u < 1)).all()
