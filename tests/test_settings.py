"""Settings declared once (core/settings.py): the learner's under `config.learner`, config.json nested, runs
of every older config version loading, a version-11 run directory evaluating and resuming exactly, and no
second declaration of a field anywhere in the package."""
import ast
import csv
import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from run_helpers import train as train_cli

import jaxbridge
from jaxbridge.core import grid
from jaxbridge.core.config import CONFIG_VERSION, TrainConfig
from jaxbridge.core.learner_settings import DQNSettings, PQNSettings
from jaxbridge.learn.hyper import Hyper

V11_RUN = Path(__file__).parent / "data" / "v11_run"
ROOT = Path(__file__).resolve().parents[1]


def test_a_learners_settings_are_set_and_read_by_name_and_saved_nested():
    config = TrainConfig(learner="pqn", q_lambda=0.3, learning_rate=1e-4, n_sample=10)
    assert type(config.learner) is PQNSettings and config.learner.name == "pqn"
    assert (config.learner.q_lambda, config.n_sample) == (0.3, 10) and not hasattr(config, "q_lambda")  # read in one place
    saved = json.loads(json.dumps(config.to_dict()))
    assert saved["learner"]["name"] == "pqn" and saved["learner"]["q_lambda"] == 0.3 and "q_lambda" not in saved
    assert saved["config_version"] == CONFIG_VERSION and TrainConfig.from_dict(saved) == config
    assert dataclasses.replace(config, learning_rate=3e-4).learner.learning_rate == 3e-4
    with pytest.raises(ValueError, match="batch_size"):  # double DQN's, not PQN's
        TrainConfig(learner="pqn", batch_size=64)
    with pytest.raises(ValueError, match="q_lambda must be at least 0"):
        TrainConfig(learner="pqn", q_lambda=-1.0)


def test_the_token_networks_settings_are_the_configs_own_whatever_the_learner_and_older_configs_move_them_there():
    config = TrainConfig(learner="pqn", attention_preference=4.0, attention_distance="now")
    assert (config.tokens.attention_preference, config.tokens.attention_distance) == (4.0, "now")
    assert not hasattr(config.learner, "attention_preference")  # a learner's settings hold no network's part
    assert grid.parse_sweeps(["attention_preference=1,3"], config) == {"attention_preference": (1.0, 3.0)}
    saved = json.loads(json.dumps(config.to_dict()))
    v15 = {k: v for k, v in saved.items() if k != "tokens"}
    v15.update(config_version=15, learner={**saved["learner"], **saved["tokens"]})
    assert TrainConfig.from_dict(v15) == config  # a version-15 learner held them
    with pytest.raises(ValueError, match="tokens.bogus"):
        TrainConfig.from_dict({**saved, "tokens": {"bogus": 1}})


def test_a_preset_leaves_out_what_the_learner_lacks_and_the_hyper_leaves_are_the_leaf_settings():
    coffee = jaxbridge.make_config("coffee")  # its env defaults: updates_per_cycle 250 (double DQN's), step_gamma
    assert coffee.learner.updates_per_cycle == 250
    pqn = jaxbridge.make_config("coffee", learner="pqn")
    assert type(pqn.learner) is PQNSettings and pqn.step_gamma == coffee.step_gamma
    assert list(vars(Hyper.of(pqn))["values"]) == ["learning_rate", "gamma", "grad_clip", "q_lambda",
                                                   "call_planner_bonus", "epsilon_start", "epsilon_end", "epsilon_decay"]
    assert "q_lambda" not in vars(Hyper.of(coffee))["values"]
    with pytest.raises(ValueError, match="pqn_epochs"):
        grid.parse_sweeps(["pqn_epochs=2,4"])  # double DQN's config has no pqn_epochs
    assert grid.parse_sweeps(["pqn_epochs=2,4"], pqn) == {"pqn_epochs": (2, 4)}
    with pytest.raises(ValueError, match="sets the experiment"):
        grid.parse_sweeps(["learner=dqn,pqn"])


def test_a_slots_settings_hold_its_traced_leaves_and_keep_the_rest():
    # In a cycle each slot's learner is made from settings whose leaves are that slot's values.
    config = TrainConfig(learner="pqn", learning_rate=1e-4, pqn_epochs=8)
    traced = config.with_leaves({**config.leaf_values(), "learning_rate": 0.5, "epsilon_end": 0.25})
    assert (traced.learner.learning_rate, traced.epsilon_end, traced.learner.pqn_epochs) == (0.5, 0.25, 8)
    assert traced.static_values() == config.static_values() and config.learner.learning_rate == 1e-4


def test_help_lists_the_chosen_learners_settings():
    pqn = train_cli("--help", "--learner", "pqn").stdout
    assert "settings of learner pqn" in pqn and "q_lambda = 0.65 [leaf]" in pqn and "batch_size = " not in pqn
    assert "batch_size = 256" in train_cli("--help").stdout  # double DQN's by default
    assert "settings of learner pqn" in jaxbridge.settings_help(preset="pqn")  # the preset's learner
    mc = jaxbridge.settings_help("examples.monte_carlo_q:MonteCarloQ")
    assert "epochs = 50\n    Full-batch Adam steps per cycle." in mc and "memory = 20" in mc


def test_a_learner_registered_by_name_brings_its_settings():
    from examples.monte_carlo_q import MonteCarloQ
    from jaxbridge.core.learner_settings import register

    register("mc_by_name", "examples.monte_carlo_q:MonteCarloQ")  # what a built-in learner's entry does
    config = jaxbridge.make_config("light_switch_door", learner="mc_by_name", epochs=3)
    assert type(config.learner) is MonteCarloQ and (config.learner.epochs, config.learner.memory) == (3, 20)
    assert TrainConfig.from_dict(json.loads(json.dumps(config.to_dict()))) == config


def flat(config: TrainConfig) -> dict:
    """`config` as a flat config.json of version 11 held it."""
    nested = config.to_dict()
    nested.pop("tokens")  # the token network's settings came later still
    learner = {k: v for k, v in nested.pop("learner").items() if k != "name"}
    return {**nested, **learner, "learner": config.learner.name, "config_version": 11}


def test_every_older_config_version_loads_as_it_was_trained():
    v11 = json.loads((V11_RUN / "config.json").read_text())
    assert v11["config_version"] == 11
    loaded = TrainConfig.from_dict(v11)
    assert type(loaded.learner) is DQNSettings and loaded.learner.updates_per_cycle == 10 and loaded.learner.buffer_capacity == 256
    assert flat(loaded) == {**{k: v for k, v in v11.items() if k not in ("q_lambda", "pqn_epochs", "pqn_minibatches")},
                            "count_bonus": 0.0, "keep_cycles": []}  # added later: their defaults, what the run had
    assert dataclasses.asdict(loaded.tokens) == {
        "attention_fixed_penalty": False, "attention_log_scale": False,  # added later: what the run had
        "attention_distance": "now", "attention_preference": 4.0,  # not the defaults: what it had
        "attention_robot_features": True, "attention_kind_noise": True}
    pqn = TrainConfig(learner="pqn", q_lambda=0.3, pqn_epochs=8)
    older = TrainConfig.from_dict({**flat(pqn), "batch_size": 64, "polyak_tau": 0.01})
    assert dataclasses.replace(older, tokens=pqn.tokens) == pqn  # DQN's fields dropped
    v1 = {k: v for k, v in v11.items() if k not in ("approach", "split_task_state", "learner", "q_lambda", "loop_guard")}
    old = TrainConfig.from_dict({**v1, "config_version": 1})
    assert (old.approach, old.learner.split_task_state, old.loop_guard, old.learner.name) == ("ours", False, False, "dqn")
    with pytest.raises(ValueError, match="unknown config fields: bogus"):
        TrainConfig.from_dict({**v11, "bogus": 1})


UNRECORDED_BY_V11 = ("test_decisions",)  # metrics added after version 11's runs


def metrics(run_dir: Path) -> list[dict]:
    return list(csv.DictReader((run_dir / "metrics.csv").open()))


def test_a_version_11_run_directory_evaluates_and_resumes_exactly(tmp_path):
    from jaxbridge.learn.setup import make_setup
    from jaxbridge.run import rundir
    from jaxbridge.run.evaluate import evaluate_run
    from jaxbridge.run.hooks import RunHooks
    from jaxbridge.run.runner import train

    run = tmp_path / "v11"
    shutil.copytree(V11_RUN, run)
    _, step, _, result, _ = evaluate_run(run)  # its cycle-1 checkpoint, on the run's own test tasks
    assert step == 1 and np.mean(result.success) == pytest.approx(float(metrics(run)[0]["test_solve_rate"]))
    jaxbridge.resume(run)
    whole = tmp_path / "whole"
    rundir.prepare(whole, overwrite=False)
    train(make_setup(TrainConfig.from_dict(json.loads((V11_RUN / "config.json").read_text()))), whole,
          RunHooks(progress=False))
    resumed, uninterrupted = metrics(run), metrics(whole)
    assert [r["cycle"] for r in resumed] == ["1", "2"] and len(uninterrupted) == 2
    for got, want in zip(resumed, uninterrupted):
        assert got.keys() == want.keys()
        for column in got:
            if got["cycle"] == "1" and column in UNRECORDED_BY_V11:
                assert got[column] == "nan", column  # the old checkpoint's cycle: unknown, not made up
                continue
            assert float(got[column]) == pytest.approx(float(want[column]), rel=1e-5, abs=1e-7), column
    assert json.loads((run / "config.json").read_text())["config_version"] == 11  # the run's file is kept as it was


SETTINGS_CLASSES = (TrainConfig, DQNSettings, PQNSettings)
NAMES = {f.name for cls in SETTINGS_CLASSES for f in dataclasses.fields(cls)} - {"name", "env", "learner"}


def parallel_lists(source: str) -> list[str]:
    """The module-level assignments of `source` that name two or more settings: a second declaration."""
    found = []
    for node in ast.parse(source).body:
        value = node.value if isinstance(node, (ast.Assign, ast.AnnAssign)) else None
        strings = {e.value for e in ast.walk(value) if isinstance(e, ast.Constant) and isinstance(e.value, str)} if value else set()
        if len(strings & NAMES) >= 2:
            found.append(f"line {node.lineno} lists {sorted(strings & NAMES)}")
    return found


def test_each_field_is_declared_once():
    """No field is declared by two settings classes, and no module of the package holds a second list,
    table or tuple of settings' names (presets set values by name: that is a use, not a declaration)."""
    annotated = [name for cls in {c for s in SETTINGS_CLASSES for c in s.__mro__}
                 for name in cls.__dict__.get("__annotations__", {}) if dataclasses.is_dataclass(cls)]
    assert len(annotated) == len(set(annotated)), sorted(n for n in annotated if annotated.count(n) > 1)
    found = {str(path.relative_to(ROOT)): lists for path in sorted((ROOT / "jaxbridge").rglob("*.py"))
             if path.name != "presets.py" and (lists := parallel_lists(path.read_text()))}
    assert not found, found


def test_the_declaration_check_finds_a_parallel_list():
    assert parallel_lists('LEAF_FIELDS = ("learning_rate", "gamma")\nRANGES = {"gamma": (0, 1)}\nX = ("gamma",)') == [
        "line 1 lists ['gamma', 'learning_rate']"]
