"""Operators from segments: the planner model's operators repaired where they stall, and lifted operators
for what the bridge's skills did that the model does not know.

* **Repair.** A model operator's calls whose model preconditions held are its examples: positive where
  its effects followed, negative where they did not (a stall). Sequential covering adds the fewest atoms
  that rule out every negative while keeping positives, simplest first (a literal before a pair, a pair
  before a quantified pair); positives a first conjunction cannot keep get a variant of their own.
* **New operators** (cluster and intersect): the calls of a skill the model gives no effects are grouped
  by what they changed, lifted over the objects they changed and where the robot was; a group's preconditions are what it
  deleted, the planner model's atoms and the relations true before every call of it, and each changing
  literal on the acted-on object that was true before every success and false before some call of the
  skill on an object of its type that changed nothing (what a failure says was missing), and each
  literal on a feature its effects change that held before every call (where the change started: the
  operator's sampler was fitted there and nowhere else).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

from jaxbridge.learn.model.predicates import Grammar
from jaxbridge.learn.model.segments import Segment, View
from planner.strips import Atom, Domain, LiftedOperator


def lift(atoms, variable_of: dict[str, str]) -> frozenset[Atom]:
    """The atoms over the named objects only, each object replaced by its variable."""
    return frozenset((a[0],) + tuple(variable_of[x] for x in a[1:]) for a in atoms if all(x in variable_of for x in a[1:]))


def bind(atoms, binding: dict[str, str]) -> frozenset[Atom]:
    return frozenset((a[0],) + tuple(binding.get(x, x) for x in a[1:]) for a in atoms)


def typed_objects(view: View, domain: Domain) -> dict[str, str]:
    """{object: type} of a state: the object view's, and those the planner's atoms name."""
    out = {a[i + 1]: t for a in view.given if a[0] in domain.predicates for i, t in enumerate(domain.predicates[a[0]])}
    return out | view.objects()


def model_bindings(op: LiftedOperator, segment: Segment, domain: Domain) -> list[dict[str, str]]:
    """The bindings of `op` that the segment's call grounds: its slot object, preconditions that held."""
    objects = typed_objects(segment.before, domain)
    choices = [[segment.slot_object] if v == op.slot_param else [o for o, t in objects.items() if t == typ]
               for v, typ in op.params]
    variables = [v for v, _ in op.params]
    bindings = (dict(zip(variables, values)) for values in itertools.product(*choices))
    return [b for b in bindings if bind(op.pre, b) <= segment.before.given]


@dataclass
class Examples:
    """An operator's lifted examples: the atoms true before each positive and each negative call."""

    positive: list[frozenset[Atom]] = field(default_factory=list)
    negative: list[frozenset[Atom]] = field(default_factory=list)


def conjunction(pos: list[frozenset[Atom]], neg: list[frozenset[Atom]], candidates: list[Atom],
                grammar: Grammar) -> list[Atom] | None:
    """The fewest atoms, each true before every positive call, that together are false before every
    negative one (greedy set cover: most negatives ruled out first, the simplest on ties); None if the
    atoms every positive shares cannot rule them all out."""
    common = [a for a in candidates if all(a in p for p in pos)]
    term, left = [], list(range(len(neg)))
    while left:
        best = max(common, key=lambda a: (sum(a not in neg[j] for j in left), -grammar.kind(a[0])), default=None)
        if best is None or all(best in neg[j] for j in left):
            return None
        term.append(best)
        left = [j for j in left if best in neg[j]]
    return term


def repair(op: LiftedOperator, examples: Examples, grammar: Grammar) -> list[LiftedOperator]:
    """`op` with the atoms that separate its successes from its stalls: one conjunction every success
    shares, else a case split on a relation between its objects (one variant where it holds, one that
    needs no relation), the fewest atoms in all; `op` itself where nothing stalled or nothing separates."""
    pos, neg = examples.positive, examples.negative
    if not neg or not pos:
        return [op]
    candidates = sorted(set().union(*pos) - set(op.pre), key=lambda a: (grammar.kind(a[0]), a))
    whole = conjunction(pos, neg, candidates, grammar)
    variants = [whole] if whole is not None else _case_split(pos, neg, candidates, grammar)
    named = lambda k: op.name if len(variants) == 1 else f"{op.name}_{k}"
    return [LiftedOperator(named(k), op.params, op.pre + tuple(sorted(term)), op.add, op.delete, op.skill, op.slot_param)
            for k, term in enumerate(variants)] or [op]


def _case_split(pos, neg, candidates, grammar: Grammar) -> list[list[Atom]]:
    """The cheapest split of the positives on a relation atom: [relation + what its side needs, what the
    other side needs against every negative]; [] if none separates."""
    best: list[list[Atom]] = []
    for relation in (a for a in candidates if len(a) == 3 and grammar.kind(a[0]) == 1):
        inside, outside = [p for p in pos if relation in p], [p for p in pos if relation not in p]
        if not inside or not outside:
            continue
        first = conjunction(inside, [n for n in neg if relation in n], candidates, grammar)
        second = conjunction(outside, neg, candidates, grammar)
        if first is not None and second is not None and (not best or len(first) + len(second) + 1 < sum(map(len, best))):
            best = [[relation] + first, second]
    return best


@dataclass
class Cluster:
    """Calls of one skill with one lifted effect: its variables (slot object's first), effects, and each
    call's binding and atoms before."""

    skill: str
    params: tuple[tuple[str, str], ...]
    add: frozenset[Atom]
    delete: frozenset[Atom]
    befores: list[frozenset[Atom]] = field(default_factory=list)  # lifted
    segments: list[tuple[Segment, dict[str, str]]] = field(default_factory=list)  # the call, variable -> object

    @property
    def robot(self) -> str | None:
        """The robot's variable (the first object of the calls' views), None where the effects leave it out."""
        segment, found = self.segments[0]
        return next((v for v, o in found.items() if o == segment.before.names[0]), None)

    def match(self, skill: str, types: dict[str, str], add, delete, slot_object) -> dict[str, str] | None:
        """variable -> object making the call's effects this cluster's, or None."""
        if skill != self.skill or sorted(types.values()) != sorted(t for _, t in self.params):
            return None
        groups = {}
        for v, t in self.params:
            groups.setdefault(t, []).append(v)
        objects = {t: [o for o, ty in types.items() if ty == t] for t in groups}
        for perms in itertools.product(*(itertools.permutations(objects[t]) for t in groups)):
            binding = {v: o for t, perm in zip(groups, perms) for v, o in zip(groups[t], perm)}
            if (slot_object is None or binding[self.params[0][0]] == slot_object) and \
                    bind(self.add, binding) == add and bind(self.delete, binding) == delete:
                return binding
        return None


def cluster_effects(calls: list[tuple[Segment, frozenset[Atom], frozenset[Atom], frozenset[Atom]]],
                    domain: Domain) -> list[Cluster]:
    """Group calls (segment, atoms before, atoms after, atoms a precondition may use before) by skill and
    lifted effect (effectless ones out)."""
    clusters: list[Cluster] = []
    for segment, before, after, seen in calls:
        add, delete = after - before, before - after
        if not add and not delete:
            continue
        objects = typed_objects(segment.before, domain) | typed_objects(segment.after, domain)
        robot = segment.before.names[0]  # where the robot is, in the model's atoms, is where the skill ran
        located = {x for a in segment.before.given if robot in a[1:] for x in a[1:]}
        named = sorted({x for a in add | delete for x in a[1:]} | located | ({segment.slot_object} - {None}))
        types = {o: objects[o] for o in named}
        for cluster in clusters:
            found = cluster.match(segment.skill, types, add, delete, segment.slot_object)
            if found is not None:
                break
        else:
            order = ([segment.slot_object] if segment.slot_object else []) + [o for o in named if o != segment.slot_object]
            found = {f"?{types[o]}{i}": o for i, o in enumerate(order)}
            variable_of = {o: v for v, o in found.items()}
            cluster = Cluster(segment.skill, tuple((v, types[o]) for v, o in found.items()), lift(add, variable_of),
                              lift(delete, variable_of))
            clusters.append(cluster)
        cluster.befores.append(lift(seen, {o: v for v, o in found.items()}))
        cluster.segments.append((segment, found))
    return clusters


def new_operator(cluster: Cluster, index: int, failures: list[frozenset[Atom]], grammar: Grammar,
                 model_fluents: frozenset[str]) -> LiftedOperator:
    """The cluster's operator (see the module): `failures` are the atoms before each effectless call of the
    skill, lifted with its object as the slot variable; `model_fluents` the planner model's fluent
    predicates. The model's static atoms that held before every call are kept where they relate the robot's
    places (the objects of its atoms), and otherwise only to bind a variable nothing else relates to the
    others: the training tasks' one layout makes many of them hold by chance."""
    always = frozenset.intersection(*cluster.befores)
    slot = cluster.params[0][0] if cluster.segments[0][0].slot_object else None

    changed = {(a[1], f) for a in cluster.add | cluster.delete for f in grammar.reads(a[0])}

    def needed(atom: Atom) -> bool:
        if atom in cluster.delete or atom[0] in model_fluents or grammar.kind(atom[0]) >= 1 and len(atom) == 3:
            return True  # what it uses up, where the robot is, relations and spans
        if not grammar.is_literal(atom[0]) or grammar.static_literal(atom[0]):
            return False
        if any((atom[1], f) in changed for f in grammar.reads(atom[0])):
            return True  # where the feature it changes started: its sampler knows no other start
        return atom[1:] == (slot,) and any(atom not in failed for failed in failures)  # a failure lacked it

    pre = [a for a in sorted(always) if needed(a)]
    static = sorted(a for a in always if grammar.kind(a[0]) == 0 and a[0] not in model_fluents)
    # How the robot's places relate holds wherever it stands (the doorway's door is in the robot's room): kept,
    # though the robot's atoms already relate its places to each other
    robot = cluster.robot
    where = {x for a in pre if a[0] in model_fluents and robot in a[1:] for x in a[1:]} - {robot}
    pre += [a for a in static if len(a) > 2 and set(a[1:]) <= where]
    pre += _binding(static, pre, cluster.params)
    return LiftedOperator(f"{cluster.skill}_{index}", cluster.params, tuple(sorted(pre)), tuple(sorted(cluster.add)),
                          tuple(sorted(cluster.delete)), cluster.skill, slot)


def _binding(static: list[Atom], pre: list[Atom], params) -> list[Atom]:
    """The static atoms, in order, that join variables `pre` leaves unrelated (a spanning forest)."""
    group = {v: v for v, _ in params}

    def root(v: str) -> str:
        while group[v] != v:
            v = group[v]
        return v

    def join(atom: Atom) -> bool:
        roots = {root(x) for x in atom[1:] if x in group}
        for r in roots:
            group[r] = min(roots)
        return len(roots) > 1

    for atom in pre:
        join(atom)
    return [a for a in static if join(a)]


def never_worked(op: LiftedOperator, examples: Examples, grammar: Grammar, made: set[str]) -> LiftedOperator:
    """A model operator with stalls and no success: it also needs the opposite of each literal every stall
    showed, where a learned operator makes that opposite (a blown fuse, then a light that never came on)."""
    if examples.positive or not examples.negative:
        return op
    shown = frozenset.intersection(*examples.negative)
    needs = sorted({(grammar.complement(a[0]),) + a[1:] for a in shown if grammar.complement(a[0]) in made})
    return LiftedOperator(op.name, op.params, op.pre + tuple(needs), op.add, op.delete, op.skill, op.slot_param)
