"""The config of a run, resolved as train.py resolves its flags and checked against its env."""
from __future__ import annotations

import dataclasses
from typing import Sequence

from jaxbridge.api.envs import EnvLike, env_name, load_env, seed_list
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.presets import preset_values
from jaxbridge.utils.errors import InputError, refusing


def make_config(env: EnvLike | None = None, seeds: int | Sequence[int] | None = None, cycles: int | None = None,
                **overrides) -> TrainConfig:
    """The TrainConfig a run of `env` trains with: TrainConfig's defaults, then its preset's values for the
    env (`preset="authors"` for the authors', default jaxbridge's), then `seeds` (a count from 0, or
    consecutive seeds), `cycles` and any field as a keyword; None means "not given". Checked as train.py
    checks it (InputError in one line: an unknown env, field or learner, a value out of range, a quirk or
    test protocol the env lacks, episodes that overflow the replay buffer, a seed block above the seeds;
    a learner of your own is checked against the learner contract when a training is prepared)."""
    given = {field: value for field, value in overrides.items() if value is not None}
    unknown = sorted(set(given) - {f.name for f in dataclasses.fields(TrainConfig)})
    if unknown:
        raise InputError(f"unknown TrainConfig field {', '.join(unknown)} (help(jaxbridge.TrainConfig) lists them)")
    if seeds is not None:
        listed = seed_list(seeds)
        if listed != list(range(listed[0], listed[0] + len(listed))):
            raise InputError(f"seeds must be consecutive, got {listed}")
        given.update(first_seed=listed[0], num_seeds=len(listed))
    if cycles is not None:
        given["cycles"] = cycles
    env = TrainConfig.env if env is None else env
    env_cls = load_env(env)
    with refusing():  # a value out of its range, e.g. a negative bonus
        config = TrainConfig(env=env_name(env), **{**preset_values(given.pop("preset", TrainConfig.preset), env_cls),
                                                   **given})
    _check_fits_env(config, env_cls)
    return config


def _check_fits_env(config: TrainConfig, env_cls) -> None:
    """Refuse a config the env cannot train with (see make_config)."""
    with refusing("env_quirks"):
        env_cls.check_quirks(config.env_quirks)
    if config.test_protocol not in env_cls.test_protocols:
        raise InputError(f"{{setting}} {config.test_protocol!r}: {env_cls.name} has "
                         f"{', '.join(f'{k} ({v})' for k, v in env_cls.test_protocols.items())}", "test_protocol")
    with refusing("episodes_per_cycle"):
        config.check_buffer_fits()
    _check_learner(config, env_cls)
    if config.seed_block > config.num_seeds:
        raise InputError(f"{{setting}} {config.seed_block} is larger than the {config.num_seeds} seeds", "seed_block")


def _check_learner(config: TrainConfig, env_cls) -> None:
    """Refuse a learner that does not load (an unknown name, a module or factory that is not there); its
    contract is checked on the training's own setups (api/training.prepare)."""
    from jaxbridge.learn.learners import learner_factory
    with refusing("learner"):
        learner_factory(config.learner)