"""The planner/bridge meta-policy: the paper's Algorithm 1 as a `lax.scan` over env steps.

Per env step, for a whole batch of episodes (any mix of seeds and tasks):

1. observe: abstract the state; the episode ends at the goal or the horizon.
2. plan: the planner looks up the next operator of an optimal plan from the current abstract state
   (in-graph table; host planner on a miss, only on steps where some episode misses).
3. planner turn: when its skill has finished, the planner checks that the atoms its model predicted
   hold, then starts the next operator's skill. It is *stuck* if they do not hold, if it has no plan,
   or if the low-level state did not change since its last step (a blocked move). Stuck hands control
   to the bridge at this same state (detection itself costs no env step).
4. bridge turn: when its skill has finished, the bridge picks an applicable ground skill or CallPlanner
   (applicable once the state changed since the bridge took over). Evaluated only on steps where some
   episode decides, so a costly learned bridge is not paid while planners act.
5. execute: CallPlanner emits one zero action and gives control back to a fresh plan from the current
   state; otherwise the running skill's action is applied.

Everything is branch-free (`jnp.where`), so it runs unchanged under `vmap`, `jit` and sharding.
"""
from __future__ import annotations

from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv, SkillCall, idle_call, tree_where
from jaxbridge.bridges import Bridge
from planner.tables import PlanLookup, PlanTable, batched_plan_lookup, holds_all, num_words, pack_atoms

PLANNER, BRIDGE = 0, 1
# Who produced a step's action, as recorded in traces.
ACTOR_PLANNER, ACTOR_BRIDGE, ACTOR_CALL_PLANNER = 0, 1, 2


@struct.dataclass
class Episode:
    env_state: Any
    stuck_state: Any  # the state at which control last passed to the bridge
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


@struct.dataclass
class BridgeTurn:
    decide: jax.Array  # bool: the bridge must choose this step
    obs: BridgeObs
    slot_mask: jax.Array  # bool[num_skills, num_slots]: applicable ground instances


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
    features: jax.Array  # float32[F]: the bridge's observation at this step
    can_plan: jax.Array  # bool: CallPlanner was applicable
    env_state: Any  # state before the step


@struct.dataclass
class EpisodeResult:
    success: jax.Array
    steps: jax.Array
    planner_calls: jax.Array
    table_misses: jax.Array
    bridge_decisions: jax.Array
    stuck_events: jax.Array


def same_state(a: jax.Array, b: jax.Array) -> jax.Array:
    """The authors' repeated-state test (numpy allclose defaults)."""
    return jnp.all(jnp.abs(a - b) <= 1e-8 + 1e-5 * jnp.abs(b))


def start_episode(env: NoveltyEnv, task: Any, horizon: jax.Array) -> Episode:
    state = env.reset(task)
    vec = env.state_vector(state)
    zero = jnp.int32(0)
    return Episode(env_state=state, stuck_state=state, t=zero, horizon=jnp.int32(horizon),
                   done=jnp.bool_(False), success=jnp.bool_(False), control=jnp.int32(PLANNER),
                   call=idle_call(), expected=jnp.zeros(num_words(env.num_atoms), jnp.uint32),
                   prev_vec=vec, planner_stepped=jnp.bool_(False), bridge_vec=vec,
                   planner_calls=jnp.int32(1), table_misses=zero, bridge_decisions=zero,
                   stuck_events=zero)


def observe(env: NoveltyEnv, ep: Episode):
    """Abstract the state and close the episode at the goal or the horizon."""
    atoms = env.abstract(ep.env_state)
    goal = env.goal_reached(ep.env_state)
    ep = ep.replace(success=ep.success | (~ep.done & goal), done=ep.done | goal | (ep.t >= ep.horizon))
    need_plan = ~ep.done & (ep.control == PLANNER) & ~ep.call.running
    return ep, atoms, pack_atoms(atoms), need_plan


def applicable_actions(env: NoveltyEnv, table: PlanTable, atoms: jax.Array, state: Any) -> jax.Array:
    """bool[num_skills, num_slots]: ground skills whose operator preconditions hold (and initiable)."""
    atoms_ext = jnp.concatenate([atoms, jnp.ones(1, bool)])  # id num_atoms = always true (padding)
    op_ok = table.op_valid & jnp.all(atoms_ext[table.op_pre], axis=-1)
    mask = jnp.zeros((env.num_skills, env.num_slots), bool).at[table.op_skill, table.op_slot].max(op_ok)
    return mask & env.skill_initiable(state)


def planner_turn(env: NoveltyEnv, ep: Episode, atoms: jax.Array, key: jax.Array, plan: PlanLookup,
                 table: PlanTable, rng: jax.Array) -> tuple[Episode, BridgeTurn]:
    """Follow the plan; on stuck hand control to the bridge; say whether the bridge must choose."""
    state, live = ep.env_state, ~ep.done
    vec = env.state_vector(state)
    planning = live & (ep.control == PLANNER)
    repeated = planning & ep.planner_stepped & same_state(vec, ep.prev_vec)
    needs_op = planning & ~ep.call.running
    can_continue = plan.found & (plan.op >= 0) & holds_all(ep.expected, key)
    stuck = repeated | (needs_op & ~can_continue)
    start_op = needs_op & ~stuck

    op = jnp.maximum(plan.op, 0)
    skill = table.op_skill[op]
    planner_call = SkillCall(skill=skill, slot=table.op_slot[op], param=env.sample_params(rng)[skill],
                             running=jnp.bool_(True), steps=jnp.int32(0))
    abandoned = ep.call.replace(running=ep.call.running & ~stuck)
    ep = ep.replace(
        call=tree_where(start_op, planner_call, abandoned),
        expected=jnp.where(start_op, plan.next_key, ep.expected),
        control=jnp.where(stuck, BRIDGE, ep.control),
        stuck_state=tree_where(stuck, state, ep.stuck_state),
        bridge_vec=jnp.where(stuck, vec, ep.bridge_vec),
        table_misses=ep.table_misses + (plan.miss & needs_op),
        stuck_events=ep.stuck_events + stuck,
    )
    slot_mask = applicable_actions(env, table, atoms, state)
    can_plan = ~same_state(vec, ep.bridge_vec)
    num_ground = jnp.concatenate([slot_mask.sum(-1), can_plan[None]]).astype(jnp.int32)
    decide = live & (ep.control == BRIDGE) & ~ep.call.running
    obs = BridgeObs(features=env.features(state, ep.stuck_state), num_ground=num_ground)
    return ep, BridgeTurn(decide=decide, obs=obs, slot_mask=slot_mask)


def execute(env: NoveltyEnv, ep: Episode, turn: BridgeTurn, choice: BridgeAction, stuck: jax.Array,
            rng: jax.Array) -> tuple[Episode, StepRecord]:
    """Start the bridge's choice if it made one, then take one env step."""
    state, live = ep.env_state, ~ep.done
    call_planner = turn.decide & (choice.skill >= env.num_skills)
    start_skill = turn.decide & ~call_planner
    skill = jnp.clip(choice.skill, 0, env.num_skills - 1)
    # The Q-function does not see which object a skill acts on: pick uniformly among its ground slots.
    scores = jnp.where(turn.slot_mask[skill], jax.random.uniform(rng, (env.num_slots,)), -1.0)
    bridge_call = SkillCall(skill=skill, slot=jnp.argmax(scores).astype(jnp.int32), param=choice.param,
                            running=jnp.bool_(True), steps=jnp.int32(0))
    call = tree_where(start_skill, bridge_call, ep.call)

    action = jnp.where(call_planner, 0.0, env.skill_action(state, call))  # CallPlanner: a no-op step
    next_state = tree_where(live, env.step(state, action), state)
    finished = env.skill_done(state, next_state, call)
    planner_acted = live & (ep.control == PLANNER)
    actor = jnp.where(call_planner, ACTOR_CALL_PLANNER, jnp.where(planner_acted, ACTOR_PLANNER, ACTOR_BRIDGE))
    record = StepRecord(live=live, actor=actor, decided=turn.decide, stuck=stuck,
                        skill=jnp.where(call_planner, env.num_skills, call.skill), slot=call.slot,
                        param=call.param, features=turn.obs.features,
                        can_plan=turn.obs.num_ground[-1] > 0, env_state=state)
    ep = ep.replace(
        env_state=next_state,
        t=ep.t + live,
        call=call.replace(running=live & ~call_planner & call.running & ~finished,
                          steps=call.steps + live),
        control=jnp.where(call_planner, PLANNER, ep.control),
        expected=jnp.where(call_planner[None], jnp.zeros_like(ep.expected), ep.expected),
        prev_vec=env.state_vector(state),
        planner_stepped=planner_acted,  # False after CallPlanner: the new plan starts fresh
        planner_calls=ep.planner_calls + call_planner,
        bridge_decisions=ep.bridge_decisions + turn.decide,
    )
    return ep, record


@partial(jax.jit, static_argnames=("env", "bridge", "max_steps", "record"))
def rollout(env: NoveltyEnv, bridge: Bridge, bridge_params: Any, tasks: Any, tables: PlanTable,
            horizons: jax.Array, key: jax.Array, max_steps: int, record: bool = False):
    """Run the meta-policy on a batch of B episodes for at most `max_steps` env steps.

    tasks, tables, horizons and bridge_params (None, or a pytree) carry a leading batch axis B.
    Returns EpisodeResult[B] and, with `record`, StepRecord[max_steps, B].
    """
    num_episodes = horizons.shape[0]
    episodes = jax.vmap(partial(start_episode, env))(tasks, horizons)
    episode_keys = jax.random.split(key, num_episodes)
    no_choice = BridgeAction(skill=jnp.zeros(num_episodes, jnp.int32),
                             param=jnp.zeros(num_episodes, jnp.float32))

    def step(episodes: Episode, t: jax.Array):
        keys = jax.vmap(lambda k: jax.random.split(jax.random.fold_in(k, t), 3))(episode_keys)
        episodes, atoms, packed, need_plan = jax.vmap(partial(observe, env))(episodes)
        plan = batched_plan_lookup(tables, packed, need_plan)
        stuck_before = episodes.stuck_events
        episodes, turn = jax.vmap(partial(planner_turn, env))(episodes, atoms, packed, plan, tables,
                                                              keys[:, 0])
        choice = jax.lax.cond(jnp.any(turn.decide),
                              lambda: jax.vmap(bridge)(bridge_params, turn.obs, keys[:, 1]),
                              lambda: no_choice)
        stuck = episodes.stuck_events > stuck_before
        episodes, rec = jax.vmap(partial(execute, env))(episodes, turn, choice, stuck, keys[:, 2])
        return episodes, (rec if record else None)

    episodes, records = jax.lax.scan(step, episodes, jnp.arange(max_steps))
    episodes, *_ = jax.vmap(partial(observe, env))(episodes)  # the goal test on the final state
    result = EpisodeResult(success=episodes.success, steps=episodes.t,
                           planner_calls=episodes.planner_calls, table_misses=episodes.table_misses,
                           bridge_decisions=episodes.bridge_decisions, stuck_events=episodes.stuck_events)
    return result, records
