"""One recorded episode on the host: what the still picture (`render`) and the animation (`animate`) draw.

`render.trace_episodes` fills these from a recorded rollout; tests build small ones by hand.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from jaxbridge.meta_policy import ACTOR_BRIDGE


@dataclass(frozen=True)
class EpisodeTrace:
    """One recorded episode: what the pictures need, nothing more. Arrays over steps describe each env
    step; arrays over steps + 1 describe the states before each step, then after the last."""

    spec: Any  # the task's host-side spec
    seed: int
    task: int  # index among its seed's tasks
    success: bool
    bridge_decisions: int
    actor: np.ndarray  # int32[steps]: ACTOR_* of each step
    xy: np.ndarray  # float32[steps + 1, 2]: the robot
    open: np.ndarray  # bool[steps + 1, D]: the open doors (Coffee: the jug graspable)
    details: np.ndarray | None = None  # float[steps + 1, K]: whatever else the env's drawer records
    # The ground skill each step ran (None in hand-made traces that do not need them).
    skill: np.ndarray | None = None  # int32[steps]: skill id; env.num_skills is CallPlanner
    slot: np.ndarray | None = None  # int32[steps]: the object it acts on (the env's slot)
    param: np.ndarray | None = None  # float32[steps]: its continuous parameter
    decided: np.ndarray | None = None  # bool[steps]: the bridge chose that skill (or CallPlanner) then

    @property
    def steps(self) -> int:
        return len(self.actor)

    @property
    def opened_at(self) -> np.ndarray:
        """int[D]: the step on which each door opened; -1 if it did not open during the episode."""
        change = self.open[1:] & ~self.open[:-1]
        first = np.argmax(np.concatenate([change, np.ones((1, change.shape[1]), bool)]), axis=0)  # steps: never
        return np.where(first < self.steps, first, -1)

    @property
    def opened_by_bridge(self) -> np.ndarray:
        """bool[D]: doors that opened on a step the bridge took (only the bridge's skills turn knobs)."""
        actor = np.append(self.actor, -1)  # index -1 (never opened) reads the pad
        return actor[self.opened_at] == ACTOR_BRIDGE


def actor_segments(actor: np.ndarray) -> list[tuple[int, int, int]]:
    """Maximal runs of steps with one actor, as (actor, first step, end step). Run (a, i, j) moved the robot
    along path points i..j: consecutive runs share a point, so the drawn path has no gaps."""
    actor = np.asarray(actor)
    cuts = np.flatnonzero(np.diff(actor)) + 1
    starts, ends = np.concatenate([[0], cuts]), np.concatenate([cuts, [len(actor)]])
    return [(int(actor[i]), int(i), int(j)) for i, j in zip(starts, ends) if j > i]


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
