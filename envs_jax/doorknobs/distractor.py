"""Doorknobs Distractor: Doorknobs with a closet door beside every doorway, the distractor task of issue 55.

The paper's feature selection looks at the interactable object closest to the robot where it got stuck.
In Doorknobs that is the knob of the door blocking the doorway the robot stands in, on the wall line at
the doorway's edge. Here each door has a closet beside it: a door of the same type, in the wall of the
room the robot comes from (of the door's two rooms, the one fewer doors from the start), spanning the
wall away from the knob's edge of the doorway. Its knob stands CLOSET_KNOB_OUT off the wall into that
room, so the robot stuck in the doorway is nearer to it than to the door's knob wherever it stands.

A closet leads nowhere: it is no obstacle, no object of the planner's problem, and inert (its knob never
turns, so it shows what a real knob shows before it is turned: rot 0, target 0.75, closed; a constant
rot along an episode is a cue a learner may use). The hand features, `oracle_object` (the real door) and
the oracle bridge are Doorknobs'; the task specs are Doorknobs' too, so the closets come with any map.
"""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import NoveltySweep, Objects
from envs_jax.doorknobs import maps
from envs_jax.doorknobs.env import SWEEP_DOORS, SWEEP_MAP_SIZE, Doorknobs, State, at_slots, sweep_horizon, sweep_task
from envs_jax.doorknobs.maps import HALLWAY_WIDTH, KNOB_TARGET, TEST_MAP_SIZE, WALL_DEPTH, DoorknobsTask, Task

# From the wall line into the room the robot comes from. The robot stuck in a doorway stands 0.055 (the
# closed door stops it) to 0.106 (it still touches the doorway) off that line, and the door's knob lies
# within 0.005 of it at the same edge of the doorway: so the closet's knob is nearer by at least 0.045
# along the wall's normal, at any place across the doorway (the oracle's stuck robots: within 0.05).
CLOSET_KNOB_OUT = 0.05
CLOSET_WIDTH = HALLWAY_WIDTH  # fits the 0.38 of wall beside the doorway
CLOSET_FEATURES = (0.0, KNOB_TARGET, 0.0)  # rot, target_rot, open: an unturned real knob's


@struct.dataclass
class ClosetTask(Task):
    """Doorknobs' task arrays and, per door slot (D = 2R), the closet beside its door."""

    closet_mask: jax.Array  # bool[D]: the slot's door has a closet (every door does)
    closet_knob: jax.Array  # float32[D, 2]: the closet's object position
    closet_door: jax.Array  # float32[D, 2, 2]: its ends on the wall's face, the doorway's first (for drawing)


def closet(spec: DoorknobsTask, door: tuple[int, int, int], from_owner: bool) -> tuple[np.ndarray, np.ndarray]:
    """(knob float[2], ends float[2, 2]) of the closet beside `door`, in the owner's wall if `from_owner`,
    else in the other room's."""
    rect, _, centre, normal = maps.door_geometry(spec.size, *door)
    along = np.array([np.cos(rect[4]), np.sin(rect[4])])  # from the knob's edge of the doorway to the other
    facing = normal if from_owner else -normal
    edge = centre - HALLWAY_WIDTH / 2 * along  # on the wall line, beside the door's knob
    face = edge + WALL_DEPTH / 2 * facing
    return edge + CLOSET_KNOB_OUT * facing, np.stack([face, face - CLOSET_WIDTH * along])


@functools.lru_cache(maxsize=4096)
def task_arrays(spec: DoorknobsTask, map_size: int) -> ClosetTask:
    """Doorknobs' arrays of the spec plus a closet per door, in the wall of its room nearer the start."""
    task = maps.task_arrays(spec, map_size)
    doors = task.door_mask.shape[0]
    mask, knob, ends = np.zeros(doors, bool), np.zeros((doors, 2), np.float32), np.zeros((doors, 2, 2), np.float32)
    distance = maps.door_distances(spec.rooms, spec.doors, spec.start_room)
    for row, col, side in spec.doors:
        owner, other = maps.door_rooms((row, col, side))
        # a grid's neighbouring rooms are never equally far from the start (odd and even), so each door
        # is crossed from one side on every shortest route
        d = 2 * (row * map_size + col) + side
        knob[d], ends[d] = closet(spec, (row, col, side), distance[owner] < distance[other])
        mask[d] = True
    return ClosetTask(**{f.name: getattr(task, f.name) for f in dataclasses.fields(task)},
                      closet_mask=mask, closet_knob=knob, closet_door=ends)


@dataclass(frozen=True)
class DoorknobsDistractor(Doorknobs):
    name = "doorknobs_distractor"
    novelty_sweep = NoveltySweep("doors to the goal", f"on {SWEEP_MAP_SIZE}x{SWEEP_MAP_SIZE} maps, every door "
                                 "closed, a closet beside each", SWEEP_DOORS, sweep_task, sweep_horizon)
    # Doorknobs' whole state, then each closet's knob (x, y, theta, rot, target_rot, open) at its 5x5 slot.
    full_state_size: ClassVar[int] = Doorknobs.full_state_size + 6 * 2 * TEST_MAP_SIZE ** 2

    def task_arrays(self, spec: DoorknobsTask) -> ClosetTask:
        return task_arrays(spec, self.map_size)

    def drawer(self):
        from envs_jax.doorknobs.drawer import DISTRACTOR_DRAWER  # matplotlib: only when drawing
        return DISTRACTOR_DRAWER

    # The closets after Doorknobs' objects: slot 1 + 3R + d is door slot d's closet.
    num_objects = property(lambda self: 1 + 5 * self._rooms)

    @property
    def candidate_slots(self) -> np.ndarray:  # the doors' and their closets'
        doors = super().candidate_slots
        return np.r_[doors, doors + 2 * self._rooms]

    def object_names(self, spec: DoorknobsTask) -> tuple[str | None, ...]:
        names, doors = super().object_names(spec), slice(1 + self._rooms, 1 + 3 * self._rooms)
        closets = self.task_arrays(spec).closet_mask
        return names + tuple(f"closet-{door}" if door and has else None for door, has in zip(names[doors], closets))

    def objects(self, state: State) -> Objects:
        task = state.task
        features = jnp.broadcast_to(jnp.asarray(CLOSET_FEATURES), task.closet_knob.shape[:1] + (3,))
        closets = Objects.of_type(2, features, task.closet_mask, True, task.closet_knob, self.object_width)
        return Objects.concat(super().objects(state), closets)

    @property
    def full_state_filled(self) -> np.ndarray:
        _, door_at = self._slots_at()
        closets = Doorknobs.full_state_size + (6 * door_at[:, None] + np.arange(6)).reshape(-1)
        return np.concatenate([super().full_state_filled, closets])

    def full_state(self, state: State) -> jax.Array:
        """Doorknobs' `full_state`, then the closets' knobs (x, y, theta, rot, target_rot, open) at their
        5x5 door slots; the closets never change, so `full_state_varying` is Doorknobs'."""
        task, (_, door_at) = state.task, self._slots_at()
        constant = jnp.broadcast_to(jnp.asarray(CLOSET_FEATURES), task.closet_knob.shape[:1] + (3,))
        knobs = jnp.concatenate([task.closet_knob, task.door_rect[:, 4:5], constant], -1)
        return jnp.concatenate([super().full_state(state),
                                at_slots(knobs, task.closet_mask, door_at, 2 * TEST_MAP_SIZE ** 2)])
