"""The learned model's planner alone (no bridge): plan from the state reached, run the plan's operators'
skills each to its end while the atoms each one ends in are the ones the model predicts, and plan afresh
from the state reached where they are not, until the goal; a skill that changes nothing, no plan, or the
horizon is a failure."""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import jax
import jax.numpy as jnp

from envs_jax.base import NoveltyEnv, SkillCall
from jaxbridge.core.meta_policy import same_state
from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.planning import ModelPlanner
from jaxbridge.learn.model.segments import TaskReader


@dataclass(frozen=True)
class PlannedEpisode:
    success: bool
    steps: int  # env steps taken
    operators: tuple[str, ...]  # the operators run, in order
    ended: str  # "goal", "no plan", "stalled" or "horizon"


@partial(jax.jit, static_argnums=0)
def _run_skill(env: NoveltyEnv, state, call: SkillCall, budget):
    """The skill call run to its end or for `budget` env steps, in one compiled loop (compiled once per env,
    an env being equal by value): (state reached, steps taken, whether any step changed the state by the
    meta-policy's repeated-state test)."""
    def step(carry):
        state, steps, changed, _ = carry
        running = call.replace(steps=call.steps + steps)
        nxt = env.after_skill_step(state, env.step(state, env.skill_action(state, running)), running)
        moved = ~same_state(env.state_vector(nxt), env.state_vector(state))
        return nxt, steps + 1, changed | moved, env.skill_done(state, nxt, running)

    state, steps, changed, _ = jax.lax.while_loop(lambda c: ~c[3] & (c[1] < budget), step,
                                                  (state, jnp.int32(0), jnp.bool_(False), jnp.bool_(False)))
    return state, steps, changed


def run_planner_alone(env: NoveltyEnv, model: LearnedModel, spec, horizon: int | None = None) -> PlannedEpisode:
    """One episode of `spec` acted by the learned model's plans alone."""
    reader, goal, planner = TaskReader(env, spec), env.planner_problem(spec).goal, ModelPlanner(model)
    horizon = spec.horizon if horizon is None else horizon
    state, steps, ran = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec))), 0, []
    planned, expected = [], None  # the plan's operators left, and the atoms the model predicts now
    while steps < horizon:
        if bool(env.goal_reached(state)):
            return PlannedEpisode(True, steps, tuple(ran), "goal")
        view = reader.observe(state)
        atoms = model.atoms(view)
        if not planned or atoms != expected:  # the plan's prediction failed (or it ran out): plan afresh
            planned = planner.plan(view, goal)
            if not planned:
                return PlannedEpisode(False, steps, tuple(ran), "no plan")
        op, planned = planned[0], planned[1:]
        expected = (atoms - op.delete) | op.add
        spec_of = env.skills[env.skill_index(op.skill)]
        sampler = model.samplers.get(op.name)
        param = sampler(view, op.slot_object, op.args) if sampler else (spec_of.param_low + spec_of.param_high) / 2
        slot = env.object_slot(op.slot_object) if op.slot_object else 0
        call = SkillCall(jnp.int32(env.skill_index(op.skill)), jnp.int32(slot), jnp.float32(param), jnp.bool_(True), jnp.int32(0))
        state, taken, changed = _run_skill(env, state, call, jnp.int32(horizon - steps))
        steps += int(taken)
        ran.append(str(op))
        if not bool(changed):
            return PlannedEpisode(False, steps, tuple(ran), "stalled")
    return PlannedEpisode(bool(env.goal_reached(state)), steps, tuple(ran), "goal" if env.goal_reached(state) else "horizon")
