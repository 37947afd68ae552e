"""Multi Novelty's tasks: where the doors stand, what locks them, where their cards lie, and which tasks
train and test (docs/design/envs.md, "Multi Novelty").

A task is a row of cells with the light in the last; doors stand in cells 1 .. N-2, at least two cells
apart, so every door has a cell of its own section (the cells after the previous door, up to it) to
hold its card. A door's `locks` are bits: KEYCARD (it opens for the robot carrying its card), LATCHED
(its latch must be lifted, then the door pushed with its stiffness). Training and the default test
tasks hold single-lock doors only; the held-out protocol's tasks hold doors with both.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

KEYCARD, LATCHED = 1, 2  # a door's locks, as bits
BOTH = KEYCARD | LATCHED  # the held-out combination: a keycard door that is also latched
SINGLE_LOCKS = (KEYCARD, LATCHED)
STIFFNESS_RANGE = (0.2, 0.8)  # a latched door's push target; the window +-0.1 stays inside [0.1, 0.9]
TRAIN_CELLS = 8
TEST_CELLS_RANGE = (12, 20)  # inclusive, drawn per task
TEST_DOORS_RANGE = (3, 5)  # inclusive: with the fuse 4-6 novelty instances, the training task's 3 and more
SWEEP_CELLS, SWEEP_COUNTS = 30, tuple(range(1, 13))  # eval.py --sweep: 1..12 instances (2x the test's 6)
TEST_PROTOCOLS = {
    "jaxbridge": "3-5 single-lock doors (keycard or latched) and the blown fuse, as training mixes them",
    "held_out": "as jaxbridge, but some doors carry both locks (a keycard door that is also latched), a "
                "combination no training task holds",
}


@dataclass(frozen=True)
class MultiNoveltyTask:
    """Host-side task spec: per door its cell, its locks, its card's cell (-1: no keycard lock) and its
    stiffness (0: no latch)."""

    num_cells: int
    door_cells: tuple[int, ...]
    locks: tuple[int, ...]
    key_cells: tuple[int, ...]
    stiffness: tuple[float, ...]
    fuse_blown: bool

    def describe(self) -> str:
        names = {KEYCARD: "keycard", LATCHED: "latched", BOTH: "keycard+latched"}
        doors = ", ".join(f"{names[lock]} in {cell}" for cell, lock in zip(self.door_cells, self.locks)) or "none"
        return f"{self.num_cells} cells, doors: {doors}{', fuse blown' if self.fuse_blown else ''}"

    @property
    def instances(self) -> int:
        """Novelty instances: one per lock of every door, and the fuse."""
        return sum(bin(lock).count("1") for lock in self.locks) + int(self.fuse_blown)

    @property
    def shortest_solution(self) -> int:
        """h, the oracle bridge's steps: N-1 moves and the light, and per stall the planner's failed step,
        the fix's skills and CallPlanner. A keycard door: the blocked move, FetchKey (a walk back to the
        card and a grip), CallPlanner and the walk back to the door; a latched door: the blocked move,
        LiftLatch, PushDoor, CallPlanner; both: the two in turn; the fuse: the failed TurnOnLight,
        ReplaceFuse, CallPlanner."""
        h = (self.num_cells - 1) + 1 + 3 * int(self.fuse_blown)
        for cell, lock, key in zip(self.door_cells, self.locks, self.key_cells):
            h += (4 + cell - key if lock & KEYCARD else 0) + (4 if lock & LATCHED else 0)
        return h

    @property
    def min_steps(self) -> int:
        """No action sequence is shorter: N-1 moves and the light, a lift and a push per latch (a push reads
        the lifted latch, a move the released door), a fuse swap before the light; a card is gripped in
        the step that leaves its cell."""
        return (self.num_cells - 1) + 1 + 2 * sum(bool(lock & LATCHED) for lock in self.locks) + int(self.fuse_blown)

    @property
    def horizon(self) -> int:
        """Light Switch Door's rule, max(30, h + 5)."""
        return max(30, self.shortest_solution + 5)


def door_cells(rng: np.random.Generator, num_cells: int, num_doors: int) -> tuple[int, ...]:
    """`num_doors` sorted cells in 1..N-2, each at least two after the one before (a free cell between
    consecutive doors for a card): uniform over such placements."""
    free = (num_cells - 2) - (num_doors - 1)
    if num_doors < 0 or free < num_doors:
        raise ValueError(f"{num_doors} doors two cells apart need at least {2 * num_doors + 1} cells, got {num_cells}")
    spots = np.sort(rng.choice(free, num_doors, replace=False))
    return tuple(int(1 + s + i) for i, s in enumerate(spots))


def task_of(rng: np.random.Generator, num_cells: int, locks: tuple[int, ...], fuse_blown: bool = True) -> MultiNoveltyTask:
    """A task with doors of the given locks, in order along the row: places them, a keycard door's card
    in a cell of its own section before it (so the card of a door further on lies behind this one), a
    latched door's stiffness."""
    cells = door_cells(rng, num_cells, len(locks))
    keys, stiffness = [], []
    for previous, cell, lock in zip((-1,) + cells, cells, locks):
        keys.append(int(rng.integers(previous + 1, cell)) if lock & KEYCARD else -1)
        stiffness.append(round(float(rng.uniform(*STIFFNESS_RANGE)), 2) if lock & LATCHED else 0.0)
    return MultiNoveltyTask(num_cells, cells, tuple(int(lock) for lock in locks), tuple(keys), tuple(stiffness),
                            bool(fuse_blown))


def train_tasks(seed: int, episodes: int) -> list[MultiNoveltyTask]:
    """A cycle's training tasks, one per episode: the seed's one layout (8 cells, a keycard door and a
    latched door in a drawn order, the blown fuse: every kind once) with the latched door's stiffness
    stratified over the episodes, the j-th drawn uniformly in the j-th of `episodes` equal parts of
    STIFFNESS_RANGE, so every cycle shows the bridge the push across the range the test doors draw from."""
    rng = np.random.default_rng(seed)
    layout = task_of(rng, TRAIN_CELLS, tuple(int(lock) for lock in rng.permutation(SINGLE_LOCKS)))
    edges = np.linspace(*STIFFNESS_RANGE, episodes + 1)
    pushes = [round(float(rng.uniform(low, high)), 2) for low, high in zip(edges, edges[1:])]
    return [replace(layout, stiffness=tuple(push if lock & LATCHED else 0.0 for lock in layout.locks)) for push in pushes]


def train_task(seed: int) -> MultiNoveltyTask:
    """The seed's training task alone: its layout, the stiffness drawn over the whole range."""
    return train_tasks(seed, 1)[0]


def test_tasks(seed: int, num_tasks: int = 10, protocol: str = "jaxbridge") -> list[MultiNoveltyTask]:
    """Per task 12-20 cells and 3-5 doors, each door's lock uniform over the protocol's choices, and the
    blown fuse. "held_out": locks from keycard, latched and both, at least one door with both."""
    if protocol not in TEST_PROTOCOLS:
        raise ValueError(f"unknown test protocol {protocol!r}; choose from {', '.join(TEST_PROTOCOLS)}")
    rng = np.random.default_rng(seed + 10000 if protocol == "jaxbridge" else (seed + 10000, 1))  # protocols draw apart
    tasks = []
    for _ in range(num_tasks):
        num_cells = int(rng.integers(TEST_CELLS_RANGE[0], TEST_CELLS_RANGE[1] + 1))
        num_doors = int(rng.integers(TEST_DOORS_RANGE[0], TEST_DOORS_RANGE[1] + 1))
        if protocol == "held_out":
            locks = rng.choice([KEYCARD, LATCHED, BOTH], num_doors)
            locks[rng.integers(num_doors)] = BOTH
        else:
            locks = rng.choice(SINGLE_LOCKS, num_doors)
        tasks.append(task_of(rng, num_cells, tuple(int(lock) for lock in locks)))
    return tasks


def sized_task(rng: np.random.Generator, num_cells: int, num_doors: int) -> MultiNoveltyTask:
    """A task of a chosen size: single-lock doors drawn as the default test tasks', and the blown fuse."""
    if num_cells < 2:
        raise ValueError(f"a row needs at least 2 cells, got {num_cells}")
    return task_of(rng, num_cells, tuple(int(lock) for lock in rng.choice(SINGLE_LOCKS, num_doors)))


def sweep_task(rng: np.random.Generator, instances: int) -> MultiNoveltyTask:
    """A generalisation-sweep task with `instances` novelty instances: the blown fuse and instances - 1
    single-lock doors in a row of 30 cells."""
    return sized_task(rng, SWEEP_CELLS, instances - 1)
