"""train.py's setting flags, made from the settings' declarations: a command line gives the config that the
same settings given by keyword give, and a value its declaration refuses is a one-line flag error (exit 2)."""
import dataclasses

import pytest
from run_helpers import cli_in_process

import jaxbridge
import train
from jaxbridge.core import grid
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.learner_settings import DQNSettings


def from_flags(*argv: str) -> tuple[TrainConfig, object]:
    """The config train.py resolves from `argv`, and the parsed flags."""
    args = train.parse_args(list(argv))
    return jaxbridge.make_config(settings=args.set, **train.given_settings(args)), args


@pytest.mark.parametrize("argv,keywords", [
    ("--env coffee --preset authors --num-seeds 32 --first-seed 200 --cycles 100 --keep-cycles 10,25,50",
     dict(env="coffee", preset="authors", num_seeds=32, first_seed=200, cycles=100, keep_cycles=(10, 25, 50))),
    ("--env doorknobs --env-quirks raw_offsets --call-planner-bonus 0.25 --updates-per-cycle 50 --batch-size 32",
     dict(env="doorknobs", env_quirks=("raw_offsets",), call_planner_bonus=0.25, updates_per_cycle=50, batch_size=32)),
    ("--loop-guard false --param-samples iid --step-gamma 0.9 --n-sample 7 --test-protocol authors",
     dict(loop_guard=False, param_samples="iid", step_gamma=0.9, n_sample=7, test_protocol="authors")),
    ("--preset pqn --num-seeds 4 --seed-block 2 --checkpoint-every 3", dict(preset="pqn", num_seeds=4, seed_block=2,
                                                                            checkpoint_every=3)),
])
def test_a_command_line_makes_the_config_its_settings_make(argv, keywords):
    config, _ = from_flags(*argv.split())
    assert config == jaxbridge.make_config(**keywords)
    assert all(getattr(config.learner if hasattr(config.learner, name) else config, name) == value
               for name, value in keywords.items())  # each flag reached its setting


def test_set_overrides_a_flag_and_sweep_keeps_its_grid():
    config, _ = from_flags("--batch-size", "32", "--set", "batch_size=64", "--set", "hidden_sizes=64x64")
    assert (config.learner.batch_size, config.learner.hidden_sizes) == (64, (64, 64))
    config, args = from_flags("--num-seeds", "2", "--sweep", "learning_rate=1e-3,3e-4", "--sweep", "epsilon_decay=3.8e-5,1e-4")
    assert train.given_settings(args) == {"num_seeds": 2}
    assert grid.parse_sweeps(args.sweep, config) == {"learning_rate": (1e-3, 3e-4), "epsilon_decay": (3.8e-5, 1e-4)}


@pytest.mark.parametrize("argv,message", [
    ("--num-seeds 0", "argument --num-seeds: expected a positive integer, got 0"),
    ("--keep-cycles 3,1", "argument --keep-cycles: expected increasing positive integers, each once"),
    ("--call-planner-bonus -1", "argument --call-planner-bonus: expected a non-negative number, got -1.0"),
    ("--step-gamma 0", "argument --step-gamma: expected a number above 0 and at most 1, got 0.0"),
    ("--epsilon-end 1.5", "argument --epsilon-end: expected a number at least 0 and at most 1, got 1.5"),
    ("--param-samples sobol", "argument --param-samples: invalid choice: 'sobol'"),
    ("--loop-guard maybe", "argument --loop-guard: expected true or false, got 'maybe'"),
])
def test_a_value_out_of_its_declaration_is_a_one_line_flag_error(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        train.parse_args(argv.split())
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and message in err and err.count("\n") == 1, err


def flagged() -> list[tuple[type, dataclasses.Field]]:
    """The declared settings train.py has a generated flag for."""
    own = [f for f in dataclasses.fields(TrainConfig) if f.name not in ("learner", *train.NO_FLAG)]
    return [(TrainConfig, f) for f in own] + [(DQNSettings, f) for f in dataclasses.fields(DQNSettings)
                                              if f.name in train.LEARNER_FLAGS]


def test_every_flag_takes_its_default_and_refuses_past_its_declared_range(capsys):
    for cls, field in flagged():
        flag, default = "--" + field.name.replace("_", "-"), field.default
        if default != ():  # an empty list is the flag left out
            text = ",".join(map(str, default)) if isinstance(default, tuple) else str(default)
            assert getattr(train.parse_args([flag, text]), field.name) == default, field.name
        low, high, low_included = field.metadata.get("range") or (None, None, True)
        outside = ([low - 1 if low_included else low] if low is not None else []) + ([high + 1] if high is not None else [])
        for value in outside:
            with pytest.raises(SystemExit) as exit_:
                train.parse_args([flag, str(value)])
            assert exit_.value.code == 2 and f"argument {flag}: expected" in capsys.readouterr().err, (flag, value)


def test_help_lists_every_setting_flag():
    proc = cli_in_process("train.py", "--help")
    assert proc.returncode == 0 and "settings of the run" in proc.stdout
    assert all(f"--{field.name.replace('_', '-')} " in proc.stdout for _, field in flagged())


def test_resume_refuses_any_setting_flag():
    proc = cli_in_process("train.py", "--resume", "runs", "--n-sample", "5", "--batch-size", "8")
    assert proc.returncode == 2 and "drop --n-sample, --batch-size" in proc.stderr, proc.stderr
