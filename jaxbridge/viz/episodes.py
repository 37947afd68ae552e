"""Recorded episodes in words: which one to draw, and the ground skills the bridge chose, as labels."""
from __future__ import annotations

import numpy as np

from envs_jax.drawing import EpisodeTrace


def pick_episode(traces: list[EpisodeTrace]) -> EpisodeTrace:
    """The solved episode on which the bridge opened the most doors (the first if tied), else the first."""
    solved = [t for t in traces if t.success]
    return max(solved, key=lambda t: int(t.opened_by_bridge.sum())) if solved else traces[0]


def object_type(env, skill: int) -> str | None:
    """The type of object a skill acts on, from the planner's operators ("door" for MoveToDoor); None if
    the skill has one ground instance (its slot means nothing)."""
    for op in env.domain.operators:
        if op.skill == env.skill_names[skill] and op.slot_param is not None:
            return dict(op.params)[op.slot_param]
    return None


def skill_label(env, skill: int, slot: int, param: float) -> str:
    """A ground skill in words: "MoveToDoor(door 5)", "TurnKey(cell 3, param 0.75)", "PickJug", "CallPlanner".
    The param shows only where the skill samples it (a constant says nothing)."""
    if skill >= env.num_skills:
        return "CallPlanner"
    spec, kind = env.skills[skill], object_type(env, skill)
    args = ([f"{kind} {slot}"] if kind else []) + ([f"param {param:.2f}"] if spec.param_low != spec.param_high else [])
    return f"{spec.name}({', '.join(args)})" if args else spec.name


def bridge_choices(env, trace: EpisodeTrace, upto: int | None = None) -> list[tuple[int, str]]:
    """(step, what the bridge chose) at each of its decisions in the first `upto` steps (all by default);
    steps count from 1, as the animation's captions do."""
    if trace.decided is None:
        return []
    end = trace.steps if upto is None else upto
    return [(int(i) + 1, skill_label(env, int(trace.skill[i]), int(trace.slot[i]), float(trace.param[i])))
            for i in np.flatnonzero(trace.decided[:end])]
