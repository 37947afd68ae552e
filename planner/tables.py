"""Compile a task's optimal plans into device lookup tables, with a host planner behind them.

Per task (host, once): ground the environment's planner model, enumerate the abstract states it can
reach from the initial state, and store for each the first operator of an optimal plan and the abstract
state the model predicts after it. Abstract states are bit-packed into uint32 words, so the in-graph
lookup is a compare over a few words per table row. A state missing from the table (the novelty can
lead the real world where the model never goes) is answered by the host planner through one batched
`jax.pure_callback`, issued only on steps where some episode misses; misses are counted.
"""
from __future__ import annotations

import itertools
import weakref
from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from planner.search import NO_OPERATOR, BitOperator, HostPlanner
from planner.strips import GroundOperator, Problem, ground

WORD_BITS = 32


def num_words(num_atoms: int) -> int:
    return max(1, -(-num_atoms // WORD_BITS))


def bits_to_words(bits: int, words: int) -> np.ndarray:
    return np.array([(bits >> (WORD_BITS * w)) & 0xFFFFFFFF for w in range(words)], dtype=np.uint32)


def words_to_bits(words: np.ndarray) -> int:
    return sum(int(w) << (WORD_BITS * i) for i, w in enumerate(np.asarray(words, dtype=np.uint64)))


def pack_atoms(atoms: jax.Array) -> jax.Array:
    """bool[A] -> uint32[W]: atom i is bit i % 32 of word i // 32."""
    words = num_words(atoms.shape[-1])
    padded = jnp.zeros(words * WORD_BITS, bool).at[: atoms.shape[-1]].set(atoms)
    weights = jnp.left_shift(jnp.uint32(1), jnp.arange(WORD_BITS, dtype=jnp.uint32))
    return jnp.sum(jnp.where(padded.reshape(words, WORD_BITS), weights, jnp.uint32(0)), axis=-1,
                   dtype=jnp.uint32)


def holds_all(required: jax.Array, words: jax.Array) -> jax.Array:
    """Every atom set in `required` is set in `words` (both packed)."""
    return jnp.all(jnp.bitwise_and(required, jnp.bitwise_not(words)) == 0, axis=-1)


@struct.dataclass
class PlanTable:
    """One task's plans and ground operators as device arrays (stackable over tasks)."""

    uid: jax.Array  # int32: key of the task's host planner
    goal_key: jax.Array  # uint32[W]
    state_keys: jax.Array  # uint32[S, W]: the abstract states the model can reach
    state_valid: jax.Array  # bool[S]
    next_op: jax.Array  # int32[S]: first operator of an optimal plan; -1 at a goal or dead end
    next_keys: jax.Array  # uint32[S, W]: the abstract state the model predicts after next_op
    op_pre: jax.Array  # uint32[O, W]: fluent preconditions, packed like states
    op_skill: jax.Array  # int32[O]
    op_slot: jax.Array  # int32[O]
    op_valid: jax.Array  # bool[O]: a ground operator of the env's model (padding and learned ones are not)
    # A learned model's device part (jaxbridge/core/learned_atoms.ModelTable: its invented atoms and its
    # operators' samplers); None for the env's own model, whose programs then hold no trace of it.
    model: Any = None


def table_shape(states: int, operators: int, num_atoms: int) -> PlanTable:
    """The shapes and dtypes of a PlanTable with `states` rows and `operators` ground operators, without
    building one (memory estimates)."""
    words = num_words(num_atoms)
    shaped = lambda shape, dtype: jax.ShapeDtypeStruct(shape, dtype)
    return PlanTable(
        uid=shaped((), np.int32), goal_key=shaped((words,), np.uint32),
        state_keys=shaped((states, words), np.uint32), state_valid=shaped((states,), np.bool_),
        next_op=shaped((states,), np.int32), next_keys=shaped((states, words), np.uint32),
        op_pre=shaped((operators, words), np.uint32), op_skill=shaped((operators,), np.int32),
        op_slot=shaped((operators,), np.int32), op_valid=shaped((operators,), np.bool_))


@struct.dataclass
class PlanLookup:
    found: jax.Array  # bool: the state was answered (table or host)
    op: jax.Array  # int32: operator to run next; -1 at a goal or a dead end
    next_key: jax.Array  # uint32[W]: predicted abstract state after `op`
    miss: jax.Array  # bool: the table lacked the state and the host planner was asked


# Held weakly: a planner lives while a task holds it (its CompiledTask in a batch or the compile cache, a
# repair run's planners), so a sweep's thousands of learned planners go with their batches.
_HOST_PLANNERS: weakref.WeakValueDictionary[int, HostPlanner] = weakref.WeakValueDictionary()
_UIDS = itertools.count(1)


def register_planner(planner) -> int:
    """The uid a table names `planner` by (anything with `decide(state) -> PolicyEntry`) for the host
    fallback, while something else holds `planner`."""
    uid = next(_UIDS)
    _HOST_PLANNERS[uid] = planner
    return uid


@dataclass
class CompiledTask:
    """Host-side view of one task: its grounding, host planner and table (numpy)."""

    uid: int
    problem: Problem
    ground_ops: list[GroundOperator]
    planner: HostPlanner
    init_state: int
    table: PlanTable  # numpy leaves
    num_reachable: int

    def plan(self) -> list[GroundOperator]:
        return [self.ground_ops[i] for i in self.planner.plan(self.init_state)]


def compile_task(env, spec, max_states: int | None = None) -> CompiledTask:
    """Ground `env`'s planner model on task `spec` and tabulate optimal plans.

    `max_states` truncates the table (tests use it to exercise the host-planner path).
    """
    problem = env.planner_problem(spec)
    ops = ground(problem)

    def bits(atoms) -> int:
        return sum(1 << env.atom_index(a) for a in atoms)

    bit_ops = [BitOperator(bits(o.pre), bits(o.add), bits(o.delete)) for o in ops]
    planner = HostPlanner(bit_ops, bits(problem.goal))
    init = bits(problem.init)
    planner.decide(init)
    policy = dict(planner.cache)  # the optimal policy on every reachable state, in BFS order
    states = list(policy)[:max_states]
    planner.calls = 0

    words = num_words(env.num_atoms)
    uid = register_planner(planner)
    table = PlanTable(
        uid=np.int32(uid),
        goal_key=bits_to_words(planner.goal, words),
        state_keys=np.stack([bits_to_words(s, words) for s in states]),
        state_valid=np.ones(len(states), bool),
        next_op=np.array([policy[s].op for s in states], np.int32),
        next_keys=np.stack([bits_to_words(policy[s].next_state, words) for s in states]),
        op_pre=np.stack([bits_to_words(o.pre, words) for o in bit_ops]),
        op_skill=np.array([env.skill_index(o.skill) for o in ops], np.int32),
        op_slot=np.array([env.object_slot(o.slot_object) if o.slot_object else 0 for o in ops],
                         np.int32),
        op_valid=np.ones(len(ops), bool),
    )
    return CompiledTask(uid, problem, ops, planner, init, table, len(policy))


def _pad(x: np.ndarray, n: int, fill) -> np.ndarray:
    pad = np.full((n - x.shape[0],) + x.shape[1:], fill, x.dtype)
    return np.concatenate([x, pad])


def stack_tables(tasks: list[CompiledTask]) -> PlanTable:
    """Pad every table to the largest one and stack them on a leading task axis (a learned model's part
    comes at its declared capacities: stacked as it is)."""
    tables = [t.table for t in tasks]
    s = max(t.state_keys.shape[0] for t in tables)
    o = max(t.op_pre.shape[0] for t in tables)

    def padded(t: PlanTable) -> PlanTable:
        return t.replace(
            state_keys=_pad(t.state_keys, s, 0), state_valid=_pad(t.state_valid, s, False),
            next_op=_pad(t.next_op, s, NO_OPERATOR), next_keys=_pad(t.next_keys, s, 0),
            op_pre=_pad(t.op_pre, o, 0), op_skill=_pad(t.op_skill, o, 0), op_slot=_pad(t.op_slot, o, 0),
            op_valid=_pad(t.op_valid, o, False))

    return jax.tree.map(lambda *xs: jax.device_put(np.stack(xs)), *[padded(t) for t in tables])


def table_lookup(table: PlanTable, key: jax.Array) -> PlanLookup:
    """In-graph lookup of one packed abstract state (one task)."""
    match = jnp.all(table.state_keys == key, axis=-1) & table.state_valid
    # At most one row matches: a plain max finds it (cheaper than argmax on CPU).
    row = jnp.max(jnp.where(match, jnp.arange(match.shape[0]), -1))
    return PlanLookup(found=row >= 0, op=table.next_op[row], next_key=table.next_keys[row],
                      miss=jnp.zeros((), bool))


def _host_decide(uid: np.ndarray, key: np.ndarray, ask: np.ndarray):
    """Host side of the fallback: answer every episode that asks (batched by vmap_method)."""
    shape = np.broadcast_shapes(uid.shape, ask.shape, key.shape[:-1])
    uid, ask = np.broadcast_to(uid, shape), np.broadcast_to(ask, shape)
    key = np.broadcast_to(key, shape + key.shape[-1:])
    found = np.zeros(shape, bool)
    op = np.full(shape, NO_OPERATOR, np.int32)
    nxt = np.zeros(key.shape, np.uint32)
    for idx in zip(*np.nonzero(ask)):
        planner = _HOST_PLANNERS.get(int(uid[idx]))
        if planner is None:  # an unknown task: answer "no plan", the episode gets stuck
            continue
        entry = planner.decide(words_to_bits(key[idx]))
        found[idx], op[idx] = True, entry.op
        nxt[idx] = bits_to_words(entry.next_state, key.shape[-1])
    return found, op, nxt


def host_lookup(uid: jax.Array, key: jax.Array, ask: jax.Array):
    """The host planner as a pure callback: (found, op, next_key) for episodes with `ask` set."""
    shapes = (jax.ShapeDtypeStruct(ask.shape, jnp.bool_), jax.ShapeDtypeStruct(ask.shape, jnp.int32),
              jax.ShapeDtypeStruct(key.shape, jnp.uint32))
    return jax.pure_callback(_host_decide, shapes, uid, key, ask, vmap_method="expand_dims")


def batched_plan_lookup(tables: PlanTable, keys: jax.Array, need: jax.Array, host: bool = True) -> PlanLookup:
    """Look up every episode of a batch; call the host planner only if some needed state is missing.
    Without `host` a missing state is left unanswered (not found) and only reported in `miss`: a program
    without host callbacks, which JAX's persistent cache can keep (the caller redoes the work with the
    host when a miss was reported)."""
    plan = jax.vmap(table_lookup)(tables, keys)
    miss = need & ~plan.found
    if not host:
        return plan.replace(miss=miss)

    def ask_host(_):
        found, op, nxt = host_lookup(tables.uid, keys, miss)
        return PlanLookup(found=plan.found | found, op=jnp.where(miss, op, plan.op),
                          next_key=jnp.where(miss[:, None], nxt, plan.next_key), miss=miss)

    return jax.lax.cond(jnp.any(miss), ask_host, lambda _: plan.replace(miss=miss), None)
