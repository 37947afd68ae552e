"""Segments: recorded episodes cut into ground skill executions, each with the states it began and ended
in, read through the env contract (the object view, `object_names`, the planner's atoms).

A segment is one call of a skill (by the planner or the bridge): its skill, the planner object its slot
names, its parameter, the `View` before and after, and how many env steps it took. The model learner reads nothing else.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import jax
import numpy as np

from envs_jax.base import ACTOR_BRIDGE, ACTOR_PLANNER, NoveltyEnv
from planner.strips import Atom, ground


@dataclass(frozen=True)
class View:
    """One state as the learner sees it: each object-view slot's planner name (None: not in the task),
    type, features and position, and the planner model's atoms that hold (static ones included)."""

    names: tuple[str | None, ...]
    types: tuple[str, ...]
    features: np.ndarray  # float32[N, W]
    position: np.ndarray  # float32[N, 3]
    given: frozenset[Atom]

    def objects(self) -> dict[str, str]:
        """{name: type} of the task's objects."""
        return {n: t for n, t in zip(self.names, self.types) if n is not None}


@dataclass(frozen=True)
class Segment:
    skill: str
    slot_object: str | None  # the planner object the call's slot names (None: a skill with one instance)
    param: float
    by_bridge: bool  # the bridge chose it (else the planner's plan did)
    before: View
    after: View
    steps: int = 1  # env steps the call took


class TaskReader:
    """What one task's states mean to the planner: its atoms by index and the objects skills' slots name."""

    def __init__(self, env: NoveltyEnv, spec):
        self.env = env
        problem = env.planner_problem(spec)
        ops = ground(problem)
        fluent = set(problem.init) | set(problem.goal) | {a for op in ops for a in op.pre | op.add | op.delete}
        self.atoms = {env.atom_index(a): a for a in fluent}
        self.static = problem.static
        self.slot_objects = {(env.skill_index(op.skill), env.object_slot(op.slot_object)): op.slot_object
                             for op in ops if op.slot_object is not None}
        self.names = env.object_names(spec)
        self.type_names = tuple(type(env).object_types)  # by type id

    def view(self, type_id, features, position, abstract) -> View:
        given = frozenset(self.atoms[i] for i in np.flatnonzero(abstract) if i in self.atoms) | self.static
        return View(self.names, tuple(self.type_names[t] for t in type_id), features, position, given)

    def observe(self, state) -> View:
        """The view of one env state of the task."""
        objects, abstract = jax.tree.map(np.asarray, _seen(self.env, state))
        return self.view(objects.type_id, objects.features, objects.position, abstract)


def _objects_and_atoms(env: NoveltyEnv, state):
    return env.objects(state), env.abstract(state)


# compiled once per env (an env is equal by value): one state, and every recorded state [T, B]
_seen = jax.jit(_objects_and_atoms, static_argnums=0)
_recorded_views = jax.jit(lambda env, states: jax.vmap(jax.vmap(partial(_objects_and_atoms, env)))(states), static_argnums=0)


def segments_from_records(env: NoveltyEnv, specs: list, records) -> list[Segment]:
    """Every completed skill call of the recorded episodes (`StepRecord[T, B]`, episode b ran `specs[b]`):
    consecutive live steps of one actor with one skill, slot and parameter, ended by the state after its
    last step (the next record's: an episode that is done keeps its state; the last record has none)."""
    objects, abstract = jax.tree.map(np.asarray, _recorded_views(env, records.env_state))
    type_id, features, position = objects.type_id, objects.features, objects.position
    live, actor, decided = (np.asarray(x) for x in (records.live, records.actor, records.decided))
    skill, slot, param = (np.asarray(x) for x in (records.skill, records.slot, records.param))
    readers: dict = {}
    segments = []
    for b, spec in enumerate(specs):
        if spec not in readers:
            readers[spec] = TaskReader(env, spec)
        reader = readers[spec]
        views: dict = {}  # one View per step: a call's end is the next call's start, its atoms read once

        def view(t: int):
            if t not in views:
                views[t] = reader.view(type_id[t, b], features[t, b], position[t, b], abstract[t, b])
            return views[t]

        steps = [t for t in np.flatnonzero(live[:, b]) if actor[t, b] in (ACTOR_PLANNER, ACTOR_BRIDGE)]
        call = lambda t: (actor[t, b], skill[t, b], slot[t, b], param[t, b])
        start = None
        for i, t in enumerate(steps):
            start = t if start is None else start
            nxt = steps[i + 1] if i + 1 < len(steps) else None
            if nxt is not None and nxt == t + 1 and call(nxt) == call(t) and not decided[nxt, b]:
                continue  # the same call goes on
            if t + 1 < live.shape[0]:
                k = int(skill[t, b])
                segments.append(Segment(env.skill_names[k], reader.slot_objects.get((k, int(slot[t, b]))),
                                        float(param[t, b]), bool(actor[t, b] == ACTOR_BRIDGE), view(start), view(t + 1),
                                        int(t - start + 1)))
            start = None
    return segments
