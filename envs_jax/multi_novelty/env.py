"""Multi Novelty: Light Switch Door's row with three kinds of novelty the planner's model does not know,
several of them in one task (the paper's second limitation, issue 54; docs/design/envs.md, "Multi Novelty").

A row of cells; the robot starts in cell 0 and must switch on the light in the last cell. The planner's
model: MoveRobot between adjacent cells, TurnOnLight in the light's cell. The novelties:

* **keycard door**: a closed door stops the robot from leaving its cell to the right; it opens for the
  robot carrying its card, which lies in an earlier cell of the door's section. The fix, FetchKey (walk
  to the card, grip it), acts on an object away from the door the robot is stuck at.
* **latched door**: stops the robot the same way; LiftLatch, then PushDoor with a force within 0.1 of
  the door's stiffness, releases it (a push with the latch down does nothing): a fix of two skills.
* **blown fuse**: TurnOnLight does nothing until ReplaceFuse at the light.

Both doors stall MoveRobot at a door, so the failed operator and the object's type do not tell them
apart; the fuse stalls TurnOnLight. A door may carry both locks (the held-out combination); it opens once
both are undone. A move right is blocked by a closed door in any cell from the robot's up to the
target's (exclusive); a move left never is. Every rule reads the pre-step state.

Each fix's grounding is unique by applicability: FetchKey is initiable for a card the robot does not
hold and can walk to (the card of a door further on lies behind a closed door), LiftLatch and PushDoor
for the closed door in the robot's cell, ReplaceFuse in the light's cell.
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import (BridgeAction, NoveltyEnv, NoveltyPredicate, NoveltySweep, Objects, SkillCall, SkillSpec,
                           named_slots)
from envs_jax.multi_novelty import tasks
from envs_jax.multi_novelty.tasks import KEYCARD, LATCHED, MultiNoveltyTask
from planner.strips import Domain, LiftedOperator, Problem

PUSH_TOLERANCE = 0.1  # a push releases a lifted latch within +-0.1 of the door's stiffness, bounds included
ON = 0.5  # the switch-like channels (light, fuse, grip, latch) act at >= 0.5
CELL_TOLERANCE = 1e-3  # "robot in cell": |x - cell.x| < 1e-3
MAX_TASK_DOORS = tasks.TEST_DOORS_RANGE[1]  # the full state holds this many doors (the test tasks' most)
DOOR_ENTRIES = 8  # a door's full-state entries: x, its card's x, keycard, card held, latched, latch up, released, stiffness
MOVE, LIGHT, FETCH, LIFT, PUSH, FUSE = range(6)  # skill ids, in `skills` order


@struct.dataclass
class Task:
    """A task padded to the env's capacity: D door slots (door_cell -1 marks padding)."""

    num_cells: jax.Array  # int32
    door_cell: jax.Array  # int32[D]
    keycard: jax.Array  # bool[D]
    latched: jax.Array  # bool[D]
    key_cell: jax.Array  # int32[D]: the door's card's cell, -1 without a keycard lock
    stiffness: jax.Array  # float32[D]: the push that releases the latch, 0 without one
    fuse_blown: jax.Array  # bool


@struct.dataclass
class State:
    robot_x: jax.Array  # float32, a cell centre i + 0.5
    light_on: jax.Array  # bool
    fuse_ok: jax.Array  # bool
    card_held: jax.Array  # bool[D]
    latch_up: jax.Array  # bool[D]
    released: jax.Array  # bool[D]: the latch is undone (lifted, then pushed)
    task: Task


def _operators() -> tuple[LiftedOperator, ...]:
    r, cur, tgt, cell, light = ("?robot", "robot"), ("?cur", "cell"), ("?tgt", "cell"), ("?cell", "cell"), ("?light", "light")
    return (
        LiftedOperator("MoveRobot", (r, cur, tgt), pre=(("Adjacent", "?cur", "?tgt"), ("RobotInCell", "?robot", "?cur")),
                       add=(("RobotInCell", "?robot", "?tgt"),), delete=(("RobotInCell", "?robot", "?cur"),),
                       skill="MoveRobot", slot_param="?tgt"),
        LiftedOperator("TurnOnLight", (r, cell, light),
                       pre=(("LightInCell", "?light", "?cell"), ("RobotInCell", "?robot", "?cell"), ("LightOff", "?light")),
                       add=(("LightOn", "?light"),), delete=(("LightOff", "?light"),), skill="TurnOnLight"),
        # The novelties' skills: the model gives them no effects (it knows no locks, cards or fuse), so
        # only the bridge uses them; where they can start is the env's `skill_initiable`.
        LiftedOperator("FetchKey", (r, ("?key", "key")), pre=(), add=(), delete=(), skill="FetchKey", slot_param="?key"),
        LiftedOperator("LiftLatch", (r, ("?door", "door")), pre=(), add=(), delete=(), skill="LiftLatch", slot_param="?door"),
        LiftedOperator("PushDoor", (r, ("?door", "door")), pre=(), add=(), delete=(), skill="PushDoor", slot_param="?door"),
        LiftedOperator("ReplaceFuse", (r, light), pre=(), add=(), delete=(), skill="ReplaceFuse"),
    )


DOMAIN = Domain(
    name="multi-novelty",
    types=("robot", "cell", "light", "door", "key"),
    predicates={"RobotInCell": ("robot", "cell"), "LightInCell": ("light", "cell"), "LightOn": ("light",),
                "LightOff": ("light",), "Adjacent": ("cell", "cell")},
    operators=_operators(),
)


@dataclass(frozen=True)
class MultiNovelty(NoveltyEnv):
    """The env at a fixed capacity: `max_cells` cells and `max_doors` doors (each with a card slot)."""

    max_cells: int = tasks.TEST_CELLS_RANGE[1]
    max_doors: int = MAX_TASK_DOORS

    name = "multi_novelty"
    skills = (SkillSpec("MoveRobot"), SkillSpec("TurnOnLight", 1.0, 1.0), SkillSpec("FetchKey"), SkillSpec("LiftLatch"),
              SkillSpec("PushDoor", 0.0, 1.0), SkillSpec("ReplaceFuse"))
    action_dim = 6  # (dx, light, fuse, grip, latch, push force)
    num_features = 6  # the closed door here: (here, needs its card, latch down, latch up, stiffness); blown fuse here
    full_state_size = 3 + DOOR_ENTRIES * MAX_TASK_DOORS  # robot x, light on, fuse ok; the doors
    domain = DOMAIN
    train_task = staticmethod(tasks.train_task)
    train_tasks = staticmethod(tasks.train_tasks)
    test_tasks = staticmethod(tasks.test_tasks)
    test_protocols = tasks.TEST_PROTOCOLS
    task_sizes = {"cells": "cells in the row", "doors": "single-lock doors, two cells apart (the fuse is always blown)"}
    # Issue 54's question: one bridge (ours, the learned selector) against a bridge per failure signature, with
    # the baselines; Maple Q and the full state with --approaches all.
    default_approaches = ("ours", "ours_learned_selection", "ours_per_signature", "ours_signature_conditioned",
                          "no_callplanner", "random", "pure_planning")
    why_not_all = "full-state networks, timed on their own"
    # both doors stall MoveRobot at a door, the fuse TurnOnLight at the light
    failure_signatures = (("MoveRobot", "door"), ("TurnOnLight", "light"))
    novelty_sweep = NoveltySweep("novelty instances (the fuse and single-lock doors)", f"in a row of {tasks.SWEEP_CELLS} cells",
                                 tasks.SWEEP_COUNTS, tasks.sweep_task, horizon=lambda spec: spec.horizon)

    @classmethod
    def sized_task(cls, rng: np.random.Generator, cells: int, doors: int) -> MultiNoveltyTask:
        return tasks.sized_task(rng, cells, doors)

    @classmethod
    def for_tasks(cls, specs: list[MultiNoveltyTask]) -> "MultiNovelty":
        return cls(max_cells=max(s.num_cells for s in specs), max_doors=max([len(s.door_cells) for s in specs] + [1]))

    def drawer(self):
        from envs_jax.multi_novelty.drawer import DRAWER  # matplotlib: only when drawing
        return DRAWER

    # ---- host: task arrays and the planner's problem ---------------------------------------------
    def task_arrays(self, spec: MultiNoveltyTask) -> Task:
        if spec.num_cells > self.max_cells or len(spec.door_cells) > self.max_doors:
            raise ValueError(f"task {spec} exceeds capacity {self}")
        padded = lambda values, fill, dtype: np.array(list(values) + [fill] * (self.max_doors - len(values)), dtype)
        locks = padded(spec.locks, 0, np.int32)
        return Task(num_cells=np.int32(spec.num_cells), door_cell=padded(spec.door_cells, -1, np.int32),
                    keycard=(locks & KEYCARD) > 0, latched=(locks & LATCHED) > 0,
                    key_cell=padded(spec.key_cells, -1, np.int32), stiffness=padded(spec.stiffness, 0.0, np.float32),
                    fuse_blown=np.bool_(spec.fuse_blown))

    def planner_problem(self, spec: MultiNoveltyTask) -> Problem:
        n = spec.num_cells
        cells = [f"cell{i}" for i in range(n)]
        doors = [f"door{j}" for j in range(len(spec.door_cells))]
        keys = [f"key{j}" for j, lock in enumerate(spec.locks) if lock & KEYCARD]
        objects = {"robby": "robot", "light": "light", **{c: "cell" for c in cells}, **{d: "door" for d in doors},
                   **{k: "key" for k in keys}}
        adjacent = {("Adjacent", cells[i], cells[j]) for i in range(n) for j in (i - 1, i + 1) if 0 <= j < n}
        static = frozenset(adjacent | {("LightInCell", "light", cells[-1])})
        init = frozenset({("RobotInCell", "robby", "cell0"), ("LightOff", "light")})
        return Problem(DOMAIN, objects, static, init, frozenset({("LightOn", "light")}))

    def plan_bound(self, spec: MultiNoveltyTask) -> tuple[int, int]:
        # States: the robot's cell x the light. Operators: MoveRobot both ways, TurnOnLight, and the
        # novelties' one per card, two per door, one fuse.
        doors = len(spec.door_cells)
        return 2 * spec.num_cells, 2 * (spec.num_cells - 1) + 1 + 3 * doors + 1

    @property
    def num_atoms(self) -> int:
        return self.max_cells + 2  # RobotInCell per cell slot, LightOn, LightOff

    def atom_index(self, atom) -> int:
        if atom[0] == "RobotInCell":
            return self.object_slot(atom[2])
        return self.max_cells + {"LightOn": 0, "LightOff": 1}[atom[0]]

    def object_slot(self, name: str) -> int:
        """A skill's slot is an index among its objects' type: cell i, door j, door j's card (key j)."""
        for prefix in ("cell", "door", "key"):
            if name.startswith(prefix):
                return int(name.removeprefix(prefix))
        return 0  # the light: one of its kind

    # ---- device: dynamics -------------------------------------------------------------------------
    def reset(self, task: Task) -> State:
        no = jnp.zeros(task.door_cell.shape, bool)
        return State(robot_x=jnp.float32(0.5), light_on=jnp.bool_(False), fuse_ok=~task.fuse_blown, card_held=no,
                     latch_up=no, released=no, task=task)

    def _cell(self, state: State) -> jax.Array:
        return jnp.floor(state.robot_x).astype(jnp.int32)

    def door_open(self, state: State) -> jax.Array:
        """bool[D]: every lock of the door undone (padding slots are not doors: never open)."""
        task = state.task
        return (task.door_cell >= 0) & (~task.keycard | state.card_held) & (~task.latched | state.released)

    def _closed(self, state: State) -> jax.Array:
        return (state.task.door_cell >= 0) & ~self.door_open(state)

    def _reachable(self, state: State, cells: jax.Array) -> jax.Array:
        """bool[...]: the robot can walk to each of `cells`: left always, right unless a closed door stands
        in a cell from the robot's up to the target's (exclusive)."""
        task, here = state.task, self._cell(state)
        blocking = self._closed(state) & (task.door_cell >= here)
        ahead = jnp.any(blocking & (task.door_cell < cells[..., None]), axis=-1)
        return (cells <= here) | ~ahead

    def _closed_door_here(self, state: State) -> tuple[jax.Array, jax.Array]:
        """(whether a closed door stands in the robot's cell, its index; 0 if none)."""
        here = self._closed(state) & (state.task.door_cell == self._cell(state))
        return jnp.any(here), jnp.argmax(here)

    def _at_light(self, state: State) -> jax.Array:
        return self._cell(state) == state.task.num_cells - 1

    def step(self, state: State, action: jax.Array) -> State:
        dx, light, fuse, grip, latch, push = (action[i] for i in range(6))
        task, cell = state.task, self._cell(state)
        here = self._closed(state) & (task.door_cell == cell)
        card_held = state.card_held | (task.keycard & (task.key_cell == cell) & (grip >= ON))
        latch_up = state.latch_up | (here & task.latched & (latch >= ON))
        pushed = here & task.latched & state.latch_up & (jnp.abs(push - task.stiffness) <= PUSH_TOLERANCE)
        at_light = self._at_light(state)
        light_on = state.light_on | (at_light & state.fuse_ok & (light >= ON))
        target = jnp.clip(state.robot_x + dx, 0.5, task.num_cells.astype(jnp.float32) - 0.5)
        blocked = (dx > 0) & ~self._reachable(state, jnp.floor(target).astype(jnp.int32))
        return state.replace(robot_x=jnp.where(blocked, state.robot_x, target), light_on=light_on,
                             fuse_ok=state.fuse_ok | (at_light & (fuse >= ON)), card_held=card_held,
                             latch_up=latch_up, released=state.released | pushed)

    def robot_in_cell(self, state: State) -> jax.Array:
        centres = jnp.arange(self.max_cells, dtype=jnp.float32) + 0.5
        return (jnp.arange(self.max_cells) < state.task.num_cells) & (jnp.abs(centres - state.robot_x) < CELL_TOLERANCE)

    def abstract(self, state: State) -> jax.Array:
        return jnp.concatenate([self.robot_in_cell(state), jnp.stack([state.light_on, ~state.light_on])])

    def goal_reached(self, state: State) -> jax.Array:
        return state.light_on

    def state_vector(self, state: State) -> jax.Array:
        flags = jnp.concatenate([jnp.stack([state.light_on, state.fuse_ok]), state.card_held, state.latch_up, state.released])
        return jnp.concatenate([state.robot_x[None], flags.astype(jnp.float32)])

    # ---- device: what the bridge sees --------------------------------------------------------------
    def features(self, state: State, stuck_state: State) -> jax.Array:
        """The paper's hand-picked selection: the closed door in the robot's cell (whether there is one,
        whether its card is still to fetch, its latch down, its latch up but not released, its
        stiffness) and whether the light here has a blown fuse; zeros for a door that is not there."""
        has, j = self._closed_door_here(state)
        task = state.task
        latch_pending = task.latched[j] & ~state.released[j]
        door = jnp.stack([jnp.bool_(True), task.keycard[j] & ~state.card_held[j], latch_pending & ~state.latch_up[j],
                          latch_pending & state.latch_up[j]]).astype(jnp.float32)
        door = jnp.concatenate([door, task.stiffness[j][None]])
        fuse = (self._at_light(state) & ~state.fuse_ok).astype(jnp.float32)
        return jnp.concatenate([jnp.where(has, door, 0.0), fuse[None]])

    def _door_rows(self, state: State) -> jax.Array:
        """float32[D, 6]: each door's object features (keycard, card held, latched, latch up, released,
        stiffness)."""
        task = state.task
        flags = jnp.stack([task.keycard, state.card_held, task.latched, state.latch_up, state.released], axis=-1)
        return jnp.concatenate([flags.astype(jnp.float32), task.stiffness[:, None]], axis=-1)

    @property
    def full_state_fits(self) -> bool:
        return self.max_doors <= MAX_TASK_DOORS

    @property
    def full_state_varying(self) -> np.ndarray:
        # robot x, light on, fuse ok; each door's card held, latch up, released. Cells, cards' places,
        # locks and stiffness are the task's.
        doors = 3 + DOOR_ENTRIES * np.arange(MAX_TASK_DOORS)[:, None] + np.array([3, 5, 6])
        return np.concatenate([[0, 1, 2], doors.reshape(-1)])

    @property
    def full_state_filled(self) -> np.ndarray:
        # the door slots beyond this env's capacity pad the vector for larger tasks
        return np.arange(3 + DOOR_ENTRIES * min(self.max_doors, MAX_TASK_DOORS))

    def full_state(self, state: State) -> jax.Array:
        """Every object's raw features ("no feature selection"): robot x, light on, fuse ok, and per door
        its x, its card's x and its own features (`_door_rows`); absent doors are zeros."""
        if not self.full_state_fits:
            raise ValueError(f"the full-state observation holds at most {MAX_TASK_DOORS} doors; this env has {self.max_doors}")
        task = state.task
        places = jnp.stack([task.door_cell + 0.5, jnp.where(task.keycard, task.key_cell + 0.5, 0.0)], axis=-1)
        doors = jnp.where((task.door_cell >= 0)[:, None], jnp.concatenate([places, self._door_rows(state)], axis=-1), 0.0)
        head = jnp.stack([state.robot_x, state.light_on.astype(jnp.float32), state.fuse_ok.astype(jnp.float32)])
        vector = jnp.concatenate([head, doors.reshape(-1)])
        return jnp.pad(vector, (0, self.full_state_size - vector.shape[0]))

    # The objects: the robot, the light, the cells, the doors and their cards. A door is acted on in its
    # cell while it is closed, a card where it lies until it is held, the light always.
    object_types = {"robot": (), "light": ("on", "fuse_ok"), "cell": (),
                    "door": ("keycard", "card_held", "latched", "latch_up", "released", "stiffness"), "key": ("held",)}
    # What a perception system would report of the novelties: a keycard door's card held and a latched door
    # released (its two locks undone), a latch lifted, a card held, the light's fuse good.
    novelty_predicates = (NoveltyPredicate("door", "card_held", when="keycard"), NoveltyPredicate("door", "released", when="latched"),
                          NoveltyPredicate("door", "latch_up"), NoveltyPredicate("key", "held"), NoveltyPredicate("light", "fuse_ok"))

    @property
    def num_objects(self) -> int:
        return 2 + self.max_cells + 2 * self.max_doors

    def _door_slot(self, j: jax.Array) -> jax.Array:
        return 2 + self.max_cells + j

    def _key_slot(self, j: jax.Array) -> jax.Array:
        return 2 + self.max_cells + self.max_doors + j

    @property
    def candidate_slots(self) -> np.ndarray:
        return np.r_[1, self._door_slot(np.arange(2 * self.max_doors))]  # the light, the doors, the cards

    def objects(self, state: State) -> Objects:
        task, width, at = state.task, self.object_width, lambda x: jnp.asarray(x, jnp.float32).reshape(-1, 1)
        nothing = lambda n: jnp.zeros((n, 0))
        light = jnp.stack([state.light_on, state.fuse_ok]).astype(jnp.float32)[None]
        return Objects.concat(
            Objects.of_type(0, nothing(1), True, False, at(state.robot_x), width),
            Objects.of_type(1, light, True, True, at(task.num_cells - 0.5), width),
            Objects.of_type(2, nothing(self.max_cells), jnp.arange(self.max_cells) < task.num_cells, False,
                            at(jnp.arange(self.max_cells) + 0.5), width),
            Objects.of_type(3, self._door_rows(state), task.door_cell >= 0, self._closed(state), at(task.door_cell + 0.5), width),
            Objects.of_type(4, at(state.card_held), task.keycard, ~state.card_held, at(task.key_cell + 0.5), width))

    def object_names(self, spec: MultiNoveltyTask) -> tuple[str | None, ...]:
        # the planner's names (its problem lists the doors and cards the novelties' skills act on)
        doors = range(len(spec.door_cells))
        keys = (f"key{j}" if spec.locks[j] & KEYCARD else None for j in doors)
        return ("robby", "light", *named_slots((f"cell{i}" for i in range(spec.num_cells)), self.max_cells),
                *named_slots((f"door{j}" for j in doors), self.max_doors), *named_slots(keys, self.max_doors))

    def oracle_object(self, state: State) -> jax.Array:
        """At a closed door: its card while the robot lacks it, else the door (its latch); at the light
        with a blown fuse: the light; elsewhere none."""
        has, j = self._closed_door_here(state)
        door = jnp.where(state.task.keycard[j] & ~state.card_held[j], self._key_slot(j), self._door_slot(j))
        light = jnp.where(self._at_light(state) & ~state.fuse_ok, 1, -1)
        return jnp.where(has, door, light).astype(jnp.int32)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        # a move beyond the row clips to it; the other channels act at >= 0.5 or near a stiffness in [0.2, 0.8]
        high = np.array([tasks.TEST_CELLS_RANGE[1], 1.0, 1.0, 1.0, 1.0, 1.0], np.float32)
        return np.r_[-high[0], np.zeros(5)].astype(np.float32), high

    # ---- device: skills ----------------------------------------------------------------------------
    def skill_action(self, state: State, call: SkillCall) -> jax.Array:
        """MoveRobot to the slot's cell; FetchKey walks to the slot's card, then grips; the rest one action."""
        task = state.task
        key = jnp.clip(call.slot, 0, self.max_doors - 1)
        to = lambda cell: cell.astype(jnp.float32) + 0.5 - state.robot_x
        at_key = self._cell(state) == task.key_cell[key]
        channel = lambda i, value: jnp.zeros(6, jnp.float32).at[i].set(value)
        return jnp.stack([
            channel(0, to(call.slot)),  # MoveRobot
            channel(1, call.param),  # TurnOnLight
            jnp.where(at_key, channel(3, 1.0), channel(0, to(task.key_cell[key]))),  # FetchKey
            channel(4, 1.0),  # LiftLatch
            channel(5, call.param),  # PushDoor with this force
            channel(2, 1.0),  # ReplaceFuse
        ])[call.skill]

    def skill_done(self, prev_state: State, state: State, call: SkillCall) -> jax.Array:
        """FetchKey ends holding the card or after its walk and grip (two steps); the rest after one."""
        fetched = state.card_held[jnp.clip(call.slot, 0, self.max_doors - 1)] | (call.steps >= 1)
        return jnp.where(call.skill == FETCH, fetched, True)

    def skill_initiable(self, state: State, skill: jax.Array, slot: jax.Array) -> jax.Array:
        """FetchKey: a card not held that the robot can walk to; LiftLatch, PushDoor: the closed door in the
        robot's cell (whatever its locks: a push at a keycard door does nothing); ReplaceFuse: at the light."""
        skill, slot = jnp.broadcast_arrays(skill, slot)
        task, j = state.task, jnp.clip(slot, 0, self.max_doors - 1)
        card = task.keycard[j] & ~state.card_held[j] & self._reachable(state, task.key_cell[j])
        door = self._closed(state)[j] & (task.door_cell[j] == self._cell(state))
        return jnp.select([skill == FETCH, (skill == LIFT) | (skill == PUSH), skill == FUSE],
                          [card, door, jnp.broadcast_to(self._at_light(state), skill.shape)], jnp.ones(skill.shape, bool))

    # ---- the hand-written bridge (tests, eval.py --bridge oracle) ------------------------------------
    def oracle_bridge(self, params, obs, key) -> BridgeAction:
        """At a closed door: FetchKey while its card is to fetch, then LiftLatch and PushDoor at its
        stiffness while it is latched; at a blown fuse ReplaceFuse; else CallPlanner."""
        _, card, latch_down, latch_up, stiffness, fuse = (obs.features[i] for i in range(6))
        skill = jnp.where(card > 0.5, FETCH, jnp.where(latch_down > 0.5, LIFT, jnp.where(
            latch_up > 0.5, PUSH, jnp.where(fuse > 0.5, FUSE, self.num_skills))))
        return BridgeAction(skill=jnp.int32(skill), param=jnp.float32(stiffness))
