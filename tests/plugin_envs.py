"""Envs that break the contract in one way each (tests/test_env_contract.py, also loaded by train.py)."""
import jax.numpy as jnp
import numpy as np

from examples.locked_box import LockedBox


class ShortFeatures(LockedBox):
    def features(self, state, stuck_state):
        return super().features(state, stuck_state)[:2]


class CountingStep(LockedBox):
    """step() depends on how often it was traced: hidden Python state."""
    calls = [0]

    def step(self, state, action):
        CountingStep.calls[0] += 1
        return super().step(state, action).replace(robot_x=state.robot_x + 0.01 * CountingStep.calls[0])


class WrongAbstraction(LockedBox):
    def abstract(self, state):
        return ~super().abstract(state)


class ClumsyOracle(LockedBox):
    def oracle_bridge(self, params, obs, key):
        return super().oracle_bridge(params, obs, key).replace(param=jnp.float32(0.9))  # misses the grip


class FloatGoal(LockedBox):
    def goal_reached(self, state):
        return state.box_open.astype(jnp.float32)


class SmallPlanBound(LockedBox):
    """Claims a plan table smaller than its planner builds (memory estimates would be too low)."""
    def plan_bound(self, spec):
        return 1, 1



class StillRobot(LockedBox):
    """Claims its robot never moves (a learner would treat its position as the task's constant)."""
    @property
    def full_state_varying(self):
        return super().full_state_varying[1:]


class EmptyBox(LockedBox):
    """Claims its tasks never fill the box's position (a learner would leave its weights out of the fit)."""
    @property
    def full_state_filled(self):
        return super().full_state_filled[:-1]


class NeverHolds(LockedBox):
    """Claims its tasks never fill `holding`, which is zero at the start and set once the key is picked up."""
    @property
    def full_state_filled(self):
        return np.delete(super().full_state_filled, 1)


NotAnEnv = object


class LeakyObjects(LockedBox):
    """An object the view masks out still carries features."""

    def objects(self, state):
        objects = super().objects(state)
        return objects.replace(mask=objects.mask.at[2].set(False))


class MisnamedKey(LockedBox):
    """The key is named after a planner object of another type (a cell)."""

    def object_names(self, spec):
        return ("robby", "cell0", "box")


class HiddenCandidate(LockedBox):
    """The box can be acted on, but its slot is left out of candidate_slots (a learned selector's tokens)."""

    candidate_slots = property(lambda self: np.array([1]))
