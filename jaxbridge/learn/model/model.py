"""The learned model: the planner's model repaired and extended from segments (`learn_model`), its atoms
and its atoms of a state (planning.py plans with it)."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from envs_jax.base import NoveltyEnv
from jaxbridge.learn.model.operators import (Cluster, Examples, bind, cluster_effects, lift, model_bindings,
                                             never_worked, new_operator, repair, typed_objects)
from jaxbridge.learn.model.predicates import Data, Grammar, Literal, given_grammar, make_grammar, read_data, stall_cuts
from jaxbridge.learn.model.samplers import Sampler, fit_sampler
from jaxbridge.learn.model.segments import Segment, View
from jaxbridge.utils.errors import InputError
from planner.strips import Atom, Domain, LiftedOperator, domain_pddl

MIN_CALLS = 2  # an effect seen once is not made an operator (a random call's accident)


@dataclass(frozen=True)
class LearnedModel:
    domain: Domain  # the repaired model: the env's, its stalling operators repaired, the learned ones added
    grammar: Grammar
    samplers: dict[str, Sampler]  # by operator name, for skills with a parameter range
    base_operators: tuple[LiftedOperator, ...] = ()  # the env's model's, as it was

    def atoms(self, view: View) -> frozenset[Atom]:
        """The model's atoms that hold in `view`: the planner's own and the invented ones it uses."""
        return view.given | frozenset(a for a in self.grammar.atoms(view) if a[0] in self.domain.predicates)

    def pddl(self, learned_only: bool = False) -> str:
        """The model as a PDDL domain; `learned_only`: with the learned operators alone (what to read)."""
        return domain_pddl(replace(self.domain, operators=self.learned_operators) if learned_only else self.domain)

    def with_domain(self, domain: Domain, skills: Sequence[str]) -> "LearnedModel":
        """This model planning with `domain` (this model's written as PDDL, edited or not), its samplers by
        operator name; InputError for a foreign one: a type, predicate (or its arguments' types) or skill
        (one of `skills`, the env's) this model does not define."""
        known = dict(self.domain.predicates) | self.grammar.signatures
        foreign = ([f"type {t}" for t in domain.types if t not in self.domain.types]
                   + [f"predicate {n}{'' if n not in known else ' with arguments ' + ' '.join(s)}"
                      for n, s in domain.predicates.items() if tuple(known.get(n, ())) != tuple(s)]
                   + [f"skill {op.skill} (action {op.name})" for op in domain.operators if op.skill not in skills])
        if foreign:
            raise InputError(f"domain {domain.name} is not this model's: {foreign[0]} is not defined here"
                             + (f" (and {len(foreign) - 1} more)" if len(foreign) > 1 else ""))
        return replace(self, domain=domain)

    @property
    def learned_operators(self) -> tuple[LiftedOperator, ...]:
        """The operators that are not the env's model's as it was."""
        return tuple(op for op in self.domain.operators if op not in self.base_operators)


def learn_model(env_cls: type[NoveltyEnv], segments: list[Segment], given: bool = False) -> LearnedModel:
    """The env's model repaired and extended from `segments` (see operators.py), over predicates invented
    from the object view, or with `given` over the env's declared `novelty_predicates` (InputError if
    it declares none)."""
    if given and not env_cls.novelty_predicates:
        raise InputError(f"learn_model: {env_cls.name} declares no novelty predicates (given=True needs them)")
    domain, data = env_cls.domain, read_data(segments, env_cls.object_types)
    calls = {op.name: _model_calls(op, segments, domain) for op in domain.operators if op.add or op.delete}
    if given:
        grammar = given_grammar(data, env_cls.novelty_predicates)
    else:
        grammar = make_grammar(data, _cuts(calls, make_grammar(data), data))
    atoms = _memo_atoms(grammar)
    examples = {name: _examples(found, atoms) for name, found in calls.items()}
    repaired = [variant for op in domain.operators if op.name in examples for variant in repair(op, examples[op.name], grammar)]
    chosen = {a[0] for op in repaired for a in op.pre} - set(domain.predicates)
    # a stall's threshold stays where a repair chose it (the atoms known so far are a superset); the
    # declared predicates stay as declared
    grammar = (grammar if given else make_grammar(data, grammar.cuts(chosen))).with_spans(chosen)
    relations = {p.name for p in grammar.relations}
    literals = {p.name for p in grammar.unary if isinstance(p, Literal)}
    new_skills = {op.skill for op in domain.operators if not op.add and not op.delete}
    # a skill the model knows is learned only for what a repaired precondition needs: its other changes
    # (an arm that rises after a twist) would tie the variant to preconditions no operator makes
    vocabulary = {skill: set(domain.predicates) | chosen | relations | (literals if skill in new_skills else set())
                  for skill in {s.skill for s in segments}}
    known = lambda view, skill: frozenset(a for a in atoms(view) if a[0] in vocabulary[skill])
    # spans are read, never made: only a precondition may use them (each plan reads them afresh)
    effects = [(s, before, after, before | grammar.span_atoms(s.before)) for s in segments
               for before, after in [(known(s.before, s.skill), known(s.after, s.skill))]
               if s.skill in new_skills or any(a[0] in chosen for a in after - before)]
    clusters = [c for c in cluster_effects(effects, domain) if len(c.segments) >= MIN_CALLS]
    # numbered on from the repaired variants (MoveRobot_0, MoveRobot_1): no two operators share a name
    added = [new_operator(c, len(repaired) + k, _failures(c, effects, domain), grammar, domain.fluent_predicates)
             for k, c in enumerate(clusters)]
    made = {a[0] for op in added for a in op.add}
    repaired = [never_worked(op, examples[op.name], grammar, made) if op.name in examples else op for op in repaired]
    used = {a[0] for op in repaired + added for a in op.pre + op.add + op.delete}
    predicates = dict(domain.predicates) | {n: s for n, s in grammar.signatures.items() if n in used}
    types = tuple(dict.fromkeys(domain.types + tuple(env_cls.object_types)))
    learned = Domain(f"{domain.name}-learned", types, predicates, tuple(repaired + added))
    return LearnedModel(learned, grammar, _samplers(env_cls, added, clusters, grammar), domain.operators)


def _memo_atoms(grammar: Grammar):
    """view -> its model atoms and `grammar`'s, each view's read once (segments share their end views)."""
    cache: dict[int, tuple[object, frozenset[Atom]]] = {}

    def atoms(view) -> frozenset[Atom]:
        if id(view) not in cache:
            cache[id(view)] = (view, view.given | grammar.atoms(view))  # the view held: its id stays its own
        return cache[id(view)][1]
    return atoms


def _model_calls(op: LiftedOperator, segments: list[Segment], domain: Domain) -> list[tuple[Segment, dict[str, str], bool]]:
    """The calls of `op`'s skill its model preconditions allowed: (call, variable -> object, whether its
    effects followed)."""
    out = []
    for segment in (s for s in segments if s.skill == op.skill):
        for binding in model_bindings(op, segment, domain):
            after = segment.after.given
            out.append((segment, binding, bind(op.add, binding) <= after and not bind(op.delete, binding) & after))
    return out


def _cuts(calls: dict[str, list], grammar: Grammar, data: Data) -> dict:
    """The thresholds the model operators' stalls ask for (`stall_cuts`), of every operator that both
    worked and stalled."""
    cuts: dict = {}
    for found in calls.values():
        if any(w for *_, w in found) and not all(w for *_, w in found):
            for measure, values in stall_cuts([(s.before, b, w) for s, b, w in found], grammar, data).items():
                cuts.setdefault(measure, set()).update(values)
    return cuts


def _examples(calls: list[tuple[Segment, dict[str, str], bool]], atoms) -> Examples:
    """A model operator's calls lifted: positive where its effects followed."""
    examples = Examples()
    for segment, binding, worked in calls:
        (examples.positive if worked else examples.negative).append(lift(atoms(segment.before), {o: v for v, o in binding.items()}))
    return examples


def _failures(cluster: Cluster, calls, domain: Domain) -> list[frozenset[Atom]]:
    """The atoms before each call of the cluster's skill that changed nothing, on an object of its slot's type."""
    slot, slot_type = cluster.params[0]
    out = []
    for segment, before, after, _ in calls:
        if segment.skill == cluster.skill and before == after and segment.slot_object is not None and \
                typed_objects(segment.before, domain).get(segment.slot_object) == slot_type:
            out.append(lift(before, {segment.slot_object: slot}))
    return out


def _samplers(env_cls: type[NoveltyEnv], operators: list[LiftedOperator], clusters: list[Cluster],
              grammar: Grammar) -> dict[str, Sampler]:
    skills, out = {s.name: s for s in env_cls.skills}, {}
    for op, cluster in zip(operators, clusters):
        spec = skills[op.skill]
        if spec.param_low < spec.param_high:
            variable, input_type, links = _input(op, grammar, env_cls.object_types)
            calls = [(segment, binding.get(variable)) for segment, binding in cluster.segments]
            out[op.name] = fit_sampler(calls, spec.param_low, spec.param_high, input_type, links)
    return out


def _input(op: LiftedOperator, grammar: Grammar, object_types) -> tuple[str | None, str | None, tuple]:
    """The variable a sampler reads (the first with features whose literals the effects change, else the
    slot's), its type where it is not the slot's, and the relations of the preconditions tying it to the slot."""
    changed = {a[1] for a in op.add + op.delete if grammar.is_literal(a[0])}
    variable = next((v for v, t in op.params if v in changed and object_types.get(t)), op.slot_param)
    if variable == op.slot_param:
        return variable, None, ()
    links = tuple((grammar.relation(a[0]), a[1] == op.slot_param) for a in op.pre
                  if grammar.relation(a[0]) and set(a[1:]) == {variable, op.slot_param})
    return variable, dict(op.params)[variable], links
