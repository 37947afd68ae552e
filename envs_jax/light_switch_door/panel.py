"""Light Switch Panel: Light Switch Door with each door's keys on a panel in the cell before the door.

The variant where committing to the original plan is the wrong thing to do (docs/DESIGN.md, "Plan
repair"). The planner walks right and gets stuck at a closed door in cell k, heading for cell k + 1.
The fix is one cell back: the robot must return to cell k - 1, a state the plan has already passed,
and set the keys there. From there a new plan reaches cell k + 1 in two moves; a bridge bound to the
original plan must get there itself, with a MoveRobot whose direction it does not choose (its
grounding is uniform, left or right, as for every bridge skill). Doors are never in adjacent cells, so
no panel shares a cell with a door, and none is in cell 0. Everything else is Light Switch Door's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from envs_jax.base import NoveltySweep
from envs_jax.light_switch_door.env import (SWEEP_CELLS, SWEEP_DOORS, TEST_DOOR_CELLS, TRAIN_CELLS, LightSwitchDoor,
                                            LightSwitchDoorTask, drawn_test_tasks)

PANEL_OFFSET = 1  # a door's keys are one cell before it


def spaced_cells(rng: np.random.Generator, first: int, last: int, count: int) -> tuple[int, ...]:
    """`count` cells in first..last (inclusive), no two adjacent, uniform over such sets: choose sorted
    distinct positions among the cells left after reserving one gap per pair, then spread them."""
    room = last - first + 1 - (count - 1)
    if count < 0 or room < count:
        raise ValueError(f"{count} non-adjacent doors do not fit in cells {first}..{last}")
    chosen = np.sort(rng.choice(room, count, replace=False))
    return tuple(int(first + c + i) for i, c in enumerate(chosen))


def train_task(seed: int) -> LightSwitchDoorTask:
    """5 cells, one door in cell 1, 2 or 3 (its panel in 0, 1 or 2: where Light Switch Door's door is)."""
    rng = np.random.default_rng(seed)
    return LightSwitchDoorTask(TRAIN_CELLS, (int(rng.choice([1, 2, 3])),), panel_offset=PANEL_OFFSET)


def test_tasks(seed: int, num_tasks: int = 10, protocol: str = "jaxbridge") -> list[LightSwitchDoorTask]:
    """Light Switch Door's sizes (N cells and K doors drawn once per seed); each task draws K
    non-adjacent door cells in 1..8 (the panels in 0..7). The protocol sets the horizon only."""
    return drawn_test_tasks(seed, num_tasks, protocol, lambda rng, k: spaced_cells(rng, 1, TEST_DOOR_CELLS - 1, k),
                            PANEL_OFFSET)


def sized_task(rng: np.random.Generator, num_cells: int, num_doors: int) -> LightSwitchDoorTask:
    """A task of a chosen size: non-adjacent doors anywhere in cells 1..N-2 (not the light's cell)."""
    if num_cells < 3:
        raise ValueError(f"need >= 3 cells (a panel, a door, the light), got {num_cells}")
    return LightSwitchDoorTask(num_cells, spaced_cells(rng, 1, num_cells - 2, num_doors), panel_offset=PANEL_OFFSET)


def sweep_task(rng: np.random.Generator, num_doors: int) -> LightSwitchDoorTask:
    """A generalisation-sweep task: `num_doors` doors (and their panels) in a row of 60 cells."""
    return sized_task(rng, SWEEP_CELLS, num_doors)


@dataclass(frozen=True)
class LightSwitchPanel(LightSwitchDoor):
    name = "light_switch_panel"
    panel_offset = PANEL_OFFSET
    train_task = staticmethod(train_task)
    test_tasks = staticmethod(test_tasks)
    novelty_sweep = NoveltySweep("doors", f"in a row of {SWEEP_CELLS} cells, keys one cell back", SWEEP_DOORS,
                                 sweep_task, horizon=lambda spec: spec.horizon)
    task_sizes = {"cells": "cells in the row", "doors": "doors, in non-adjacent cells 1..cells-2"}

    @classmethod
    def sized_task(cls, rng: np.random.Generator, cells: int, doors: int) -> LightSwitchDoorTask:
        return sized_task(rng, cells, doors)
