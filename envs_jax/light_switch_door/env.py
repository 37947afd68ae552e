"""Light Switch Door (the authors' `grid_row_door`), as the authors' code defines it.

A row of cells; the robot starts in cell 0 and must switch on the light in the last cell. The novelty:
doors. A closed door stops the robot from leaving the door's cell to the right; it opens when both of
its keys are within 0.1 (inclusive) of their targets. The keys are the authors' float64 sums of float32
actions, kept exactly (`envs_jax.precision.ExactKey`), so every door opens at the step theirs does; what
the bridge sees of a key is its nearest float32. The planner's model knows nothing of doors.
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import (BridgeAction, NoveltyEnv, NoveltyPredicate, NoveltySweep, Objects, SkillCall, SkillSpec,
                           named_slots)
from envs_jax.precision import ExactKey, ExactWindow, exact_window
from planner.strips import Domain, LiftedOperator, Problem

MOVE_TARGET, TURN_TARGET, LIGHT_TARGET = 0.5, 0.75, 0.75  # same_levels=True
DOOR_TOLERANCE = 0.1  # a key is "at" its target within +-0.1, bounds included
LIGHT_ON_TOLERANCE = 0.1  # LightOn: |level - target| < 0.1
LIGHT_SWITCH_VALUE = 0.75  # the light responds only to dlight == 0.75 exactly
CELL_TOLERANCE = 1e-3  # "robot in cell": |x - cell.x| < 1e-3
TRAIN_CELLS = 5
TEST_CELLS_RANGE = (10, 20)  # inclusive
TEST_DOORS_RANGE = (2, 4)  # inclusive
TEST_DOOR_CELLS = 9  # test doors are drawn from cells 0..8 (the authors' test_grid_row_num_cells - 1)
TRAIN_STEPS = 100
AUTHORS_HORIZON = 30  # the authors' code's test horizon (the paper's table: max(30, h + 5))
SWEEP_CELLS, SWEEP_DOORS = 60, tuple(range(1, 17))  # eval.py --sweep: 1..16 doors in a row of 60 cells


@dataclass(frozen=True)
class LightSwitchDoorTask:
    """Host-side task spec."""

    num_cells: int
    door_cells: tuple[int, ...]
    fixed_horizon: int | None = None  # the authors' code's fixed test horizon, instead of the paper's rule
    panel_offset: int = 0  # each door's keys are this many cells before it (0: in its own cell, the paper's)

    def describe(self) -> str:
        panels = f", keys {self.panel_offset} cell(s) back" if self.panel_offset else ""
        return f"{self.num_cells} cells, {len(self.door_cells)} doors{panels}"

    @property
    def shortest_solution(self) -> int:
        """h: (N-1) moves + 1 light + 4 per door (blocked move, MoveKey, TurnKey, CallPlanner), and per
        door with its keys k cells back, k moves back to them and k forward again."""
        return (self.num_cells - 1) + 1 + (4 + 2 * self.panel_offset) * len(self.door_cells)

    @property
    def min_steps(self) -> int:
        """No action sequence reaches the goal in fewer env steps: N-1 moves, the light, and one step per
        door that sets both its keys (skills take two, and the planner bumps into the first door; keys
        on a panel can be set in passing)."""
        return (self.num_cells - 1) + 1 + len(self.door_cells)

    @property
    def horizon(self) -> int:
        """The paper's test horizon max(30, h + 5), or the authors' code's fixed 30 (`fixed_horizon`). Keys
        on panels add 4 steps per door: the walk back is a MoveRobot whose direction is drawn, and each
        draw of "right" bumps into the closed door (one such bump per door on average)."""
        slack = 5 + (4 * len(self.door_cells) if self.panel_offset else 0)
        return self.fixed_horizon or max(30, self.shortest_solution + slack)


def train_task(seed: int) -> LightSwitchDoorTask:
    """5 cells, one door in cell 0, 1 or 2 (`choice({1,2,3}) - 0.5` in the authors' code)."""
    rng = np.random.default_rng(seed)
    return LightSwitchDoorTask(TRAIN_CELLS, (int(rng.choice([1, 2, 3])) - 1,))


TEST_PROTOCOLS = {"jaxbridge": "horizon max(30, h + 5), the paper's",
                  "authors": f"horizon {AUTHORS_HORIZON}, the authors' code (a task whose shortest solution is longer "
                             f"is unsolvable, e.g. seed 2's 20 cells and 3 doors: 32 steps)"}


def test_tasks(seed: int, num_tasks: int = 10, protocol: str = "jaxbridge") -> list[LightSwitchDoorTask]:
    """N cells and K doors drawn once per seed; each task draws K distinct door cells in 0..8. The
    protocol sets the horizon only (TEST_PROTOCOLS)."""
    return drawn_test_tasks(seed, num_tasks, protocol, lambda rng, k: tuple(
        int(c) for c in rng.choice(TEST_DOOR_CELLS, k, replace=False)))


def drawn_test_tasks(seed: int, num_tasks: int, protocol: str, door_cells, panel_offset: int = 0) -> list[LightSwitchDoorTask]:
    """Test tasks of N cells and K doors drawn once per seed, each task's K door cells by
    `door_cells(rng, K)` (the variants' draws differ only there)."""
    rng = np.random.default_rng(seed + 10000)
    num_cells = int(rng.integers(TEST_CELLS_RANGE[0], TEST_CELLS_RANGE[1] + 1))
    num_doors = int(rng.integers(TEST_DOORS_RANGE[0], TEST_DOORS_RANGE[1] + 1))
    fixed = {"jaxbridge": None, "authors": AUTHORS_HORIZON}[protocol]
    return [LightSwitchDoorTask(num_cells, door_cells(rng, num_doors), fixed, panel_offset) for _ in range(num_tasks)]


def sized_task(rng: np.random.Generator, num_cells: int, num_doors: int) -> LightSwitchDoorTask:
    """A task of a chosen size: doors in distinct cells anywhere but the light's cell."""
    if not 2 <= num_cells or not 0 <= num_doors <= num_cells - 1:
        raise ValueError(f"need >= 2 cells and 0..cells-1 doors, got {num_cells} cells, {num_doors} doors")
    cells = rng.choice(num_cells - 1, num_doors, replace=False)
    return LightSwitchDoorTask(num_cells, tuple(sorted(int(c) for c in cells)))


def sweep_task(rng: np.random.Generator, num_doors: int) -> LightSwitchDoorTask:
    """A generalisation-sweep task: `num_doors` doors anywhere in a row of 60 cells (training: 5 cells and
    1 door; test: 10-20 cells, 2-4 doors in the first 9); its horizon is the paper's max(30, h + 5)."""
    return sized_task(rng, SWEEP_CELLS, num_doors)


@struct.dataclass
class Task:
    """A task padded to the env's capacity."""

    num_cells: jax.Array  # int32
    door_cell: jax.Array  # int32[D]; -1 marks padding
    keys_cell: jax.Array  # int32[D]: the cell where each door's keys turn (its own, or a panel's); -1 padding
    key_target: jax.Array  # float32[D, 2]: each door's (move, turn) targets
    key_window: ExactWindow  # [D, 2]: the keys within DOOR_TOLERANCE of their targets
    light_target: jax.Array  # float32


@struct.dataclass
class State:
    robot_x: jax.Array  # float32, a cell centre i + 0.5
    light_level: jax.Array  # float32
    keys: ExactKey  # [D, 2]: each door's (move, turn) keys
    task: Task


def _operators() -> tuple[LiftedOperator, ...]:
    r, cur, tgt, cell, light = ("?robot", "robot"), ("?cur", "cell"), ("?tgt", "cell"), \
        ("?cell", "cell"), ("?light", "light")
    in_cell = ("RobotInCell", "?robot", "?cell")
    return (
        LiftedOperator("MoveRobot", (r, cur, tgt),
                       pre=(("Adjacent", "?cur", "?tgt"), ("RobotInCell", "?robot", "?cur")),
                       add=(("RobotInCell", "?robot", "?tgt"),),
                       delete=(("RobotInCell", "?robot", "?cur"),), skill="MoveRobot", slot_param="?tgt"),
        LiftedOperator("TurnOnLight", (r, cell, light),
                       pre=(("LightInCell", "?light", "?cell"), in_cell, ("LightOff", "?light")),
                       add=(("LightOn", "?light"),), delete=(("LightOff", "?light"),),
                       skill="TurnOnLight", slot_param="?cell"),
        LiftedOperator("TurnOffLight", (r, cell, light),
                       pre=(("LightInCell", "?light", "?cell"), in_cell, ("LightOn", "?light")),
                       add=(("LightOff", "?light"),), delete=(("LightOn", "?light"),),
                       skill="TurnOffLight", slot_param="?cell"),
        # The door skills: the model gives them no effects, so only the bridge ever uses them.
        LiftedOperator("MoveKey", (r, cell), pre=(in_cell,), add=(), delete=(), skill="MoveKey",
                       slot_param="?cell"),
        LiftedOperator("TurnKey", (r, cell), pre=(in_cell,), add=(), delete=(), skill="TurnKey",
                       slot_param="?cell"),
    )


DOMAIN = Domain(
    name="light-switch-door",
    types=("robot", "cell", "light"),
    predicates={"RobotInCell": ("robot", "cell"), "LightInCell": ("light", "cell"),
                "LightOn": ("light",), "LightOff": ("light",), "Adjacent": ("cell", "cell")},
    operators=_operators(),
)


@dataclass(frozen=True)
class LightSwitchDoor(NoveltyEnv):
    """The env at a fixed capacity: `max_cells` cells and `max_doors` doors per task."""

    max_cells: int = 20
    max_doors: int = 4

    name = "light_switch_door"
    panel_offset = 0  # each door's keys turn in its own cell (the panel variant: envs_jax.light_switch_door.panel)
    skills = (SkillSpec("MoveRobot"), SkillSpec("TurnOnLight", 0.75, 0.75),
              SkillSpec("TurnOffLight", 0.75, 0.75), SkillSpec("MoveKey", -1.0, 1.0),
              SkillSpec("TurnKey", -1.0, 1.0))
    action_dim = 4  # (dx, dlight, dmove, dturn)
    num_features = 5  # (door here, move_key, move_target, turn_key, turn_target)
    # The full state (no feature selection) is padded to the largest task the env generates.
    max_task_cells, max_task_doors = TEST_CELLS_RANGE[1], TEST_DOORS_RANGE[1]
    full_state_size = 1 + 3 + max_task_cells + 5 * max_task_doors  # robot, light, cells, doors
    domain = DOMAIN
    train_task = staticmethod(train_task)
    test_tasks = staticmethod(test_tasks)
    train_steps = TRAIN_STEPS
    novelty_sweep = NoveltySweep("doors", f"in a row of {SWEEP_CELLS} cells", SWEEP_DOORS, sweep_task,
                                 horizon=lambda spec: spec.horizon)

    task_sizes = {"cells": "cells in the row", "doors": "doors, in distinct cells but the light's"}
    test_protocols = TEST_PROTOCOLS
    authors_defaults = {"n_sample": 100, "test_protocol": "authors"}

    @classmethod
    def sized_task(cls, rng: np.random.Generator, cells: int, doors: int) -> LightSwitchDoorTask:
        return sized_task(rng, cells, doors)

    def drawer(self):
        from envs_jax.light_switch_door.drawer import DRAWER  # matplotlib: only when drawing
        return DRAWER

    @classmethod
    def for_tasks(cls, specs: list[LightSwitchDoorTask]) -> "LightSwitchDoor":
        return cls(max_cells=max(s.num_cells for s in specs),
                   max_doors=max([len(s.door_cells) for s in specs] + [1]))

    # ---- host: task arrays and the planner's problem ---------------------------------------------
    def task_arrays(self, spec: LightSwitchDoorTask) -> Task:
        if spec.num_cells > self.max_cells or len(spec.door_cells) > self.max_doors:
            raise ValueError(f"task {spec} exceeds capacity {self}")
        doors = np.full(self.max_doors, -1, np.int32)
        doors[: len(spec.door_cells)] = spec.door_cells
        keys_cell = np.where(doors >= 0, doors - spec.panel_offset, -1).astype(np.int32)
        key_target = np.tile(np.array([MOVE_TARGET, TURN_TARGET], np.float32), (self.max_doors, 1))
        return Task(num_cells=np.int32(spec.num_cells), door_cell=doors, keys_cell=keys_cell, key_target=key_target,
                    key_window=exact_window(key_target, DOOR_TOLERANCE), light_target=np.float32(LIGHT_TARGET))

    def planner_problem(self, spec: LightSwitchDoorTask) -> Problem:
        n = spec.num_cells
        cells = [f"cell{i}" for i in range(n)]
        objects = {"robby": "robot", "light": "light", **{c: "cell" for c in cells}}
        adjacent = {("Adjacent", cells[i], cells[j]) for i in range(n) for j in (i - 1, i + 1)
                    if 0 <= j < n}
        static = frozenset(adjacent | {("LightInCell", "light", cells[-1])})
        init = frozenset({("RobotInCell", "robby", "cell0"), ("LightOff", "light")})
        return Problem(DOMAIN, objects, static, init, frozenset({("LightOn", "light")}))

    def plan_bound(self, spec: LightSwitchDoorTask) -> tuple[int, int]:
        # States: the robot's cell x the light on or off. Operators: MoveRobot both ways along the row,
        # TurnOnLight and TurnOffLight in the light's cell, MoveKey and TurnKey in every cell.
        return 2 * spec.num_cells, 2 * (spec.num_cells - 1) + 2 + 2 * spec.num_cells

    @property
    def num_atoms(self) -> int:
        return self.max_cells + 2  # RobotInCell(robby, cell_i) for every cell slot, LightOn, LightOff

    @property
    def num_slots(self) -> int:
        return self.max_cells  # every skill's slot is a cell

    def atom_index(self, atom) -> int:
        if atom[0] == "RobotInCell":
            return self.object_slot(atom[2])
        return self.max_cells + {"LightOn": 0, "LightOff": 1}[atom[0]]

    def object_slot(self, name: str) -> int:
        return int(name.removeprefix("cell"))

    # ---- device: dynamics -------------------------------------------------------------------------
    def reset(self, task: Task) -> State:
        doors = task.door_cell.shape
        return State(robot_x=jnp.float32(0.5), light_level=jnp.float32(0.0),
                     keys=ExactKey.zeros(doors + (2,)), task=task)

    def _cell_centres(self) -> jax.Array:
        return jnp.arange(self.max_cells, dtype=jnp.float32) + 0.5

    def _here(self, state: State, cells: jax.Array) -> jax.Array:
        """bool[D]: which of the doors' `cells` (door_cell or keys_cell) is the robot's cell."""
        return (cells >= 0) & (jnp.abs(cells.astype(jnp.float32) + 0.5 - state.robot_x) < CELL_TOLERANCE)

    def door_open(self, state: State) -> jax.Array:
        """bool[D]: both keys within the inclusive tolerance of their targets."""
        return jnp.all(state.task.key_window.contains(state.keys), axis=-1)

    def _light_on(self, state: State) -> jax.Array:
        return jnp.abs(state.light_level - state.task.light_target) < LIGHT_ON_TOLERANCE

    def step(self, state: State, action: jax.Array) -> State:
        """All rules read the pre-step state (envs.md §2.3)."""
        dx, dlight, dkeys = action[0], action[1], action[2:]  # dkeys: (dmove, dturn)
        closed = ~self.door_open(state)
        # Doors: keys of a closed door turn in their cell (the door's) and clip; open doors are frozen.
        keys = state.keys.add_clipped(dkeys, where=(self._here(state, state.task.keys_cell) & closed)[:, None])
        # Light: only dlight == 0.75 exactly, only in the light's cell, only while off.
        light_x = state.task.num_cells.astype(jnp.float32) - 0.5
        switch = ((jnp.abs(state.robot_x - light_x) < CELL_TOLERANCE) & (dlight == LIGHT_SWITCH_VALUE)
                  & ~self._light_on(state))
        light_level = jnp.where(switch, LIGHT_SWITCH_VALUE, state.light_level)
        # Move: a closed door blocks leaving its cell to the right (dx < 0 always may move).
        blocked = jnp.any(self._here(state, state.task.door_cell) & closed) & ~(dx < 0)
        moved = jnp.clip(state.robot_x + dx, 0.0, state.task.num_cells.astype(jnp.float32))
        return state.replace(robot_x=jnp.where(blocked, state.robot_x, moved), light_level=light_level,
                             keys=keys)

    def robot_in_cell(self, state: State) -> jax.Array:
        valid = jnp.arange(self.max_cells) < state.task.num_cells
        return valid & (jnp.abs(self._cell_centres() - state.robot_x) < CELL_TOLERANCE)

    def abstract(self, state: State) -> jax.Array:
        on = self._light_on(state)
        return jnp.concatenate([self.robot_in_cell(state), jnp.stack([on, ~on])])

    def goal_reached(self, state: State) -> jax.Array:
        return self._light_on(state)

    def state_vector(self, state: State) -> jax.Array:
        keys = state.keys.to_float32().reshape(-1)
        return jnp.concatenate([jnp.stack([state.robot_x, state.light_level]), keys])

    def features(self, state: State, stuck_state: State) -> jax.Array:
        """envs.md §2.7: the keys in the robot's cell (keys and targets) and a flag; zeros if none."""
        here = self._here(state, state.task.keys_cell)
        d = jnp.argmax(here)
        has = jnp.any(here)
        door = self._keys_and_targets(state)[d]
        return jnp.concatenate([has[None].astype(jnp.float32), jnp.where(has, door, 0.0)])

    def _keys_and_targets(self, state: State) -> jax.Array:
        """float32[D, 4]: each door's (move_key, move_target, turn_key, turn_target) as observed."""
        return jnp.stack([state.keys.to_float32(), state.task.key_target], axis=-1).reshape(-1, 4)

    @property
    def full_state_fits(self) -> bool:
        return self.max_cells <= self.max_task_cells and self.max_doors <= self.max_task_doors

    @property
    def full_state_varying(self) -> np.ndarray:
        # robot x, light level, and each door's two keys; cells, targets and door positions are the task's
        doors = 4 + self.max_cells + 5 * np.arange(self.max_doors)[:, None] + np.array([1, 3])
        return np.concatenate([[0, 2], doors.reshape(-1)])

    def full_state(self, state: State) -> jax.Array:
        """Every object's raw features (method.md §4.3, "no feature selection"): robot x; light x,
        level, target; each cell's x; each door's x, keys and targets; absent objects are zeros."""
        if not self.full_state_fits:
            raise ValueError(f"the full-state observation holds at most {self.max_task_cells} cells and "
                             f"{self.max_task_doors} doors; this env has {self.max_cells} and {self.max_doors}")
        task = state.task
        cell_x = jnp.where(jnp.arange(self.max_cells) < task.num_cells, self._cell_centres(), 0.0)
        has_door = task.door_cell >= 0
        doors = jnp.concatenate([task.door_cell[:, None].astype(jnp.float32) + 0.5,
                                 self._keys_and_targets(state)], axis=-1)
        light = jnp.stack([task.num_cells.astype(jnp.float32) - 0.5, state.light_level, task.light_target])
        vector = jnp.concatenate([state.robot_x[None], light, cell_x,
                                  jnp.where(has_door[:, None], doors, 0.0).reshape(-1)])
        return jnp.pad(vector, (0, self.full_state_size - vector.shape[0]))

    # The paper's objects (envs.md §2): the robot, the light, the cells and the doors. A door is acted on
    # where its keys turn (its own cell, or a panel's): that is its position, and its own cell is an
    # offset from there. Positions are not features: a feature says what an object is, not where.
    object_types = {"robot": (), "light": ("level", "target"), "cell": (),
                    "door": ("door_offset", "move_key", "move_target", "turn_key", "turn_target")}
    # What a perception system would report of a door: each of its keys at its target (the door is open
    # while both are)
    novelty_predicates = (NoveltyPredicate("door", "move_key", DOOR_TOLERANCE, above=False, other="move_target"),
                          NoveltyPredicate("door", "turn_key", DOOR_TOLERANCE, above=False, other="turn_target"))

    @property
    def num_objects(self) -> int:
        return 2 + self.max_cells + self.max_doors

    candidate_slots = property(lambda self: np.r_[1, 2 + self.max_cells + np.arange(self.max_doors)])  # light, doors

    def objects(self, state: State) -> Objects:
        task, width, at = state.task, self.object_width, lambda x: jnp.asarray(x, jnp.float32).reshape(-1, 1)
        light_x, nothing = task.num_cells.astype(jnp.float32) - 0.5, lambda n: jnp.zeros((n, 0))
        doors = jnp.concatenate([at(task.door_cell - task.keys_cell), self._keys_and_targets(state)], axis=-1)
        return Objects.concat(
            Objects.of_type(0, nothing(1), True, False, at(state.robot_x), width),
            Objects.of_type(1, jnp.stack([state.light_level, task.light_target])[None], True, True, at(light_x), width),
            Objects.of_type(2, nothing(self.max_cells), jnp.arange(self.max_cells) < task.num_cells, False,
                            at(self._cell_centres()), width),
            Objects.of_type(3, doors, task.door_cell >= 0, True, at(task.keys_cell + 0.5), width))

    def object_names(self, spec: LightSwitchDoorTask) -> tuple[str | None, ...]:
        # the planner's robot, light and cells; the doors are the novelty's, unknown to its model
        return ("robby", "light", *named_slots((f"cell{i}" for i in range(spec.num_cells)), self.max_cells),
                *named_slots((f"door{j}" for j in range(len(spec.door_cells))), self.max_doors))

    def oracle_object(self, state: State) -> jax.Array:
        """The door whose keys turn in the robot's cell."""
        here = self._here(state, state.task.keys_cell)
        return jnp.where(jnp.any(here), 2 + self.max_cells + jnp.argmax(here), -1).astype(jnp.int32)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        # The authors' box is unbounded: a move past the row's ends is clipped to it and keys clip to
        # [0, 1]. dlight acts only at exactly LIGHT_SWITCH_VALUE, a point no continuous policy samples.
        bound = np.array([self.max_task_cells, 1.0, 1.0, 1.0], np.float32)  # one box for every capacity
        return -bound, bound

    # ---- device: skills (all singleton: one action, then terminate) ----------------------------
    def skill_action(self, state: State, call: SkillCall) -> jax.Array:
        dx = self._cell_centres()[call.slot] - state.robot_x
        zero = jnp.float32(0.0)
        actions = jnp.stack([
            jnp.stack([dx, zero, zero, zero]),  # MoveRobot to the slot's cell
            jnp.stack([zero, call.param, zero, zero]),  # TurnOnLight
            jnp.stack([zero, call.param, zero, zero]),  # TurnOffLight
            jnp.stack([zero, zero, call.param, zero]),  # MoveKey
            jnp.stack([zero, zero, zero, call.param]),  # TurnKey
        ])
        return actions[call.skill]

    def skill_done(self, prev_state: State, state: State, call: SkillCall) -> jax.Array:
        return jnp.bool_(True)

    # ---- the hand-written bridge used as an oracle in tests and eval ----------------------------
    def oracle_bridge(self, params, obs, key):
        """Set the keys here exactly to their targets, then CallPlanner; with no keys here and the keys on
        panels (`panel_offset`), move (MoveRobot's grounding picks left or right) until some are."""
        has, move_key, move_target, turn_key, turn_target = (obs.features[i] for i in range(5))
        move_off = (has > 0.5) & (jnp.abs(move_key - move_target) > DOOR_TOLERANCE)
        turn_off = (has > 0.5) & (jnp.abs(turn_key - turn_target) > DOOR_TOLERANCE)
        call_planner = self.num_skills
        no_keys = self.skill_index("MoveRobot") if self.panel_offset else call_planner
        skill = jnp.where(move_off, self.skill_index("MoveKey"),
                          jnp.where(turn_off, self.skill_index("TurnKey"), jnp.where(has > 0.5, call_planner, no_keys)))
        param = jnp.where(move_off, move_target - move_key, turn_target - turn_key)
        return BridgeAction(skill=jnp.int32(skill), param=jnp.float32(param))
