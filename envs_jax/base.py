"""The env contract: what the meta-policy, the learner, the planner and the renderer use of an env.

An env is a frozen dataclass holding only its capacity (max cells, rooms, cups...), which fixes every
array shape, so it is hashable and a static argument of `jax.jit`; everything that changes is in pytrees.
Subclass `NoveltyEnv`, implement its abstract methods and set its class attributes; `jaxbridge.check_env`
checks an env against this contract (docs/NEW_ENV.md walks through one).

Skills are parameterised options. A ground skill is (skill id, slot, param): the slot picks the object
the skill acts on (MoveRobot's target cell, MoveToDoor's door), the param is its continuous argument,
drawn from the skill's sampler: uniform in [param_low, param_high] (equal bounds = a constant).
"""
from __future__ import annotations

import abc
import dataclasses
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Hashable, Protocol

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


POSITION_DIM = 3  # an object's position: (x, y, z), unused axes zero


@struct.dataclass
class Objects:
    """The paper's object-oriented view of a state: one row per object slot, slot 0 the robot.

    Features are the object's type's own (`NoveltyEnv.object_types` names them), padded with zeros to the
    widest type's; a slot of the capacity that the task does not fill is masked out, all zeros."""

    type_id: jax.Array  # int32[N]: index into object_types
    features: jax.Array  # float32[N, W]
    mask: jax.Array  # bool[N]: a real object of the task
    interactable: jax.Array  # bool[N]: a skill can act on it (the paper's candidates for feature selection)
    position: jax.Array  # float32[N, 3]: where the robot would act on it, for distances

    @staticmethod
    def of_type(type_id: int, features: jax.Array, mask: jax.Array, interactable: jax.Array | bool,
                position: jax.Array, width: int) -> "Objects":
        """Rows of one type: features float32[n, k] (k <= width), position float32[n, p] (p <= 3);
        masked-out rows are zeroed."""
        n, k = features.shape
        mask = jnp.broadcast_to(jnp.asarray(mask, bool), (n,))
        zeroed = lambda x, size: jnp.where(mask[:, None], jnp.pad(x.astype(jnp.float32), ((0, 0), (0, size - x.shape[1]))), 0.0)
        return Objects(type_id=jnp.full(n, type_id, jnp.int32), features=zeroed(features, width), mask=mask,
                       interactable=mask & jnp.asarray(interactable, bool), position=zeroed(position, POSITION_DIM))

    @staticmethod
    def concat(*groups: "Objects") -> "Objects":
        return jax.tree.map(lambda *xs: jnp.concatenate(xs), *groups)


@struct.dataclass
class BridgeAction:
    """A bridge's choice: a skill (num_skills = CallPlanner) and its continuous parameter; a low-level
    bridge (Controls.low_level) gives the env's raw action instead of a skill, or CallPlanner."""

    skill: jax.Array  # int32
    param: jax.Array  # float32
    action: jax.Array | None = None  # float32[A]: a low-level bridge's raw action


@dataclass(frozen=True)
class NoveltySweep:
    """An env's generalisation sweep (`eval.py RUN --sweep novelties`): tasks with more and more novelty
    instances, beyond what the bridge trained and was tested on."""

    counted: str  # what the x axis counts, e.g. "doors to the goal"
    setting: str  # the rest of the tasks, e.g. "on 7x7 maps"
    counts: tuple[int, ...]
    task: Callable[[np.random.Generator, int], Any]  # a task spec with k of them
    horizon: Callable[[Any], int]  # the spec's horizon, by the env's rule


@dataclass(frozen=True)
class NoveltyPredicate:
    """A fact about the novelty that a perception system would report and the planner's model leaves out,
    in the model learner's terms (`NoveltyEnv.novelty_predicates`): on each object of `type`, its feature
    `feature` above `threshold` (below it or equal: `above=False`); with `other`, the distance between
    `feature` and that other feature of the object instead (a band: within it is `above=False`); with
    `when`, a flag feature of the object (0 or 1), the predicate reads "flag implies this": it holds
    wherever the flag is off, too (a keycard door has its card held)."""

    type: str
    feature: str
    threshold: float = 0.5  # a flag's (0 or 1)
    above: bool = True
    other: str | None = None
    when: str | None = None


def named_slots(names, capacity: int) -> tuple[str | None, ...]:
    """`names` in the first slots of a type's `capacity`, None in the rest (`object_names`' padding)."""
    names = tuple(names)
    return names + (None,) * (capacity - len(names))


def idle_call() -> SkillCall:
    return SkillCall(skill=jnp.int32(0), slot=jnp.int32(0), param=jnp.float32(0.0),
                     running=jnp.bool_(False), steps=jnp.int32(0))


def tree_where(cond: jax.Array, a: Any, b: Any) -> Any:
    """Branch-free select between two pytrees of the same structure."""
    return jax.tree.map(lambda x, y: jnp.where(cond, x, y), a, b)


def stack_trees(trees: list[Any]) -> Any:
    """Stack pytrees of numpy/jax leaves on a new leading axis (device arrays)."""
    return jax.tree.map(lambda *xs: jax.device_put(np.stack(xs)), *trees)


class TaskSpec(Protocol, Hashable):
    """A host-side task description (a frozen dataclass): hashable, so equal specs share a compilation."""

    @property
    def horizon(self) -> int:
        """Env steps a test episode of this task may take."""

    @property
    def min_steps(self) -> int:
        """No action sequence reaches the goal in fewer env steps (train.py refuses shorter horizons)."""

    def describe(self) -> str:
        """The task's size in words, e.g. "11 cells, 3 doors"."""


class NoveltyEnv(abc.ABC):
    """Base class of every env. Shapes below: B batch, D = len(state_vector), F = num_features,
    S = full_state_size, A = action_dim, K = num_skills; one unbatched state unless said otherwise.

    Class attributes an env sets:
      name: str                          the short name (`--env`, run files)
      skills: tuple[SkillSpec, ...]      the skills, in skill-id order; id K is CallPlanner
      action_dim: int                    A, the low-level action's length
      num_features: int                  F, the bridge's object-centric observation
      full_state_size: int               S, the "no feature selection" observation (padded)
      domain: planner.Domain             the planner's lifted model, which omits the novelty
      object_types: dict[str, tuple]     the object view's types, "robot" first: type name -> feature names
    """

    name: ClassVar[str]
    skills: ClassVar[tuple[SkillSpec, ...]]
    action_dim: ClassVar[int]
    num_features: ClassVar[int]
    full_state_size: ClassVar[int]
    domain: ClassVar[Any]
    # Training hyperparameters where this env departs from TrainConfig's defaults (jaxbridge.make_config).
    train_defaults: ClassVar[dict] = {}
    # How `eval.py RUN --sweep novelties` grows this env's tasks (None: no sweep).
    novelty_sweep: ClassVar[NoveltySweep | None] = None
    # The approaches train.py runs when none are named: the paper's figure for this env (None: all six),
    # and why the others are left out of it.
    default_approaches: ClassVar[tuple[str, ...] | None] = None
    why_not_all: ClassVar[str] = ""
    # The failure signatures (stalled planner skill, object type) the env's novelties stall at: a bridge per
    # signature has a network for each and one for every other (None: one for every pair; jaxbridge/core/signatures.py).
    failure_signatures: ClassVar[tuple[tuple[str, str], ...] | None] = None
    # The sizes `sized_task` takes (name -> what it counts), e.g. {"cells": ..., "doors": ...}.
    task_sizes: ClassVar[dict[str, str]] = {}
    # The test-task distributions `test_tasks` draws (name -> what it is), the first the default; an env
    # with more than one takes `protocol=` in test_tasks (e.g. "authors": the authors' logged runs).
    test_protocols: ClassVar[dict[str, str]] = {"jaxbridge": "the env's test tasks"}
    # Training hyperparameters of the authors' code where this env's differ from the common ones
    # (jaxbridge/core/presets.py, `train.py --preset authors`).
    authors_defaults: ClassVar[dict] = {}
    # Behaviours of the authors' env that this one departs from but can switch back on (name -> what it
    # does); each is a bool field of the env's dataclass, off by default (`with_quirks`).
    quirks: ClassVar[dict[str, str]] = {}
    # The novelty's facts a perception system would report (its planner model still leaves them out): the
    # model learner's predicates in its *given* setting (`learn_model(..., given=True)`), the upper bound
    # of the predicates it invents; () declares none.
    novelty_predicates: ClassVar[tuple[NoveltyPredicate, ...]] = ()

    # ---- host: tasks and the planner's model -------------------------------------------------------
    @staticmethod
    @abc.abstractmethod
    def train_task(seed: int) -> TaskSpec:
        """The seed's training task (numpy RNG seeded by `seed`)."""

    @classmethod
    def train_tasks(cls, seed: int, episodes: int) -> list[TaskSpec]:
        """The training task of each of a cycle's `episodes` episodes, the same in every cycle:
        `train_task(seed)` for each by default; an env overrides it to show what one task cannot (Multi
        Novelty: a latched door's stiffness spread over its range)."""
        return [cls.train_task(seed)] * episodes

    @staticmethod
    @abc.abstractmethod
    def test_tasks(seed: int, num_tasks: int = 10) -> list[TaskSpec]:
        """The seed's test tasks (an env with several `test_protocols` also takes `protocol=NAME`)."""

    @classmethod
    @abc.abstractmethod
    def for_tasks(cls, specs: list[TaskSpec]) -> "NoveltyEnv":
        """The env at the smallest capacity that holds every spec."""

    @classmethod
    def sized_task(cls, rng: np.random.Generator, **sizes: int) -> TaskSpec:
        """A task of the sizes named in `task_sizes` (`eval.py RUN --task-size name=N,...`); ValueError
        for sizes it cannot build."""
        raise ValueError(f"env {cls.name!r} builds no tasks of a chosen size")

    @abc.abstractmethod
    def task_arrays(self, spec: TaskSpec) -> Any:
        """The spec padded to this env's capacity: the env's Task struct of numpy arrays."""

    @abc.abstractmethod
    def planner_problem(self, spec: TaskSpec) -> Any:
        """The planner's STRIPS problem (planner.Problem over `domain`) for the spec."""

    def plan_bound(self, spec: TaskSpec) -> tuple[int, int] | None:
        """Upper bounds (abstract states the planner's model reaches from the spec's start, its ground
        operators) when the env knows them without grounding; lets eval.py refuse a task whose plan table
        cannot fit before building it. None: the estimate grounds one task to count them."""
        return None

    @property
    @abc.abstractmethod
    def num_atoms(self) -> int:
        """N: fluent ground atoms of the abstract state, in a fixed layout (`abstract`, `atom_index`)."""

    @abc.abstractmethod
    def atom_index(self, atom: tuple[str, ...]) -> int:
        """The position in [0, N) of a fluent ground atom, e.g. ("RobotInCell", "robby", "cell3")."""

    @abc.abstractmethod
    def object_slot(self, name: str) -> int:
        """The slot (int) of a named object a skill may act on, e.g. "cell3" -> 3."""

    # ---- device: dynamics, pure and vmappable ------------------------------------------------------
    @abc.abstractmethod
    def reset(self, task: Any) -> Any:
        """The initial State (a flax struct holding its task) of one padded Task."""

    @abc.abstractmethod
    def step(self, state: Any, action: jax.Array) -> Any:
        """The State after the float32[A] action."""

    @abc.abstractmethod
    def abstract(self, state: Any) -> jax.Array:
        """bool[N]: which fluent atoms hold (the planner's view of the state)."""

    @abc.abstractmethod
    def goal_reached(self, state: Any) -> jax.Array:
        """bool[]: the task's goal holds."""

    @abc.abstractmethod
    def state_vector(self, state: Any) -> jax.Array:
        """float32[D]: the low-level state, for "did anything change" (stuck detection, CanPlan)."""

    # ---- device: what the bridge sees --------------------------------------------------------------
    @abc.abstractmethod
    def features(self, state: Any, stuck_state: Any) -> jax.Array:
        """float32[F]: the bridge's object-centric observation (`stuck_state`: where the bridge took over)."""

    @abc.abstractmethod
    def full_state(self, state: Any) -> jax.Array:
        """float32[S]: every object's raw features, padded (the "no feature selection" observation)."""

    # The paper's state: a set of typed objects with real-valued features (`Objects`). Type ids index
    # `object_types` ({type name: its feature names}, "robot" first); the robot is slot 0.
    object_types: ClassVar[dict[str, tuple[str, ...]]] = {}

    @property
    def num_objects(self) -> int:
        """N, the object slots of this env's capacity."""
        raise NotImplementedError(f"{type(self).__name__} has no object view (object_types, objects)")

    @property
    def object_width(self) -> int:
        """W, the widest type's feature count: every object's features are padded to it."""
        return max(len(names) for names in self.object_types.values())

    def objects(self, state: Any) -> Objects:
        """The state as objects: N slots, each with its type, features, mask, interactability, position.
        A feature says what an object is (a key's turn, a cup's liquid); where it is, is its position."""
        raise NotImplementedError(f"{type(self).__name__} has no object view (object_types, objects)")

    def object_names(self, spec: TaskSpec) -> tuple[str | None, ...]:
        """The planner object each object-view slot is in the task `spec` (N entries, slot order): a name of
        `planner_problem(spec).objects` of the slot's type, a new name for an object the planner's model
        leaves out (a novelty's doors, cards, closets), None for a slot the task does not fill. A model
        learner reads states through it (`check_env` checks names, types and masks agree)."""
        raise NotImplementedError(f"{type(self).__name__} names no planner objects for its object view (object_names)")

    @property
    def candidate_slots(self) -> np.ndarray:
        """int[C]: the slots that can ever be interactable, ascending (static: the learned selector's
        tokens are the robot's and these; `check_env` checks no other slot is ever interactable).
        Default: every slot but the robot's."""
        return np.arange(1, self.num_objects)

    def oracle_object(self, state: Any) -> jax.Array:
        """int32[]: the slot of the object the novelty's fix acts on in this state (the oracle's), -1 if
        none; what a learned selector's attention is measured against (eval.py --attention)."""
        raise NotImplementedError(f"{type(self).__name__} does not say which object its fix acts on")

    @property
    def full_state_varying(self) -> np.ndarray:
        """int[V]: the positions of `full_state` that can change within a task, ascending; every other
        entry is fixed by the task (walls, poses, targets, padding). The learners then store only these
        and multiply the task's constants once per task (`check_env` checks the rest stay put).
        Default: all of them."""
        return np.arange(self.full_state_size)

    @property
    def full_state_filled(self) -> np.ndarray:
        """int[U]: the positions of `full_state` that a task of this env's capacity can fill, ascending; the
        others pad it for larger tasks and are zero in all its states (Doorknobs: the slots of a 5x5 map
        beyond a 2x2 one). A learner's fit on this env's tasks leaves their weights out, as no gradient
        reaches them (`check_env` checks a training task leaves them zero). Default: all of them."""
        return np.arange(self.full_state_size)

    @property
    def full_state_fits(self) -> bool:
        """Whether `full_state` can hold every object of this env's capacity (S is fixed by the largest
        test task, so larger sweep tasks are beyond the full-state ablations' input)."""
        return True

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """float32[A] low and high: the box the low-level baselines act in (every skill's action lies in
        it); where the authors' action space is unbounded, the range past which an action changes nothing
        more. Optional: an env without it has no low-level baselines."""
        raise NotImplementedError(f"env {self.name!r} states no action bounds (the low-level baselines need them)")

    # ---- device: skills ----------------------------------------------------------------------------
    @abc.abstractmethod
    def skill_action(self, state: Any, call: SkillCall) -> jax.Array:
        """float32[A]: the running ground skill's next action."""

    @abc.abstractmethod
    def skill_done(self, prev_state: Any, state: Any, call: SkillCall) -> jax.Array:
        """bool[]: the skill has terminated after the step prev_state -> state."""

    def skill_initiable(self, state, skill: jax.Array, slot: jax.Array) -> jax.Array:
        """bool[...]: ground skills (broadcast shapes) that can start in `state`. Preconditions are
        checked by the planner model; envs whose skills need more (a motion plan) override this."""
        return jnp.ones(jnp.broadcast_shapes(skill.shape, slot.shape), bool)

    @classmethod
    def check_quirks(cls, names) -> None:
        """ValueError naming the first of `names` that is not one of this env's `quirks`."""
        unknown = [n for n in names if n not in cls.quirks]
        if unknown:
            known = ", ".join(f"{k} ({v})" for k, v in cls.quirks.items()) or "none"
            raise ValueError(f"env {cls.name!r} has no quirk {unknown[0]!r} (its quirks: {known})")

    def with_quirks(self, names) -> "NoveltyEnv":
        """This env with the named `quirks` switched on; ValueError for a name it does not have."""
        self.check_quirks(names)
        return dataclasses.replace(self, **{n: True for n in names}) if names else self

    # ---- optional hooks ----------------------------------------------------------------------------
    def after_skill_step(self, state: Any, next_state: Any, call: SkillCall) -> Any:
        """`next_state` after the running skill's policy acted in `state` (not called on CallPlanner's
        no-op): where an env remembers something about its skills' calls. Default: nothing."""
        return next_state

    def share_between_episodes(self, states: Any, groups: jax.Array) -> Any:
        """A batch of states after a step, where episodes of the same group (int[B]: one seed's concurrent
        episodes) share something outside any one episode. Default: nothing is shared."""
        return states

    def oracle_bridge(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        """A hand-written bridge that fixes the novelty (tests, `eval.py --bridge oracle`); optional."""
        raise NotImplementedError(f"env {self.name!r} has no oracle bridge")

    @property
    def has_oracle(self) -> bool:
        return type(self).oracle_bridge is not NoveltyEnv.oracle_bridge

    def drawer(self):
        """The env's episode drawer (an envs_jax.drawing.Drawer), or None if it draws nothing."""
        return None

    # ---- derived: skill bookkeeping ----------------------------------------------------------------
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
        """float32[*shape, K]: one draw from every skill's parameter sampler."""
        u = jax.random.uniform(key, shape + (self.num_skills,))
        return self.param_from_uniform(jnp.arange(self.num_skills), u)

    def stack_tasks(self, specs: list) -> Any:
        """The specs' Task structs stacked on a leading axis (device arrays)."""
        return stack_trees([self.task_arrays(s) for s in specs])
