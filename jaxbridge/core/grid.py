"""Hyperparameter grids: `train.py --sweep key=v1,v2 --sweep key2=...` as the settings of one experiment.

A setting is a set of config overrides (one value per swept key: a TrainConfig field, or one of its
learner's or its token network's, by name); the grid is their cartesian product, in the order the keys
and values were given.
Settings that differ only in leaf hyperparameters (`setting(..., leaf=True)`, core/settings.py) share one
compiled program; any other key (n_sample, widths, updates per cycle, ...) makes programs of its own
(`program_groups`).
"""
from __future__ import annotations

import dataclasses
import itertools

from jaxbridge.core import settings as declared
from jaxbridge.core.config import TrainConfig


def sections(config: TrainConfig) -> tuple[type, ...]:
    """The settings classes whose fields set `config` by name: TrainConfig's, its learner's, its token network's."""
    return TrainConfig, type(config.learner), type(config.tokens)


def owner(config: TrainConfig, key: str) -> type | None:
    """The settings class that declares `key` for `config` (one of its `sections`); None if none does."""
    for cls in sections(config):
        if key in declared.fields_of(cls) and key != "name":
            return cls
    return None


def sweepable(config: TrainConfig) -> list[str]:
    return [name for cls in sections(config) for name in declared.fields_of(cls)
            if name != "name" and declared.is_swept(cls, name)]


def parse_value(key: str, text: str, config: TrainConfig | None = None):
    """`text` as a value of setting `key` of `config` (default: TrainConfig's defaults), as
    core/settings.parse_value reads it; ValueError (one line) if it is not one."""
    config = config or TrainConfig()
    cls = owner(config, key)
    if cls is None:
        raise ValueError(f"{key}: not a setting of TrainConfig, of learner {config.learner.name} or of the token network")
    return declared.parse_value(cls, key, text)


def parse_sweeps(texts: list[str], config: TrainConfig | None = None) -> dict[str, tuple]:
    """{key: values} from `key=v1,v2` texts, for a sweep from `config` (default: TrainConfig's defaults);
    ValueError (one line) for an unknown or unsweepable key, a value of the wrong type or out of range, a
    repeated key or value."""
    config, grid = config or TrainConfig(), {}
    for text in texts:
        key, sep, values = text.partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not values.strip():
            raise ValueError(f"--sweep {text!r}: expected key=value1,value2,...")
        cls = owner(config, key)
        if cls is None:
            raise ValueError(f"--sweep {key}: not a hyperparameter; sweepable: {', '.join(sweepable(config))}")
        if not declared.is_swept(cls, key):
            raise ValueError(f"--sweep {key}: sets the experiment, not a setting; sweepable: {', '.join(sweepable(config))}")
        if key in grid:
            raise ValueError(f"--sweep {key} is given twice; list all its values in one --sweep")
        try:
            parsed = tuple(declared.parse_value(cls, key, v.strip()) for v in values.split(","))
        except ValueError as err:
            raise ValueError(f"--sweep {err}") from None
        if len(set(parsed)) < len(parsed):
            raise ValueError(f"--sweep {key}: a value is repeated in {values}")
        for value in parsed:
            try:
                dataclasses.replace(config, **{key: value})
            except ValueError as err:
                raise ValueError(f"--sweep {key}={value}: {err}") from None
        grid[key] = parsed
    return grid


def settings(grid: dict[str, tuple]) -> list[dict]:
    """The grid's settings, each {key: value}: the cartesian product, the first key slowest."""
    return [dict(zip(grid, values)) for values in itertools.product(*grid.values())]


def value_text(value) -> str:
    """A value as a sweep's text writes it (hidden_sizes (64, 64): 64x64)."""
    return "x".join(map(str, value)) if isinstance(value, tuple) else str(value)


def setting_name(setting: dict) -> str:
    """A setting as it names its run directory and table row, e.g. learning_rate=0.0003,gamma=0.9."""
    return ",".join(f"{key}={value_text(value)}" for key, value in setting.items())


def program_groups(configs: list[TrainConfig]) -> list[list[int]]:
    """Indices of `configs` grouped by everything but their leaf hyperparameters: each group is one
    compiled program (learn/online.Cycle), in first-appearance order."""
    groups: dict[tuple, list[int]] = {}
    for i, config in enumerate(configs):
        groups.setdefault(config.static_values(), []).append(i)
    return list(groups.values())
