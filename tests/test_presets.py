"""`--preset`: every value a preset sets reaches the config the learner uses, and its test tasks."""
import dataclasses

import pytest

from envs_jax import env_class
from jaxbridge.commands.train import make_config
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.presets import AUTHORS, preset_values
from jaxbridge.learn.setup import make_setup
from jaxbridge.utils.cli import UsageError

ENVS = ("light_switch_door", "doorknobs", "coffee")
# reference/method.md §7: n_sample per env in the authors' logged runs (Coffee: configuration A).
AUTHORS_N_SAMPLE = {"light_switch_door": 100, "doorknobs": 10, "coffee": 10}


@pytest.mark.parametrize("env", ENVS)
def test_the_authors_preset_reaches_the_learner_and_its_bridge(env):
    config, _ = make_config({"env": env, "preset": "authors", "num_seeds": 1})
    setup = make_setup(config)
    learner_config = setup.dqn.config  # what the updates, targets and polyak steps read
    expected = {**AUTHORS, "n_sample": AUTHORS_N_SAMPLE[env], "preset": "authors"}
    assert {k: getattr(learner_config, k) for k in expected} == expected
    assert setup.bridge(setup.test_env).n_sample == AUTHORS_N_SAMPLE[env]
    assert setup.dqn.net.ensemble == 1
    assert config.to_dict()["preset"] == "authors"  # config.json records it with every resolved value


def test_the_authors_test_tasks_light_switch_door_fixed_horizon_30():
    """The authors' code's fixed horizon 30: seed 2's 20 cells and 3 doors need 32 steps (unsolvable);
    the tasks themselves are the same draws as ours."""
    config, _ = make_config({"env": "light_switch_door", "preset": "authors", "num_seeds": 3})
    ours = make_setup(dataclasses.replace(config, test_protocol="jaxbridge")).test
    theirs = make_setup(config).test
    assert [(s.num_cells, s.door_cells) for s in theirs.specs] == [(s.num_cells, s.door_cells) for s in ours.specs]
    assert set(theirs.arrays.horizons.tolist()) == {30}
    assert max(s.shortest_solution for s in theirs.specs) == 32  # seed 2
    assert min(ours.arrays.horizons.tolist()) == 30 and max(ours.arrays.horizons.tolist()) == 37


def test_the_authors_test_tasks_coffee_four_cups_horizon_100():
    config, _ = make_config({"env": "coffee", "preset": "authors", "num_seeds": 2})
    test = make_setup(config).test
    assert {len(s.cups) for s in test.specs} == {4} and set(test.arrays.horizons.tolist()) == {100}
    ours = make_setup(TrainConfig.for_env("coffee", num_seeds=2)).test
    assert {len(s.cups) for s in ours.specs} == {1, 2, 3, 4} and set(ours.arrays.horizons.tolist()) == {110}


@pytest.mark.parametrize("env", ENVS)
def test_the_jaxbridge_preset_is_the_default_config(env):
    assert make_config({"env": env})[0] == TrainConfig.for_env(env) == TrainConfig.for_env(env, "jaxbridge")
    assert make_config({"env": env})[0].preset == "jaxbridge"


def test_flags_override_the_preset_and_bad_names_are_refused():
    config, _ = make_config({"env": "doorknobs", "preset": "authors", "batch_size": 128, "test_protocol": "jaxbridge"})
    assert config.batch_size == 128 and config.n_target_sample == 1 and config.test_protocol == "jaxbridge"
    with pytest.raises(UsageError, match="has no|has jaxbridge"):
        make_config({"env": "doorknobs", "test_protocol": "authors"})  # Doorknobs' authors' tasks are ours
    with pytest.raises(ValueError, match="unknown preset"):
        preset_values("theirs", env_class("coffee"))
