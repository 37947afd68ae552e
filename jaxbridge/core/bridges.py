"""Hand-made bridge policies: random, pure planning ("none") and each env's oracle.

A bridge is a pure function `(params, obs: BridgeObs, key) -> BridgeAction`, called once per decision;
`params` is whatever it learns (None for these). Skill index `num_skills` is CallPlanner. Bridges are
frozen dataclasses, equal when their fields are, so equal bridges are one static argument to `jax.jit`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv

Bridge = Callable[[object, BridgeObs, jax.Array], BridgeAction]


@dataclass(frozen=True)
class RandomBridge:
    """A uniformly random applicable skill, CallPlanner included once it is applicable, with a parameter
    from the skill's sampler; the meta-policy then grounds it uniformly among its applicable ground
    operators. With `ground_operators` each skill is drawn as often as it has applicable ground
    operators, so the action is uniform over ground operators (the authors' draw: docs/DESIGN.md)."""

    env: NoveltyEnv
    ground_operators: bool = False

    def __call__(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        env = self.env
        k_skill, k_param = jax.random.split(key)
        weights = (obs.num_ground if self.ground_operators else obs.num_ground > 0).astype(jnp.float32)
        skill = jax.random.categorical(k_skill, jnp.log(weights))  # log 0 = -inf: never chosen
        params_all = env.sample_params(k_param)
        param = jnp.where(skill < env.num_skills, params_all[jnp.minimum(skill, env.num_skills - 1)], 0.0)
        return BridgeAction(skill=skill.astype(jnp.int32), param=param)


@dataclass(frozen=True)
class PurePlanningBridge:
    """No bridge: whenever the plan is stuck, re-plan from the current state (the paper's pure planning
    baseline). CallPlanner's "state changed" precondition does not apply to it."""

    env: NoveltyEnv

    def __call__(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        return BridgeAction(skill=jnp.int32(self.env.num_skills), param=jnp.float32(0.0))


@dataclass(frozen=True)
class OracleBridge:
    """The env's hand-written novelty fixer (`NoveltyEnv.oracle_bridge`, e.g. set the door keys, then
    CallPlanner)."""

    env: NoveltyEnv

    def __call__(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        return self.env.oracle_bridge(params, obs, key)


BRIDGES = {"oracle": OracleBridge, "random": RandomBridge, "none": PurePlanningBridge}


def make_bridge(name: str, env: NoveltyEnv) -> Bridge:
    if name not in BRIDGES:
        raise ValueError(f"unknown bridge {name!r}; choose from {', '.join(BRIDGES)}")
    if BRIDGES[name] is OracleBridge and not env.has_oracle:
        raise ValueError(f"env {env.name!r} has no oracle bridge")
    return BRIDGES[name](env)
