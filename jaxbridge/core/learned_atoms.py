"""A learned model on the device: its invented atoms evaluated from the object view, and its operators'
samplers (the arrays of jaxbridge/learn/model/device.py's compilation, one task each).

An invented ground atom is one of a few kinds over object-view rows, each the device form of one
predicate of the learner's grammar (learn/model/predicates.py): a unary predicate (a literal on one
feature, or "X implies Y" as the disjunction of two literals) of row a; a and b at one place; a before b
along x; every member of a type at a's place satisfying a unary predicate; every member from a's place
up to b's doing so. The planner's own atoms stay the env's (`abstract`); the invented ones follow them.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from envs_jax.base import Objects

NO_ATOM, UNARY, SAME_PLACE, BEFORE, ALL_AT, SPAN = range(6)


@struct.dataclass
class InventedAtoms:
    """J invented ground atoms of one task (padding: kind NO_ATOM, never holds)."""

    kind: jax.Array  # int32[J]
    rows: jax.Array  # int32[J, 2]: the object-view rows of its arguments (a, b)
    feature: jax.Array  # int32[J, 2]: its unary predicate as up to two literals, OR-ed
    threshold: jax.Array  # float32[J, 2]
    above: jax.Array  # bool[J, 2]: a literal holds where its feature is above its threshold (else at or below)
    used: jax.Array  # bool[J, 2]: the literal is part of the unary predicate
    members: jax.Array  # int32[J]: the type id a quantified atom ranges over


@struct.dataclass
class ModelTable:
    """One task's learned-model part of its plan table (planner/tables.PlanTable.model)."""

    invented: InventedAtoms
    named: jax.Array  # bool[N]: object-view rows the task names (what a quantified atom ranges over)
    op_row: jax.Array  # int32[O]: the object-view row of each operator's slot object (its sampler's input)
    op_weights: jax.Array  # float32[O, W + 1]: the operator's linear sampler (features, then the intercept)
    op_sampled: jax.Array  # bool[O]: the operator has a sampler (else the skill's uniform draw)
    op_low: jax.Array  # float32[O]: the sampler's clip range
    op_high: jax.Array  # float32[O]
    place_tolerance: float = struct.field(pytree_node=False, default=1e-3)  # positions this close are one place


def invented_holds(model: ModelTable, objects: Objects) -> jax.Array:
    """bool[J]: which invented atoms hold in the state seen as `objects`."""
    atoms, tol = model.invented, model.place_tolerance
    values = objects.features[:, atoms.feature]  # [N, J, 2]
    unary = jnp.any(((values > atoms.threshold) == atoms.above) & atoms.used, axis=-1).T  # [J, N]
    a, b = atoms.rows[:, 0], atoms.rows[:, 1]
    pos, x = objects.position, objects.position[:, 0]
    fails = model.named[None, :] & (objects.type_id[None, :] == atoms.members[:, None]) & ~unary
    at_a = jnp.max(jnp.abs(pos[a][:, None, :] - pos[None, :, :]), axis=-1) < tol  # [J, N]
    from_a_to_b = (x[None, :] >= x[a][:, None] - tol) & (x[None, :] < x[b][:, None] - tol)
    before = x[a] < x[b] - tol
    by_kind = jnp.stack([
        jnp.zeros_like(before),
        jnp.take_along_axis(unary, a[:, None], axis=1)[:, 0],
        jnp.max(jnp.abs(pos[a] - pos[b]), axis=-1) < tol,
        before,
        ~jnp.any(fails & at_a, axis=-1),
        before & ~jnp.any(fails & from_a_to_b, axis=-1),
    ])
    return jnp.take_along_axis(by_kind, atoms.kind[None, :], axis=0)[0]


def sampled_param(model: ModelTable, op: jax.Array, objects: Objects) -> jax.Array:
    """The parameter operator `op`'s sampler gives for its slot object's features, clipped to its range."""
    inputs = jnp.append(objects.features[model.op_row[op]], 1.0)
    return jnp.clip(jnp.dot(model.op_weights[op], inputs), model.op_low[op], model.op_high[op])
