"""A brax view of an env from its training task's stuck state: low-level continuous RL, the alternative the
paper's introduction argues against but never ran (issue 22).

An episode starts where the planner of the seed's training task first gets stuck (the planner runs once,
at construction, as it does in ours). The agent then emits the env's raw action, squashed to [-1, 1] and
scaled to the env's `action_bounds`, one env step per agent step; it observes what ours' bridge sees (the
object-centric features, or the full state) and gets reward 1 on the step the goal holds. With
`call_planner`, one more action dimension, when positive (and once the state changed since the agent
took over, as ours' CallPlanner), hands control to the planner, which acts until it is stuck again or
the task is solved: that whole stretch is one agent step. Episodes end at the goal or the task horizon
(in env steps). Everything is the meta-policy's own code (core/meta_policy), with the agent as a
low-level bridge, so the evaluation on test tasks is the same `rollout` as every other approach's.
"""
from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from functools import partial

import jax
import jax.numpy as jnp

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv
from jaxbridge.core.meta_policy import (Controls, MetaPolicy, PlannerTurn, bridge_step, observation, observation_size,
                                        planner_step, start_episode, step_randomness)
from jaxbridge.core.observations import FEATURES, FULL_STATE
from jaxbridge.core.tasks import TaskArrays

with contextlib.redirect_stdout(io.StringIO()):  # brax prints its optional GPU backends' failed imports
    from brax.envs.base import Env, State


def low_level_controls(call_planner: bool, full_state: bool = False) -> Controls:
    return Controls(call_planner=call_planner, low_level=True, observation=FULL_STATE if full_state else FEATURES)


def agent_action_size(env: NoveltyEnv, call_planner: bool) -> int:
    """The agent's action: the env's, and one more entry for CallPlanner where it has it."""
    return env.action_dim + int(call_planner)


def scaled_choice(env: NoveltyEnv, squashed: jax.Array, can_call: jax.Array, call_planner: bool) -> BridgeAction:
    """A low-level bridge's choice from an action in [-1, 1]^(A [+1]): the first A entries scaled to the
    env's bounds; with `call_planner`, CallPlanner when the last entry is positive and it is applicable."""
    low, high = (jnp.asarray(b) for b in env.action_bounds())
    squashed = jnp.clip(squashed, -1.0, 1.0)
    action = low + (squashed[:env.action_dim] + 1.0) * 0.5 * (high - low)
    calls = (squashed[-1] > 0) & can_call if call_planner else jnp.bool_(False)
    return BridgeAction(skill=jnp.where(calls, env.num_skills, 0).astype(jnp.int32), param=jnp.float32(0.0),
                        action=action)


@dataclass(frozen=True)
class GivenActionBridge:
    """The adapter's bridge: its params are the agent's squashed action."""

    env: NoveltyEnv
    call_planner: bool

    def __call__(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        return scaled_choice(self.env, params, obs.num_ground[-1] > 0, self.call_planner)


def _advance(env: NoveltyEnv, controls: Controls, tables, turn: PlannerTurn, key: jax.Array,
             bridge_params: jax.Array | None) -> PlannerTurn:
    """With `bridge_params` (the agent's action): the bridge's step, then the planner's steps until the
    bridge must choose again or the episode ends; without: only the planner's steps."""
    bridge = GivenActionBridge(env, controls.call_planner)
    groups = jnp.zeros(1, jnp.int32)
    max_steps = turn.episodes.horizon[0] + 1

    def one(turn: PlannerTurn, i, params) -> PlannerTurn:
        uniforms, bits, keys = step_randomness(jax.random.fold_in(key, i)[None], 1)
        params = jnp.zeros((1, agent_action_size(env, controls.call_planner))) if params is None else params[None]
        episodes, _ = bridge_step(MetaPolicy(env, bridge, params, controls), tables, turn, bits[0], keys[0], groups)
        return planner_step(env, controls, tables, episodes, uniforms[0], host_planner=False)

    if bridge_params is not None:
        turn = one(turn, 0, bridge_params)

    def planner_acts(carry):
        i, turn = carry
        return (i < max_steps) & ~turn.decide[0] & ~turn.episodes.done[0]

    _, turn = jax.lax.while_loop(planner_acts, lambda c: (c[0] + 1, one(c[1], c[0], None)), (jnp.int32(1), turn))
    return turn


class BridgeEnv(Env):
    """brax.envs.Env over one training task (`task`: TaskArrays with a leading axis of 1)."""

    def __init__(self, env: NoveltyEnv, task: TaskArrays, call_planner: bool, full_state: bool = False,
                 key: jax.Array | None = None):
        self.env, self.task = env, task
        self.controls = low_level_controls(call_planner, full_state)
        episodes = jax.vmap(partial(start_episode, env, self.controls))(task.tasks, task.horizons)
        key = jax.random.key(0) if key is None else key
        turn = planner_step(env, self.controls, task.tables, episodes, jnp.zeros(1), host_planner=False)
        self.stuck = jax.jit(partial(_advance, env, self.controls, task.tables, bridge_params=None))(turn, key)

    @property
    def observation_size(self) -> int:
        return observation_size(self.env, self.controls)

    @property
    def action_size(self) -> int:
        return agent_action_size(self.env, self.controls.call_planner)

    @property
    def backend(self) -> str:
        return "jax"  # no brax physics: the env's own dynamics

    def _state(self, turn: PlannerTurn, reward: jax.Array, info: dict, metrics: dict) -> State:
        ep = turn.episodes
        obs = observation(self.env, self.controls, jax.tree.map(lambda x: x[0], ep.env_state),
                          jax.tree.map(lambda x: x[0], ep.stuck_state))
        return State(pipeline_state=turn, obs=obs, reward=reward, done=ep.done[0].astype(jnp.float32),
                     metrics={**metrics, "success": ep.success[0].astype(jnp.float32)}, info=info)

    def reset(self, rng: jax.Array) -> State:
        return self._state(self.stuck, jnp.float32(0.0), {"key": rng}, {})

    def step(self, state: State, action: jax.Array) -> State:
        key, now = jax.random.split(state.info["key"])
        before = state.pipeline_state.episodes.success[0]
        turn = _advance(self.env, self.controls, self.task.tables, state.pipeline_state, now, action)
        reward = (turn.episodes.success[0] & ~before).astype(jnp.float32)
        return self._state(turn, reward, {**state.info, "key": key}, state.metrics)  # wrappers add entries
