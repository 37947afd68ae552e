"""train.py's work once its flags are parsed: the config, the experiment directory, new or resumed runs."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable

from jaxbridge.commands.envs import load_env
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.approaches import APPROACHES
from jaxbridge.utils.cli import UsageError

# train.py flags that set the run's config (flag name = config field); --resume takes the saved config.
CONFIG_FLAGS = ("env", "num_seeds", "first_seed", "cycles", "episodes_per_cycle", "train_steps", "updates_per_cycle",
                "batch_size", "call_planner_bonus", "checkpoint_every", "seed_block")


def make_config(flags: dict) -> tuple[TrainConfig, type]:
    """The config of the flags given (None: not given) and its env class; refused in one line where it
    cannot train."""
    given = {field: flags[field] for field in CONFIG_FLAGS if flags.get(field) is not None}
    spec = given.pop("env", TrainConfig.env)
    env_cls = load_env(spec)
    config = TrainConfig(env=spec, **{**env_cls.train_defaults, **given})
    if config.episodes_per_cycle * config.train_steps > config.buffer_capacity:
        raise UsageError(f"--episodes-per-cycle x {config.train_steps} steps must fit the replay buffer "
                         f"({config.buffer_capacity} transitions)")
    if config.seed_block > config.num_seeds:
        raise UsageError(f"--seed-block {config.seed_block} is larger than the {config.num_seeds} seeds")
    needed = {seed: env_cls.train_task(seed).min_steps for seed in config.seeds}
    worst = max(needed, key=needed.get)
    if config.train_steps < needed[worst]:
        raise UsageError(f"--train-steps {config.train_steps} is too small to ever reach the goal: seed {worst}'s "
                         f"training task needs at least {needed[worst]} steps")
    return config, env_cls


def default_approaches(env_cls) -> list[str]:
    """What train.py trains when --approaches is not given (saying so where it is not all six)."""
    approaches = list(env_cls.default_approaches or APPROACHES)
    skipped = [a for a in APPROACHES if a not in approaches]
    if skipped:
        print(f"{env_cls.name}: not running {', '.join(skipped)} by default ({env_cls.why_not_all}); "
              f"--approaches all runs them", file=sys.stderr)
    return approaches


def new_experiment(flags: dict, approaches: list[str] | None, out: Path, name: str | None, overwrite: bool,
                   progress: bool, workers: int | None, devices: list) -> tuple[Path, Callable[[], dict]]:
    """(experiment directory, the training to run) of a new experiment."""
    from jaxbridge.run.experiments import train_approaches
    from jaxbridge.run.runner import prepare_run_dir

    config, env_cls = make_config(flags)
    approaches = approaches or default_approaches(env_cls)
    out_dir = out / (name or env_cls.name)
    try:
        prepare_run_dir(out_dir, overwrite)
    except FileExistsError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"cannot write experiment directory {out_dir}: {err.strerror}") from None
    return out_dir, lambda: train_approaches(config, approaches, out_dir, progress, workers=workers, devices=devices)


def resumed(run_dir: Path, progress: bool, workers: int | None, devices: list) -> Callable[[], dict]:
    """The training that continues the experiment (or one approach's run) in `run_dir`."""
    from jaxbridge.learn.setup import make_setup
    from jaxbridge.run.experiments import is_experiment_dir, load_experiment, train_approaches
    from jaxbridge.run.runner import load_config, train

    try:
        if is_experiment_dir(run_dir):
            config, approaches = load_experiment(run_dir)
            load_env(config.env)
            return lambda: train_approaches(config, approaches, run_dir, progress, resume=True, workers=workers,
                                            devices=devices)
        config = load_config(run_dir)
        setup = make_setup(config, load_env(config.env))
        return lambda: {config.approach: train(setup, run_dir, progress, resume=True, devices=devices)}
    except ValueError as err:
        raise UsageError(str(err)) from None


def report(name: str, info: dict) -> str:
    """One approach's summary line."""
    at = info["test_solve_rate_at"]
    last = max((int(c) for c in at), default=None)
    return (f"{name:>20}: mean test solve rate at the last cycle {info['mean_test_solve_rate_per_cycle'][-1]:.2f}; "
            f"smooth reward at cycle {info['cycles']}: {info['smooth_reward_final']['mean']:.3f}"
            + (f"; at cycle {last}: {at[str(last)]['mean']:.2f}" if last else "") + f" ({info['elapsed_s']:.0f} s)")
