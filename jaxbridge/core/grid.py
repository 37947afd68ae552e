"""Hyperparameter grids: `train.py --sweep key=v1,v2 --sweep key2=...` as the settings of one experiment.

A setting is a set of config overrides (one value per swept key); the grid is their cartesian product,
in the order the keys and values were given. Settings that differ only in numeric hyperparameters
(config.LEAF_FIELDS) share one compiled program; any other key (n_sample, widths, updates per cycle,
...) makes programs of its own (`program_groups`).
"""
from __future__ import annotations

import dataclasses
import itertools
import typing

from jaxbridge.core.config import LEAF_FIELDS, TrainConfig

# What an experiment is rather than how it learns: not sweepable (use separate experiments).
NOT_SWEPT = ("env", "approach", "preset", "env_quirks", "test_protocol", "num_seeds", "first_seed", "cycles",
             "seed_block", "checkpoint_every")
FIELDS = {f.name: f for f in dataclasses.fields(TrainConfig)}
SWEEPABLE = tuple(name for name in FIELDS if name not in NOT_SWEPT)


def parse_value(key: str, text: str):
    """`text` as a value of TrainConfig field `key` (booleans: true/false/1/0; hidden_sizes: 64x64;
    env_quirks: names joined by + or none); ValueError (one line) if it is not one."""
    kind = typing.get_type_hints(TrainConfig)[key]
    try:
        if kind is bool:
            if text.lower() not in ("true", "false", "1", "0"):
                raise ValueError
            return text.lower() in ("true", "1")
        if kind is int:
            return int(text)
        if kind is float:
            return float(text)
        if key == "hidden_sizes":  # e.g. 64x64
            return tuple(int(w) for w in text.split("x"))
        if key == "env_quirks":  # e.g. raw_offsets, or a+b (a comma would start the next value of a sweep)
            return () if text == "none" else tuple(text.split("+"))
        return text
    except ValueError:
        expected = {"hidden_sizes": "widths like 64x64", bool: "true or false", int: "an integer",
                    float: "a number"}.get(key if key == "hidden_sizes" else kind, "a value")
        raise ValueError(f"{key}: expected {expected}, got {text!r}") from None


def parse_sweeps(texts: list[str]) -> dict[str, tuple]:
    """{key: values} from `key=v1,v2` texts; ValueError (one line) for an unknown or unsweepable key, a
    value of the wrong type or out of range, a repeated key or value."""
    grid: dict[str, tuple] = {}
    for text in texts:
        key, sep, values = text.partition("=")
        key = key.strip().replace("-", "_")
        if not sep or not values.strip():
            raise ValueError(f"--sweep {text!r}: expected key=value1,value2,...")
        if key not in FIELDS:
            raise ValueError(f"--sweep {key}: not a hyperparameter; sweepable: {', '.join(SWEEPABLE)}")
        if key in NOT_SWEPT:
            raise ValueError(f"--sweep {key}: sets the experiment, not a setting; sweepable: {', '.join(SWEEPABLE)}")
        if key in grid:
            raise ValueError(f"--sweep {key} is given twice; list all its values in one --sweep")
        try:
            parsed = tuple(parse_value(key, v.strip()) for v in values.split(","))
        except ValueError as err:
            raise ValueError(f"--sweep {err}") from None
        if len(set(parsed)) < len(parsed):
            raise ValueError(f"--sweep {key}: a value is repeated in {values}")
        for value in parsed:
            try:
                TrainConfig(**{key: value})
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
        static = tuple(getattr(config, name) for name in FIELDS if name not in LEAF_FIELDS)
        groups.setdefault(static, []).append(i)
    return list(groups.values())
