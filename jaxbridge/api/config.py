"""The config of a run, resolved as train.py resolves its flags and checked against its env."""
from __future__ import annotations

import dataclasses
from typing import Sequence

from jaxbridge.api.envs import EnvLike, check_test_protocol, env_name, load_env, seed_list
from jaxbridge.core import grid, presets
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.learner_settings import LearnerSettings, settings_class
from jaxbridge.core.settings import declared, described
from jaxbridge.core.token_settings import TokenSettings
from jaxbridge.utils.errors import InputError, refusing


def make_config(env: EnvLike | None = None, seeds: int | Sequence[int] | None = None, cycles: int | None = None,
                settings: Sequence[str] | None = None, **overrides) -> TrainConfig:
    """The TrainConfig a run of `env` trains with: TrainConfig's defaults, then its preset's values for the
    env (`preset="authors"` for the authors', default jaxbridge's), then `seeds` (a count from 0, or
    consecutive seeds), `cycles` and any field (the learner's too: `batch_size=64`) as a keyword; None means
    "not given". Checked as train.py
    checks it (InputError in one line: an unknown env, field or learner, a value out of range, a quirk or
    test protocol the env lacks, episodes that overflow the replay buffer, a seed block above the seeds;
    a learner of your own is checked against the learner contract when a training is prepared)."""
    return config_and_env(env, seeds, cycles, settings, **overrides)[0]


def config_and_env(env: EnvLike | None = None, seeds: int | Sequence[int] | None = None, cycles: int | None = None,
                   settings: Sequence[str] | None = None, **overrides) -> tuple[TrainConfig, type]:
    """`make_config`'s config with the env class it resolved, so that a training resolves its env once."""
    given = {field: value for field, value in overrides.items() if value is not None}
    if seeds is not None:
        listed = seed_list(seeds)
        if listed != list(range(listed[0], listed[0] + len(listed))):
            raise InputError(f"seeds must be consecutive, got {listed}")
        given.update(first_seed=listed[0], num_seeds=len(listed))
    if cycles is not None:
        given["cycles"] = cycles
    env = TrainConfig.env if env is None else env
    env_cls = load_env(env)
    with refusing():  # an unknown setting or learner, a value out of its range (e.g. a negative bonus)
        config = _over_preset(presets.preset_values(given.pop("preset", TrainConfig.preset), env_cls),
                              env=env_name(env), **given)
    with refusing("set"):
        config = dataclasses.replace(config, **setting_values(settings or [], config))
    _check_fits_env(config, env_cls)
    return config, env_cls


def _over_preset(values: dict, **given) -> TrainConfig:
    """`given` over a preset's `values`. A preset's value for a setting the chosen learner lacks is left out
    (an env's double-DQN defaults do not apply to PQN); a given one is refused (ValueError). A learner given
    as settings is taken whole: the preset's values for it are left out."""
    learner = given.get("learner", values.get("learner", TrainConfig.learner.name))
    kept = {f.name for f in (*dataclasses.fields(TrainConfig), *declared(TokenSettings))}
    if not isinstance(learner, LearnerSettings):
        kept |= {f.name for f in declared(settings_class(learner))}
    return TrainConfig(**{**{k: v for k, v in values.items() if k in kept}, **given})


def setting_values(texts: Sequence[str], config: TrainConfig) -> dict:
    """{name: value} of `NAME=VALUE` texts, each value read as the setting of `config` (or of its learner)
    it names is typed; ValueError in one line for a malformed text or an unknown name."""
    values = {}
    for text in texts:
        name, sep, value = text.partition("=")
        if not sep:
            raise ValueError(f"{text!r}: expected NAME=VALUE")
        values[name.strip().replace("-", "_")] = grid.parse_value(name.strip().replace("-", "_"), value.strip(), config)
    return values


def settings_help(learner: str | None = None, preset: str | None = None) -> str:
    """What train.py --help lists below its flags (the run's settings are flags there): the settings of
    `learner` (default: the preset's learner, else double DQN), then the object-token network's, each with
    its default and its docstring ("[leaf]": a sweep over it shares one compiled program)."""
    name = learner or presets.preset_learner(preset) or TrainConfig.learner.name
    with refusing("learner"):
        cls = settings_class(name)
    return (f"settings of learner {name} (--set NAME=VALUE; --sweep NAME=V1,V2):\n" + described(cls, skip=("name",))
            + "\n\nsettings of the object-token network (the learned selector's; --set, --sweep):\n"
            + described(TokenSettings))


def _check_fits_env(config: TrainConfig, env_cls) -> None:
    """Refuse a config the env cannot train with (see make_config)."""
    with refusing("env_quirks"):
        env_cls.check_quirks(config.env_quirks)
    check_test_protocol(env_cls, config.test_protocol)
    with refusing("episodes_per_cycle"):
        config.check_buffer_fits()
    if config.seed_block > config.num_seeds:
        raise InputError(f"{{setting}} {config.seed_block} is larger than the {config.num_seeds} seeds", "seed_block")


def default_test_protocol(env_cls) -> str:
    """The test protocol a plain `train.py --env E` trains on, and `eval.py --env E --bridge B` evaluates."""
    return presets.preset_values(presets.DEFAULT_PRESET, env_cls).get("test_protocol", TrainConfig.test_protocol)


def preset_values(preset: str, env: EnvLike) -> dict:
    """{setting: value}: what `preset` (a key of PRESETS) sets on `env` before yours, `make_config`'s first
    layer over TrainConfig's defaults, with "preset" itself. InputError for an unknown preset or env."""
    env_cls = load_env(env)
    with refusing("preset"):
        return presets.preset_values(preset, env_cls)
