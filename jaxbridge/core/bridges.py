"""Hand-made bridge policies: random, pure planning ("none") and each env's oracle.

A bridge is a pure function `(params, obs: BridgeObs, key) -> BridgeAction`, called once per decision.
`params` is whatever the bridge learns (None for these). Skill index `num_skills` is CallPlanner.
"""
from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv

Bridge = Callable[[object, BridgeObs, jax.Array], BridgeAction]


def random_bridge(env: NoveltyEnv) -> Bridge:
    """A uniformly random applicable skill, CallPlanner included once it is applicable, with a parameter
    from the skill's sampler; the meta-policy then grounds it uniformly among its applicable ground
    operators. (The authors drew uniformly over ground operators instead, so a skill with two ground
    instances, like MoveRobot left/right, took twice the share; uniform over skills reaches an opened door
    and CallPlanner there 2.5x as often on Light Switch Door, see docs/RESULTS.md.)"""

    def act(params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        k_skill, k_param = jax.random.split(key)
        weights = (obs.num_ground > 0).astype(jnp.float32)
        skill = jax.random.categorical(k_skill, jnp.log(weights))  # log 0 = -inf: never chosen
        params_all = env.sample_params(k_param)
        param = jnp.where(skill < env.num_skills, params_all[jnp.minimum(skill, env.num_skills - 1)], 0.0)
        return BridgeAction(skill=skill.astype(jnp.int32), param=param)

    return act


def pure_planning_bridge(env: NoveltyEnv) -> Bridge:
    """No bridge: whenever the plan is stuck, re-plan from the current state (the paper's pure
    planning baseline). CallPlanner's "state changed" precondition does not apply to it."""

    def act(params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        return BridgeAction(skill=jnp.int32(env.num_skills), param=jnp.float32(0.0))

    return act


def oracle_bridge(env: NoveltyEnv) -> Bridge:
    """The env's hand-written novelty fixer (e.g. set the door keys, then CallPlanner)."""
    return env.oracle_bridge


BRIDGES = {"oracle": oracle_bridge, "random": random_bridge, "none": pure_planning_bridge}


def make_bridge(name: str, env: NoveltyEnv) -> Bridge:
    if name not in BRIDGES:
        raise ValueError(f"unknown bridge {name!r}; choose from {', '.join(BRIDGES)}")
    return BRIDGES[name](env)
