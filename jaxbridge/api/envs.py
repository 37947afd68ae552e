"""Envs and their tasks for the Python API: by name, `package.module:Class` or class, checked once."""
from __future__ import annotations

import os
import sys
from typing import Iterable

import numpy as np

from envs_jax import NoveltyEnv, env_class, is_builtin, registered
from jaxbridge.core.check_env import EnvContractError, check_env
from jaxbridge.run.evaluate import sized_specs_per_seed
from jaxbridge.utils.errors import InputError, refusing

EnvLike = str | type[NoveltyEnv]


def env_names() -> list[str]:
    """The registered envs' names."""
    return registered()


def load_env(env: EnvLike) -> type[NoveltyEnv]:
    """The env class `env` names (or is); one not built in is checked against the env contract first
    (InputError naming what breaks it). `package.module:Class` resolves from the working directory too."""
    if not isinstance(env, str):
        name = env_name(env)
        return env if is_builtin(name) else _checked(env, name)
    if os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.insert(0, os.getcwd())  # `examples.locked_box:LockedBox` from the working directory
    with refusing():
        env_cls = env_class(env)
    return env_cls if is_builtin(env) else _checked(env_cls, env)


_CHECKED: set[type[NoveltyEnv]] = set()  # plug-in env classes that passed check_env in this process


def _checked(env_cls: type[NoveltyEnv], spec: str) -> type[NoveltyEnv]:
    """`env_cls` once check_env passed it; checked once per process (check_env traces: seconds)."""
    if env_cls not in _CHECKED:
        try:
            check_env(env_cls)
        except EnvContractError as err:
            raise InputError(f"env {spec} breaks the env contract: {err}") from None
        _CHECKED.add(env_cls)
    return env_cls


def env_name(env: EnvLike) -> str:
    """A name TrainConfig.env resolves: the registered name, or package.module:Class for a class."""
    if isinstance(env, str):
        return env
    if env.name in registered() and env_class(env.name) is env:
        return env.name
    return f"{env.__module__}:{env.__qualname__}"


def make_env(env: EnvLike, **capacity) -> NoveltyEnv:
    """An env instance: `env` by name ("light_switch_door", "package.module:Class") or class, sized by its
    capacity fields (e.g. `make_env("light_switch_door", max_cells=40, max_doors=6)`; default: the
    class's defaults). Its methods are the env contract (envs_jax/base.py, docs/NEW_ENV.md)."""
    return load_env(env)(**capacity)


def tasks(env: EnvLike, seeds: int | Iterable[int], num_tasks: int = 10, size: dict[str, int] | None = None,
          protocol: str = "jaxbridge") -> dict[int, list]:
    """Each seed's task specs: its test tasks (`env.test_tasks(seed, num_tasks, protocol)`), or with `size`
    (the env's `task_sizes`, e.g. {"cells": 40, "doors": 3}) tasks of that size, drawn as eval.py
    --task-size draws them. `seeds`: a count (0..n-1) or the seeds. Returns {seed: [spec, ...]}."""
    env_cls = load_env(env)
    if size is None:
        return {s: list(env_cls.test_tasks(s, num_tasks, protocol)) for s in seed_list(seeds)}
    return sized_specs_per_seed(seed_list(seeds), num_tasks, sized_tasks(env_cls, size))


def sized_tasks(env_cls: type[NoveltyEnv], size: dict[str, int]):
    """`size` as a task drawer `draw(rng) -> spec` (the env's `sized_task` hook), refused in one line
    (InputError about `task_size`) if the env has no such sizes or the values do not make a task."""
    if not env_cls.task_sizes:
        raise InputError(f"{{setting}}: env {env_cls.name} builds no tasks of a chosen size", "task_size")
    unknown = sorted(set(size) - set(env_cls.task_sizes))
    if unknown:
        raise InputError(f"{{setting}}: {env_cls.name} takes "
                         f"{', '.join(f'{k} ({v})' for k, v in env_cls.task_sizes.items())}; not {', '.join(unknown)}",
                         "task_size")
    with refusing("task_size", (ValueError, TypeError)):
        env_cls.sized_task(np.random.default_rng(0), **size)  # refuse bad sizes before anything is built
    return lambda rng: env_cls.sized_task(rng, **size)


def seed_list(seeds: int | Iterable[int]) -> list[int]:
    """A count (0..n-1) or the seeds themselves, as a list."""
    listed = list(range(seeds)) if isinstance(seeds, int) else [int(s) for s in seeds]
    if not listed or min(listed) < 0:
        raise InputError(f"seeds: a positive count or non-negative seeds, got {seeds!r}")
    return listed


def check_test_protocol(env_cls: type[NoveltyEnv], protocol: str) -> None:
    """InputError (about the setting test_protocol) unless `protocol` is one of the env's test protocols."""
    if protocol not in env_cls.test_protocols:
        raise InputError(f"{{setting}} {protocol!r}: {env_cls.name} has "
                         f"{', '.join(f'{k} ({v})' for k, v in env_cls.test_protocols.items())}", "test_protocol")
