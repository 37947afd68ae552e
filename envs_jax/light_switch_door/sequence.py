"""Light Switch Sequence: Light Switch Door whose one door has a combination lock of k dials, a knob
for the length of the fix (the paper's third limitation: epsilon-greedy exploration works for short
fixes, probably not for long ones; docs/design/envs.md, "Light Switch Sequence").

A row of cells; the robot starts in cell 0 and must switch on the light in the last cell, as in Light
Switch Door. The novelty: one door, in cell d, with a lock of k dials. The closed door stops the robot
from leaving cell d to the right. A step in cell d that presses the lock (press >= 0.5) enters its dial
value (clipped to [0, 1]) on the lock's next dial i: within 0.1 (inclusive) of that dial's target, dial
i is set and the lock moves on to dial i + 1; otherwise the lock resets to dial 0. The lock shows the
value last entered. The door opens when all k dials are set, and an open lock stays as it is. Every
task's dial i has the same target (`dial_target(i)`, in [0.1, 0.9], so its window lies inside [0, 1]).
The planner's model knows nothing of the lock: its plan gets stuck at the door.

The bridge's skill SetDial(p) enters p on the next dial; it is grounded once (the robot's cell), so each
of the k decisions of the fix (SetDial, with p in the next dial's window) is the bridge's own choice of a
skill and a parameter. The bridge sees whether the lock is here, how much of it is set (i / k) and the
next dial's target.

k is `fix_length`, a class attribute: the training and test tasks of `LightSwitchSequence` (registered as
"light_switch_sequence") have 2 dials, those of `LightSwitchSequence.of_length(k)` k, which train.py and
eval.py name as `envs_jax.light_switch_door.sequence:LightSwitchSequence_k<k>`. Tasks of any length for
evaluation: `sized_task` (`--task-size dials=8`) and the novelty sweep (1 to 16 dials).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import BridgeAction, NoveltyPredicate, NoveltySweep, Objects, SkillCall, SkillSpec, named_slots
from envs_jax.light_switch_door import env as lsd
from envs_jax.light_switch_door.env import LightSwitchDoor
from planner.strips import Domain, LiftedOperator, Problem

DEFAULT_LENGTH = 2  # the registered env's k: as long as Light Switch Door's fix of one door (its two keys)
DIAL_TOLERANCE = 0.1  # a dial is set by a value within +-0.1 of its target, bounds included (LSD's keys')
PRESS_THRESHOLD = 0.5  # an action enters its dial value when its press is at least this
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
SWEEP_LENGTHS = tuple(range(1, 17))  # eval.py --sweep novelties: 1..16 dials


def dial_target(i: np.ndarray) -> np.ndarray:
    """float32: dial i's target, the same in every task. A golden-ratio sequence spread over [0.1, 0.9]:
    consecutive targets are about 0.31 apart or more, so no one value sets two dials in a row."""
    return np.float32(0.1 + 0.8 * np.mod(0.5 + np.asarray(i, np.float64) * GOLDEN, 1.0))


@dataclass(frozen=True)
class LightSwitchSequenceTask:
    """Host-side task spec."""

    num_cells: int
    door_cell: int  # 0 .. num_cells - 2
    dials: int  # k, the fix's length

    def describe(self) -> str:
        return f"{self.num_cells} cells, a door of {self.dials} dial{'s' * (self.dials != 1)}"

    @property
    def shortest_solution(self) -> int:
        """h: (N-1) moves + 1 light + the blocked move + k dials + CallPlanner (the oracle's steps)."""
        return (self.num_cells - 1) + 1 + 1 + self.dials + 1

    @property
    def min_steps(self) -> int:
        """N-1 moves, the light, and one step per dial (a step enters one value, and the step that sets the
        last dial does not also move: the door opens after it)."""
        return (self.num_cells - 1) + 1 + self.dials

    @property
    def horizon(self) -> int:
        """Light Switch Door's rule, max(30, h + 5), with this task's h: it grows with k, so the oracle
        always has room. No room for restarts: a greedy bridge that misses dial i meets dial i again in
        the same state and misses it again."""
        return max(30, self.shortest_solution + 5)


def _task(rng: np.random.Generator, num_cells: int, dials: int) -> LightSwitchSequenceTask:
    return LightSwitchSequenceTask(num_cells, int(rng.integers(0, num_cells - 1)), dials)


@struct.dataclass
class Task:
    """A task padded to the env's capacity; the one door is a door axis of length 1, as Light Switch
    Door's doors (its drawer draws this env unchanged)."""

    num_cells: jax.Array  # int32
    door_cell: jax.Array  # int32[1]
    keys_cell: jax.Array  # int32[1]: where the lock is turned, the door's own cell
    dials: jax.Array  # int32: k
    dial_target: jax.Array  # float32[max_dials]; zero beyond k
    light_target: jax.Array  # float32


@struct.dataclass
class State:
    robot_x: jax.Array  # float32, a cell centre i + 0.5
    light_level: jax.Array  # float32
    dials_set: jax.Array  # int32: the lock's next dial (k: open)
    dialled: jax.Array  # float32: the value last entered
    task: Task


# The planner's model: Light Switch Door's moves and light, and SetDial in place of its key skills. Like
# them it has no effects (only the bridge uses it), and its one grounding is the robot's cell.
DOMAIN = Domain(
    name="light-switch-sequence",
    types=lsd.DOMAIN.types,
    predicates=lsd.DOMAIN.predicates,
    operators=tuple(op for op in lsd.DOMAIN.operators if op.skill in ("MoveRobot", "TurnOnLight", "TurnOffLight"))
    + (LiftedOperator("SetDial", (("?robot", "robot"), ("?cell", "cell")), pre=(("RobotInCell", "?robot", "?cell"),),
                      add=(), delete=(), skill="SetDial", slot_param="?cell"),),
)


@dataclass(frozen=True)
class LightSwitchSequence(LightSwitchDoor):
    """The env at a fixed capacity: `max_cells` cells and locks of up to `max_dials` dials (one door)."""

    max_doors: int = 1
    max_dials: int = 16

    name = "light_switch_sequence"
    fix_length: ClassVar[int] = DEFAULT_LENGTH  # k of the training and test tasks (`of_length`)
    skills = (SkillSpec("MoveRobot"), SkillSpec("TurnOnLight", 0.75, 0.75), SkillSpec("TurnOffLight", 0.75, 0.75),
              SkillSpec("SetDial", 0.0, 1.0))
    action_dim = 4  # (dx, dlight, dial, press)
    num_features = 3  # (lock here, dials set / k, next dial's target)
    full_state_size = 1 + 3 + lsd.TEST_CELLS_RANGE[1] + 5  # robot, light, cells, door
    domain = DOMAIN
    novelty_sweep = NoveltySweep("dials", f"one door, rows of {lsd.TEST_CELLS_RANGE[0]}-{lsd.TEST_CELLS_RANGE[1]} cells",
                                 SWEEP_LENGTHS, lambda rng, k: LightSwitchSequence.sized_task(rng, dials=k),
                                 horizon=lambda spec: spec.horizon)
    task_sizes = {"cells": "cells in the row (default: drawn as the test tasks')",
                  "dials": "dials on the door's lock, the fix's length k (default: the env's)"}
    test_protocols = {"jaxbridge": "horizon max(30, h + 5), Light Switch Door's rule"}
    authors_defaults = {"n_sample": 100}  # Light Switch Door's, but there is no authors' protocol here
    default_approaches = ("ours", "random", "pure_planning")
    why_not_all = "the knob measures how ours' exploration finds a fix of k decisions; the ablations ask other questions"

    @classmethod
    def of_length(cls, k: int) -> type["LightSwitchSequence"]:
        """The env whose training and test tasks have k dials: one class per k, made once, named
        `LightSwitchSequence_k<k>` in this module (so `module:Class` names it, and pickle finds it)."""
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"a fix length is a positive int, got {k!r}")
        k = int(k)
        if k == DEFAULT_LENGTH:
            return LightSwitchSequence
        if k not in _BY_LENGTH:
            title = f"LightSwitchSequence_k{k}"
            _BY_LENGTH[k] = type(LightSwitchSequence)(title, (LightSwitchSequence,), {
                "__module__": __name__, "__qualname__": title, "__doc__": f"Light Switch Sequence, {k} dials.",
                "fix_length": k, "name": f"light_switch_sequence_k{k}"})
        return _BY_LENGTH[k]

    # ---- host: tasks ----------------------------------------------------------------------------------
    @classmethod
    def train_task(cls, seed: int) -> LightSwitchSequenceTask:
        """5 cells, the door in cell 0, 1 or 2 (Light Switch Door's draw), k dials."""
        rng = np.random.default_rng(seed)
        return LightSwitchSequenceTask(lsd.TRAIN_CELLS, int(rng.choice([1, 2, 3])) - 1, cls.fix_length)

    @classmethod
    def test_tasks(cls, seed: int, num_tasks: int = 10) -> list[LightSwitchSequenceTask]:
        """N cells drawn once per seed (10-20), each task's door in cells 0..8, k dials: the draws do not
        depend on k, so a seed's tasks at two lengths differ only in their locks."""
        rng = np.random.default_rng(seed + 10000)
        num_cells = int(rng.integers(lsd.TEST_CELLS_RANGE[0], lsd.TEST_CELLS_RANGE[1] + 1))
        doors = rng.integers(0, lsd.TEST_DOOR_CELLS, num_tasks)
        return [LightSwitchSequenceTask(num_cells, int(d), cls.fix_length) for d in doors]

    @classmethod
    def sized_task(cls, rng: np.random.Generator, cells: int | None = None,
                   dials: int | None = None) -> LightSwitchSequenceTask:
        """A task of a chosen size: the door anywhere but the light's cell."""
        cells = int(rng.integers(lsd.TEST_CELLS_RANGE[0], lsd.TEST_CELLS_RANGE[1] + 1)) if cells is None else cells
        dials = cls.fix_length if dials is None else dials
        if cells < 2 or dials < 1:
            raise ValueError(f"need >= 2 cells and >= 1 dial, got {cells} cells, {dials} dials")
        return _task(rng, cells, dials)

    @classmethod
    def for_tasks(cls, specs: list[LightSwitchSequenceTask]) -> "LightSwitchSequence":
        return cls(max_cells=max(s.num_cells for s in specs), max_dials=max(s.dials for s in specs))

    # ---- host: task arrays and the planner's problem ---------------------------------------------------
    def task_arrays(self, spec: LightSwitchSequenceTask) -> Task:
        if spec.num_cells > self.max_cells or spec.dials > self.max_dials:
            raise ValueError(f"task {spec} exceeds capacity {self}")
        door = np.array([spec.door_cell], np.int32)
        targets = np.where(np.arange(self.max_dials) < spec.dials, dial_target(np.arange(self.max_dials)), 0.0)
        return Task(num_cells=np.int32(spec.num_cells), door_cell=door, keys_cell=door, dials=np.int32(spec.dials),
                    dial_target=targets.astype(np.float32), light_target=np.float32(lsd.LIGHT_TARGET))

    def planner_problem(self, spec: LightSwitchSequenceTask) -> Problem:
        return dataclasses.replace(super().planner_problem(spec), domain=DOMAIN)  # the same row and light

    def plan_bound(self, spec: LightSwitchSequenceTask) -> tuple[int, int]:
        # States: the robot's cell x the light on or off. Operators: MoveRobot both ways along the row,
        # the two light switches in the light's cell, SetDial in every cell.
        return 2 * spec.num_cells, 2 * (spec.num_cells - 1) + 2 + spec.num_cells

    # ---- device: dynamics -----------------------------------------------------------------------------
    def reset(self, task: Task) -> State:
        return State(robot_x=jnp.float32(0.5), light_level=jnp.float32(0.0), dials_set=jnp.int32(0),
                     dialled=jnp.float32(0.0), task=task)

    def door_open(self, state: State) -> jax.Array:
        """bool[1]: every dial set."""
        return (state.dials_set >= state.task.dials)[None]

    def _next_target(self, state: State) -> jax.Array:
        """The next dial's target; 0 once the lock is open."""
        return jnp.where(state.dials_set < state.task.dials,
                         state.task.dial_target[jnp.minimum(state.dials_set, self.max_dials - 1)], 0.0)

    def step(self, state: State, action: jax.Array) -> State:
        """All rules read the pre-step state, as Light Switch Door's."""
        dx, dlight, dial, press = action[0], action[1], jnp.clip(action[2], 0.0, 1.0), action[3]
        closed = ~self.door_open(state)[0]
        at_lock = self._here(state, state.task.door_cell)[0]
        # The lock: an entry sets the next dial or, wrong, starts the sequence again from dial 0.
        entry = at_lock & closed & (press >= PRESS_THRESHOLD)
        right = jnp.abs(dial - self._next_target(state)) <= DIAL_TOLERANCE
        dials_set = jnp.where(entry, jnp.where(right, state.dials_set + 1, 0), state.dials_set)
        # Light: Light Switch Door's (only dlight == 0.75 exactly, only in the light's cell, only while off).
        light_x = state.task.num_cells.astype(jnp.float32) - 0.5
        switch = ((jnp.abs(state.robot_x - light_x) < lsd.CELL_TOLERANCE) & (dlight == lsd.LIGHT_SWITCH_VALUE)
                  & ~self._light_on(state))
        # Move: the closed door blocks leaving its cell to the right (dx < 0 always may move).
        blocked = at_lock & closed & ~(dx < 0)
        moved = jnp.clip(state.robot_x + dx, 0.0, state.task.num_cells.astype(jnp.float32))
        return state.replace(robot_x=jnp.where(blocked, state.robot_x, moved),
                             light_level=jnp.where(switch, lsd.LIGHT_SWITCH_VALUE, state.light_level),
                             dials_set=dials_set, dialled=jnp.where(entry, dial, state.dialled))

    def state_vector(self, state: State) -> jax.Array:
        # The value last entered is part of the state: a wrong entry at dial 0 changes it, so the loop
        # guard does not take SetDial away after one miss (another value may be right).
        return jnp.stack([state.robot_x, state.light_level, state.dials_set.astype(jnp.float32), state.dialled])

    # ---- device: what the bridge sees ------------------------------------------------------------------
    def _door_features(self, state: State) -> jax.Array:
        """float32[2]: (dials set / k, next dial's target)."""
        return jnp.stack([state.dials_set.astype(jnp.float32) / state.task.dials.astype(jnp.float32),
                          self._next_target(state)])

    def features(self, state: State, stuck_state: State) -> jax.Array:
        """The lock in the robot's cell: a flag, how much of it is set, the next target; zeros if none."""
        here = self._here(state, state.task.door_cell)[0]
        return jnp.concatenate([here[None].astype(jnp.float32), jnp.where(here, self._door_features(state), 0.0)])

    @property
    def full_state_fits(self) -> bool:
        return self.max_cells <= lsd.TEST_CELLS_RANGE[1]

    @property
    def full_state_varying(self) -> np.ndarray:
        # robot x, light level, and the door's dials set, next target and last value; the rest is the task's
        door = 4 + self.max_cells
        return np.array([0, 2, door + 1, door + 3, door + 4])

    def full_state(self, state: State) -> jax.Array:
        """Every object's raw features: robot x; light x, level, target; each cell's x; the door's x, dials
        set, dials, next target and last value entered; absent cells are zeros."""
        if not self.full_state_fits:
            raise ValueError(f"the full-state observation holds at most {lsd.TEST_CELLS_RANGE[1]} cells; "
                             f"this env has {self.max_cells}")
        task = state.task
        cell_x = jnp.where(jnp.arange(self.max_cells) < task.num_cells, self._cell_centres(), 0.0)
        light = jnp.stack([task.num_cells.astype(jnp.float32) - 0.5, state.light_level, task.light_target])
        door = jnp.stack([task.door_cell[0].astype(jnp.float32) + 0.5, state.dials_set.astype(jnp.float32),
                          task.dials.astype(jnp.float32), self._next_target(state), state.dialled])
        vector = jnp.concatenate([state.robot_x[None], light, cell_x, door])
        return jnp.pad(vector, (0, self.full_state_size - vector.shape[0]))

    # The paper's objects: the robot, the light, the cells and the door, whose features are the lock's.
    object_types = {"robot": (), "light": ("level", "target"), "cell": (), "door": ("progress", "next_target")}
    # What a perception system would report of the door: open, every dial set (progress 1; k < 1000)
    novelty_predicates = (NoveltyPredicate("door", "progress", 0.999),)

    @property
    def num_objects(self) -> int:
        return 2 + self.max_cells + 1

    candidate_slots = property(lambda self: np.array([1, 2 + self.max_cells]))  # the light, the door

    def object_names(self, spec: LightSwitchSequenceTask) -> tuple[str | None, ...]:
        cells = (f"cell{i}" for i in range(spec.num_cells))
        return ("robby", "light", *named_slots(cells, self.max_cells), "door")  # the row's one door

    def objects(self, state: State) -> Objects:
        task, width, at = state.task, self.object_width, lambda x: jnp.asarray(x, jnp.float32).reshape(-1, 1)
        light_x, nothing = task.num_cells.astype(jnp.float32) - 0.5, lambda n: jnp.zeros((n, 0))
        return Objects.concat(
            Objects.of_type(0, nothing(1), True, False, at(state.robot_x), width),
            Objects.of_type(1, jnp.stack([state.light_level, task.light_target])[None], True, True, at(light_x), width),
            Objects.of_type(2, nothing(self.max_cells), jnp.arange(self.max_cells) < task.num_cells, False,
                            at(self._cell_centres()), width),
            Objects.of_type(3, self._door_features(state)[None], True, True, at(task.door_cell + 0.5), width))

    def oracle_object(self, state: State) -> jax.Array:
        """The door, when the robot is in its cell."""
        here = self._here(state, state.task.door_cell)[0]
        return jnp.where(here, 2 + self.max_cells, -1).astype(jnp.int32)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        # dx within the largest row; a dial value past [0, 1] is clipped to it; press acts at >= 0.5.
        bound = np.array([lsd.TEST_CELLS_RANGE[1], 1.0, 1.0, 1.0], np.float32)
        return -bound, bound

    # ---- device: skills (all singleton: one action, then terminate) -----------------------------------
    def skill_action(self, state: State, call: SkillCall) -> jax.Array:
        dx = self._cell_centres()[call.slot] - state.robot_x
        zero, one = jnp.float32(0.0), jnp.float32(1.0)
        actions = jnp.stack([
            jnp.stack([dx, zero, zero, zero]),  # MoveRobot to the slot's cell
            jnp.stack([zero, call.param, zero, zero]),  # TurnOnLight
            jnp.stack([zero, call.param, zero, zero]),  # TurnOffLight
            jnp.stack([zero, zero, call.param, one]),  # SetDial: enter the parameter on the next dial
        ])
        return actions[call.skill]

    # ---- the hand-written bridge used as an oracle in tests and eval ------------------------------------
    def oracle_bridge(self, params, obs, key):
        """At a closed lock, enter the next dial's target; then (or anywhere else) CallPlanner: k + 1
        decisions per task."""
        here, progress, target = obs.features[0], obs.features[1], obs.features[2]
        dialling = (here > 0.5) & (progress < 1.0)
        skill = jnp.where(dialling, self.skill_index("SetDial"), self.num_skills)
        return BridgeAction(skill=jnp.int32(skill), param=jnp.where(dialling, target, 0.0).astype(jnp.float32))


_BY_LENGTH: dict[int, type[LightSwitchSequence]] = {}


def __getattr__(attribute: str):
    """`LightSwitchSequence_k<k>`: the class of `LightSwitchSequence.of_length(k)` (how `train.py --env
    envs_jax.light_switch_door.sequence:LightSwitchSequence_k8` trains at k = 8)."""
    prefix = "LightSwitchSequence_k"
    digits = attribute.removeprefix(prefix)
    if attribute.startswith(prefix) and digits.isdigit() and str(int(digits)) == digits and int(digits) >= 1:
        return LightSwitchSequence.of_length(int(digits))
    raise AttributeError(f"module {__name__!r} has no attribute {attribute!r}")
