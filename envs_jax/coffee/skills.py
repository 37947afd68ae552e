"""Coffee skills (envs.md §4.6) as closed-loop pure functions: the action of each skill in a state, and
when it has finished.

Every skill moves with one helper: head for a 3-D point, at most 2.5 per step, as a normalised action.
Every skill also finishes when a step made no progress (the state did not change). This replaces the
authors' class-level "repeated state" flag, which, once set by any execution of MoveToTwistJug or
PickJug, made both options end after one step for the rest of the learning cycle (envs.md §4.6); here
each execution only looks at its own last step. The env's `shared_repeat_flag` quirk switches the
authors' flag back on (`remember_call`, `skill_done`).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.coffee import world
from envs_jax.base import SkillCall
from envs_jax.coffee.world import FINGERS, MAX_POSITION_STEP, POUR_TILT, SAFE_Z, TILT, X, Y, Z, SkillMemory, State

MOVE_TO_TWIST_JUG, TWIST_JUG, PICK_JUG, PLACE_JUG_IN_MACHINE, TURN_MACHINE_ON, POUR = range(6)
NEAR = 0.1  # squared distance at which a skill counts a waypoint as reached
TWIST_RANGE = 2 * np.pi / 3  # TwistJug's parameter p in [-1, 1] asks for the absolute rotation p * 2pi/3
WRIST_STEP = np.pi / 4  # the wrist's largest turn in one step (world.ACTION_SCALE), and so a twisted jug's
PICK_APPROACH = 1.5  # PickJug comes down this far in front (-y) of the handle, then moves in +y onto it
BUTTON_HEIGHT_TOL = 0.04  # squared: TurnMachineOn rises or sinks to the button's height first


def move_to(state: State, target: jax.Array, dtilt: jax.Array = 0.0) -> jax.Array:
    """float32[6]: a normalised action heading the robot for `target` (x, y, z), plus a tilt command."""
    delta = target - state.robot[:3]
    length = jnp.sqrt(jnp.sum(delta ** 2))
    step = delta * jnp.minimum(1.0, MAX_POSITION_STEP / jnp.maximum(length, 1e-12)) / MAX_POSITION_STEP
    return jnp.concatenate([step, jnp.stack([jnp.asarray(dtilt, jnp.float32), 0.0, 0.0])])


def _only(index: int, value) -> jax.Array:
    return jnp.zeros(6, jnp.float32).at[index].set(value)


def _tilt_toward(state: State, tilt: float) -> jax.Array:
    return jnp.clip((tilt - state.robot[TILT]) / (np.pi / 4), -1.0, 1.0)


def _pick(cases: list[tuple[jax.Array, jax.Array]], otherwise: jax.Array) -> jax.Array:
    """The action of the first case whose condition holds (an if/elif chain, branch-free)."""
    action = otherwise
    for condition, then in reversed(cases):
        action = jnp.where(condition, then, action)
    return action


def move_to_twist_jug(state: State) -> jax.Array:
    """Above the jug: descend onto its top; elsewhere: head for the point high above the jug."""
    above = world.sq_dist(state.robot[:2], state.jug_xy) < NEAR
    return move_to(state, jnp.where(above, world.jug_top(state),
                                    jnp.concatenate([state.jug_xy, jnp.float32(SAFE_Z)[None]])))


def twist_jug(state: State, param: jax.Array) -> jax.Array:
    """Turn the wrist toward the absolute rotation param * 2pi/3 (at most pi/4 a step); once within 0.1,
    go straight up, which ends Twisting."""
    error = param * TWIST_RANGE - state.jug_rot
    up = move_to(state, state.robot[:3].at[Z].set(SAFE_Z))
    return jnp.where(jnp.abs(error) < NEAR, up, _only(world.WRIST, jnp.clip(error / WRIST_STEP, -1.0, 1.0)))


def fewest_steps_twist(rot: jax.Array) -> jax.Array:
    """TwistJug's parameter that makes a jug at rotation `rot` graspable (|rot| < PICK_JUG_ROT_TOL) in the
    fewest wrist steps; for a jug already graspable, meaningless.

    `twist_jug` turns the jug by a full WRIST_STEP toward the asked rotation while it is further than one
    step away, then lands on it. So k, the fewest steps that bring |rot| under the grasp's tolerance, is
    also the number the twist takes for any asked rotation (on rot's side of 0) from |rot| - k WRIST_STEP,
    where k full steps end, up to the tolerance. Ask for the middle of that interval, the rotation furthest
    from both ends, so that a float32 rounding can neither cost a step nor leave the jug ungraspable. The
    jug's 1.5 takes k = 1, to 0.88 (p = 0.42), where p = 0 takes two (to 0.71, then 0). The robot's wrist
    turns with the jug and stops at +-2pi; from the stuck planner's wrist of 0 (no skill but TwistJug turns
    it), less than |rot| of twist never meets that stop."""
    size, tolerance = jnp.abs(rot), world.PICK_JUG_ROT_TOL
    steps = jnp.floor((size - tolerance) / WRIST_STEP) + 1
    after_full_steps = size - steps * WRIST_STEP
    return jnp.sign(rot) * (after_full_steps + tolerance) / 2 / TWIST_RANGE


def pick_jug(state: State) -> jax.Array:
    """At the handle: close the fingers; in line with it in front: move onto it; above the approach
    point: descend to the handle's height; at the safe height: fly above the approach point; else rise."""
    robot, grip = state.robot[:3], world.handle(state)
    approach = grip.at[Y].add(-PICK_APPROACH)
    in_line = (grip[Y] > robot[Y]) & ((grip[X] - robot[X]) ** 2 + (grip[Z] - robot[Z]) ** 2 < NEAR)
    return _pick([
        (world.sq_dist(robot, grip) < NEAR, _only(FINGERS, -1.0)),
        (in_line, move_to(state, grip)),
        (world.sq_dist(robot[:2], approach[:2]) < NEAR, move_to(state, approach)),
        ((robot[Z] - SAFE_Z) ** 2 < NEAR, move_to(state, approach.at[Z].set(SAFE_Z))),
    ], move_to(state, robot.at[Z].set(SAFE_Z)))


def place_jug_in_machine(state: State) -> jax.Array:
    """Carry the jug onto the dispense point and open the fingers there; a jug at the table's height
    first goes up (so it is carried in the air)."""
    jug = world.jug_point(state)
    toward = move_to(state, state.robot[:3] + (world.DISPENSE - jug))
    return _pick([
        (world.sq_dist(jug, world.DISPENSE) < NEAR, _only(FINGERS, 1.0)),
        (jug[Z] > 0.0, toward),
    ], _only(Z, 1.0))


def turn_machine_on(state: State) -> jax.Array:
    """Go to the button's height, then push into the button."""
    at_height = (world.BUTTON[Z] - state.robot[Z]) ** 2 < BUTTON_HEIGHT_TOL
    return jnp.where(at_height, move_to(state, jnp.asarray(world.BUTTON)),
                     move_to(state, state.robot[:3].at[Z].set(world.BUTTON[Z])))


def pour(state: State, cup: jax.Array) -> jax.Array:
    """With the jug at the cup's pouring position: tilt it; above it: descend (levelling the jug); at the
    safe height: fly the jug above it; else rise (levelling)."""
    jug, target = world.jug_point(state), world.pour_positions(state.task)[cup]
    level = _tilt_toward(state, 0.0)
    carry_jug_to = lambda point: move_to(state, state.robot[:3] + (point - jug), level)
    return _pick([
        (world.sq_dist(jug, target) < NEAR, _only(TILT, _tilt_toward(state, POUR_TILT))),
        (world.sq_dist(jug[:2], target[:2]) < NEAR, carry_jug_to(target)),
        ((state.robot[Z] - SAFE_Z) ** 2 < NEAR, carry_jug_to(target.at[Z].set(jug[Z]))),
    ], move_to(state, state.robot[:3].at[Z].set(SAFE_Z), level))


def skill_action(state: State, call: SkillCall) -> jax.Array:
    actions = jnp.stack([move_to_twist_jug(state), twist_jug(state, call.param), pick_jug(state),
                         place_jug_in_machine(state), turn_machine_on(state), pour(state, call.slot)])
    return actions[call.skill]


def remember_call(state: State, next_state: State, call: SkillCall) -> State:
    """The authors' MoveToTwistJug and PickJug policies remember the state they last acted in (any
    execution, the planner's or the bridge's); acting again in an identical state sets the repeated flag
    (envs.md §4.6). `call` acted in `state`; returns `next_state` remembering it."""
    vec, memory = world.state_vector(state), state.memory
    pick, twist = call.skill == PICK_JUG, call.skill == MOVE_TO_TWIST_JUG
    seen = jnp.where(pick, memory.pick_seen, memory.twist_seen)
    repeated = (pick | twist) & jnp.all(vec == seen)
    return next_state.replace(memory=SkillMemory(
        repeated=next_state.memory.repeated | repeated,
        pick_seen=jnp.where(pick, vec, memory.pick_seen), twist_seen=jnp.where(twist, vec, memory.twist_seen)))


def skill_done(prev_state: State, state: State, call: SkillCall, repeat_flag: bool = False) -> jax.Array:
    """Each skill's own termination (envs.md §4.6), or a step that changed nothing. With the authors'
    `repeat_flag`, MoveToTwistJug and PickJug end by their flag instead of by a step without progress."""
    reached = jnp.stack([
        world.twisting(state),  # MoveToTwistJug
        world.hand_empty(state),  # TwistJug
        state.jug_held,  # PickJug
        ~state.jug_held & world.jug_in_machine(state),  # PlaceJugInMachine
        state.machine_on,  # TurnMachineOn
        world.cup_filled(state)[call.slot],  # Pour
    ])[call.skill]
    no_progress = jnp.all(world.state_vector(prev_state) == world.state_vector(state))
    if repeat_flag:
        remembering = (call.skill == MOVE_TO_TWIST_JUG) | (call.skill == PICK_JUG)
        return reached | jnp.where(remembering, state.memory.repeated, no_progress)
    return reached | no_progress
