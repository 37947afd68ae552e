"""The learner contract (jaxbridge/learn/learner.py): both built-in learners pass `check_learner`, broken ones are
refused naming the method, PQN's Q(lambda) targets are the formula's, PQN resumes exactly and evaluates, the
example learner of docs/NEW_LEARNER.md trains from the command line, and a sweep over a leaf setting trains each value
(each slot's learner is made from its own settings, its leaves traced)."""
import csv
import json
from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from run_helpers import cli_in_process, one_line_error, train as train_cli, trained_whole_and_resumed

import jaxbridge
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.learner import LearnerContractError, check_learner
from jaxbridge.learn.setup import make_setup
from jaxbridge.learn.transitions import Transition
from jaxbridge.run.evaluate import evaluate_run


EXAMPLE = "examples.monte_carlo_q:MonteCarloQ"


def one_seed_tasks(setup):
    return jax.tree.map(lambda x: x[:setup.config.episodes_per_cycle], setup.train.arrays.tasks)


@pytest.mark.parametrize("env", ["light_switch_door", "coffee"])
@pytest.mark.parametrize("learner", ["dqn", "pqn"])
def test_both_learners_keep_the_contract_on_features_and_on_the_full_state(env, learner):
    for approach in ("ours", "maple_q"):  # the object-centric features; the full state (DQN: split off)
        config = jaxbridge.make_config(env, approach=approach, learner=learner, num_seeds=1)
        setup = make_setup(config)
        assert check_learner(setup.learner, config, one_seed_tasks(setup)) is setup.learner


def test_a_broken_learner_is_refused_naming_the_method_and_what_it_expected(tmp_path):
    config = TrainConfig()
    for spec, message in (("tests.plugin_learners:GrowingState", "GrowingState.observe: expected a state of init's shapes"),
                          ("tests.plugin_learners:VectorLoss", "VectorLoss.learn: expected loss a float32 scalar")):
        learner = make_setup(replace(config, learner=spec)).learner
        with pytest.raises(LearnerContractError, match=message.replace("(", r"\(")):
            check_learner(learner, config)
    with pytest.raises(LearnerContractError, match="object: expected an attribute 'env'"):
        check_learner(object(), config)
    with pytest.raises(ValueError, match="unknown learner 'nope'; choose from dqn, pqn"):
        make_setup(replace(config, learner="nope"))
    # train.py checks a learner of your own before anything is written
    proc = cli_in_process("train.py", "--learner", "tests.plugin_learners:GrowingState", "--approaches", "ours",
                          "--num-seeds", "1", "--out", str(tmp_path))
    one_line_error(proc, 2, "--learner: GrowingState.observe: expected a state of init's shapes")
    assert not any(tmp_path.iterdir())


def test_pqn_targets_are_q_lambda_returns_backwards_through_the_decisions():
    config = TrainConfig(learner="pqn", num_seeds=1, gamma=0.8, episodes_per_cycle=1, train_steps=5)
    pqn = make_setup(config).learner
    c = 0.25  # the network's value everywhere: a zero output kernel and this bias
    params = jax.tree_util.tree_map_with_path(
        lambda path, x: jnp.full_like(x, c) if "bias" in str(path[-1]) and x.shape == (1,) else
        (jnp.zeros_like(x) if x.shape[-1:] == (1,) else x), pqn.init(jax.random.key(0)).params)
    # decisions at rows 0, 2 and 3 of one episode; the last reaches the goal (reward 1, done)
    valid = jnp.array([[True, False, True, True, False]])
    features = jnp.zeros((1, 5, pqn.num_features))
    batch = Transition(features=features, skill=jnp.zeros((1, 5), jnp.int32), param=jnp.zeros((1, 5)),
                       reward=jnp.array([[0.0, 0.0, 0.0, 1.0, 0.0]]), done=jnp.array([[False, False, False, True, True]]),
                       next_features=features, next_num_ground=jnp.ones((1, 5, pqn.env.num_skills + 1), jnp.int32))
    returns = jax.jit(lambda hyper: pqn.lambda_returns(hyper, params, batch, valid, jax.random.key(1)))
    for q_lambda in (0.0, 0.5, 1.0):  # one-step targets, a mix, Monte Carlo returns
        g3 = 1.0
        g2 = 0.8 * ((1 - q_lambda) * c + q_lambda * g3)
        g0 = 0.8 * ((1 - q_lambda) * c + q_lambda * g2)
        got = np.asarray(returns(Hyper.of(replace(config, q_lambda=q_lambda))))[0]
        np.testing.assert_allclose(got[[0, 2, 3]], [g0, g2, g3], rtol=1e-6)


def test_a_pqn_run_resumes_to_the_same_metrics_and_its_evaluation_finds_its_test_rate(tmp_path):
    config = jaxbridge.make_config("light_switch_door", preset="pqn", num_seeds=2, cycles=3, episodes_per_cycle=2,
                                 pqn_epochs=4, checkpoint_every=1, num_test_tasks=2)
    trained_whole_and_resumed(make_setup(config), tmp_path, crash_at=3)
    whole = (tmp_path / "whole" / "metrics.csv").read_bytes()
    assert (tmp_path / "crashed" / "metrics.csv").read_bytes() == whole and whole.count(b"\n") == 7
    rows = list(csv.DictReader((tmp_path / "whole" / "metrics.csv").open()))
    assert all(float(r["loss"]) > 0 for r in rows) and all(int(r["buffer_size"]) == int(r["train_decisions"]) for r in rows)
    assert json.loads((tmp_path / "crashed" / "config.json").read_text())["learner"]["name"] == "pqn"
    _, step, _, result, _ = evaluate_run(tmp_path / "crashed")
    last = [float(r["test_solve_rate"]) for r in rows if r["cycle"] == "3"]
    assert step == 3 and np.mean(result.success) == pytest.approx(np.mean(last))


def test_the_example_learner_trains_from_the_command_line_sweeps_its_own_settings_and_its_checkpoint_evaluates(tmp_path):
    # One run: its own settings set (memory: 3 cycles, all of a 3-cycle run) and swept (epochs: its
    # default 50, and 7), each setting its own run directory.
    learner = EXAMPLE
    proc = train_cli("--env", "examples.locked_box:LockedBox", "--approaches", "ours", "--learner", learner,
                     "--num-seeds", "2", "--cycles", "3", "--set", "memory=3", "--sweep", "epochs=50,7",
                     "--no-progress", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    for epochs in (50, 7):
        saved = json.loads((tmp_path / "locked_box" / f"ours@epochs={epochs}" / "config.json").read_text())["learner"]
        assert (saved["name"], saved["epochs"], saved["memory"]) == (learner, epochs, 3)  # what --resume and eval.py load
    run = tmp_path / "locked_box" / "ours@epochs=50"
    rates = {c: np.mean([float(r["test_solve_rate"]) for r in csv.DictReader((run / "metrics.csv").open())
                         if r["cycle"] == c]) for c in ("1", "3")}
    assert rates["1"] <= 0.3 and rates["3"] >= 0.8, rates  # it learned the key (a random bridge: about 0.1)
    _, step, _, result, _ = evaluate_run(run)
    assert step == 3 and np.mean(result.success) == pytest.approx(rates["3"])
    refused = cli_in_process("train.py", "--env", "examples.locked_box:LockedBox", "--learner", learner, "--set", "memory=0",
                             "--out", str(tmp_path / "refused"))
    assert refused.returncode == 2 and "memory must be at least 1" in refused.stderr


def test_each_setting_starts_from_its_own_learners_init():
    # A sweep's settings share one program; a leaf its learner's init reads is still each setting's own.
    config = TrainConfig(learner="tests.plugin_learners:LeafInInit", num_seeds=1)
    setup = make_setup(config)
    low, high = (setup.init_learners(replace(config, learning_rate=rate)).params for rate in (1e-3, 4e-3))
    jax.tree.map(lambda a, b: np.testing.assert_allclose(4 * np.asarray(a), np.asarray(b), rtol=1e-6), low, high)
    assert jax.tree.leaves(setup.init_learners().params)[0].sum() == jax.tree.leaves(low)[0].sum()  # its own config's


def test_a_sweep_over_the_example_learners_learning_rate_trains_each_value():
    # One program for both settings (a leaf), each slot stepping at its own rate: the same first cycle's
    # decisions, barely fitted at 1e-6 and far at 3e-2 (a learning rate read as a constant trained both alike).
    experiment = jaxbridge.train("light_switch_door", "ours", seeds=1, cycles=2, learner=EXAMPLE,
                                 sweep={"learning_rate": (1e-6, 3e-2)})
    slow, fast = (experiment.metrics[f"ours@learning_rate={rate}"] for rate in ("1e-06", "0.03"))
    assert slow["train_decisions"][0, 0] == fast["train_decisions"][0, 0] > 0  # the same decisions to fit
    assert fast["q_abs_max"][0, 0] > 100 * slow["q_abs_max"][0, 0]
    assert fast["loss"][0, 0] < 0.9 * slow["loss"][0, 0]

