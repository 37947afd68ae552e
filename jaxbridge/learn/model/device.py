"""A learned model's plan tables: the meta-policy plans with a repaired model as it plans with the env's.

Per task (host, once per model): index the invented ground atoms after the env's atoms (every binding of
the model's invented predicates to the task's objects), and tabulate the plan found from the first state.
A state off that plan asks the host planner, as any table miss does. The host planner grounds the model
as `planning.plan` does, every atom no operator changes static (read from the state asked about), and
plans with search.py (A* with h_ff over helpful actions); where the model has no plan, the env's own
model answers.

The device holds no learned grounding: a learned operator is a code (`core/learned_atoms.py`) naming its
lifted operator, its sampler's input row and its slot. The table's operators are the env model's, the
bridge's to ground its choices among, as with the env's table. An operator's check after it ran is what
the model predicts of the atoms its operators change: an invented atom that no operator makes (a
quantified one) is read afresh at each plan, never predicted.
"""
from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import NoveltyEnv
from jaxbridge.core.learned_atoms import (ALL_AT, BEFORE, NO_ATOM, SAME_PLACE, SPAN, UNARY, InventedAtoms, ModelTable,
                                          learned_code)
from jaxbridge.core.tasks import TaskArrays, TaskBatch, compiled_task
from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.operators import typed_objects
from jaxbridge.learn.model.predicates import PLACE_TOLERANCE, AllAt, Before, Either, Literal, SamePlace, Span
from jaxbridge.learn.model.search import find_plan
from jaxbridge.learn.model.segments import TaskReader, View
from planner.heuristic import Relaxation
from planner.search import NO_OPERATOR, BitOperator, PolicyEntry
from planner.strips import Atom, GroundOperator, Problem, ground
from planner.tables import CompiledTask, bits_to_words, num_words, register_planner, stack_tables


@dataclass(frozen=True)
class TaskModel:
    """One task under a learned model: its first state, objects, static env atoms and goal, and its atoms'
    layout (the env's fluent atoms at their indices, the invented ones after them)."""

    env: NoveltyEnv
    spec: object
    model: LearnedModel
    view: View
    objects: dict[str, str]
    static: frozenset[Atom]
    goal: frozenset[Atom]
    env_atoms: dict[int, Atom]
    invented: tuple[Atom, ...]

    @functools.cached_property
    def index(self) -> dict[Atom, int]:
        return {a: i for i, a in self.env_atoms.items()} | {a: self.env.num_atoms + j for j, a in enumerate(self.invented)}

    @functools.cached_property
    def atom_at(self) -> dict[int, Atom]:
        return {i: a for a, i in self.index.items()}

    @property
    def env_mask(self) -> int:
        """The bits of the env's own atoms."""
        return (1 << self.env.num_atoms) - 1

    def bits(self, atoms) -> int:
        return sum(1 << self.index[a] for a in atoms if a in self.index)

    def atoms(self, state: int) -> frozenset[Atom]:
        return frozenset(self.atom_at[i] for i in range(state.bit_length()) if state >> i & 1 and i in self.atom_at)


def task_model(env: NoveltyEnv, spec, model: LearnedModel) -> TaskModel:
    """Task `spec` under `model`: every binding of its invented predicates to the task's objects indexed."""
    reader = TaskReader(env, spec)
    state = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))
    view = reader.observe(state)
    # sorted: the grounding's order, so its plans, must not follow the hash order of a set
    objects, problem = dict(sorted(typed_objects(view, model.domain).items())), env.planner_problem(spec)
    invented = [(name, *args) for name, types in model.domain.predicates.items() if name in model.grammar.signatures
                for args in itertools.product(*[[o for o, t in objects.items() if t == ty] for ty in types])]
    return TaskModel(env, spec, model, view, objects, problem.static, problem.goal, reader.atoms, tuple(invented))


@dataclass
class LearnedPlanner:
    """A learned model's host planner for one task: the first operator of a plan from any state (search.py),
    cached by state; the env model's planner (`fallback`) where the learned one finds no plan."""

    task: TaskModel
    fallback: object  # planner.search.HostPlanner over the env's atoms
    cache: dict[int, PolicyEntry] = field(default_factory=dict)
    groundings: dict[frozenset[Atom], tuple[list[GroundOperator], Relaxation]] = field(default_factory=dict)
    uid: int = 0  # its plan tables' name for it (register_planner), once registered
    model_tables: dict[tuple[int, int, int], ModelTable] = field(default_factory=dict)  # by capacities

    @classmethod
    def of(cls, env: NoveltyEnv, spec, model: LearnedModel, cache: dict | None = None) -> "LearnedPlanner":
        """Task `spec`'s planner under `model`, with the answers of `cache` (a saved planner's)."""
        return cls(task_model(env, spec, model), compiled_task(env, spec).planner, dict(cache or {}))

    @functools.cached_property
    def derived(self) -> frozenset[str]:
        """The model's predicates no operator changes: static within a plan, read from the state."""
        return frozenset(self.task.model.domain.predicates) - self.task.model.domain.fluent_predicates

    @functools.cached_property
    def checked(self) -> int:
        """The bits a prediction covers: the env's atoms and the invented ones some operator changes."""
        made = self.task.model.domain.fluent_predicates
        return self.task.env_mask | self.task.bits(a for a in self.task.invented if a[0] in made)

    @property
    def goal(self) -> int:
        return self.task.bits(self.task.goal)

    def decide(self, state: int) -> PolicyEntry:
        if state not in self.cache:
            self._plan(state)
        return self.cache[state]

    def _plan(self, state: int) -> None:
        # A plan found answers its later states too (those not answered already: an answer, once given,
        # stays), so a plan of n steps costs one search, not n. The answers depend on the order of the
        # questions; a run saves its planners' caches beside its checkpoints, so a resumed run answers alike.
        ops, relaxation = self._grounding(frozenset(a for a in self.task.atoms(state) if a[0] in self.derived))
        found = find_plan(relaxation.ops, self.goal, state, relaxation)
        if found is None:
            self.cache[state] = self.fallback.decide(state & self.task.env_mask)
        elif not found:
            self.cache[state] = PolicyEntry(NO_OPERATOR, state, 0)
        for step, index in enumerate(found or ()):
            op = relaxation.ops[index]
            nxt = (state & ~op.delete) | op.add
            self.cache.setdefault(state, PolicyEntry(self._code(ops[index]), nxt & self.checked, len(found) - step))
            state = nxt

    def _grounding(self, derived: frozenset[Atom]) -> tuple[list[GroundOperator], Relaxation]:
        """The model grounded with `derived` atoms (and the env's static ones) static, and the delete
        relaxation of its bit operators (kept: a task's derived atoms take few values)."""
        if derived not in self.groundings:
            task = self.task
            ops = ground(Problem(task.model.domain, task.objects, task.static | derived, frozenset(), task.goal))
            bit_ops = [BitOperator(task.bits(o.pre), task.bits(o.add), task.bits(o.delete)) for o in ops]
            self.groundings[derived] = ops, Relaxation(bit_ops)
        return self.groundings[derived]

    def _code(self, op: GroundOperator) -> int:
        task = self.task
        lifted = [o.name for o in task.model.domain.operators].index(op.name)
        sampler, names = task.model.samplers.get(op.name), task.view.names
        source = sampler.input_object(task.view, op.slot_object, op.args) if sampler else op.slot_object
        slot = task.env.object_slot(op.slot_object) if op.slot_object else 0
        assert 0 <= slot < task.env.num_objects, f"{op}: slot {slot} outside the env's {task.env.num_objects}"
        return learned_code(lifted, names.index(source) if source in names else 0, slot, len(names), task.env.num_objects)


def _invented_predicates(task: TaskModel) -> list[str]:
    """The names of the predicates of the task's invented atoms, in order of first use."""
    return list(dict.fromkeys(atom[0] for atom in task.invented))


def _invented_atoms(task: TaskModel, capacity: int, predicate_capacity: int) -> InventedAtoms:
    """The device form of the task's invented atoms and their predicates, padded to the capacities."""
    grammar, names = task.model.grammar, task.view.names
    by_name = {p.name: p for p in grammar.unary + grammar.relations + grammar.all_at + grammar.spans}
    predicates = [by_name[name] for name in _invented_predicates(task)]
    type_ids = {t: i for i, t in enumerate(type(task.env).object_types)}
    P = predicate_capacity
    feature, other, members = np.zeros((P, 2), np.int32), np.full((P, 2), -1, np.int32), np.zeros(P, np.int32)
    threshold, above, used = np.zeros((P, 2), np.float32), np.zeros((P, 2), bool), np.zeros((P, 2), bool)
    for i, p in enumerate(predicates):
        unary = p.unary if isinstance(p, (AllAt, Span)) else p
        if isinstance(unary, (Literal, Either)):
            for k, lit in enumerate((unary.guard, unary.literal) if isinstance(unary, Either) else (unary,)):
                feature[i, k], threshold[i, k], above[i, k], used[i, k] = lit.feature, lit.threshold, lit.above, True
                other[i, k] = -1 if lit.other is None else lit.other
        if isinstance(p, (AllAt, Span)):
            members[i] = type_ids[p.unary.type]
    kind, predicate, rows = np.full(capacity, NO_ATOM, np.int32), np.zeros(capacity, np.int32), np.zeros((capacity, 2), np.int32)
    index = {p.name: i for i, p in enumerate(predicates)}
    for j, atom in enumerate(task.invented):
        p, args = by_name[atom[0]], [names.index(a) for a in atom[1:]]
        predicate[j], rows[j] = index[atom[0]], (args[0], args[-1])
        self_relation = isinstance(p, SamePlace) and args[0] == args[-1]  # one the grammar never states
        kind[j] = NO_ATOM if self_relation else {SamePlace: SAME_PLACE, Before: BEFORE, AllAt: ALL_AT, Span: SPAN}.get(type(p), UNARY)
    return InventedAtoms(kind, predicate, rows, feature, other, threshold, above, used, members)


def _model_table(task: TaskModel, atoms: int, predicates: int, operators: int) -> ModelTable:
    """The task's invented atoms (padded to `atoms`, their predicates to `predicates`) and the model's
    lifted operators' skills and samplers (padded to `operators`)."""
    env, width = task.env, task.env.object_width + 1
    skill, weights = np.zeros(operators, np.int32), np.zeros((operators, width), np.float32)
    sampled, low, high = np.zeros(operators, bool), np.zeros(operators, np.float32), np.zeros(operators, np.float32)
    for i, op in enumerate(task.model.domain.operators):
        skill[i] = env.skill_index(op.skill)
        if (sampler := task.model.samplers.get(op.name)) is not None:
            weights[i], sampled[i], low[i], high[i] = sampler.weights, True, sampler.low, sampler.high
    return ModelTable(_invented_atoms(task, atoms, predicates), np.array([n is not None for n in task.view.names]), skill, weights,
                      sampled, low, high, slots=env.num_objects, place_tolerance=PLACE_TOLERANCE)


def compile_model_task(planner: LearnedPlanner, atoms: int, predicates: int, operators: int) -> CompiledTask:
    """`planner`'s task's plan table: the env model's operators; as rows the plan from the first state and
    every state the planner has answered (a task met again finds them in the table); the learned model's
    part at capacities `atoms` (invented atoms), `predicates` (theirs) and `operators` (lifted operators)."""
    task = planner.task
    own, words = compiled_task(task.env, task.spec), num_words(task.env.num_atoms + atoms)
    init = task.bits(task.model.atoms(task.view))
    states, state = [], init
    while (entry := planner.decide(state)).op != NO_OPERATOR and state not in states:
        states.append(state)
        state = entry.next_state | (state & ~planner.checked)  # what the model predicts, the rest as it was
    states = list(dict.fromkeys(states + [s for s, e in planner.cache.items() if e.op != NO_OPERATOR])) or [init]
    if (atoms, predicates, operators) not in planner.model_tables:
        planner.model_tables[atoms, predicates, operators] = _model_table(task, atoms, predicates, operators)
    planner.uid = planner.uid or register_planner(planner)
    key = lambda s: bits_to_words(s, words)
    table = own.table.replace(
        uid=np.int32(planner.uid), goal_key=key(planner.goal),
        state_keys=np.stack([key(s) for s in states]), state_valid=np.ones(len(states), bool),
        next_op=np.array([planner.decide(s).op for s in states], np.int32),
        next_keys=np.stack([key(planner.decide(s).next_state) for s in states]),
        op_pre=np.pad(own.table.op_pre, ((0, 0), (0, words - own.table.op_pre.shape[1]))),
        model=planner.model_tables[atoms, predicates, operators])
    return CompiledTask(planner.uid, own.problem, own.ground_ops, planner, init, table, len(states))


def _with_rows(table, rows: int):
    """`table` with its plan rows padded to `rows` (invalid rows)."""
    pad = lambda x, fill: np.concatenate([x, np.full((rows - x.shape[0],) + x.shape[1:], fill, x.dtype)])
    return table.replace(state_keys=pad(table.state_keys, 0), state_valid=pad(table.state_valid, False),
                         next_op=pad(table.next_op, NO_OPERATOR), next_keys=pad(table.next_keys, 0))


MIN_ROWS = 128  # plan rows at least: the states a task's first cycles answer fit, so its program compiles once


@dataclass(frozen=True)
class Capacities:
    """A planned batch's padded sizes: invented atoms, their predicates, lifted operators and plan rows."""

    atoms: int = 1
    predicates: int = 1
    operators: int = 1
    rows: int = MIN_ROWS

    @classmethod
    def of(cls, tables) -> "Capacities":
        """The capacities a batch's plan tables were padded to."""
        invented = tables.model.invented
        return cls(invented.kind.shape[-1], invented.feature.shape[-2], tables.model.op_skill.shape[-1],
                   tables.state_keys.shape[-2])

    def at_least(self, other: "Capacities") -> "Capacities":
        return Capacities(*map(max, dataclasses.astuple(self), dataclasses.astuple(other)))


def _capacity(n: int) -> int:
    """The next power of two: a model that grows a little keeps its shapes, and a cycle its program."""
    return 1 << max(0, n - 1).bit_length()


def model_batch(env: NoveltyEnv, specs: list, owners: list[int], models: dict[int, LearnedModel],
                horizons: list[int] | None = None, planners: dict | None = None,
                least: Capacities = Capacities()) -> TaskBatch:
    """A batch of `specs` (task b owned by `owners[b]`, under `env`, sized for them all) planned with each
    owner's learned model (owners are seeds, or a sweep's slots). `planners`: each (owner, spec, env)'s
    LearnedPlanner kept between batches (reused while the owner's model is the same), so a later batch's
    tables hold the states the planners answered. Padded to at least `least` (a run's earlier batches'
    capacities: a model that shrinks keeps the cycle's program)."""
    planners = {} if planners is None else planners
    for owner, spec in dict.fromkeys(zip(owners, specs)):
        kept = planners.get((owner, spec, env))
        if kept is None or kept.task.model is not models[owner]:
            planners[owner, spec, env] = LearnedPlanner.of(env, spec, models[owner])
    mine = {(o, s): planners[o, s, env] for o, s in dict.fromkeys(zip(owners, specs))}
    atoms = max(least.atoms, _capacity(max(len(p.task.invented) for p in mine.values())))
    predicates = max(least.predicates, _capacity(max(len(_invented_predicates(p.task)) for p in mine.values())))
    operators = max(least.operators, _capacity(max(len(m.domain.operators) for m in models.values())))
    compiled = {k: compile_model_task(p, atoms, predicates, operators) for k, p in mine.items()}
    horizons = [s.horizon for s in specs] if horizons is None else horizons
    chosen = [compiled[o, s] for o, s in zip(owners, specs)]
    rows = max(least.rows, _capacity(max(MIN_ROWS, *(c.table.state_keys.shape[0] for c in chosen))))
    chosen[0] = dataclasses.replace(chosen[0], table=_with_rows(chosen[0].table, rows))  # the stack pads the rest
    arrays = TaskArrays(tasks=env.stack_tasks(specs), tables=stack_tables(chosen), horizons=jnp.asarray(horizons, jnp.int32))
    return TaskBatch(env=env, specs=list(specs), seeds=np.asarray(owners), compiled=chosen, arrays=arrays)
