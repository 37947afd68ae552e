"""The planner/bridge meta-policy: the paper's Algorithm 1 as a `lax.scan` over env steps.

Per env step, for a whole batch of episodes (any mix of seeds and tasks):

1. observe: abstract the state (a learned model adds its invented atoms); the episode ends at the goal
   or the horizon.
2. plan: the planner looks up the next operator of an optimal plan from the current abstract state
   (in-graph table; host planner on a miss, only on steps where some episode misses).
3. planner turn: when its skill has finished, the planner checks that the atoms its model predicted
   hold, then starts the next operator's skill. It is *stuck* if they do not hold, if it has no plan,
   or if the low-level state did not change since its last step (a blocked move). Stuck hands control
   to the bridge at this same state (detection itself costs no env step), remembering the stalled
   operator's skill (the failure signature's first half, core/signatures.py).
4. bridge turn: when its skill has finished, the bridge picks an applicable ground skill or CallPlanner
   (applicable once the state changed since the bridge took over; with the loop guard, a skill it
   already chose in this same state, which left it unchanged, is not). Evaluated only on steps where
   some episode decides, so a costly learned bridge is not paid while planners act.
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

from envs_jax.base import (ACTOR_BRIDGE, ACTOR_CALL_PLANNER, ACTOR_PLANNER, BridgeObs, NoveltyEnv, SkillCall,
                           idle_call, tree_where)
from jaxbridge.core.bridges import Bridge
from jaxbridge.core.episode import (BRIDGE, PLANNER, Controls, Decision, Episode, EpisodeResult, StepRecord, observation,
                                    observation_size)
from jaxbridge.core.learned_atoms import invented_holds, learned_call
from jaxbridge.core.tasks import TaskArrays
from planner.tables import (PlanLookup, PlanTable, batched_plan_lookup, holds_all, num_words, pack_atoms,
                            table_lookup)


def same_state(a: jax.Array, b: jax.Array) -> jax.Array:
    """The authors' repeated-state test (numpy allclose defaults)."""
    return jnp.all(jnp.abs(a - b) <= 1e-8 + 1e-5 * jnp.abs(b))


def start_episode(env: NoveltyEnv, controls: Controls, task: Any, horizon: jax.Array, plan_length: int = 0,
                  words: int | None = None) -> Episode:
    """The planner starts in control with a plan from the initial state (without a planner, the bridge
    starts). `plan_length`: the plan states kept with `plan_progress`; `words`: of a packed abstract state
    (default: the env's atoms; a learned model's tables have more)."""
    state = env.reset(task)
    words = num_words(env.num_atoms) if words is None else words
    vec = env.state_vector(state)
    zero = jnp.int32(0)
    return Episode(env_state=state, stuck_state=state, stalled_skill=jnp.int32(-1), t=zero, horizon=jnp.int32(horizon),
                   done=jnp.bool_(False), success=jnp.bool_(False),
                   control=jnp.int32(PLANNER if controls.planner else BRIDGE),
                   call=idle_call(), expected=jnp.zeros(words, jnp.uint32),
                   prev_vec=vec, planner_stepped=jnp.bool_(False), bridge_vec=vec,
                   planner_calls=jnp.int32(int(controls.planner)), table_misses=zero, bridge_decisions=zero,
                   stuck_events=zero, decision_vec=vec, decision_skill=jnp.int32(-1),
                   no_op_skills=jnp.zeros(env.num_skills, bool),
                   plan_keys=jnp.zeros((plan_length, words), jnp.uint32),
                   plan_ops=jnp.full(plan_length, -1, jnp.int32), plan_at=zero, new_plan=jnp.bool_(True))


def observe(env: NoveltyEnv, ep: Episode, table: PlanTable | None = None):
    """Abstract the state (with a learned model's table, its invented atoms after the env's) and close the
    episode at the goal or the horizon."""
    goal = env.goal_reached(ep.env_state)
    ep = ep.replace(success=ep.success | (~ep.done & goal), done=ep.done | goal | (ep.t >= ep.horizon))
    need_plan = ~ep.done & (ep.control == PLANNER) & ~ep.call.running
    atoms = env.abstract(ep.env_state)
    if table is not None and table.model is not None:
        atoms = jnp.concatenate([atoms, invented_holds(table.model, env.objects(ep.env_state))])
    return ep, pack_atoms(atoms), need_plan


def applicable_ops(env: NoveltyEnv, table: PlanTable, atoms: jax.Array, state: Any) -> jax.Array:
    """bool[O]: ground operators whose preconditions hold and whose skill can start.

    These are the bridge's ground actions (the authors' applicable ground NSRTs)."""
    pre_hold = holds_all(table.op_pre, atoms[None, :])
    return table.op_valid & pre_hold & env.skill_initiable(state, table.op_skill, table.op_slot)


def count_by_skill(env: NoveltyEnv, table: PlanTable, op_ok: jax.Array) -> jax.Array:
    """int32[num_skills]: applicable ground operators of each skill."""
    of_skill = table.op_skill[None, :] == jnp.arange(env.num_skills)[:, None]
    return jnp.sum(of_skill & op_ok[None, :], axis=-1, dtype=jnp.int32)


def guard_loops(ep: Episode, vec: jax.Array, skill_counts: jax.Array, can_plan: jax.Array):
    """The loop guard: (skill counts without the skills that left this state unchanged, those skills).

    In a deterministic env a skill that changed nothing changes nothing when chosen again in the same
    state with the same grounding and parameter, and a greedy bridge would choose it again until the
    horizon (docs/TUNING.md). The whole skill is left out (the Q-function's argmax would land
    on a nearby parameter again), so another parameter that would have worked is lost at this state.
    The set grows while the bridge decides in the same state and empties when it decides in another;
    where it would leave nothing to choose, nothing is left out."""
    unchanged = (ep.decision_skill >= 0) & same_state(vec, ep.decision_vec)
    last = jnp.arange(skill_counts.shape[0]) == ep.decision_skill  # CallPlanner (num_skills) adds nothing
    no_ops = unchanged & (ep.no_op_skills | last)
    guarded = jnp.where(no_ops, 0, skill_counts)
    keep = can_plan | jnp.any(guarded > 0)
    return jnp.where(keep, guarded, skill_counts), no_ops & keep


def hashed_choice(mask: jax.Array, bits: jax.Array) -> jax.Array:
    """A uniformly random set entry of `mask` (0 if none), from one random uint32.

    Each index gets a score from an integer hash of (bits, index) (the murmur3 finaliser) in the high
    bits and its own index in the low bits, so one plain max picks the winner (no ties): on CPU much
    cheaper than a uniform per entry, an argmax, or a cumulative-sum search."""
    n = mask.shape[-1]
    index_bits = max(1, (n - 1).bit_length())
    index = jnp.arange(n, dtype=jnp.uint32)
    x = bits ^ (index * jnp.uint32(0x9E3779B9))
    x = (x ^ (x >> 16)) * jnp.uint32(0x85EBCA6B)
    x = (x ^ (x >> 13)) * jnp.uint32(0xC2B2AE35)
    x = x ^ (x >> 16)
    score = ((x >> index_bits) << index_bits) | index
    best = jnp.max(jnp.where(mask, score, jnp.uint32(0)))
    return (best & jnp.uint32((1 << index_bits) - 1)).astype(jnp.int32)


def planner_turn(env: NoveltyEnv, ep: Episode, atoms: jax.Array, plan: PlanLookup, table: PlanTable,
                 u_param: jax.Array) -> tuple[Episode, jax.Array]:
    """Follow the plan; on stuck hand control to the bridge; say whether the bridge must choose."""
    state, live = ep.env_state, ~ep.done
    vec = env.state_vector(state)
    planning = live & (ep.control == PLANNER)
    repeated = planning & ep.planner_stepped & same_state(vec, ep.prev_vec)
    needs_op = planning & ~ep.call.running
    effects_hold = holds_all(ep.expected, atoms)
    can_continue = plan.found & (plan.op >= 0) & effects_hold
    stuck = repeated | (needs_op & ~can_continue)
    stalled_op = repeated | ~effects_hold  # its operator's skill stalled; else there was no plan
    start_op = needs_op & ~stuck

    op = jnp.maximum(plan.op, 0)
    skill, slot = table.op_skill[op], table.op_slot[op]
    param = env.param_from_uniform(skill, u_param)
    if table.model is not None:  # a learned model's operator: a code of its skill, slot and sampler
        learned = learned_call(table.model, plan.op, env.objects(state))
        skill, slot = jnp.where(learned.learned, learned.skill, skill), jnp.where(learned.learned, learned.slot, slot)
        param = jnp.where(learned.learned & learned.sampled, learned.param, env.param_from_uniform(skill, u_param))
    planner_call = SkillCall(skill=skill, slot=slot, param=param, running=jnp.bool_(True), steps=jnp.int32(0))
    abandoned = ep.call.replace(running=ep.call.running & ~stuck)
    ep = ep.replace(
        call=tree_where(start_op, planner_call, abandoned),
        expected=jnp.where(start_op, plan.next_key, ep.expected),
        control=jnp.where(stuck, BRIDGE, ep.control),
        stuck_state=tree_where(stuck, state, ep.stuck_state),
        stalled_skill=jnp.where(stuck, jnp.where(stalled_op, ep.call.skill, -1), ep.stalled_skill),
        bridge_vec=jnp.where(stuck, vec, ep.bridge_vec),
        table_misses=ep.table_misses + (plan.miss & needs_op),
        stuck_events=ep.stuck_events + stuck,
        plan_at=ep.plan_at + start_op,
    )
    decide = live & (ep.control == BRIDGE) & ~ep.call.running
    return ep, decide


@struct.dataclass
class MetaPolicy:
    """Algorithm 1's players on one env: the planner, acting through each episode's plan table, and the bridge
    policy `bridge` with its `params` (None, or a pytree with a leading episode axis; with `shared_params`,
    one pytree every episode uses: one network whose layers multiply all episodes at once). `controls`
    picks the approach's parts of the meta-policy. Only `params` is traced."""

    env: NoveltyEnv = struct.field(pytree_node=False)
    bridge: Bridge = struct.field(pytree_node=False)
    params: Any = None
    controls: Controls = struct.field(pytree_node=False, default=Controls())
    shared_params: bool = struct.field(pytree_node=False, default=False)


def bridge_turn(policy: MetaPolicy, ep: Episode, table: PlanTable, atoms: jax.Array, key: jax.Array,
                choice_bits: jax.Array) -> Decision:
    """The bridge observes, chooses a skill and parameter, and the choice is grounded uniformly at
    random among the applicable ground operators of that skill (the Q-function does not see objects).
    CallPlanner is applicable once the state changed since the bridge took over (and never without it)."""
    env, controls = policy.env, policy.controls
    state = ep.env_state
    vec = env.state_vector(state)
    op_ok = applicable_ops(env, table, atoms, state)
    can_plan = ~same_state(vec, ep.bridge_vec) & controls.call_planner
    skill_counts, no_ops = count_by_skill(env, table, op_ok), jnp.zeros(env.num_skills, bool)
    if controls.loop_guard:
        skill_counts, no_ops = guard_loops(ep, vec, skill_counts, can_plan)
        op_ok = op_ok & ~no_ops[table.op_skill]
    num_ground = jnp.concatenate([skill_counts, can_plan[None].astype(jnp.int32)])
    obs = BridgeObs(features=observation(env, controls, state, ep.stuck_state, ep.stalled_skill), num_ground=num_ground)
    choice = policy.bridge(policy.params, obs, key)
    skill = jnp.clip(choice.skill, 0, env.num_skills if controls.call_planner else env.num_skills - 1)
    op = hashed_choice(op_ok & (table.op_skill == skill), choice_bits)
    action = choice.action if controls.low_level else jnp.zeros(env.action_dim, jnp.float32)
    return Decision(skill=skill.astype(jnp.int32), slot=table.op_slot[op], param=choice.param,
                    features=obs.features, num_ground=num_ground, no_op_skills=no_ops, action=action)


def execute(env: NoveltyEnv, ep: Episode, decide: jax.Array, decision: Decision, stuck: jax.Array,
            progressed: jax.Array, low_level: bool = False) -> tuple[Episode, StepRecord]:
    """Start the bridge's decision if it made one, then take one env step (a low-level bridge's decision
    is its raw action for this one step: no skill starts, and it decides again at the next)."""
    state, live = ep.env_state, ~ep.done
    call_planner = decide & (decision.skill >= env.num_skills)
    raw = decide & ~call_planner & low_level
    start_skill = decide & ~call_planner & ~raw
    bridge_call = SkillCall(skill=decision.skill, slot=decision.slot, param=decision.param,
                            running=jnp.bool_(True), steps=jnp.int32(0))
    call = tree_where(start_skill, bridge_call, ep.call)

    vec = env.state_vector(state)
    action = jnp.where(call_planner, 0.0, env.skill_action(state, call))  # CallPlanner: a no-op step
    if low_level:
        action = jnp.where(raw, decision.action, action)
    next_state = tree_where(live, env.step(state, action), state)
    acted = live & ~call_planner & ~raw & call.running  # a skill's policy chose this step's action
    next_state = tree_where(acted, env.after_skill_step(state, next_state, call), next_state)
    finished = env.skill_done(state, next_state, call)
    planner_acted = live & (ep.control == PLANNER)
    actor = jnp.where(call_planner, ACTOR_CALL_PLANNER, jnp.where(planner_acted, ACTOR_PLANNER, ACTOR_BRIDGE))
    record = StepRecord(live=live, actor=actor, decided=decide, stuck=stuck,
                        skill=jnp.where(call_planner, env.num_skills, call.skill), slot=call.slot,
                        param=call.param, features=decision.features, num_ground=decision.num_ground,
                        env_state=state, progressed=progressed)
    ep = ep.replace(
        env_state=next_state,
        t=ep.t + live,
        call=call.replace(running=live & ~call_planner & call.running & ~finished,
                          steps=call.steps + live),
        control=jnp.where(call_planner, PLANNER, ep.control),
        expected=jnp.where(call_planner, jnp.zeros_like(ep.expected), ep.expected),
        prev_vec=vec,
        planner_stepped=planner_acted,  # False after CallPlanner: the new plan starts fresh
        planner_calls=ep.planner_calls + call_planner,
        bridge_decisions=ep.bridge_decisions + decide,
        decision_vec=jnp.where(decide, vec, ep.decision_vec),
        decision_skill=jnp.where(decide, decision.skill, ep.decision_skill),
        no_op_skills=jnp.where(decide, decision.no_op_skills, ep.no_op_skills),
    )
    return ep, record


def plan_states(table: PlanTable, key: jax.Array, first: PlanLookup, length: int) -> tuple[jax.Array, jax.Array]:
    """The plan from abstract state `key`: its states (uint32[length, W], `key` first) and the operator
    from each to the next (int32[length], -1 past the plan's end). The first step is `first` (the
    table's or the host planner's answer at `key`), the rest the table's; the plan ends at the goal,
    a dead end, a state the table lacks, or `length`."""
    def follow(carry, k):
        key, going = carry
        look = tree_where(k == 0, first, table_lookup(table, key))
        op = jnp.where(going & look.found, look.op, -1)
        return (look.next_key, op >= 0), (key, op)

    _, (keys, ops) = jax.lax.scan(follow, (key, jnp.bool_(True)), jnp.arange(length))
    return keys, ops


def hand_back_at_progress(resume_plan: bool, ep: Episode, atoms: jax.Array) -> tuple[Episode, jax.Array]:
    """Where the bridge's skill has finished in a state holding every atom of a later state of its plan
    than the one the planner was heading for when stuck (the furthest such), control goes back to the
    planner: to that state's place in the plan with `resume_plan`, else to a new plan."""
    index = jnp.arange(ep.plan_ops.shape[0])
    is_state = jnp.concatenate([jnp.ones(1, bool), ep.plan_ops[:-1] >= 0])
    reached = is_state & (index >= jnp.maximum(ep.plan_at, 1)) & holds_all(ep.plan_keys, atoms[None, :])
    at = jnp.max(jnp.where(reached, index, -1))
    progressed = ~ep.done & (ep.control == BRIDGE) & ~ep.call.running & (at >= 0)
    replan = progressed & (not resume_plan)
    return ep.replace(control=jnp.where(progressed, PLANNER, ep.control),
                      expected=jnp.where(progressed, jnp.zeros_like(ep.expected), ep.expected),
                      plan_at=jnp.where(progressed & resume_plan, at, ep.plan_at),
                      new_plan=ep.new_plan | replan, planner_calls=ep.planner_calls + replan), progressed


def follow_plan(resume_plan: bool, tables: PlanTable, episodes: Episode, atoms: jax.Array, plan: PlanLookup,
                need_plan: jax.Array) -> tuple[Episode, PlanLookup]:
    """Record the plan of every episode starting one (a batch; only on steps where some does); with
    `resume_plan`, the planner's next operator is the recorded plan's, not the table's."""
    new = need_plan & episodes.new_plan
    length = episodes.plan_ops.shape[-1]

    def record(_):
        keys, ops = jax.vmap(partial(plan_states, length=length))(tables, atoms, plan)
        return jnp.where(new[:, None, None], keys, episodes.plan_keys), jnp.where(new[:, None], ops, episodes.plan_ops)

    keys, ops = jax.lax.cond(jnp.any(new), record, lambda _: (episodes.plan_keys, episodes.plan_ops), None)
    episodes = episodes.replace(plan_keys=keys, plan_ops=ops, plan_at=jnp.where(new, 0, episodes.plan_at),
                                new_plan=episodes.new_plan & ~new)
    if resume_plan:
        rows = jnp.arange(ops.shape[0])
        op = ops[rows, episodes.plan_at]
        plan = plan.replace(found=op >= 0, op=op, next_key=keys[rows, jnp.minimum(episodes.plan_at + 1, length - 1)])
    return episodes, plan


def step_randomness(keys: jax.Array, max_steps: int):
    """All of a rollout's randomness, drawn up front in two batched calls (per-step draws of a few
    numbers are dominated by PRNG call overhead on CPU): per step and episode, two uniforms (planner
    parameter), random bits (grounding the bridge's choice) and a key for the bridge. An episode's draws
    depend only on its own key, whatever else is in the batch."""
    def per_episode(key):
        k_uniform, k_bits, k_bridge = jax.random.split(key, 3)
        return (jax.random.uniform(k_uniform, (max_steps,)),
                jax.random.bits(k_bits, (max_steps,), jnp.uint32), jax.random.split(k_bridge, max_steps))

    return jax.tree.map(lambda x: jnp.swapaxes(x, 0, 1), jax.vmap(per_episode)(keys))


def no_plan(num_episodes: int, words: int) -> PlanLookup:
    return PlanLookup(found=jnp.zeros(num_episodes, bool), op=jnp.full(num_episodes, -1, jnp.int32),
                      next_key=jnp.zeros((num_episodes, words), jnp.uint32), miss=jnp.zeros(num_episodes, bool))


@struct.dataclass
class PlannerTurn:
    """A batch of episodes after steps 1-3 of a meta-policy step, before the bridge's turn."""

    episodes: Episode
    atoms: jax.Array  # uint32[B, W]: the packed abstract states
    decide: jax.Array  # bool[B]: the bridge must choose now
    stuck: jax.Array  # bool[B]: the planner got stuck at this state
    progressed: jax.Array  # bool[B]: the bridge reached a later state of its plan and handed back (plan_progress)


def planner_step(env: NoveltyEnv, controls: Controls, tables: PlanTable, episodes: Episode,
                 param_uniforms: jax.Array, host_planner: bool = True) -> PlannerTurn:
    """Steps 1-3 on a batch: observe (with `plan_progress`, the bridge's hand-back at a later plan state),
    look the plan up, the planner's turn."""
    episodes, packed, need_plan = jax.vmap(partial(observe, env))(episodes, tables)
    progressed = jnp.zeros_like(need_plan)
    if controls.plan_progress:
        episodes, progressed = jax.vmap(partial(hand_back_at_progress, controls.resume_plan))(episodes, packed)
        need_plan = need_plan | progressed
    if controls.planner:
        plan = batched_plan_lookup(tables, packed, need_plan, host_planner)
    else:  # pure RL: the control never returns to a planner, nothing is looked up
        plan = no_plan(packed.shape[0], packed.shape[-1])
    if controls.plan_progress:
        episodes, plan = follow_plan(controls.resume_plan, tables, episodes, packed, plan, need_plan)
    stuck_before = episodes.stuck_events
    episodes, decide = jax.vmap(partial(planner_turn, env))(episodes, packed, plan, tables, param_uniforms)
    return PlannerTurn(episodes, packed, decide, episodes.stuck_events > stuck_before, progressed)


def bridge_step(policy: MetaPolicy, tables: PlanTable, turn: PlannerTurn, choice_bits: jax.Array,
                bridge_keys: jax.Array, groups: jax.Array) -> tuple[Episode, StepRecord]:
    """Steps 4-5 on a batch: the bridge's turn where it must choose, then one env step."""
    env, controls = policy.env, policy.controls
    episodes, num_episodes = turn.episodes, turn.decide.shape[0]
    no_decision = Decision(skill=jnp.zeros(num_episodes, jnp.int32), slot=jnp.zeros(num_episodes, jnp.int32),
                           param=jnp.zeros(num_episodes, jnp.float32),
                           features=jnp.zeros((num_episodes, observation_size(env, controls)), jnp.float32),
                           num_ground=jnp.zeros((num_episodes, env.num_skills + 1), jnp.int32),
                           no_op_skills=jnp.zeros((num_episodes, env.num_skills), bool),
                           action=jnp.zeros((num_episodes, env.action_dim), jnp.float32))
    decision = jax.lax.cond(  # the bridge only runs on steps where some episode must choose
        jnp.any(turn.decide),
        lambda: jax.vmap(bridge_turn, in_axes=(None if policy.shared_params else 0,) + (0,) * 5)(
            policy, episodes, tables, turn.atoms, bridge_keys, choice_bits),
        lambda: no_decision)
    episodes, rec = jax.vmap(partial(execute, env, low_level=controls.low_level))(episodes, turn.decide, decision,
                                                                                  turn.stuck, turn.progressed)
    return episodes.replace(env_state=env.share_between_episodes(episodes.env_state, groups)), rec


@partial(jax.jit, static_argnames=("max_steps", "record", "host_planner"))
def rollout(policy: MetaPolicy, batch: TaskArrays, keys: jax.Array, max_steps: int, record: bool = False,
            groups: jax.Array | None = None, host_planner: bool = True):
    """Run the meta-policy on a batch of B episodes for at most `max_steps` env steps.

    `batch` (the episodes' tasks, plan tables and horizons) and keys (one per episode) carry a leading batch
    axis B, as `policy.params` does unless shared. `groups` (int[B], default: one group) says
    which episodes run concurrently in one world, for what an env shares between them
    (`share_between_episodes`: one seed's episodes of a cycle phase). Without `host_planner`, a state
    missing from a plan table is not planned on the host (the episode finds no plan); it is only counted
    in `table_misses`, and the results are then not the meta-policy's (learn/online.Cycle reruns them).
    Returns EpisodeResult[B] and, with `record`, StepRecord[max_steps, B].
    """
    env, controls = policy.env, policy.controls
    tasks, tables, horizons = batch.tasks, batch.tables, batch.horizons
    num_episodes = horizons.shape[0]
    groups = jnp.zeros(num_episodes, jnp.int32) if groups is None else groups
    plan_length = max_steps + 1 if controls.plan_progress else 0  # no plan is longer than the episode
    words = tables.goal_key.shape[-1]
    episodes = jax.vmap(partial(start_episode, env, controls, plan_length=plan_length, words=words))(tasks, horizons)

    def step(episodes: Episode, randomness):
        param_uniforms, choice_bits, bridge_keys = randomness  # float32[B], uint32[B], key[B]
        turn = planner_step(env, controls, tables, episodes, param_uniforms, host_planner)
        episodes, rec = bridge_step(policy, tables, turn, choice_bits, bridge_keys, groups)
        return episodes, (rec if record else None)

    randomness = step_randomness(keys, max_steps)
    if record:  # the records are one row per step: every step runs
        episodes, records = jax.lax.scan(step, episodes, randomness)
    else:  # stop once every episode is done: the steps after it change none of the results
        def more(carry):
            t, episodes = carry
            return (t < max_steps) & ~jnp.all(episodes.done)

        def one_step(carry):
            t, episodes = carry
            return t + 1, step(episodes, jax.tree.map(lambda r: r[t], randomness))[0]

        _, episodes = jax.lax.while_loop(more, one_step, (jnp.int32(0), episodes))
        records = None
    episodes, *_ = jax.vmap(partial(observe, env))(episodes)  # the goal test on the final state
    result = EpisodeResult(success=episodes.success, steps=episodes.t,
                           planner_calls=episodes.planner_calls, table_misses=episodes.table_misses,
                           bridge_decisions=episodes.bridge_decisions, stuck_events=episodes.stuck_events)
    return result, records
