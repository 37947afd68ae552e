"""A learned model on the device: its invented atoms evaluated from the object view, and its operators'
samplers (the arrays of jaxbridge/learn/model/device.py's compilation, one task each).

An invented ground atom is one of a few kinds over object-view rows, each the device form of one
predicate of the learner's grammar (learn/model/predicates.py): a unary predicate (a literal on one
feature or on its distance to another, or "X implies Y" as the disjunction of two literals) of row a; a and b at one place; a before b
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
    """J invented ground atoms of one task over P predicates (padding: kind NO_ATOM, never holds). Each
    predicate is evaluated once over every object (pairs: a relation's [N, N]); an atom reads its cell."""

    kind: jax.Array  # int32[J]
    predicate: jax.Array  # int32[J]: its predicate's index
    rows: jax.Array  # int32[J, 2]: the object-view rows of its arguments (a, b)
    feature: jax.Array  # int32[P, 2]: a predicate's unary part as up to two literals, OR-ed
    other: jax.Array  # int32[P, 2]: a band's other feature (the literal reads the distance to it), else -1
    threshold: jax.Array  # float32[P, 2]
    above: jax.Array  # bool[P, 2]: a literal holds where what it reads is above its threshold (else at or below)
    used: jax.Array  # bool[P, 2]: the literal is part of the unary predicate
    members: jax.Array  # int32[P]: the type id a quantified predicate ranges over


# A learned operator in a plan table is a code from here up: (lifted operator * rows + input row) * slots + slot.
LEARNED_CODES = 1 << 24


@struct.dataclass
class ModelTable:
    """One task's learned-model part of its plan table (planner/tables.PlanTable.model): its invented
    atoms, and per lifted operator its skill and sampler."""

    invented: InventedAtoms
    named: jax.Array  # bool[N]: object-view rows the task names (what a quantified atom ranges over)
    op_skill: jax.Array  # int32[L]
    op_weights: jax.Array  # float32[L, W + 1]: the linear sampler on the input row's features, then the intercept
    op_sampled: jax.Array  # bool[L]: the operator has a sampler (else its skill's uniform draw)
    op_low: jax.Array  # float32[L]: the sampler's clip range
    op_high: jax.Array  # float32[L]
    slots: int = struct.field(pytree_node=False, default=1)  # the env's skill slots, for the codes
    place_tolerance: float = struct.field(pytree_node=False, default=1e-3)  # positions this close are one place


def learned_code(lifted: int, input_row: int, slot: int, rows: int, slots: int) -> int:
    """The plan table's code of a learned operator."""
    return LEARNED_CODES + (lifted * rows + input_row) * slots + slot


def invented_holds(model: ModelTable, objects: Objects) -> jax.Array:
    """bool[J]: which invented atoms hold in the state seen as `objects`."""
    atoms, tol = model.invented, model.place_tolerance
    values = objects.features[:, atoms.feature]  # [N, P, 2]
    values = jnp.where(atoms.other >= 0, jnp.abs(values - objects.features[:, jnp.maximum(atoms.other, 0)]), values)
    unary = jnp.any(((values > atoms.threshold) == atoms.above) & atoms.used, axis=-1).T  # [P, N]
    pos, x = objects.position, objects.position[:, 0]
    same = jnp.max(jnp.abs(pos[:, None, :] - pos[None, :, :]), axis=-1) < tol  # [N, N]
    before = x[:, None] < x[None, :] - tol  # [N, N]
    fails = model.named[None, :] & (objects.type_id[None, :] == atoms.members[:, None]) & ~unary  # [P, N]
    none_fail_at = ~jnp.any(fails[:, None, :] & same[None], axis=-1)  # [P, N]: no failing member at the place
    # failing members left of each place: a span [a, b) holds none where b's count equals a's
    failing_left = jnp.sum(fails[:, None, :] & (x[None, None, :] < x[None, :, None] - tol), axis=-1)  # [P, N]
    p, a, b = atoms.predicate, atoms.rows[:, 0], atoms.rows[:, 1]
    by_kind = jnp.stack([jnp.zeros_like(p, bool), unary[p, a], same[a, b], before[a, b], none_fail_at[p, a],
                         before[a, b] & (failing_left[p, b] == failing_left[p, a])])
    return jnp.take_along_axis(by_kind, atoms.kind[None, :], axis=0)[0]


@struct.dataclass
class LearnedCall:
    """What a plan table's operator code asks the planner to run, where it is a learned operator's."""

    learned: jax.Array  # bool: the code is a learned operator's
    skill: jax.Array  # int32
    slot: jax.Array  # int32
    param: jax.Array  # float32: its sampler's value (where `sampled`)
    sampled: jax.Array  # bool


def learned_call(model: ModelTable, code: jax.Array, objects: Objects) -> LearnedCall:
    """Decode a learned operator's code: its skill, slot, and its sampler's parameter on the input row's
    features, clipped to its range."""
    rows = objects.features.shape[0]
    rest = jnp.maximum(code - LEARNED_CODES, 0)
    slot, input_row, lifted = rest % model.slots, (rest // model.slots) % rows, rest // (model.slots * rows)
    inputs = jnp.append(objects.features[input_row], 1.0)
    param = jnp.clip(jnp.dot(model.op_weights[lifted], inputs), model.op_low[lifted], model.op_high[lifted])
    return LearnedCall(code >= LEARNED_CODES, model.op_skill[lifted], slot, param, model.op_sampled[lifted])
