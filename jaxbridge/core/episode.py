"""What the meta-policy (`meta_policy.py`) keeps and reports: which of its parts a run uses (`Controls`),
an episode in progress, the bridge's decision, one env step's record and an episode's result."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from envs_jax.base import NoveltyEnv, SkillCall
from jaxbridge.core.observations import FEATURES, Observation
from jaxbridge.core.signatures import signature_features, signature_width

PLANNER, BRIDGE = 0, 1  # who is in control of an episode


@dataclass(frozen=True)
class Controls:
    """Which parts of the meta-policy a run uses (static: each combination compiles once).

    The paper's ablations switch the first three off (the authors' code); the loop guard comes from
    the run's config (`Setup.controls`), so build a run's controls there, not from the approach alone."""

    planner: bool = True  # False: pure RL, the bridge acts from the first step and nothing plans
    call_planner: bool = True  # False: no CallPlanner; once stuck, the bridge keeps control
    # What the bridge sees (core/observations.py): the env's hand-made features (the paper's selection),
    # every object's raw features (FULL_STATE), the closest object's read off the object view, or tokens.
    observation: Observation = FEATURES
    loop_guard: bool = False  # a skill that left the state unchanged is not applicable again in that state
    low_level: bool = False  # the bridge emits the env's raw action each step instead of a skill (brax baselines)
    # The plan-repair baselines (issue 38, docs/DESIGN.md): the bridge's problem ends once the abstract
    # state holds every atom of a later state of the plan it got stuck in; control then goes back to
    # the planner, which replans, or with `resume_plan` continues that plan from the state reached.
    plan_progress: bool = False
    resume_plan: bool = False
    # The failure signature (issue 54, core/signatures.py): the stalled operator's skill and the type of
    # the object it stalled at, appended to what the bridge sees as two one-hots.
    signature: bool = False


def observation_size(env: NoveltyEnv, controls: Controls) -> int:
    return controls.observation.size(env) + (signature_width(env) if controls.signature else 0)


def observation(env: NoveltyEnv, controls: Controls, state: Any, stuck_state: Any,
                stalled_skill: jax.Array | int = -1) -> jax.Array:
    """What the bridge sees (core/observations.py): the env's object-centric features, the full padded
    state, the closest object's by the paper's rule, or the object tokens; with `signature`, then the
    failure signature of the stall (`stalled_skill`, the object at the robot in `stuck_state`)."""
    seen = controls.observation.observe(env, state, stuck_state)
    if not controls.signature:
        return seen
    return jnp.concatenate([seen, signature_features(env, stalled_skill, stuck_state)])


@struct.dataclass
class Episode:
    env_state: Any
    stuck_state: Any  # the state at which control last passed to the bridge
    stalled_skill: jax.Array  # int32: the skill of the operator that stalled there (-1: none, no plan)
    t: jax.Array  # int32: env steps taken
    horizon: jax.Array  # int32
    done: jax.Array  # bool
    success: jax.Array  # bool
    control: jax.Array  # int32: PLANNER or BRIDGE
    call: SkillCall  # the skill being executed
    expected: jax.Array  # uint32[W]: atoms the model predicts after the planner's operator (0 = none)
    prev_vec: jax.Array  # float32[D]: low-level state before the previous step
    planner_stepped: jax.Array  # bool: the current plan's policy acted on the previous step
    bridge_vec: jax.Array  # float32[D]: low-level state when the bridge took over (for CanPlan)
    planner_calls: jax.Array  # int32: plans made (the first one, then one per CallPlanner)
    table_misses: jax.Array  # int32: lookups answered by the host planner
    bridge_decisions: jax.Array  # int32: choices made by the bridge, CallPlanner included
    stuck_events: jax.Array  # int32
    decision_vec: jax.Array  # float32[D]: low-level state at the bridge's last decision (loop guard)
    decision_skill: jax.Array  # int32: the skill it chose there (-1: none yet; num_skills: CallPlanner)
    no_op_skills: jax.Array  # bool[num_skills]: skills the bridge chose in this state that left it unchanged
    # The current plan, with `plan_progress` (zero length without): its abstract states from the one it
    # was made in, the operator from each to the next (-1 past its end), and where the episode is on it.
    plan_keys: jax.Array  # uint32[L, W]
    plan_ops: jax.Array  # int32[L]
    plan_at: jax.Array  # int32: the index of the plan state the running operator should reach
    new_plan: jax.Array  # bool: the next operator starts a new plan, whose states are then recorded


@struct.dataclass
class Decision:
    """The bridge's choice for one episode, grounded on the task's objects."""

    skill: jax.Array  # int32; num_skills = CallPlanner
    slot: jax.Array  # int32
    param: jax.Array  # float32
    features: jax.Array  # float32[F]: what the bridge saw
    num_ground: jax.Array  # int32[num_skills + 1]: what it could choose from (CallPlanner last)
    no_op_skills: jax.Array  # bool[num_skills]: the loop guard's skills left out of num_ground
    action: jax.Array  # float32[A]: a low-level bridge's raw action (zeros for skill bridges)


@struct.dataclass
class StepRecord:
    """One env step of one episode (traces for learning, rendering and tests)."""

    live: jax.Array  # bool: the step happened (episode not over)
    actor: jax.Array  # int32: ACTOR_*
    decided: jax.Array  # bool: the bridge chose an action at this step
    stuck: jax.Array  # bool: the planner got stuck at this step's state
    skill: jax.Array  # int32: skill executed (num_skills for CallPlanner)
    slot: jax.Array  # int32
    param: jax.Array  # float32
    features: jax.Array  # float32[F]: the bridge's observation (at decisions; zeros otherwise)
    num_ground: jax.Array  # int32[num_skills + 1]: its applicable actions (at decisions)
    env_state: Any  # state before the step
    progressed: jax.Array  # bool: the bridge reached a later state of the plan here and handed back (plan_progress)

    @property
    def can_plan(self) -> jax.Array:
        """CallPlanner was applicable (at decisions)."""
        return self.num_ground[..., -1] > 0


@struct.dataclass
class EpisodeResult:
    success: jax.Array
    steps: jax.Array
    planner_calls: jax.Array
    table_misses: jax.Array
    bridge_decisions: jax.Array
    stuck_events: jax.Array
