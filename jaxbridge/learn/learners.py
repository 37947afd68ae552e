"""The learners by name (`config.learner.name`): each name's factory makes the learner (learn/learner.QLearner)
of a run from its config, the training env, the bridge's observation width and whether that observation
is the full state; it reads its settings from `config.learner` (their class: core/learner_settings.py).
A learner of your own is `package.module:factory` (docs/NEW_LEARNER.md), or `register`ed."""
from __future__ import annotations

from typing import Callable

from envs_jax.base import NoveltyEnv
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.learner_settings import DQNSettings, plugin_factory, register_settings
from jaxbridge.learn import dqn, pqn
from jaxbridge.learn.learner import QLearner

LearnerFactory = Callable[[TrainConfig, NoveltyEnv, int, bool], QLearner]

_REGISTRY: dict[str, LearnerFactory] = {}


def register(name: str, factory: LearnerFactory) -> None:
    """Give a learner factory a short name for `--learner`, with the settings class it is marked with
    (core/learner_settings.learner_settings; double DQN's if unmarked)."""
    if not name or ":" in name:
        raise ValueError(f"a learner name is a non-empty string without ':', got {name!r}")
    _REGISTRY[name] = factory
    register_settings(name, getattr(factory, "settings", DQNSettings))


# The built-in learners, one line each: a factory marked with its settings class (double DQN's if unmarked).
register("dqn", dqn.make_learner)
register("pqn", pqn.make_learner)


def registered() -> list[str]:
    return list(_REGISTRY)


def learner_factory(spec: str) -> LearnerFactory:
    """The factory named by `spec`: a registered name or `package.module:factory`; ValueError in one line."""
    if spec in _REGISTRY:
        return _REGISTRY[spec]
    if ":" not in spec:
        raise ValueError(f"unknown learner {spec!r}; choose from {', '.join(_REGISTRY)}, or give package.module:factory")
    return plugin_factory(spec)
