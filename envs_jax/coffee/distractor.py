"""Coffee Distractor: Coffee with one cup just past the jug's handle, the distractor task of issue 37.

The paper's feature selection looks at the interactable object closest to the robot where it got stuck.
In Coffee that is the jug: the planner's PickJug leaves the robot at the handle, 0.42 from the jug's
centre. Here every task moves its first cup's centre DECOY_GAP past the handle, so that cup is nearer to
the stuck robot than the jug is; its features say nothing of the rotation the bridge must fix. The
training task has it too: a selector learns to pass over an object only where it has met one.
Everything else is Coffee's (the cup is filled like any other).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from envs_jax.base import NoveltySweep
from envs_jax.coffee import world
from envs_jax.coffee.env import Coffee
from envs_jax.coffee.world import CoffeeTask

# From the handle, outwards: the cup (radius 0.24) clears the jug (radius 0.4) at 0.72 from its centre
# and is 0.3 from the robot at the handle, against the jug's 0.42.
DECOY_GAP = 0.3
# The jug's x at most this: pouring holds the jug 0.96 right of a cup, and the robot at its handle must
# stay inside the workspace (x <= 10) for the jug to reach the decoy cup. Set for the handle of a jug
# twisted to rot 0 (straight below it); the oracle's twist to 0.88 puts it 0.32 further right, so the
# robot stops at the wall with the jug up to 0.3 short, within the Pour skill's reach (squared 0.1).
JUG_MAX_X = 8.3


def with_decoy(task: CoffeeTask) -> CoffeeTask:
    """The task with its first cup moved past the jug's handle (its capacity kept) and the jug's x capped
    at JUG_MAX_X; the other cups are on the far side of the table (x <= 6.76), clear of it."""
    jug = (min(task.jug[0], JUG_MAX_X), task.jug[1])
    angle = world.JUG_INIT_ROT - np.pi / 2  # the handle's direction from the jug's centre (world.handle)
    reach = world.HANDLE_OFFSET + DECOY_GAP
    x, y = jug[0] + reach * np.cos(angle), jug[1] + reach * np.sin(angle)
    return dataclasses.replace(task, jug=jug, cups=((float(x), float(y), task.cups[0][2]),) + task.cups[1:])


def train_task(seed: int) -> CoffeeTask:
    return with_decoy(world.train_task(seed))


def test_tasks(seed: int, num_tasks: int = 10, protocol: str = "jaxbridge") -> list[CoffeeTask]:
    return [with_decoy(task) for task in world.test_tasks(seed, num_tasks, protocol)]


def sweep_task(rng: np.random.Generator, num_cups: int) -> CoffeeTask:
    return with_decoy(world.sweep_task(rng, num_cups))


@dataclass(frozen=True)
class CoffeeDistractor(Coffee):
    name = "coffee_distractor"
    train_task = staticmethod(train_task)
    test_tasks = staticmethod(test_tasks)
    novelty_sweep = NoveltySweep("cups", "to fill after twisting the jug, one past its handle", world.SWEEP_CUPS,
                                 sweep_task, world.sweep_horizon)

    @classmethod
    def sized_task(cls, rng, cups: int) -> CoffeeTask:
        return with_decoy(super().sized_task(rng, cups))
