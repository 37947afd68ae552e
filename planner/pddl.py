"""Read PDDL text back into the planner's STRIPS model: the inverse of strips.py's `domain_pddl` and
`problem_pddl`.

The subset read is what the writer emits: :strips and :typing requirements, a flat list of types (a
parent `object` is allowed, no other hierarchy: grounding matches types exactly), typed predicates, and
actions with typed parameters, a conjunction of positive atoms as precondition and added and `(not ...)`
deleted atoms as effect. Negative preconditions are refused: `LiftedOperator` and the bitset search
(`BitOperator.pre`) hold positive preconditions only. Each action's executing skill and slot variable, for
which PDDL has no place, travel in a comment line the writer puts inside the action,
`; skill: NAME slot: ?var` (slot left out when None); without it the skill is the action's name and the
slot None. Anything else (unbalanced parentheses, an unknown requirement or section, an undeclared
predicate, type, variable or object, a wrong arity or argument type, a problem for another domain) raises
`PDDLError` with a one-line message naming where.
"""
from __future__ import annotations

import re

from planner.strips import Atom, Domain, LiftedOperator, Problem

REQUIREMENTS = (":strips", ":typing")
_TOKEN = re.compile(r";[^\n]*|[()]|[^\s();]+")
_NOTE = re.compile(r";\s*skill:\s*(\S+)(?:\s+slot:\s*(\S+))?\s*$")


class PDDLError(ValueError):
    """Malformed PDDL, or PDDL outside the subset the planner's model can hold."""


class _List(list):
    """One parenthesised expression: its items, the line it opens on, and the skill notes inside it."""

    def __init__(self, line: int):
        super().__init__()
        self.line, self.notes = line, []


def _parse(text: str, what: str) -> _List:
    """The single top-level expression of `text`; comments other than skill notes are dropped."""
    stack, line, last = [_List(1)], 1, 0
    for match in _TOKEN.finditer(text):
        line += text.count("\n", last, match.start())
        last, token = match.start(), match.group()
        if token == "(":
            stack.append(_List(line))
            stack[-2].append(stack[-1])
        elif token == ")":
            if len(stack) == 1:
                raise PDDLError(f"{what}, line {line}: unbalanced ')'")
            stack.pop()
        elif token.startswith(";"):
            note = _NOTE.match(token)
            if note:
                stack[-1].notes.append((note.group(1), note.group(2), line))
        else:
            stack[-1].append(token)
    if len(stack) > 1:
        raise PDDLError(f"{what}: unbalanced '(' opened on line {stack[-1].line}")
    top = stack[0]
    if len(top) != 1 or not isinstance(top[0], _List) or not top[0] or _key(top[0][0]) != "define":
        raise PDDLError(f"{what}: expected exactly one (define ...) expression")
    return top[0]


def _key(item) -> str:
    """A keyword as compared (PDDL keywords are case-insensitive; names keep their case)."""
    return item.lower() if isinstance(item, str) else ""


def _header(define: _List, kind: str, what: str) -> tuple[str, list[_List]]:
    """The name in `(define (kind NAME) ...)` and the sections after it."""
    head = define[1] if len(define) > 1 else None
    if not isinstance(head, _List) or len(head) != 2 or _key(head[0]) != kind or not isinstance(head[1], str):
        raise PDDLError(f"{what}: expected (define ({kind} NAME) ...)")
    sections = define[2:]
    for section in sections:
        if not isinstance(section, _List) or not section or not _key(section[0]).startswith(":"):
            raise PDDLError(f"{kind} {head[1]}, line {getattr(section, 'line', '?')}: expected a (:section ...)")
    return head[1], sections


def _names(items, where: str) -> list[str]:
    if not all(isinstance(x, str) for x in items):
        raise PDDLError(f"{where}: expected names, got a parenthesised expression")
    return list(items)


def _typed(items, types, where: str) -> list[tuple[str, str]]:
    """`a b - t c - u` -> [(a, t), (b, t), (c, u)]; every name needs a declared type."""
    items, out, pending = _names(items, where), [], []
    for i, item in enumerate(items):
        if item == "-":
            continue
        if i > 0 and items[i - 1] == "-":
            if not pending:
                raise PDDLError(f"{where}: type {item} names nothing")
            if item not in types:
                raise PDDLError(f"{where}: undeclared type {item}")
            out += [(name, item) for name in pending]
            pending = []
        else:
            pending.append(item)
    if pending or (items and items[-1] == "-"):
        raise PDDLError(f"{where}: {' '.join(pending) or '-'} has no type (the reader needs :typing)")
    return out


def _check_requirements(section: _List, where: str) -> None:
    for req in _names(section[1:], where):
        if _key(req) not in REQUIREMENTS:
            raise PDDLError(f"{where}: requirement {req} is not supported (only {' '.join(REQUIREMENTS)})")


def _types(section: _List, where: str) -> tuple[str, ...]:
    items = _names(section[1:], where)
    if items and items[-1] == "-":
        raise PDDLError(f"{where}: :types ends in '-'")
    for i, item in enumerate(items[:-1]):
        if item == "-" and items[i + 1].lower() != "object":
            raise PDDLError(f"{where}: type hierarchies are not supported (parent type {items[i + 1]})")
    return tuple(t for i, t in enumerate(items) if t != "-" and (i == 0 or items[i - 1] != "-"))


def _predicates(section: _List, types, where: str) -> dict[str, tuple[str, ...]]:
    out = {}
    for decl in section[1:]:
        if not isinstance(decl, _List) or not decl or not isinstance(decl[0], str):
            raise PDDLError(f"{where}, line {section.line}: expected (Predicate ?arg - type ...)")
        if decl[0] in out:
            raise PDDLError(f"{where}, line {decl.line}: predicate {decl[0]} declared twice")
        out[decl[0]] = tuple(t for _, t in _typed(decl[1:], types, f"{where}, predicate {decl[0]}"))
    return out


def _atom(expr, predicates, arg_types: dict[str, str], where: str) -> Atom:
    """One atom over the names in `arg_types` (variables of an action, or a problem's objects)."""
    line = f"{where}, line {getattr(expr, 'line', '?')}"
    if not isinstance(expr, _List) or not expr or not isinstance(expr[0], str):
        raise PDDLError(f"{line}: expected an atom (Predicate arg ...)")
    name = expr[0]
    if _key(name) in ("not", "or", "imply", "exists", "forall", "when", "="):
        raise PDDLError(f"{line}: ({name} ...) is not supported here (only atoms, conjunctions and delete effects)")
    args = _names(expr[1:], line)
    if name not in predicates:
        raise PDDLError(f"{line}: undeclared predicate {name}")
    if len(args) != len(predicates[name]):
        raise PDDLError(f"{line}: {name} takes {len(predicates[name])} argument(s), got {len(args)}")
    for arg, want in zip(args, predicates[name]):
        if arg not in arg_types:
            raise PDDLError(f"{line}: unknown {'variable' if arg.startswith('?') else 'object'} {arg} in {name}")
        if arg_types[arg] != want:
            raise PDDLError(f"{line}: {name} wants a {want}, got {arg} - {arg_types[arg]}")
    return (name,) + tuple(args)


def _conjuncts(expr, where: str) -> list:
    """The parts of `(and ...)`, or the expression itself; `()` is the empty conjunction."""
    if not isinstance(expr, _List):
        raise PDDLError(f"{where}: expected a parenthesised formula, got {expr}")
    return list(expr[1:]) if expr and _key(expr[0]) == "and" else ([expr] if expr else [])


def _effects(expr, predicates, arg_types, where: str) -> tuple[tuple[Atom, ...], tuple[Atom, ...]]:
    add, delete = [], []
    for part in _conjuncts(expr, where):
        if isinstance(part, _List) and part and _key(part[0]) == "not":
            if len(part) != 2:
                raise PDDLError(f"{where}, line {part.line}: (not ...) takes one atom")
            delete.append(_atom(part[1], predicates, arg_types, where))
        else:
            add.append(_atom(part, predicates, arg_types, where))
    return tuple(add), tuple(delete)


def _fields(action: _List, where: str) -> dict[str, object]:
    """`:parameters X :precondition Y :effect Z` -> {':parameters': X, ...}."""
    rest, out = action[2:], {}
    if len(rest) % 2:
        raise PDDLError(f"{where}: expected :keyword value pairs")
    for key, value in zip(rest[::2], rest[1::2]):
        if _key(key) not in (":parameters", ":precondition", ":effect") or _key(key) in out:
            raise PDDLError(f"{where}: unexpected or repeated {key if isinstance(key, str) else '(...)'}")
        out[_key(key)] = value
    return out


def _skill_note(action: _List, name: str, variables, where: str) -> tuple[str, str | None]:
    if not action.notes:
        return name, None  # foreign PDDL: the skill of the same name, one ground slot
    if len(action.notes) > 1:
        raise PDDLError(f"{where}, line {action.notes[1][2]}: more than one '; skill:' line")
    skill, slot, line = action.notes[0]
    if slot is not None and slot not in variables:
        raise PDDLError(f"{where}, line {line}: slot {slot} is not a parameter")
    return skill, slot


def _action(action: _List, types, predicates, domain: str) -> LiftedOperator:
    if len(action) < 2 or not isinstance(action[1], str):
        raise PDDLError(f"domain {domain}, line {action.line}: expected (:action NAME ...)")
    name = action[1]
    where = f"domain {domain}, action {name}"
    fields = _fields(action, where)
    params = fields.get(":parameters", _List(action.line))
    if not isinstance(params, _List):
        raise PDDLError(f"{where}: :parameters needs a parenthesised list")
    params = tuple(_typed(params, types, where))
    arg_types = dict(params)
    if len(arg_types) != len(params) or not all(v.startswith("?") for v in arg_types):
        raise PDDLError(f"{where}: parameters must be distinct ?variables")
    empty = _List(action.line)
    pre = tuple(_atom(p, predicates, arg_types, where) for p in _conjuncts(fields.get(":precondition", empty), where))
    add, delete = _effects(fields.get(":effect", empty), predicates, arg_types, where)
    skill, slot = _skill_note(action, name, arg_types, where)
    return LiftedOperator(name, params, pre, add, delete, skill, slot)


def read_domain(text: str) -> Domain:
    """The `Domain` of a PDDL domain text (see the module docstring for the subset)."""
    name, sections = _header(_parse(text, "domain"), "domain", "domain")
    where = f"domain {name}"
    types, predicates, actions = (), {}, []
    for section in sections:
        key = _key(section[0])
        if key == ":requirements":
            _check_requirements(section, where)
        elif key == ":types":
            types = _types(section, where)
        elif key == ":predicates":
            predicates = _predicates(section, types, where)
        elif key == ":action":
            actions.append(_action(section, types, predicates, name))
        else:
            raise PDDLError(f"{where}, line {section.line}: section {section[0]} is not supported")
    names = [a.name for a in actions]
    if len(set(names)) != len(names):
        raise PDDLError(f"{where}: two actions share a name")
    return Domain(name, types, predicates, tuple(actions))


def read_problem(text: str, domain: Domain) -> Problem:
    """The `Problem` of a PDDL problem text over `domain`; :init is split into static atoms (predicates no
    operator changes) and fluent ones, as `Problem` holds them."""
    name, sections = _header(_parse(text, "problem"), "problem", "problem")
    where = f"problem {name}"
    objects, atoms, goal, seen = {}, [], [], set()
    for section in sections:
        key = _key(section[0])
        if key in seen:
            raise PDDLError(f"{where}, line {section.line}: section {section[0]} given twice")
        seen.add(key)
        if key == ":domain":
            if section[1:] != [domain.name]:
                raise PDDLError(f"{where}: written for domain {' '.join(map(str, section[1:]))}, not {domain.name}")
        elif key == ":requirements":
            _check_requirements(section, where)
        elif key == ":objects":
            pairs = _typed(section[1:], domain.types, f"{where}, :objects")
            objects = dict(pairs)
            if len(objects) != len(pairs):
                raise PDDLError(f"{where}: an object is declared twice")
        elif key == ":init":
            atoms = [_atom(a, domain.predicates, objects, f"{where}, :init") for a in section[1:]]
        elif key == ":goal":
            if len(section) != 2:
                raise PDDLError(f"{where}, line {section.line}: (:goal ...) takes one formula")
            goal = [_atom(a, domain.predicates, objects, f"{where}, :goal") for a in _conjuncts(section[1], where)]
        else:
            raise PDDLError(f"{where}, line {section.line}: section {section[0]} is not supported")
    if ":domain" not in seen:
        raise PDDLError(f"{where}: no (:domain NAME)")
    fluent = domain.fluent_predicates
    return Problem(domain, objects, frozenset(a for a in atoms if a[0] not in fluent),
                   frozenset(a for a in atoms if a[0] in fluent), frozenset(goal))
