"""A count bonus for exploration (`count_bonus`, a learner setting; off by default): an intrinsic reward
for reaching a bridge observation that is new in its episode, scaled down as the seed sees it more often
(docs/design/learning.md, "Exploration").

Epsilon-greedy finds a fix of k decisions by chance, and a fix whose every wrong decision undoes the
progress so far (Light Switch Sequence's lock) needs k right decisions in a row: the goal's reward arrives
after a number of episodes that grows geometrically with k. The bonus rewards each step that reaches an
observation the episode has not seen yet, so a right decision, which changes what the bridge sees (the
fix's progress is in its features), is rewarded where it happens, long before the goal first is.

The bonus of a transition to observation o is `count_bonus x new_in_episode(o) / sqrt(N(o))`: the product
of an episodic bonus (1 the first time in the episode, else 0) and a global one (N(o), how often the seed
has reached o, this visit included), the combination Henaff et al. (ICML 2023) found robust. An observation
is counted by its features rounded to a grid of COUNT_GRID, hashed into a table of TABLE_SIZE counts per
seed: exact for features that take few values (the abstract state and the fix's progress here), a
coarse count for continuous ones. Transitions that end an episode (at the goal or the time limit) get no
bonus: they have no next observation.

It wraps any learner (`with_exploration`), so every learning approach and learner gets it alike: the
bonus is added to the transitions' rewards before the learner's `observe`, and the counts are part of the
learner state (checkpointed and resumed with it). Off, the learner is not wrapped: the same program.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.learner import QLearner
from jaxbridge.learn.transitions import Transition

COUNT_GRID = 0.05  # features are counted rounded to multiples of this
TABLE_SIZE = 4096  # hashed counts per seed (16 KiB of int32)


@struct.dataclass
class CountState:
    """A learner's state with the seed's observation counts. `key` and `decisions` are the cycle's (it splits
    and adds to them here); the inner state's copies are brought up to date before each inner call."""

    inner: Any
    counts: jax.Array  # int32[TABLE_SIZE]
    key: jax.Array
    decisions: jax.Array


def observation_slots(features: jax.Array) -> jax.Array:
    """int32[...]: each feature vector's (float32[..., F]) slot in the count table: the features rounded to
    COUNT_GRID, mixed by fixed odd multipliers (uint32 arithmetic wraps), folded into the table."""
    grid = jnp.round(features / COUNT_GRID).astype(jnp.int32).astype(jnp.uint32)
    multipliers = np.random.default_rng(0).integers(1, 2**31, features.shape[-1]).astype(np.uint32) * 2 + 1
    mixed = (grid * jnp.asarray(multipliers, jnp.uint32)).sum(-1, dtype=jnp.uint32)
    mixed = (mixed ^ (mixed >> 15)) * jnp.uint32(0x2C1B3C6D)
    return ((mixed ^ (mixed >> 12)) % TABLE_SIZE).astype(jnp.int32)


def new_in_episode(slots: jax.Array, counted: jax.Array, first: jax.Array) -> jax.Array:
    """bool[T]: row t of one episode is counted and its slot is not that of the episode's first observation
    (`first`) nor of any counted row before t."""
    earlier = jnp.tril(slots[None, :] == slots[:, None], k=-1) & counted[None, :]
    return counted & ~earlier.any(1) & (slots != first)


def count_bonus(scale: float, counts: jax.Array, transitions: Transition, valid: jax.Array
                ) -> tuple[jax.Array, jax.Array]:
    """(bonus float32[episodes, T], counts after this cycle's visits): the bonus of each decision's transition
    ([episodes, T] rows, `valid` the decisions), and the count table with every counted visit added."""
    slots = observation_slots(transitions.next_features)
    counted = valid & ~transitions.done
    first = jnp.take_along_axis(observation_slots(transitions.features), jnp.argmax(valid, 1)[:, None], 1)[:, 0]
    new = jax.vmap(new_in_episode)(slots, counted, first)
    flat, hits = slots.reshape(-1), counted.reshape(-1).astype(jnp.int32)
    after = counts.at[flat].add(hits)
    # N(o) for a visit: the visits before this cycle, and this cycle's up to and including it
    so_far = (jnp.tril(flat[:, None] == flat[None, :]) * hits[None, :]).sum(1)
    visits = (counts[flat] + so_far).reshape(slots.shape)
    bonus = jnp.where(new, scale / jnp.sqrt(jnp.maximum(visits, 1).astype(jnp.float32)), 0.0)
    return bonus.astype(jnp.float32), after


@dataclass(frozen=True)
class CountExploration:
    """A learner (learn/learner.QLearner) whose transitions get the count bonus before `inner` observes them."""

    inner: QLearner
    scale: float

    env = property(lambda self: self.inner.env)
    net = property(lambda self: self.inner.net)
    num_features = property(lambda self: self.inner.num_features)
    shares_network = property(lambda self: self.inner.shares_network)

    def init(self, key: jax.Array) -> CountState:
        inner = self.inner.init(key)
        return CountState(inner=inner, counts=jnp.zeros(TABLE_SIZE, jnp.int32), key=inner.key, decisions=inner.decisions)

    def greedy(self, state: CountState) -> Any:
        return self.inner.greedy(state.inner)

    def observe(self, state: CountState, transitions: Transition, valid: jax.Array) -> CountState:
        bonus, counts = count_bonus(self.scale, state.counts, transitions, valid)
        inner = self.inner.observe(_synced(state), transitions.replace(reward=transitions.reward + bonus), valid)
        return state.replace(inner=inner, counts=counts)

    def learn(self, state: CountState, decisions: jax.Array, tasks: Any) -> tuple[CountState, jax.Array, jax.Array]:
        inner, loss, q_abs_max = self.inner.learn(_synced(state), decisions, tasks)
        return state.replace(inner=inner, key=inner.key, decisions=inner.decisions), loss, q_abs_max

    def stored(self, state: CountState) -> jax.Array:
        return self.inner.stored(state.inner)


def _synced(state: CountState) -> Any:
    """The inner state with the cycle's key and decision count."""
    return state.inner.replace(key=state.key, decisions=state.decisions)


def with_exploration(learner: QLearner, config: TrainConfig) -> QLearner:
    """`learner` with the config's exploration bonus, or as it is where there is none (`count_bonus` 0, or a
    learner whose settings have no such setting)."""
    scale = getattr(config.learner, "count_bonus", 0.0)
    return CountExploration(learner, float(scale)) if scale > 0 else learner
