"""From rollout records to MDP transitions: one transition per bridge decision.

A transition runs from one bridge decision to the next decision of the same episode, or to the
episode's end. So a CallPlanner transition spans the whole planner rollout after it (to the goal, the
next stuck state, or the end of the episode): the paper's atomic CallPlanner. Reward 1 when the goal is
reached within the transition (plus an optional CallPlanner bonus); the goal ends the MDP, and so does
the time limit, without bootstrapping.

The plan-repair baselines (`Controls.plan_progress`) have the authors' RAPid-Learn-style rewards instead:
a cost per env step, and a terminal reward when the bridge hands back at a later state of its plan.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from jaxbridge.core.episode import StepRecord

# The authors' plan-progress rewards (-1 per step, a large reward at a later plan state) scaled to ours'
# reward of 1 at the end: a step costs 0.01, so a whole training episode (100 steps) costs as much as
# reaching the plan is worth.
PROGRESS_STEP_COST = 0.01


@struct.dataclass
class Transition:
    features: jax.Array  # float32[F]
    skill: jax.Array  # int32 (num_skills = CallPlanner)
    param: jax.Array  # float32
    reward: jax.Array  # float32
    done: jax.Array  # bool: no bootstrapping from next_* (goal reached or episode over)
    next_features: jax.Array  # float32[F]
    next_num_ground: jax.Array  # int32[num_skills + 1]: applicable actions at the next decision
    task: jax.Array | None = None  # int32: its training task's row of the task-constant values (with a split)
    steps: jax.Array | None = None  # int32: env steps it spans (with a step discount)


def count_before(flags: jax.Array) -> jax.Array:
    """int32[T + 1]: how many of flags[:t] are set, for every t (a difference of two is a count over a span)."""
    return jnp.concatenate([jnp.zeros(1, jnp.int32), jnp.cumsum(flags.astype(jnp.int32))])


def episode_transitions(records: StepRecord, success: jax.Array, call_planner_skill: int,
                        call_planner_bonus: float = 0.0, count_steps: bool = False, plan_progress: bool = False
                        ) -> tuple[Transition, jax.Array]:
    """Transitions of one episode (records over time, [T]); returns (Transition[T], valid[T]). With
    `plan_progress`, a transition during which the bridge handed back at a later plan state ends its MDP
    with reward 1; any other costs PROGRESS_STEP_COST per env step (1 if it reached the goal)."""
    steps = records.decided.shape[0]
    decided = records.decided & records.live
    index = jnp.arange(steps)
    # next_decision[t] = first decision strictly after t, or `steps` if none.
    later = jnp.where(decided, index, steps)
    suffix_min = jax.lax.cummin(later, reverse=True)
    next_decision = jnp.concatenate([suffix_min[1:], jnp.array([steps])])
    has_next = next_decision < steps
    nxt = jnp.minimum(next_decision, steps - 1)
    goal = ~has_next & success  # the episode ended at the goal during this transition
    bonus = jnp.where(records.skill == call_planner_skill, call_planner_bonus, 0.0)
    # The env steps from each decision to the next one (or to the episode's end).
    live_before = count_before(records.live)
    span = live_before[next_decision] - live_before[index]
    reward, done = jnp.where(goal, 1.0 + bonus, 0.0), ~has_next
    if plan_progress:  # a hand-back in (t, next decision]
        handed_back = count_before(records.progressed)
        reached = handed_back[nxt + 1] > handed_back[index + 1]
        reward = jnp.where(reached | goal, 1.0, -PROGRESS_STEP_COST * span)
        done = done | reached
    transition = Transition(
        features=records.features, skill=records.skill, param=records.param,
        reward=reward.astype(jnp.float32), done=done,
        next_features=records.features[nxt], next_num_ground=records.num_ground[nxt],
        steps=span if count_steps else None)
    return transition, decided


def empty_transitions(shape: tuple[int, ...], num_features: int, num_skills: int, counts_steps: bool) -> Transition:
    """Transitions of `shape` holding nothing (a state's fixed-shape slots before any is stored): zeros, done,
    nothing applicable at the next decision; with step counts where a step discount is on."""
    features = jnp.zeros(shape + (num_features,), jnp.float32)
    return Transition(features=features, skill=jnp.zeros(shape, jnp.int32), param=jnp.zeros(shape, jnp.float32),
                      reward=jnp.zeros(shape, jnp.float32), done=jnp.ones(shape, bool), next_features=features,
                      next_num_ground=jnp.zeros(shape + (num_skills + 1,), jnp.int32),
                      steps=jnp.zeros(shape, jnp.int32) if counts_steps else None)


def for_buffer(transitions: Transition) -> Transition:
    """Transitions as the replay buffer keeps them: without next_features, which `successor_features`
    reads back from the features stored after them. A full-state observation is wide (Doorknobs: 2027
    values, 265 MB per seed for 32768 transitions), so this halves the buffer, its copies and its
    checkpoints."""
    return transitions.replace(next_features=None)


def successor_features(features: jax.Array, slots: jax.Array) -> jax.Array:
    """next_features of the transitions stored at `slots` of a buffer's `features` [capacity, F].

    An episode's transitions are stored in order, in one insert: a transition that is not done is
    followed (modulo the capacity) by its episode's next decision, whose features are exactly its
    next_features, and FIFO overwriting reaches a slot before the one after it. For a done transition
    the next slot holds something unrelated, which never counts (no bootstrapping past `done`)."""
    return features[(slots + 1) % features.shape[0]]
