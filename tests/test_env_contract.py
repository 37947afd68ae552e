"""The env contract: check_env on envs that keep it and on envs that break it, the registry, plug-in envs
from the command line."""
import csv
import subprocess
import sys
from pathlib import Path

import pytest

import envs_jax
from envs_jax import env_class, register
from envs_jax.base import NoveltyPredicate
from examples.locked_box import LockedBox
from jaxbridge import EnvContractError, check_env
import plugin_envs
from run_helpers import cli_in_process

ROOT = Path(__file__).resolve().parents[1]


def test_the_example_env_keeps_the_contract_and_its_oracle_solves_its_tasks():
    assert check_env(LockedBox) is LockedBox
    assert check_env(LockedBox.for_tasks(LockedBox.test_tasks(0, 2))) is LockedBox  # an instance: its class


@pytest.mark.parametrize("broken, message", [
    (plugin_envs.ShortFeatures, "ShortFeatures.features: expected float32[3], got float32[2]"),
    (plugin_envs.FloatGoal, "FloatGoal.goal_reached: expected bool[], got float32[]"),
    (plugin_envs.CountingStep, "CountingStep.step: expected the same values from the same inputs"),
    (plugin_envs.WrongAbstraction, "WrongAbstraction.abstract(reset(task)): expected the atoms of planner_problem"),
    (plugin_envs.SmallPlanBound, "SmallPlanBound.plan_bound: expected (states, operators) at least the"),
    (plugin_envs.StillRobot, "StillRobot.full_state_varying: expected every entry that changes within a task, got entries [0]"),
    (plugin_envs.EmptyBox, "EmptyBox.full_state_filled: expected every entry a training task sets, got entries [4]"),
    (plugin_envs.NeverHolds, "NeverHolds.full_state_filled: expected every entry a training task sets, got entries [1] "
                             "also set in random bridges' episodes"),
    (plugin_envs.ClumsyOracle, "ClumsyOracle.oracle_bridge: expected every test task of seed 0 solved"),
    (plugin_envs.LeakyObjects, "LeakyObjects.objects: expected every masked-out slot zero and not interactable"),
    (plugin_envs.HiddenCandidate, "HiddenCandidate.objects: expected no slot outside candidate_slots interactable, got slots [2]"),
    (plugin_envs.MisnamedKey, "MisnamedKey.object_names: expected the planner's type of every planner object it names, "
                              "got ('cell0', 'cell', 'key')"),
])
def test_check_env_names_the_broken_method_and_what_it_expected(broken, message):
    with pytest.raises(EnvContractError) as caught:
        check_env(broken)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_check_env_refuses_a_class_with_missing_methods_or_attributes():
    class Half(envs_jax.NoveltyEnv):
        name, skills, action_dim, num_features, full_state_size = "half", (envs_jax.SkillSpec("Go"),), 1, 1, 1

    with pytest.raises(EnvContractError, match=r"Half: expected every abstract method .* missing abstract, "):
        check_env(Half)

    class Nameless(LockedBox):
        num_features = 0

    with pytest.raises(EnvContractError, match=r"Nameless.num_features: expected a positive int, got 0"):
        check_env(Nameless)

    class Unseen(LockedBox):  # a novelty predicate on a feature its type lacks
        novelty_predicates = (NoveltyPredicate("box", "locked"),)

    with pytest.raises(EnvContractError, match=r"Unseen.novelty_predicates: expected NoveltyPredicates on features of their type"):
        check_env(Unseen)


def test_env_names_resolve_to_classes_and_bad_names_say_why():
    assert env_class("light_switch_door") is envs_jax.LightSwitchDoor
    assert env_class("examples.locked_box:LockedBox") is LockedBox
    register("tests_locked_box", lambda: LockedBox)  # a factory: the module is imported when the name is used
    assert env_class("tests_locked_box") is LockedBox and "tests_locked_box" in envs_jax.registered()
    for spec, message in (("nowhere", "unknown env 'nowhere'; choose from coffee, coffee_distractor, doorknobs, doorknobs_distractor, light_switch_door"),
                          ("no_such_module:Env", "cannot import module 'no_such_module'"),
                          ("examples.locked_box:Missing", "has no attribute 'Missing'"),
                          ("tests.plugin_envs:NotAnEnv", "not a subclass of envs_jax.NoveltyEnv")):
        with pytest.raises(ValueError, match=message):
            env_class(spec)
    with pytest.raises(ValueError, match="without ':'"):
        register("a:b", LockedBox)


def train(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "train.py", "--no-progress", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)


def test_a_plugin_env_trains_from_the_command_line_and_its_bridge_beats_the_random_one(tmp_path):
    proc = train("--env", "examples.locked_box:LockedBox", "--approaches", "ours,random", "--num-seeds", "2",
                 "--cycles", "3", "--updates-per-cycle", "300", "--out", str(tmp_path))  # enough to learn its one key
    assert proc.returncode == 0, proc.stderr
    config = (tmp_path / "locked_box" / "ours" / "config.json").read_text()
    assert '"env": "examples.locked_box:LockedBox"' in config  # what --resume and eval.py load again
    rows = {r["approach"]: r for r in csv.DictReader((tmp_path / "locked_box" / "results.csv").open())}
    assert set(rows) == {"ours", "random"}
    last = {a: [float(r["test_solve_rate"]) for r in csv.DictReader((tmp_path / "locked_box" / a / "metrics.csv").open())
                if r["cycle"] == "3"] for a in ("ours", "random")}
    assert sum(last["ours"]) / 2 >= 0.8 > 0.3 >= sum(last["random"]) / 2, last  # test solve rate at cycle 3


def test_a_broken_plugin_env_is_refused_in_one_line_naming_the_method(tmp_path):
    proc = cli_in_process("train.py", "--no-progress", "--env", "tests.plugin_envs:ShortFeatures", "--out", str(tmp_path))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().count("\n") == 0
    assert "ShortFeatures.features: expected float32[3], got float32[2]" in proc.stderr
    assert not any(tmp_path.iterdir())  # refused before anything was written
