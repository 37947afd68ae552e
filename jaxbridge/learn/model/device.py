"""A learned model's plan tables: the meta-policy plans with a repaired model as it plans with the env's.

Per task (host, once per model): ground the learned domain over the task's objects, keeping as
preconditions every invented predicate but the literals on features no segment changes (those prune the
grounding, read off the task's first state); index the invented ground atoms after the env's atoms; and
tabulate the plan A* finds from the first state. The table's operators are the env model's (the bridge
grounds its choices among them, as with the env's table) followed by the learned model's (the planner's
alone). A state off that plan asks the host planner, A* again, as any table miss does. Each operator's
check after it ran is what the learned model predicts of the atoms its operators change: an invented atom
no operator makes (a quantified one) is read afresh at each plan, never predicted.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import NoveltyEnv
from jaxbridge.core.learned_atoms import ALL_AT, BEFORE, NO_ATOM, SAME_PLACE, SPAN, UNARY, InventedAtoms, ModelTable
from jaxbridge.core.tasks import TaskArrays, TaskBatch, compiled_task
from jaxbridge.learn.model.model import LearnedModel
from jaxbridge.learn.model.operators import typed_objects
from jaxbridge.learn.model.predicates import PLACE_TOLERANCE, AllAt, Before, Either, Literal, SamePlace, Span
from jaxbridge.learn.model.segments import TaskReader, View
from planner.heuristic import astar
from planner.search import NO_OPERATOR, UNREACHABLE, BitOperator, PolicyEntry
from planner.strips import Atom, GroundOperator, Problem, ground
from planner.tables import CompiledTask, PlanTable, bits_to_words, num_words, register_planner, stack_tables


@dataclass
class LearnedPlanner:
    """A learned model's host planner for one task: A* (h_ff) from any state, each found plan's states cached."""

    ops: list[BitOperator]
    goal: int
    offset: int  # the table's index of ops[0] (the env model's operators come first)
    checked: int  # the bits an operator's check covers: atoms some operator changes
    cache: dict[int, PolicyEntry] = field(default_factory=dict)

    def decide(self, state: int) -> PolicyEntry:
        if state not in self.cache:
            found = astar(self.ops, self.goal, state).plan
            if found is None:
                self.cache[state] = PolicyEntry(NO_OPERATOR, state, UNREACHABLE)
            for k, i in enumerate(found or ()):
                op = self.ops[i]
                nxt = (state & ~op.delete) | op.add
                self.cache.setdefault(state, PolicyEntry(self.offset + i, nxt & self.checked, len(found) - k))
                state = nxt
            self.cache.setdefault(state, PolicyEntry(NO_OPERATOR, state, 0))
        return self.cache[state]


@dataclass(frozen=True)
class Grounding:
    """One task's learned grounding: its operators and invented atoms (index: `env.num_atoms` + position)."""

    ops: list[GroundOperator]
    invented: list[Atom]
    problem: Problem
    view: View  # the task's first state


def first_view(env: NoveltyEnv, spec) -> View:
    """The task's first state as the learner reads it."""
    state = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))
    objects = jax.tree.map(np.asarray, env.objects(state))
    return TaskReader(env, spec).view(objects.type_id, objects.features, objects.position, np.asarray(env.abstract(state)))


def ground_model(env: NoveltyEnv, spec, model: LearnedModel) -> Grounding:
    """`model`'s domain grounded on task `spec` (see the module's note on what stays a precondition)."""
    view, env_problem = first_view(env, spec), env.planner_problem(spec)
    env_static = set(env_problem.domain.predicates) - env_problem.domain.fluent_predicates
    static_literals = {p for p in model.domain.predicates if model.grammar.static_literal(p)}
    atoms = model.atoms(view)
    static = env_problem.static | frozenset(a for a in atoms if a[0] in static_literals)
    fluent = frozenset(model.domain.predicates) - env_static - static_literals
    problem = Problem(model.domain, typed_objects(view, model.domain), static,
                      frozenset(a for a in atoms if a[0] in fluent), env_problem.goal)
    ops = ground(problem, fluent)
    env_fluent = env_problem.domain.fluent_predicates
    invented = sorted({a for op in ops for a in op.pre | op.add | op.delete if a[0] not in env_fluent})
    return Grounding(ops, invented, problem, view)


def _invented_atoms(env: NoveltyEnv, grounding: Grounding, model: LearnedModel, capacity: int) -> InventedAtoms:
    """The device form of the task's invented atoms, padded to `capacity`."""
    grammar = model.grammar
    predicates = {p.name: p for p in grammar.unary + grammar.relations + grammar.all_at + grammar.spans}
    type_ids = {t: i for i, t in enumerate(type(env).object_types)}
    names = grounding.view.names
    kind, rows = np.full(capacity, NO_ATOM, np.int32), np.zeros((capacity, 2), np.int32)
    feature, threshold = np.zeros((capacity, 2), np.int32), np.zeros((capacity, 2), np.float32)
    above, used, members = np.zeros((capacity, 2), bool), np.zeros((capacity, 2), bool), np.zeros(capacity, np.int32)
    for j, atom in enumerate(grounding.invented):
        p, args = predicates[atom[0]], [names.index(a) for a in atom[1:]]
        rows[j] = (args[0], args[-1])
        unary = p.unary if isinstance(p, (AllAt, Span)) else p
        if isinstance(unary, (Literal, Either)):
            literals = (unary.guard, unary.literal) if isinstance(unary, Either) else (unary,)
            for k, lit in enumerate(literals):
                feature[j, k], threshold[j, k], above[j, k], used[j, k] = lit.feature, lit.threshold, lit.above, True
        if isinstance(p, (AllAt, Span)):
            members[j] = type_ids[p.unary.type]
        # a relation of an object with itself is one the grammar never states
        self_relation = isinstance(p, SamePlace) and args[0] == args[-1]
        kind[j] = NO_ATOM if self_relation else {SamePlace: SAME_PLACE, Before: BEFORE, AllAt: ALL_AT, Span: SPAN}.get(type(p), UNARY)
    return InventedAtoms(kind, rows, feature, threshold, above, used, members)


def compile_model_task(env: NoveltyEnv, spec, model: LearnedModel, grounding: Grounding, atoms: int,
                       operators: int) -> CompiledTask:
    """Task `spec`'s plan table under `model` (its `grounding`), its invented atoms padded to `atoms` and
    its operators' sampler rows to `operators`."""
    own = compiled_task(env, spec)
    base, words = len(own.ground_ops), num_words(env.num_atoms + atoms)
    env_fluent = env.planner_problem(spec).domain.fluent_predicates
    index = {a: env.num_atoms + j for j, a in enumerate(grounding.invented)}
    index_of = lambda a: index[a] if a in index else env.atom_index(a)
    bits = lambda atoms: sum(1 << index_of(a) for a in atoms if a in index or a[0] in env_fluent)
    ops = grounding.ops
    made = model.domain.fluent_predicates
    checked = (1 << env.num_atoms) - 1 | bits(a for a in grounding.invented if a[0] in made)
    planner = LearnedPlanner([BitOperator(bits(o.pre), bits(o.add), bits(o.delete)) for o in ops],
                             bits(grounding.problem.goal), base, checked)
    init = bits(model.atoms(grounding.view))
    states, state = [], init
    while (entry := planner.decide(state)).op != NO_OPERATOR and len(states) < len(ops):
        states.append(state)
        state = (state & ~planner.ops[entry.op - base].delete) | planner.ops[entry.op - base].add
    states = states or [init]  # a table has a row: the first state's, answered by the host planner
    key = lambda s: bits_to_words(s, words)
    widen = lambda x: np.pad(x, ((0, 0), (0, words - x.shape[1])))
    table = PlanTable(
        uid=np.int32(register_planner(planner)), goal_key=key(planner.goal),
        state_keys=np.stack([key(s) for s in states]), state_valid=np.ones(len(states), bool),
        next_op=np.array([planner.decide(s).op for s in states], np.int32),
        next_keys=np.stack([key(planner.decide(s).next_state) for s in states]),
        op_pre=np.concatenate([widen(own.table.op_pre), np.stack([key(o.pre) for o in planner.ops]).reshape(-1, words)]),
        op_skill=np.concatenate([own.table.op_skill, np.array([env.skill_index(o.skill) for o in ops], np.int32)]),
        op_slot=np.concatenate([own.table.op_slot, np.array([env.object_slot(o.slot_object) if o.slot_object else 0
                                                             for o in ops], np.int32)]),
        op_valid=np.concatenate([own.table.op_valid, np.zeros(len(ops), bool)]),
        model=_model_table(env, grounding, model, base, atoms, operators))
    return CompiledTask(int(table.uid), grounding.problem, own.ground_ops + ops, planner, init, table, len(states))


def _model_table(env: NoveltyEnv, grounding: Grounding, model: LearnedModel, base: int, atoms: int,
                 operators: int) -> ModelTable:
    names, width = grounding.view.names, env.object_width + 1
    row, weights = np.zeros(operators, np.int32), np.zeros((operators, width), np.float32)
    sampled, low, high = np.zeros(operators, bool), np.zeros(operators, np.float32), np.zeros(operators, np.float32)
    for i, op in enumerate(grounding.ops, start=base):
        if (sampler := model.samplers.get(op.name)) is not None:
            row[i] = names.index(op.slot_object) if op.slot_object in names else 0
            weights[i], sampled[i], low[i], high[i] = sampler.weights, True, sampler.low, sampler.high
    return ModelTable(_invented_atoms(env, grounding, model, atoms), np.array([n is not None for n in names]),
                      row, weights, sampled, low, high, place_tolerance=PLACE_TOLERANCE)


def _capacity(n: int) -> int:
    """The next power of two: a model that grows a little keeps its shapes, and a cycle its program."""
    return 1 << max(0, n - 1).bit_length()


def model_batch(env_cls: type[NoveltyEnv], specs: list, seeds: list[int], models: dict[int, LearnedModel],
                horizons: list[int] | None = None) -> TaskBatch:
    """A batch of `specs` (task b of seed `seeds[b]`) planned with each seed's learned model."""
    env = env_cls.for_tasks(specs)
    groundings: dict = {}
    for spec, seed in zip(specs, seeds):
        if (seed, spec) not in groundings:
            groundings[seed, spec] = ground_model(env, spec, models[seed])
    atoms = _capacity(max(len(g.invented) for g in groundings.values()))
    operators = _capacity(max(len(compiled_task(env, s).ground_ops) + len(groundings[seed, s].ops) for s, seed in zip(specs, seeds)))
    compiled = {k: compile_model_task(env, k[1], models[k[0]], g, atoms, operators) for k, g in groundings.items()}
    horizons = [s.horizon for s in specs] if horizons is None else horizons
    tasks = [compiled[seed, spec] for spec, seed in zip(specs, seeds)]
    arrays = TaskArrays(tasks=env.stack_tasks(specs), tables=stack_tables(tasks), horizons=jnp.asarray(horizons, jnp.int32))
    return TaskBatch(env=env, specs=list(specs), seeds=np.asarray(seeds), compiled=tasks, arrays=arrays)
