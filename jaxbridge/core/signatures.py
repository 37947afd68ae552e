"""Failure signatures (issue 54): which planner operator stalled, and on what type of object.

The meta-policy knows the planner's step that stalled; the object is the paper's selection in the stuck
state (the interactable object closest to the robot, `observations.closest_object`). A signature is the
pair (the stalled operator's skill, that object's type), each part one of a static, env-given set plus
"none" (no plan, so no operator; no interactable object). Both signature approaches see it as two
one-hots after their features; the per-signature bridges pick their network by it: one per signature
the env declares (`NoveltyEnv.failure_signatures`) and one for all others, or one per signature.
"""
from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import NoveltyEnv
from jaxbridge.core.observations import closest_object


def planner_skills(env: NoveltyEnv) -> np.ndarray:
    """int[P]: the skills of the operators the planner's model gives effects, ascending (those a plan can
    hold; the effect-less ones are only the bridge's)."""
    return np.array(sorted({env.skill_index(op.skill) for op in env.domain.operators if op.add or op.delete}), np.int32)


def signature_shape(env: NoveltyEnv) -> tuple[int, int]:
    """(stalled skills, object types), each with its "none" last."""
    return len(planner_skills(env)) + 1, len(env.object_types) + 1


def num_signatures(env: NoveltyEnv) -> int:
    skills, types = signature_shape(env)
    return skills * types


def signature_width(env: NoveltyEnv) -> int:
    """The length of `signature_features`."""
    return sum(signature_shape(env))


def signature_features(env: NoveltyEnv, stalled_skill: jax.Array, stuck_state: Any) -> jax.Array:
    """float32[P + 1 + T + 1]: one_hot(the stalled skill among `planner_skills`, "none" last) ++
    one_hot(the type of the interactable object closest to the robot in the stuck state, "none" last)."""
    skills, types = signature_shape(env)
    known = planner_skills(env)
    is_known = known == stalled_skill
    skill = jnp.where(jnp.any(is_known), jnp.argmax(is_known), skills - 1)
    objects = env.objects(stuck_state)
    slot, found = closest_object(objects)
    kind = jnp.where(found, objects.type_id[slot], types - 1)
    return jnp.concatenate([jax.nn.one_hot(skill, skills), jax.nn.one_hot(kind, types)])


def signature_index(one_hots: jax.Array, shape: tuple[int, int]) -> jax.Array:
    """int32[...]: the signature id (skill part x types + type part) of `signature_features` [..., P + 1 + T + 1]."""
    skills, types = shape
    return (jnp.argmax(one_hots[..., :skills], -1) * types + jnp.argmax(one_hots[..., skills:], -1)).astype(jnp.int32)


def signature_members(env: NoveltyEnv) -> tuple[int, ...]:
    """The network of each signature id of a bridge per signature: the env's `failure_signatures` one each, in
    their order, and every other signature the next one; without a declaration, every signature its own.
    Static (a tuple), so the number of networks is too."""
    if env.failure_signatures is None:
        return tuple(range(num_signatures(env)))
    skills, types = signature_shape(env)
    known, kinds = planner_skills(env).tolist(), list(env.object_types)
    declared = [known.index(env.skill_index(skill)) * types + kinds.index(kind) for skill, kind in env.failure_signatures]
    return tuple(declared.index(i) if i in declared else len(declared) for i in range(skills * types))
