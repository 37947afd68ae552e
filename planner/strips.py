"""A small typed STRIPS model: lifted operators, grounding by static facts, and PDDL text.

Each environment states its planner model (the operators of envs.md, which leave the novelty out) as
`LiftedOperator`s. Grounding binds them to one task's objects and drops every binding whose static
preconditions (predicates that no operator adds or deletes) are false, as a naive grounder does.
"""
from __future__ import annotations

from dataclasses import dataclass

Atom = tuple[str, ...]  # ("RobotInCell", "robby", "cell3"); variables start with "?"


@dataclass(frozen=True)
class LiftedOperator:
    """A STRIPS operator over typed variables, executed by the skill `skill`.

    `slot_param` names the variable whose object picks the skill's ground slot (e.g. MoveRobot's target
    cell); None for skills with a single ground instance.
    """

    name: str
    params: tuple[tuple[str, str], ...]  # (variable, type)
    pre: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]
    skill: str
    slot_param: str | None = None


@dataclass(frozen=True)
class Domain:
    name: str
    types: tuple[str, ...]
    predicates: dict[str, tuple[str, ...]]  # predicate name -> argument types
    operators: tuple[LiftedOperator, ...]

    @property
    def fluent_predicates(self) -> frozenset[str]:
        """Predicates some operator changes; every other predicate is static."""
        return frozenset(a[0] for op in self.operators for a in op.add + op.delete)


@dataclass(frozen=True)
class Problem:
    domain: Domain
    objects: dict[str, str]  # object name -> type, in a fixed order
    static: frozenset[Atom]
    init: frozenset[Atom]  # fluent atoms true at the start
    goal: frozenset[Atom]


@dataclass(frozen=True)
class GroundOperator:
    name: str
    args: tuple[str, ...]
    pre: frozenset[Atom]  # fluent preconditions only (static ones were checked when grounding)
    add: frozenset[Atom]
    delete: frozenset[Atom]
    skill: str
    slot_object: str | None

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


def _bind(atoms: tuple[Atom, ...], binding: dict[str, str]) -> frozenset[Atom]:
    return frozenset((a[0],) + tuple(binding.get(x, x) for x in a[1:]) for a in atoms)


def _static_bindings(variables: list[str], choices: list[list[str]], static_pre: tuple[Atom, ...],
                     static: frozenset[Atom]):
    """Every binding of `variables` (in itertools.product order) under which `static_pre` holds. Each
    static atom is checked as soon as its last variable is bound, and a static atom that binds that
    variable once draws its values from an index of the static facts instead of trying every object: a
    row of n cells grounds MoveRobot in O(n), not O(n^2) (a 7x7 Doorknobs map has ~80k candidate
    bindings of MoveThroughDoor, a few hundred valid)."""
    last = {v: i for i, v in enumerate(variables)}
    check_at: list[list[Atom]] = [[] for _ in variables]
    for atom in static_pre:
        depth = max((last[x] for x in atom[1:] if x in last), default=0)
        check_at[depth].append(atom)
    if not variables:
        if _bind(static_pre, {}) <= static:
            yield {}
        return
    # (fact with one argument blanked) -> the values that argument takes in the static facts
    facts: dict[tuple, set[str]] = {}
    for fact in static:
        for pos in range(1, len(fact)):
            facts.setdefault(fact[:pos] + (None,) + fact[pos + 1:], set()).add(fact[pos])
    rank = [{value: i for i, value in enumerate(c)} for c in choices]
    drawn_at = [[a for a in atoms if a[1:].count(variables[d]) == 1] for d, atoms in enumerate(check_at)]

    def values_at(depth: int, binding: dict[str, str]) -> list[str]:
        if not drawn_at[depth]:
            return choices[depth]
        var = variables[depth]
        allowed = None
        for atom in drawn_at[depth]:
            found = facts.get(tuple(None if x == var else binding.get(x, x) for x in atom), set())
            allowed = found if allowed is None else allowed & found
        return sorted((v for v in allowed if v in rank[depth]), key=rank[depth].__getitem__)

    def extend(depth: int, binding: dict[str, str]):
        for value in values_at(depth, binding):
            binding[variables[depth]] = value
            if all(_bind((a,), binding) <= static for a in check_at[depth]):
                if depth + 1 == len(variables):
                    yield dict(binding)
                else:
                    yield from extend(depth + 1, binding)
        binding.pop(variables[depth], None)

    yield from extend(0, {})


def ground(problem: Problem) -> list[GroundOperator]:
    """All bindings of every operator whose static preconditions hold, in a deterministic order."""
    fluent = problem.domain.fluent_predicates
    by_type: dict[str, list[str]] = {}
    for name, typ in problem.objects.items():
        by_type.setdefault(typ, []).append(name)
    ops = []
    for op in problem.domain.operators:
        variables = [v for v, _ in op.params]
        choices = [by_type.get(t, []) for _, t in op.params]
        static_pre = tuple(a for a in op.pre if a[0] not in fluent)
        fluent_pre = tuple(a for a in op.pre if a[0] in fluent)
        for binding in _static_bindings(variables, choices, static_pre, problem.static):
            values = tuple(binding[v] for v in variables)
            ops.append(GroundOperator(
                name=op.name, args=tuple(values), pre=_bind(fluent_pre, binding),
                add=_bind(op.add, binding), delete=_bind(op.delete, binding), skill=op.skill,
                slot_object=binding[op.slot_param] if op.slot_param else None))
    return ops


# ------------------------------------------------------------------------------------------------ PDDL


def _pddl_atom(atom: Atom) -> str:
    return "(" + " ".join(atom) + ")"


def _pddl_and(atoms) -> str:
    return "(and " + " ".join(atoms) + ")"


def domain_pddl(domain: Domain) -> str:
    """The domain as PDDL text (:strips :typing), e.g. for an external planner; each action's skill and
    slot variable ride in a `; skill: NAME slot: ?var` comment line that planner.pddl reads back."""
    preds = []
    for name, types in domain.predicates.items():
        args = " ".join(f"?a{i} - {t}" for i, t in enumerate(types))
        preds.append(f"({name} {args})".replace(" )", ")"))
    actions = []
    for op in domain.operators:
        params = " ".join(f"{v} - {t}" for v, t in op.params)
        effect = [_pddl_atom(a) for a in op.add] + [f"(not {_pddl_atom(a)})" for a in op.delete]
        # PDDL has no place for the skill and its slot: a comment that planner.pddl reads back.
        note = f"; skill: {op.skill}" + (f" slot: {op.slot_param}" if op.slot_param else "")
        actions.append(
            f"  (:action {op.name}\n    {note}\n    :parameters ({params})\n"
            f"    :precondition {_pddl_and(_pddl_atom(a) for a in op.pre)}\n"
            f"    :effect {_pddl_and(effect)})")
    return (f"(define (domain {domain.name})\n  (:requirements :strips :typing)\n"
            f"  (:types {' '.join(domain.types)})\n  (:predicates {' '.join(preds)})\n"
            + "\n".join(actions) + ")\n")


def problem_pddl(problem: Problem, name: str = "task") -> str:
    """The problem as PDDL text: objects, static and fluent initial atoms, goal."""
    objects = " ".join(f"{o} - {t}" for o, t in problem.objects.items())
    init = " ".join(_pddl_atom(a) for a in sorted(problem.static | problem.init))
    goal = _pddl_and(_pddl_atom(a) for a in sorted(problem.goal))
    return (f"(define (problem {name}) (:domain {problem.domain.name})\n  (:objects {objects})\n"
            f"  (:init {init})\n  (:goal {goal}))\n")
