"""Locked Box: an example env written only against the public API (docs/NEW_ENV.md walks through it).

A row of cells; the robot starts in cell 0 and must open the box in the last cell. The novelty: the box
is locked, and its key lies in some other cell. The planner's model knows nothing of the key: it walks to
the box and tries to open it, which does nothing, so it is stuck. The bridge must fetch the key (MoveToKey,
then PickKey with a grip within 0.1 of 0.5) and call the planner, which walks back and opens the box.

    python train.py --env examples.locked_box:LockedBox --num-seeds 2 --cycles 3
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax import BridgeAction, NoveltyEnv, Objects, SkillCall, SkillSpec, register
from planner import Domain, LiftedOperator, Problem

GRIP, GRIP_TOLERANCE = 0.5, 0.1  # PickKey holds the key when |grip - 0.5| <= 0.1
OPEN_VALUE = 1.0  # the box responds to dopen == 1 only
TRAIN_CELLS, TEST_CELLS = 5, (6, 10)  # test: 6..10 cells, drawn per task


@dataclass(frozen=True)
class LockedBoxTask:
    num_cells: int
    key_cell: int  # 0 .. num_cells - 2

    def describe(self) -> str:
        return f"{self.num_cells} cells, key in cell {self.key_cell}"

    @property
    def min_steps(self) -> int:
        return 3  # pick the key, move to the box, open it

    @property
    def horizon(self) -> int:
        return 2 * self.num_cells + 10  # walk there, fetch the key, walk back, with room for mistakes


def _task(rng: np.random.Generator, num_cells: int) -> LockedBoxTask:
    return LockedBoxTask(num_cells, int(rng.integers(0, num_cells - 1)))


@struct.dataclass
class Task:
    num_cells: jax.Array  # int32
    key_cell: jax.Array  # int32


@struct.dataclass
class State:
    robot_x: jax.Array  # float32: a cell centre i + 0.5
    holding: jax.Array  # bool: the robot holds the key
    box_open: jax.Array  # bool
    task: Task


def _move(name: str, skill: str, pre=(), add=(), delete=()) -> LiftedOperator:
    params = (("?robot", "robot"), ("?cell", "cell"))
    return LiftedOperator(name, params, pre=(("RobotInCell", "?robot", "?cell"), *pre), add=add, delete=delete,
                          skill=skill, slot_param="?cell")


DOMAIN = Domain(
    name="locked-box",
    types=("robot", "cell"),
    predicates={"RobotInCell": ("robot", "cell"), "BoxInCell": ("cell",), "BoxOpen": (), "BoxClosed": (),
                "Adjacent": ("cell", "cell")},
    operators=(
        LiftedOperator("MoveRobot", (("?robot", "robot"), ("?cur", "cell"), ("?tgt", "cell")),
                       pre=(("Adjacent", "?cur", "?tgt"), ("RobotInCell", "?robot", "?cur")),
                       add=(("RobotInCell", "?robot", "?tgt"),), delete=(("RobotInCell", "?robot", "?cur"),),
                       skill="MoveRobot", slot_param="?tgt"),
        _move("OpenBox", "OpenBox", pre=(("BoxInCell", "?cell"), ("BoxClosed",)), add=(("BoxOpen",),),
              delete=(("BoxClosed",),)),
        # The key's skills: the model knows no key, so they have no effects and only the bridge uses them.
        _move("MoveToKey", "MoveToKey"),
        _move("PickKey", "PickKey"),
    ),
)


@dataclass(frozen=True)
class LockedBox(NoveltyEnv):
    max_cells: int = TEST_CELLS[1]

    name = "locked_box"
    skills = (SkillSpec("MoveRobot"), SkillSpec("OpenBox", OPEN_VALUE, OPEN_VALUE), SkillSpec("MoveToKey"),
              SkillSpec("PickKey", 0.0, 1.0))
    action_dim = 3  # (dx, dgrip, dopen)
    num_features = 3  # holding the key, at the key's cell, distance to the key / cells
    full_state_size = 5  # robot x, holding, box open, key x, box x
    domain = DOMAIN
    task_sizes = {"cells": "cells in the row (at least 2)"}

    # ---- host -----------------------------------------------------------------------------------------
    @staticmethod
    def train_task(seed: int) -> LockedBoxTask:
        return _task(np.random.default_rng(seed), TRAIN_CELLS)

    @staticmethod
    def test_tasks(seed: int, num_tasks: int = 10) -> list[LockedBoxTask]:
        rng = np.random.default_rng(seed + 10000)
        return [_task(rng, int(rng.integers(TEST_CELLS[0], TEST_CELLS[1] + 1))) for _ in range(num_tasks)]

    @classmethod
    def sized_task(cls, rng: np.random.Generator, cells: int) -> LockedBoxTask:
        if cells < 2:
            raise ValueError(f"a locked box needs at least 2 cells, got {cells}")
        return _task(rng, cells)

    @classmethod
    def for_tasks(cls, specs: list[LockedBoxTask]) -> "LockedBox":
        return cls(max_cells=max(s.num_cells for s in specs))

    def task_arrays(self, spec: LockedBoxTask) -> Task:
        return Task(num_cells=np.int32(spec.num_cells), key_cell=np.int32(spec.key_cell))

    def planner_problem(self, spec: LockedBoxTask) -> Problem:
        cells = [f"cell{i}" for i in range(spec.num_cells)]
        adjacent = {("Adjacent", a, b) for a, b in zip(cells, cells[1:])} | {("Adjacent", b, a) for a, b in zip(cells, cells[1:])}
        objects = {"robby": "robot", **{c: "cell" for c in cells}}
        static = frozenset(adjacent | {("BoxInCell", cells[-1])})
        return Problem(DOMAIN, objects, static, frozenset({("RobotInCell", "robby", "cell0"), ("BoxClosed",)}),
                       frozenset({("BoxOpen",)}))

    @property
    def num_atoms(self) -> int:
        return self.max_cells + 2  # RobotInCell per cell, BoxOpen, BoxClosed

    def atom_index(self, atom) -> int:
        if atom[0] == "RobotInCell":
            return self.object_slot(atom[2])
        return self.max_cells + {"BoxOpen": 0, "BoxClosed": 1}[atom[0]]

    def object_slot(self, name: str) -> int:
        return int(name.removeprefix("cell"))

    # ---- device: dynamics -----------------------------------------------------------------------------
    def reset(self, task: Task) -> State:
        return State(robot_x=jnp.float32(0.5), holding=jnp.bool_(False), box_open=jnp.bool_(False), task=task)

    def _at(self, state: State, cell: jax.Array) -> jax.Array:
        return jnp.abs(state.robot_x - (cell.astype(jnp.float32) + 0.5)) < 1e-3

    def step(self, state: State, action: jax.Array) -> State:
        dx, dgrip, dopen = action[0], action[1], action[2]
        pick = self._at(state, state.task.key_cell) & (jnp.abs(dgrip - GRIP) <= GRIP_TOLERANCE)
        unlock = self._at(state, state.task.num_cells - 1) & (dopen == OPEN_VALUE) & state.holding
        robot_x = jnp.clip(state.robot_x + dx, 0.5, state.task.num_cells.astype(jnp.float32) - 0.5)
        return state.replace(robot_x=robot_x, holding=state.holding | pick, box_open=state.box_open | unlock)

    def abstract(self, state: State) -> jax.Array:
        in_cell = (jnp.arange(self.max_cells) < state.task.num_cells) & self._at(state, jnp.arange(self.max_cells))
        return jnp.concatenate([in_cell, jnp.stack([state.box_open, ~state.box_open])])

    def goal_reached(self, state: State) -> jax.Array:
        return state.box_open

    def state_vector(self, state: State) -> jax.Array:
        return jnp.stack([state.robot_x, state.holding.astype(jnp.float32), state.box_open.astype(jnp.float32)])

    def features(self, state: State, stuck_state: State) -> jax.Array:
        key_x = state.task.key_cell.astype(jnp.float32) + 0.5
        distance = jnp.abs(key_x - state.robot_x) / state.task.num_cells.astype(jnp.float32)
        return jnp.stack([state.holding.astype(jnp.float32), self._at(state, state.task.key_cell).astype(jnp.float32),
                          distance])

    def full_state(self, state: State) -> jax.Array:
        return jnp.stack([state.robot_x, state.holding.astype(jnp.float32), state.box_open.astype(jnp.float32),
                          state.task.key_cell.astype(jnp.float32) + 0.5, state.task.num_cells.astype(jnp.float32) - 0.5])

    # The state as typed objects (the paper's view): the robot, the key and the box; both can be acted on.
    object_types = {"robot": ("holding",), "key": ("held",), "box": ("open",)}
    num_objects = 3

    def objects(self, state: State) -> Objects:
        at = lambda x: jnp.reshape(x, (1, 1)).astype(jnp.float32)
        key_x = state.task.key_cell.astype(jnp.float32) + 0.5
        box_x = state.task.num_cells.astype(jnp.float32) - 0.5
        return Objects.concat(Objects.of_type(0, at(state.holding), True, False, at(state.robot_x), 1),
                              Objects.of_type(1, at(state.holding), True, True, at(key_x), 1),
                              Objects.of_type(2, at(state.box_open), True, True, at(box_x), 1))

    def object_names(self, spec: LockedBoxTask) -> tuple[str | None, ...]:
        return ("robby", "key", "box")  # the key and the box: the novelty's, unknown to the planner's model

    def oracle_object(self, state: State) -> jax.Array:
        return jnp.where(state.holding, 2, 1).astype(jnp.int32)  # the key until it is held, then the box

    # ---- device: skills (each one step) ---------------------------------------------------------------
    def skill_action(self, state: State, call: SkillCall) -> jax.Array:
        to = lambda cell: cell.astype(jnp.float32) + 0.5 - state.robot_x
        zero = jnp.float32(0.0)
        return jnp.stack([
            jnp.stack([to(call.slot), zero, zero]),  # MoveRobot to the slot's cell
            jnp.stack([zero, zero, call.param]),  # OpenBox
            jnp.stack([to(state.task.key_cell), zero, zero]),  # MoveToKey
            jnp.stack([zero, call.param, zero]),  # PickKey with this grip
        ])[call.skill]

    def skill_done(self, prev_state: State, state: State, call: SkillCall) -> jax.Array:
        return jnp.bool_(True)

    def oracle_bridge(self, params, obs, key) -> BridgeAction:
        """Fetch the key (MoveToKey, PickKey at the grip), then CallPlanner."""
        holding, at_key = obs.features[0] > 0.5, obs.features[1] > 0.5
        skill = jnp.where(holding, self.num_skills, jnp.where(at_key, self.skill_index("PickKey"),
                                                              self.skill_index("MoveToKey")))
        return BridgeAction(skill=jnp.int32(skill), param=jnp.float32(GRIP))


register("locked_box", LockedBox)
