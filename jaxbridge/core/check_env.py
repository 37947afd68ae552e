"""`check_env`: does an env keep the contract of envs_jax/base.py?

It builds tasks and checks, in order: the class attributes; the host side (task specs, capacities, task
arrays); the planner's model (it grounds, its plan tables build, the abstraction of the initial state is
the model's initial state); every device function (pure: jit, vmap and a second call give the same
values; the declared shapes and dtypes); that a training task's states set no entry beyond
`full_state_filled`; and, when the env has an oracle bridge, that it solves its own test tasks through the
meta-policy. The first broken promise raises `EnvContractError`, one line naming the method and what was
expected.
"""
from __future__ import annotations

from typing import Any, Callable

import chex
import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import POSITION_DIM, NoveltyEnv, NoveltyPredicate, SkillCall, SkillSpec, stack_trees
from jaxbridge.core.bridges import OracleBridge, RandomBridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import evaluation_batch, make_batch
from planner.strips import Domain, Problem
from planner.tables import compile_task, pack_atoms


class EnvContractError(ValueError):
    """An env breaks the contract; the message names the method and what was expected."""


def check_env(env_or_class: NoveltyEnv | type[NoveltyEnv], seed: int = 0, num_test_tasks: int = 2,
              oracle: bool = True) -> type[NoveltyEnv]:
    """Check an env class (or an instance's class) against the contract; returns the class.

    `seed` and `num_test_tasks` pick the tasks checked; `oracle=False` skips the oracle's rollout."""
    cls = env_or_class if isinstance(env_or_class, type) else type(env_or_class)
    _check_class(cls)
    train_spec, test_specs = _check_specs(cls, seed, num_test_tasks)
    env = cls.for_tasks([train_spec, *test_specs])
    _expect(isinstance(env, cls), f"{cls.__name__}.for_tasks", f"an instance of {cls.__name__}", type(env).__name__)
    _expect(env == cls.for_tasks([train_spec, *test_specs]) and hash(env) == hash(cls.for_tasks([train_spec, *test_specs])),
            f"{cls.__name__}.for_tasks", "equal, hashable envs for equal specs (a frozen dataclass)", "unequal ones")
    for spec in (train_spec, *test_specs):
        _check_planner(env, spec)
    _check_device(env, [env.task_arrays(s) for s in (train_spec, *test_specs[:1])])
    if cls.object_types:
        for spec in (train_spec, *test_specs):
            _check_object_names(env, spec)
    _check_filled(cls, train_spec, seed)
    if oracle and env.has_oracle:
        _check_oracle(cls, seed, num_test_tasks)
    return cls


def _expect(ok: bool, where: str, expected: str, got: Any) -> None:
    if not ok:
        raise EnvContractError(f"{where}: expected {expected}, got {got}")


def _calls(where: str, fn: Callable, *args) -> Any:
    """fn(*args), with any exception reported as a contract error of `where`."""
    try:
        return fn(*args)
    except EnvContractError:
        raise
    except Exception as err:  # noqa: BLE001 -- whatever an env raises is reported, in one line
        raise EnvContractError(f"{where} raised {type(err).__name__}: {err}") from None


# ---- the class ---------------------------------------------------------------------------------------
def _check_class(cls: type) -> None:
    _expect(isinstance(cls, type) and issubclass(cls, NoveltyEnv), "env", "a subclass of envs_jax.NoveltyEnv", cls)
    name = cls.__name__
    missing = sorted(getattr(cls, "__abstractmethods__", ()))
    _expect(not missing, name, "every abstract method of NoveltyEnv implemented", f"missing {', '.join(missing)}")
    for attr, kind in (("name", str), ("action_dim", int), ("num_features", int), ("full_state_size", int)):
        value = getattr(cls, attr, None)
        _expect(isinstance(value, kind) and (kind is str or value > 0) and bool(value), f"{name}.{attr}",
                f"a {'non-empty string' if kind is str else 'positive int'}", repr(value))
    skills = getattr(cls, "skills", None)
    _expect(isinstance(skills, tuple) and skills and all(isinstance(s, SkillSpec) for s in skills),
            f"{name}.skills", "a non-empty tuple of SkillSpec", repr(skills))
    for s in skills:
        _expect(s.param_low <= s.param_high, f"{name}.skills[{s.name}]", "param_low <= param_high",
                f"{s.param_low} > {s.param_high}")
    domain = getattr(cls, "domain", None)
    _expect(isinstance(domain, Domain), f"{name}.domain", "a planner.Domain", type(domain).__name__)
    names = {s.name for s in skills}
    for op in domain.operators:
        _expect(op.skill in names, f"{name}.domain operator {op.name}", f"a skill among {sorted(names)}", repr(op.skill))
    types = getattr(cls, "object_types", None)
    _expect(isinstance(types, dict) and list(types)[:1] == ["robot"] and all(
        isinstance(f, tuple) and all(isinstance(n, str) for n in f) for f in types.values()),
        f"{name}.object_types", "the object view's types, the robot's first: {type name: (feature name, ...)}",
        repr(types))
    _check_novelty_predicates(cls, types)


def _check_novelty_predicates(cls: type, types: dict[str, tuple]) -> None:
    """Each declared novelty predicate reads features its type has (the model learner's given setting)."""
    for p in getattr(cls, "novelty_predicates", ()):
        named = {p.feature, p.other, p.when} - {None} if isinstance(p, NoveltyPredicate) else {None}
        _expect(isinstance(p, NoveltyPredicate) and named <= set(types.get(p.type, ())), f"{cls.__name__}.novelty_predicates",
                "NoveltyPredicates on features of their type in object_types", repr(p))


def _check_specs(cls: type[NoveltyEnv], seed: int, num_test_tasks: int) -> tuple[Any, list]:
    name = cls.__name__
    train_spec = _calls(f"{name}.train_task", cls.train_task, seed)
    tests = _calls(f"{name}.test_tasks", cls.test_tasks, seed, num_test_tasks)
    _expect(isinstance(tests, list) and len(tests) == num_test_tasks, f"{name}.test_tasks({seed}, {num_test_tasks})",
            f"a list of {num_test_tasks} specs", repr(tests)[:80])
    _expect(train_spec == cls.train_task(seed) and tests == cls.test_tasks(seed, num_test_tasks),
            f"{name}.train_task/test_tasks", "the same specs for the same seed", "different ones")
    episodes = _calls(f"{name}.train_tasks", cls.train_tasks, seed, 3)
    _expect(isinstance(episodes, list) and len(episodes) == 3 and episodes == cls.train_tasks(seed, 3),
            f"{name}.train_tasks({seed}, 3)", "a list of 3 specs, the same for the same seed", repr(episodes)[:80])
    for spec in (train_spec, *episodes, *tests):
        _calls(f"{name} task spec {spec!r:.60}: hash", hash, spec)
        for attr in ("horizon", "min_steps"):
            value = getattr(spec, attr, None)
            _expect(isinstance(value, (int, np.integer)) and value > 0, f"{name} task spec .{attr}",
                    "a positive int", repr(value))
        _expect(isinstance(_calls(f"{name} task spec .describe", spec.describe), str), f"{name} task spec .describe()",
                "a string", "something else")
    return train_spec, tests


# ---- the planner's model -----------------------------------------------------------------------------
def _check_planner(env: NoveltyEnv, spec: Any) -> None:
    name = type(env).__name__
    problem = _calls(f"{name}.planner_problem", env.planner_problem, spec)
    _expect(isinstance(problem, Problem), f"{name}.planner_problem", "a planner.Problem", type(problem).__name__)
    for atom in sorted(problem.init | problem.goal):
        index = _calls(f"{name}.atom_index({atom})", env.atom_index, atom)
        _expect(isinstance(index, (int, np.integer)) and 0 <= index < env.num_atoms, f"{name}.atom_index({atom})",
                f"an int in [0, num_atoms = {env.num_atoms})", repr(index))
    compiled = _calls(f"{name}: grounding the planner's model and building its plan table", compile_task, env, spec)
    bound = _calls(f"{name}.plan_bound", env.plan_bound, spec)
    if bound is not None:
        reached = (compiled.num_reachable, len(compiled.ground_ops))
        _expect(len(bound) == 2 and all(b >= r for b, r in zip(bound, reached)), f"{name}.plan_bound",
                f"(states, operators) at least the {reached} the planner found", repr(bound))
    initial = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))
    packed = np.asarray(pack_atoms(_calls(f"{name}.abstract", env.abstract, initial)))
    expected = np.asarray(compiled.table.state_keys[0])  # row 0: the model's initial state
    _expect(np.array_equal(packed, expected), f"{name}.abstract(reset(task))",
            "the atoms of planner_problem(spec).init (abstraction and model disagree)", "other atoms")


# ---- device functions ----------------------------------------------------------------------------------
def _check_device(env: NoveltyEnv, task_arrays: list) -> None:
    """Shapes, dtypes and purity of every device function, on one task and on a batch of two."""
    name = type(env).__name__
    tasks = stack_trees(task_arrays)
    task = jax.tree.map(lambda x: x[0], tasks)
    state = _calls(f"{name}.reset", jax.jit(env.reset), task)
    _traced_alike(f"{name}.reset", env.reset, task)
    vec = _shape(f"{name}.state_vector", _calls(f"{name}.state_vector", jax.eval_shape, env.state_vector, state),
                 jnp.float32)
    zero = jnp.zeros(env.action_dim, jnp.float32)
    stepped = _calls(f"{name}.step", jax.eval_shape, env.step, state, zero)
    _calls(f"{name}.step: the state's structure, shapes and dtypes", chex.assert_trees_all_equal_shapes_and_dtypes,
           stepped, jax.eval_shape(lambda s: s, state))
    skill_ids, slots = jnp.arange(env.num_skills, dtype=jnp.int32), jnp.zeros(env.num_skills, jnp.int32)
    calls = SkillCall(skill=skill_ids, slot=slots, param=jnp.zeros(env.num_skills, jnp.float32),
                      running=jnp.ones(env.num_skills, bool), steps=jnp.zeros(env.num_skills, jnp.int32))
    one_call = jax.tree.map(lambda x: x[0], calls)
    functions = {  # name -> (function of one state, expected shape, dtype)
        "abstract": (env.abstract, (env.num_atoms,), jnp.bool_),
        "goal_reached": (env.goal_reached, (), jnp.bool_),
        "state_vector": (env.state_vector, vec.shape, jnp.float32),
        "step": (lambda s: env.state_vector(env.step(s, env.skill_action(s, one_call))), vec.shape, jnp.float32),
        "features": (lambda s: env.features(s, s), (env.num_features,), jnp.float32),
        "full_state": (env.full_state, (env.full_state_size,), jnp.float32),
        "skill_action": (lambda s: jax.vmap(env.skill_action, (None, 0))(s, calls), (env.num_skills, env.action_dim),
                         jnp.float32),
        "skill_done": (lambda s: jax.vmap(env.skill_done, (None, None, 0))(s, env.step(s, zero), calls),
                       (env.num_skills,), jnp.bool_),
        "skill_initiable": (lambda s: env.skill_initiable(s, skill_ids, slots), (env.num_skills,), jnp.bool_),
    }
    batch_of_states = jax.eval_shape(jax.vmap(env.reset), tasks)
    for method, (fn, shape, dtype) in functions.items():  # shapes first: abstract traces, nothing compiled
        where = f"{name}.{method}"
        _shape(where, _calls(where, jax.eval_shape, fn, state), dtype, shape)
        _shape(f"{where} under vmap", _calls(f"{where} under vmap", jax.eval_shape, jax.vmap(fn), batch_of_states),
               dtype, (len(task_arrays),) + shape)
    # Then each function traced twice to the same program, and values, all functions in one program: one
    # state's and a vmapped batch's must agree.
    for method, (fn, _, _) in functions.items():
        _traced_alike(f"{name}.{method}", fn, state)
    every = lambda s: {method: fn(s) for method, (fn, _, _) in functions.items()}
    first, batched = jax.jit(every)(state), jax.jit(jax.vmap(every))(jax.vmap(env.reset)(tasks))
    for method in functions:
        _same(f"{name}.{method} under vmap", first[method], batched[method][0])
    _check_objects(env, jax.vmap(env.reset)(tasks))


def _check_objects(env: NoveltyEnv, states: Any) -> None:
    """The object view of a batch of states: its shapes, slot 0 the robot, finite values, every slot the
    task does not fill masked out and zero, features zero beyond each type's own, jit and vmap agreeing."""
    where, types = f"{type(env).__name__}.objects", list(type(env).object_types)
    n, width = env.num_objects, env.object_width
    objects = _calls(where, jax.jit(jax.vmap(env.objects)), states)
    batch = (jax.tree.leaves(states)[0].shape[0],)
    for field, dtype, shape in (("type_id", jnp.int32, (n,)), ("features", jnp.float32, (n, width)),
                                ("mask", jnp.bool_, (n,)), ("interactable", jnp.bool_, (n,)),
                                ("position", jnp.float32, (n, POSITION_DIM))):
        _shape(f"{where}.{field}", getattr(objects, field), dtype, batch + shape)
    values = jax.tree.map(np.asarray, objects)
    _expect(((values.type_id >= 0) & (values.type_id < len(types))).all(), f"{where}.type_id",
            f"type ids in 0..{len(types) - 1}", np.unique(values.type_id))
    _expect((values.type_id[:, 0] == 0).all() and values.mask[:, 0].all(), where, "slot 0 the robot, a real object",
            f"type {values.type_id[:, 0]}, mask {values.mask[:, 0]}")
    _expect(np.isfinite(values.features).all() and np.isfinite(values.position).all(), where,
            "finite features and positions", "NaN or inf")
    out = ~values.mask
    _expect(not (values.features[out].any() or values.position[out].any() or values.interactable[out].any()), where,
            "every masked-out slot zero and not interactable", "a masked-out slot with values")
    own = np.array([len(names) for names in type(env).object_types.values()])[values.type_id]
    beyond = np.arange(width) >= own[..., None]
    _expect(not values.features[beyond].any(), f"{where}.features", "zeros beyond each type's own features",
            "values in the padding")
    candidates = np.asarray(env.candidate_slots)
    _expect(candidates.ndim == 1 and (np.diff(candidates) > 0).all() and ((candidates >= 1) & (candidates < n)).all(),
            f"{type(env).__name__}.candidate_slots", f"ascending slots in 1..{n - 1}", candidates)
    never = np.setdiff1d(np.arange(n), candidates)
    _expect(not values.interactable[:, never].any(), where, "no slot outside candidate_slots interactable",
            f"slots {np.unique(never[np.nonzero(values.interactable[:, never])[1]]).tolist()}")
    one = jax.tree.map(lambda x: x[0], states)
    _same(where, jax.jit(env.objects)(one), jax.tree.map(lambda x: x[0], objects))
    acted_on = np.asarray(_shape(f"{type(env).__name__}.oracle_object", _calls(
        f"{type(env).__name__}.oracle_object", jax.jit(jax.vmap(env.oracle_object)), states), jnp.int32, batch))
    _expect(((acted_on == -1) | ((acted_on >= 0) & (acted_on < n))).all(), f"{type(env).__name__}.oracle_object",
            f"a slot in 0..{n - 1} or -1", acted_on)


def _check_object_names(env: NoveltyEnv, spec: Any) -> None:
    """`object_names`: one entry per slot, a unique name exactly for the slots the task fills, and a name
    the planner's problem holds only for an object of the slot's type."""
    where, types = f"{type(env).__name__}.object_names", list(type(env).object_types)
    names = _calls(where, env.object_names, spec)
    view = jax.tree.map(np.asarray, jax.jit(env.objects)(env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))))
    _expect(isinstance(names, tuple) and len(names) == env.num_objects, where, f"a tuple of num_objects = {env.num_objects}",
            f"{type(names).__name__} of {len(names) if hasattr(names, '__len__') else '?'}")
    named = np.array([name is not None for name in names])
    _expect(np.array_equal(named, view.mask), where, "a name for exactly the slots objects() masks in",
            f"names at {np.flatnonzero(named).tolist()}, mask at {np.flatnonzero(view.mask).tolist()}")
    given = [name for name in names if name is not None]
    _expect(len(set(given)) == len(given) and all(isinstance(n, str) for n in given), where, "unique str names", given)
    planner_objects = env.planner_problem(spec).objects
    wrong = [(name, planner_objects[name], types[t]) for name, t in zip(names, view.type_id)
             if name in planner_objects and planner_objects[name] != types[t]]
    _expect(not wrong, where, "the planner's type of every planner object it names", wrong[0] if wrong else None)


def _shape(where: str, value: Any, dtype, shape: tuple | None = None) -> jax.Array:
    shown = f"{getattr(value, 'dtype', type(value).__name__)}{list(getattr(value, 'shape', ()))}"
    want = f"{jnp.dtype(dtype).name}{list(shape) if shape is not None else '[D]'}"
    ok = (isinstance(value, (jax.Array, jax.ShapeDtypeStruct)) and value.dtype == dtype
          and (value.shape == shape if shape is not None else len(value.shape) == 1))
    _expect(ok, where, want, shown)
    return value


def _traced_alike(where: str, fn: Callable, *args) -> None:
    """A second trace is the same program, constants included: the function depends on its inputs alone
    (no hidden Python state), checked without compiling it twice."""
    first, second = (jax.make_jaxpr(lambda *a: fn(*a))(*args) for _ in range(2))  # new functions: no cached trace
    consts_equal = len(first.consts) == len(second.consts) and all(
        np.array_equal(np.asarray(a), np.asarray(b)) for a, b in zip(first.consts, second.consts))
    if str(first) != str(second) or not consts_equal:
        raise EnvContractError(f"{where}: expected the same values from the same inputs (a second trace), "
                               f"got different ones (hidden state or randomness?)")


def _same(where: str, *values: Any) -> None:
    """Equal values from equal inputs, one at a time and in a batch (jit, vmap)."""
    try:
        for other in values[1:]:
            chex.assert_trees_all_close(values[0], other, rtol=1e-5, atol=1e-5)
    except AssertionError:
        raise EnvContractError(f"{where}: expected the same values from the same inputs (jit, vmap), "
                               f"got different ones (hidden state or randomness?)") from None


# ---- the oracle ----------------------------------------------------------------------------------------
def _check_oracle(cls: type[NoveltyEnv], seed: int, num_test_tasks: int) -> None:
    batch = evaluation_batch(cls, [seed], num_test_tasks)
    where = f"{cls.__name__}.oracle_bridge"
    result, records = _calls(where, lambda: rollout(MetaPolicy(batch.env, OracleBridge(batch.env)), batch.arrays,
                                                    jax.random.split(jax.random.key(seed), batch.size),
                                                    batch.max_steps, record=True))
    solved = np.asarray(result.success)
    _expect(solved.all(), where, f"every test task of seed {seed} solved within its horizon",
            f"{int(solved.sum())} of {solved.size} (unsolved: tasks {np.flatnonzero(~solved).tolist()})")
    _check_varying(batch.env, records)


def _positions(where: str, positions: Any, size: int) -> np.ndarray:
    """A declaration of full-state positions: ascending distinct ints in [0, size)."""
    positions = np.asarray(positions)
    _expect(positions.ndim == 1 and np.issubdtype(positions.dtype, np.integer) and np.all(np.diff(positions) > 0)
            and (positions.size == 0 or 0 <= positions[0] <= positions[-1] < size), where,
            f"ascending distinct ints in [0, full_state_size = {size})", repr(positions))
    return positions


def _check_filled(cls: type[NoveltyEnv], spec: Any, seed: int) -> None:
    """`full_state_filled` of the env at a training task's capacity names every entry the task's initial
    full state sets and, when it leaves some out, every entry set along random bridges' episodes of the
    task (the learners neither store nor fit the rest on such tasks)."""
    env, name = cls.for_tasks([spec]), cls.__name__
    filled = _positions(f"{name}.full_state_filled", env.full_state_filled, env.full_state_size)
    full = _calls(f"{name}.full_state", jax.jit(lambda task: env.full_state(env.reset(task))), env.task_arrays(spec))
    _expect_filled(name, filled, np.asarray(full), "its initial state")
    if filled.size == env.full_state_size:
        return
    batch = make_batch(cls, [spec] * 4, [seed] * 4)
    _, records = rollout(MetaPolicy(batch.env, RandomBridge(batch.env)), batch.arrays,
                         jax.random.split(jax.random.key(seed), batch.size), batch.max_steps, record=True)
    states = np.asarray(jax.jit(jax.vmap(jax.vmap(batch.env.full_state)))(records.env_state))
    _expect_filled(name, filled, states * np.asarray(records.live)[..., None], "random bridges' episodes")


def _expect_filled(name: str, filled: np.ndarray, states: np.ndarray, where: str) -> None:
    flat = states.reshape(-1, states.shape[-1])
    unnamed = np.setdiff1d(np.flatnonzero((flat != 0).any(axis=0)), filled)
    _expect(unnamed.size == 0, f"{name}.full_state_filled", "every entry a training task sets",
            f"entries {unnamed[:8].tolist()} also set in {where}")


def _check_varying(env: NoveltyEnv, records: Any) -> None:
    """`full_state_varying` names every entry that moved along the oracle's episodes (states [T, B])."""
    where = f"{type(env).__name__}.full_state_varying"
    varying = _positions(where, env.full_state_varying, env.full_state_size)
    states = np.asarray(jax.jit(jax.vmap(jax.vmap(env.full_state)))(records.env_state))
    moved = (states != states[:1]) & np.asarray(records.live)[..., None]
    unnamed = np.setdiff1d(np.flatnonzero(moved.any(axis=(0, 1))), varying)
    _expect(unnamed.size == 0, where, "every entry that changes within a task",
            f"entries {unnamed[:8].tolist()} also change along the oracle's episodes")
