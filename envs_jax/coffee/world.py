"""Coffee worlds (envs.md §4.1-4.5): constants, task sampling, the state, the predicates and the
dynamics. The env class (`coffee.Coffee`) and the skills (`coffee_skills`) build on these.

All positions are (x, y, z) in the [0, 10]^3 workspace. The robot's pose is one vector in the order of
its features: x, y, z, tilt, wrist, fingers. Cups are padded to the env's capacity with a mask.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import tree_where

# ---- §4.1 constants ----------------------------------------------------------------------------------
X, Y, Z, TILT, WRIST, FINGERS = range(6)  # the robot's pose vector
POSE_LOW = np.array([0.0, 0.0, 0.0, 0.0, -2 * np.pi, 0.1], np.float32)
POSE_HIGH = np.array([10.0, 10.0, 10.0, np.pi / 4, 2 * np.pi, 0.4], np.float32)
ROBOT_INIT = np.array([5.0, 5.0, 10.0, 0.0, 0.0, 0.4], np.float32)
FINGERS_OPEN, FINGERS_CLOSED = 0.4, 0.1
POUR_TILT = np.pi / 4  # the tilt range's top: pouring
SAFE_Z = 10.0  # the workspace's top, where skills travel
# A normalised action in [-1, 1]^6 times these is the pose change.
ACTION_SCALE = np.array([2.5, 2.5, 2.5, np.pi / 4, np.pi / 4, 1.0], np.float32)
MAX_POSITION_STEP = 2.5  # skills cap their 3-D step at this norm

MACHINE_XY, MACHINE_SIZE = (8.5, 7.5), (1.0, 2.0, 4.0)  # corner and (x, y, z) lengths (for drawing)
BUTTON = np.array([9.0, 7.5, 3.0], np.float32)
BUTTON_RADIUS = 0.2  # compared with the squared distance, as the authors did
DISPENSE = np.array([9.0, 7.06, 0.0], np.float32)

JUG_RADIUS, JUG_HEIGHT = 0.4, 1.5  # the jug top (x, y, 1.5) is where the robot twists it
JUG_X_RANGE, JUG_Y_RANGE = (8.0, 9.0), (2.4, 4.6)
JUG_INIT_ROT = 1.5  # same_levels: always rotated past PickJug's reach
HANDLE_OFFSET, HANDLE_HEIGHT = 0.42, 1.125  # radial, absolute z; also the robot's height above the jug

CUP_RADIUS = 0.24
CUP_X_RANGE, CUP_Y_RANGE = (0.74, 6.76), (2.4, 4.6)
CUP_PADDING = 0.5  # cups keep their circles grown by this apart
CAPACITY_RANGE, TARGET_FRACTION = (0.75, 1.5), 0.75
CUP_TRIES = 10  # position draws per cup before all cups are redrawn
POUR_OFFSET = np.array([0.96, 0.24], np.float32)  # the jug's (x, y) when pouring, from the cup's centre
POUR_Z = 2.0625  # the jug's z when pouring
POUR_VELOCITY = 0.15  # liquid per pouring step

# Tolerances; those called "squared" compare with squared distances.
GRASP_FINGER_TOL = 0.01
GRASP_POSITION_TOL = 0.5  # squared
PICK_JUG_ROT_TOL = np.pi / 3  # the novelty: the grasp needs |rot| below this
DISPENSE_TOL = 1.0  # squared
POUR_ANGLE_TOL = 0.1
POUR_POSITION_TOL = 1.0  # squared
TWIST_TOL = 0.5  # squared: Twisting's reach around the jug top

TRAIN_CUPS, TEST_CUPS = (1,), (1, 2, 3, 4)  # each task draws its number of cups uniformly from these
MAX_CUPS = max(TEST_CUPS)
TEST_HORIZON = 110  # see env.py: within 10 steps of the oracle bridge's longest on seeds 0-7
AUTHORS_TEST_CUPS, AUTHORS_TEST_HORIZON = (4,), 100  # the authors' logged runs


# ---- §4.3 task generation ------------------------------------------------------------------------------
@dataclass(frozen=True)
class CoffeeTask:
    """Host-side task spec (hashable)."""

    cups: tuple[tuple[float, float, float], ...]  # per cup (x, y, capacity); target = 0.75 capacity
    jug: tuple[float, float]
    horizon: int = TEST_HORIZON

    @property
    def min_steps(self) -> int:
        """No episode reaches the goal in fewer env steps: each cup needs more than its target poured,
        POUR_VELOCITY per step (a lower bound: the jug must also be twisted, filled and carried)."""
        return sum(int(np.floor(TARGET_FRACTION * capacity / POUR_VELOCITY)) + 1 for _, _, capacity in self.cups)

    def describe(self) -> str:
        return f"{len(self.cups)} cup{'s' if len(self.cups) != 1 else ''}"


def _sample_cups(rng: np.random.Generator, num_cups: int) -> list[tuple[float, float, float]]:
    """Per cup up to 10 positions until its grown circle clears the cups before it, then its capacity;
    a cup that finds no place starts all cups over."""
    clearance = 2 * (CUP_RADIUS + CUP_PADDING)
    while True:
        cups: list[tuple[float, float, float]] = []
        for _ in range(num_cups):
            for _ in range(CUP_TRIES):
                x, y = rng.uniform(*CUP_X_RANGE), rng.uniform(*CUP_Y_RANGE)
                if all((x - cx) ** 2 + (y - cy) ** 2 > clearance ** 2 for cx, cy, _ in cups):
                    break
            else:
                break
            cups.append((float(x), float(y), float(rng.uniform(*CAPACITY_RANGE))))
        if len(cups) == num_cups:
            return cups


def sample_task(rng: np.random.Generator, cup_counts: tuple[int, ...]) -> CoffeeTask:
    """The authors' draw order: the number of cups, the cups, then the jug's (x, y); the jug's rotation
    is the fixed JUG_INIT_ROT (same_levels), so it takes no draw."""
    cups = _sample_cups(rng, int(rng.choice(cup_counts)))
    jug = (float(rng.uniform(*JUG_X_RANGE)), float(rng.uniform(*JUG_Y_RANGE)))
    return CoffeeTask(tuple(cups), jug)


def train_task(seed: int) -> CoffeeTask:
    """The seed's single training task: one cup."""
    return sample_task(np.random.default_rng(seed), TRAIN_CUPS)


# name -> (cup counts each test task draws from, test horizon)
TEST_DRAWS = {"jaxbridge": (TEST_CUPS, TEST_HORIZON), "authors": (AUTHORS_TEST_CUPS, AUTHORS_TEST_HORIZON)}
TEST_PROTOCOLS = {"jaxbridge": f"1-4 cups per task, horizon {TEST_HORIZON}",
                  "authors": f"4 cups per task, horizon {AUTHORS_TEST_HORIZON}: the authors' logged runs"}


def test_tasks(seed: int, num_tasks: int = 10, protocol: str = "jaxbridge") -> list[CoffeeTask]:
    """The seed's test tasks: each draws its number of cups uniformly from the protocol's counts (ours
    1-4; the logged paper runs used 4 cups always, the authors' HEAD 1), in the authors' draw order."""
    cup_counts, horizon = TEST_DRAWS[protocol]
    rng = np.random.default_rng(seed + 10000)
    return [dataclasses.replace(sample_task(rng, cup_counts), horizon=horizon) for _ in range(num_tasks)]


SWEEP_CUPS = (1, 2, 3, 4, 5, 6)  # eval.py --sweep: 1..6 cups, beyond the test tasks' 4
SWEEP_STEPS_PER_CUP = 20  # the oracle needs 14-17 more steps per cup (max 102 for 4 cups, 131 for 6)


def sweep_task(rng: np.random.Generator, num_cups: int) -> CoffeeTask:
    return sample_task(rng, (num_cups,))


def sweep_horizon(spec: CoffeeTask) -> int:
    """The test horizon, plus 20 steps for every cup beyond the test tasks' 4."""
    return spec.horizon + SWEEP_STEPS_PER_CUP * max(0, len(spec.cups) - MAX_CUPS)


# ---- device arrays ------------------------------------------------------------------------------------
@struct.dataclass
class Task:
    """A task padded to the env's cup capacity C."""

    cup_xy: jax.Array  # float32[C, 2]
    cup_capacity: jax.Array  # float32[C]
    cup_target: jax.Array  # float32[C]
    cup_mask: jax.Array  # bool[C]
    jug_xy: jax.Array  # float32[2]


@struct.dataclass
class SkillMemory:
    """What the authors' MoveToTwistJug and PickJug policies kept between calls (envs.md §4.6), used only
    with the env's `shared_repeat_flag` quirk (skills.remember_call); the dynamics never read it."""

    repeated: jax.Array  # bool: one of them was called twice in the same state
    pick_seen: jax.Array  # float32[D]: the state vector PickJug last acted in (inf: never)
    twist_seen: jax.Array  # float32[D]: the same for MoveToTwistJug


@struct.dataclass
class State:
    robot: jax.Array  # float32[6]: x, y, z, tilt, wrist, fingers
    jug_xy: jax.Array  # float32[2]
    jug_rot: jax.Array  # float32
    jug_held: jax.Array  # bool
    jug_filled: jax.Array  # bool
    machine_on: jax.Array  # bool
    cup_liquid: jax.Array  # float32[C]: current liquid
    task: Task
    memory: SkillMemory


def state_vector(state: State) -> jax.Array:
    """float32[12 + C]: everything that changes, for "did the state change"."""
    flags = jnp.stack([state.jug_rot, state.jug_held, state.jug_filled, state.machine_on]).astype(jnp.float32)
    return jnp.concatenate([state.robot, state.jug_xy, flags, state.cup_liquid])


def task_arrays(spec: CoffeeTask, max_cups: int) -> Task:
    n = len(spec.cups)
    if n > max_cups:
        raise ValueError(f"task with {n} cups exceeds the capacity of {max_cups}")
    cups = np.zeros((max_cups, 3), np.float32)
    cups[:n] = spec.cups
    return Task(cup_xy=cups[:, :2], cup_capacity=cups[:, 2], cup_target=TARGET_FRACTION * cups[:, 2],
                cup_mask=np.arange(max_cups) < n, jug_xy=np.array(spec.jug, np.float32))


def reset(task: Task) -> State:
    never = jnp.full(12 + task.cup_mask.shape[-1], jnp.inf, jnp.float32)  # no state vector holds inf
    return State(robot=jnp.asarray(ROBOT_INIT), jug_xy=task.jug_xy, jug_rot=jnp.float32(JUG_INIT_ROT),
                 jug_held=jnp.bool_(False), jug_filled=jnp.bool_(False), machine_on=jnp.bool_(False),
                 cup_liquid=jnp.zeros(task.cup_mask.shape, jnp.float32), task=task,
                 memory=SkillMemory(repeated=jnp.bool_(False), pick_seen=never, twist_seen=never))


# ---- geometry -----------------------------------------------------------------------------------------
def sq_dist(a: jax.Array, b: jax.Array) -> jax.Array:
    return jnp.sum((a - b) ** 2, axis=-1)


def handle(state: State) -> jax.Array:
    """float32[3]: the jug's handle, 0.42 from its centre at angle rot - pi/2, at height 1.125."""
    angle = state.jug_rot - np.pi / 2
    return jnp.stack([state.jug_xy[0] + HANDLE_OFFSET * jnp.cos(angle),
                      state.jug_xy[1] + HANDLE_OFFSET * jnp.sin(angle), jnp.float32(HANDLE_HEIGHT)])


def jug_top(state: State) -> jax.Array:
    return jnp.concatenate([state.jug_xy, jnp.float32(JUG_HEIGHT)[None]])


def jug_point(state: State) -> jax.Array:
    """float32[3]: where the jug is for placing and pouring: its (x, y) at the robot's height less the
    handle's."""
    return jnp.concatenate([state.jug_xy, (state.robot[Z] - HANDLE_HEIGHT)[None]])


def pour_positions(task: Task) -> jax.Array:
    """float32[C, 3]: where the jug pours into each cup."""
    xy = task.cup_xy + POUR_OFFSET
    return jnp.concatenate([xy, jnp.full(xy.shape[:-1] + (1,), POUR_Z, jnp.float32)], axis=-1)


# ---- §4.5 predicates (each on one state) ------------------------------------------------------------
def twisting(state: State) -> jax.Array:
    """Twisting(robot, jug): the robot is nearer the jug top than the handle, and within reach of it."""
    to_top = sq_dist(state.robot[:3], jug_top(state))
    return (sq_dist(state.robot[:3], handle(state)) >= to_top) & (to_top < TWIST_TOL)


def jug_in_machine(state: State) -> jax.Array:
    return ~state.jug_held & (sq_dist(state.jug_xy, DISPENSE[:2]) < DISPENSE_TOL)


def on_table(state: State) -> jax.Array:
    return ~state.jug_held & ~jug_in_machine(state)


def hand_empty(state: State) -> jax.Array:
    return ~twisting(state) & ~state.jug_held


def pressing_button(state: State) -> jax.Array:
    return sq_dist(state.robot[:3], BUTTON) < BUTTON_RADIUS


def jug_above_cup(state: State) -> jax.Array:
    """bool[C]: JugAboveCup(jug, c) (= RobotAboveCup(robot, c)): the held jug is within reach of c's
    pouring position."""
    near = sq_dist(jug_point(state), pour_positions(state.task)) < POUR_POSITION_TOL
    return state.task.cup_mask & state.jug_held & near


def cup_filled(state: State) -> jax.Array:
    """bool[C]: more liquid than the cup's target (padding never holds)."""
    return state.task.cup_mask & (state.cup_liquid > state.task.cup_target)


def goal_reached(state: State) -> jax.Array:
    return jnp.all(cup_filled(state) | ~state.task.cup_mask)


# ---- §4.4 dynamics ------------------------------------------------------------------------------------
def step(state: State, action: jax.Array) -> State:
    """One env step: the new pose, then exactly one of the branches button > holding (drop, pour, carry)
    > twisting > grasp, then the jug fills if it stands in the machine and the machine is on."""
    old = state.robot
    pose = jnp.clip(old + jnp.clip(action, -1.0, 1.0) * ACTION_SCALE, POSE_LOW, POSE_HIGH)
    moved = pose - old  # after clipping: a wrist at its limit does not count as wrist motion
    level = pose.at[TILT].set(0.0).at[WRIST].set(0.0)

    press = (sq_dist(pose[:3], BUTTON) < BUTTON_RADIUS) & ~state.machine_on
    holding = ~press & state.jug_held
    drop = holding & (jnp.abs(pose[FINGERS] - FINGERS_OPEN) < GRASP_FINGER_TOL)
    tilted = holding & ~drop & (jnp.abs(pose[TILT] - POUR_TILT) < POUR_ANGLE_TOL)
    carry = holding & ~drop & ~tilted
    # Pouring reaches the cup nearest to the jug (which stays where it was); no cup in reach, or one
    # that would overflow, makes the whole step a no-op.
    reach = jnp.where(state.task.cup_mask, sq_dist(jug_point(state), pour_positions(state.task)), jnp.inf)
    cup = jnp.argmin(reach)
    fits = state.cup_liquid[cup] + POUR_VELOCITY <= state.task.cup_capacity[cup]
    pour = tilted & (reach[cup] < POUR_POSITION_TOL) & fits
    free = ~press & ~state.jug_held
    twist = free & twisting(state)  # the pre-step state decides
    grasp = (free & ~twist & (jnp.abs(pose[FINGERS] - FINGERS_CLOSED) < GRASP_FINGER_TOL)
             & (sq_dist(pose[:3], handle(state)) < GRASP_POSITION_TOL)
             & (jnp.abs(state.jug_rot) < PICK_JUG_ROT_TOL) & (moved[WRIST] == 0.0))

    robot = jnp.where(press, level.at[:3].set(BUTTON), pose)
    robot = jnp.where(pour, pose.at[:3].set(old[:3]).at[FINGERS].set(FINGERS_CLOSED), robot)
    robot = jnp.where(carry, level.at[FINGERS].set(FINGERS_CLOSED), robot)
    robot = jnp.where(grasp, level.at[:3].set(handle(state)), robot)
    new = state.replace(
        robot=robot,
        jug_xy=jnp.where(carry, state.jug_xy + moved[:2], state.jug_xy),
        jug_rot=jnp.where(twist, state.jug_rot + moved[WRIST], state.jug_rot),
        jug_held=(state.jug_held & ~drop) | grasp,
        machine_on=state.machine_on | press,
        cup_liquid=state.cup_liquid.at[cup].add(jnp.where(pour, POUR_VELOCITY, 0.0)),
    )
    new = new.replace(jug_filled=new.jug_filled | (jug_in_machine(new) & new.machine_on))
    frozen = tilted & ~pour
    return tree_where(frozen, state, new)
