"""The environment interface shared by Light Switch Door, Doorknobs and Coffee.

An environment is a frozen (hashable) object holding only static configuration, chiefly the padded
capacity (max cells, rooms, cups...) that fixes every array shape, so it can be a static argument of
`jax.jit`. Everything that changes is in pytrees:

* host: `train_task(seed)`, `test_tasks(seed, n)` draw task specs with numpy from the seed;
  `task_arrays(spec)` pads one spec into the env's `Task` struct; `planner_problem(spec)` states the
  planner's STRIPS problem (which omits the novelty).
* device, pure and vmappable: `reset(task) -> State`, `step(state, action) -> State`,
  `abstract(state) -> bool[num_atoms]` (fluent atoms in a fixed layout), `goal_reached(state)`,
  `state_vector(state)` (the low-level state, for "did anything change"), `features(state, stuck_state)`
  (the bridge's object-centric observation), `full_state(state)` (every object's raw features padded
  to `full_state_size`, the "no feature selection" observation), and the skills: `skill_action(state, call)`,
  `skill_done(prev_state, state, call)`, `skill_initiable(state)`.

Skills are parameterised options. A ground skill is (skill id, slot, param): the slot picks the object
the skill acts on (MoveRobot's target cell, MoveToDoor's door), the param is its continuous argument,
drawn from the skill's sampler: uniform in [param_low, param_high] (equal bounds = a constant).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct


# Who produced a step's action, as the meta-policy records it (traces, drawings).
ACTOR_PLANNER, ACTOR_BRIDGE, ACTOR_CALL_PLANNER = 0, 1, 2


@dataclass(frozen=True)
class SkillSpec:
    name: str
    param_low: float = 0.0  # the NSRT sampler: uniform in [low, high]; low == high is a constant
    param_high: float = 0.0


@struct.dataclass
class SkillCall:
    """A ground skill being executed, with what a closed-loop skill may need to remember."""

    skill: jax.Array  # int32
    slot: jax.Array  # int32
    param: jax.Array  # float32
    running: jax.Array  # bool: started and not yet terminated
    steps: jax.Array  # int32: env steps taken so far by this call


@struct.dataclass
class BridgeObs:
    """What a bridge policy sees when it must choose."""

    features: jax.Array  # float32[num_features]: the env's object-centric features
    num_ground: jax.Array  # int32[num_skills + 1]: applicable ground instances per skill, CallPlanner last


@struct.dataclass
class BridgeAction:
    """A bridge's choice: a skill (num_skills = CallPlanner) and its continuous parameter."""

    skill: jax.Array  # int32
    param: jax.Array  # float32


@dataclass(frozen=True)
class NoveltySweep:
    """An env's generalisation sweep (`eval.py RUN --sweep novelties`): tasks with more and more novelty
    instances, beyond what the bridge trained and was tested on."""

    counted: str  # what the x axis counts, e.g. "doors to the goal"
    setting: str  # the rest of the tasks, e.g. "on 7x7 maps"
    counts: tuple[int, ...]
    task: Callable[[np.random.Generator, int], Any]  # a task spec with k of them
    horizon: Callable[[Any], int]  # the spec's horizon, by the env's rule


def idle_call() -> SkillCall:
    return SkillCall(skill=jnp.int32(0), slot=jnp.int32(0), param=jnp.float32(0.0),
                     running=jnp.bool_(False), steps=jnp.int32(0))


def tree_where(cond: jax.Array, a: Any, b: Any) -> Any:
    """Branch-free select between two pytrees of the same structure."""
    return jax.tree.map(lambda x, y: jnp.where(cond, x, y), a, b)


def stack_trees(trees: list[Any]) -> Any:
    """Stack pytrees of numpy/jax leaves on a new leading axis (device arrays)."""
    return jax.tree.map(lambda *xs: jnp.asarray(np.stack(xs)), *trees)


class NoveltyEnv:
    """Base class: shared skill bookkeeping. Subclasses are frozen dataclasses (see module doc)."""

    name: ClassVar[str]
    skills: ClassVar[tuple[SkillSpec, ...]]
    action_dim: ClassVar[int]
    num_features: ClassVar[int]
    full_state_size: ClassVar[int]
    # Training hyperparameters where this env departs from the paper-wide defaults (TrainConfig.for_env).
    train_defaults: ClassVar[dict] = {}
    # How eval.py's generalisation sweep grows this env's tasks.
    novelty_sweep: ClassVar[NoveltySweep]
    # The approaches train.py runs when none are named (None: all six) and why not all.
    default_approaches: ClassVar[tuple[str, ...] | None] = None
    why_not_all: ClassVar[str] = ""

    # ---- skills ---------------------------------------------------------------------------------
    @property
    def num_skills(self) -> int:
        return len(self.skills)

    @property
    def skill_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.skills)

    def skill_index(self, name: str) -> int:
        return self.skill_names.index(name)

    def param_from_uniform(self, skill: jax.Array, u: jax.Array) -> jax.Array:
        """Skill `skill`'s parameter sampler applied to a uniform draw u in [0, 1)."""
        low = jnp.array([s.param_low for s in self.skills], jnp.float32)
        high = jnp.array([s.param_high for s in self.skills], jnp.float32)
        return low[skill] + (high[skill] - low[skill]) * u

    def sample_params(self, key: jax.Array, shape: tuple[int, ...] = ()) -> jax.Array:
        """float32[*shape, num_skills]: one draw from every skill's parameter sampler."""
        u = jax.random.uniform(key, shape + (self.num_skills,))
        return self.param_from_uniform(jnp.arange(self.num_skills), u)

    def skill_initiable(self, state, skill: jax.Array, slot: jax.Array) -> jax.Array:
        """bool[...]: ground skills (broadcast shapes) that can start in `state`. Preconditions are
        checked by the planner model; envs whose skills need more (a motion plan) override this."""
        return jnp.ones(jnp.broadcast_shapes(skill.shape, slot.shape), bool)

    @property
    def full_state_fits(self) -> bool:
        """Whether `full_state` can hold every object of this env's capacity: its size is fixed by the
        largest test task, so larger (sweep) tasks are beyond the full-state ablations' input."""
        return True

    # ---- tasks ------------------------------------------------------------------------------------
    def stack_tasks(self, specs: list) -> Any:
        return stack_trees([self.task_arrays(s) for s in specs])
