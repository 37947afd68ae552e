"""The learned model: the planner's model repaired and extended from segments (`learn_model`), its atoms
and its atoms of a state (planning.py plans with it)."""
from __future__ import annotations

from dataclasses import dataclass

from envs_jax.base import NoveltyEnv
from jaxbridge.learn.model.operators import (Cluster, Examples, bind, cluster_effects, lift, model_bindings,
                                             never_worked, new_operator, repair, typed_objects)
from jaxbridge.learn.model.predicates import Grammar, Literal, make_grammar
from jaxbridge.learn.model.samplers import Sampler, fit_sampler
from jaxbridge.learn.model.segments import Segment, View
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

    def pddl(self) -> str:
        return domain_pddl(self.domain)

    @property
    def learned_operators(self) -> tuple[LiftedOperator, ...]:
        """The operators that are not the env's model's as it was."""
        return tuple(op for op in self.domain.operators if op not in self.base_operators)


def learn_model(env_cls: type[NoveltyEnv], segments: list[Segment]) -> LearnedModel:
    """The env's model repaired and extended from `segments` (see operators.py)."""
    domain, grammar = env_cls.domain, make_grammar(segments, env_cls.object_types)
    cache: dict[int, frozenset[Atom]] = {}
    atoms = lambda view, base=grammar: cache.setdefault(id(view), view.given | base.atoms(view))
    examples = {op.name: _model_examples(op, segments, domain, atoms) for op in domain.operators if op.add or op.delete}
    repaired = [variant for op in domain.operators if op.name in examples for variant in repair(op, examples[op.name], grammar)]
    chosen = {a[0] for op in repaired for a in op.pre} - set(domain.predicates)
    grammar = grammar.with_spans(chosen)
    vocabulary = set(domain.predicates) | chosen | {p.name for p in grammar.unary if isinstance(p, Literal)} \
        | {p.name for p in grammar.relations}
    known = lambda view: frozenset(a for a in atoms(view) if a[0] in vocabulary)
    new_skills = {op.skill for op in domain.operators if not op.add and not op.delete}
    # spans are read, never made: only a precondition may use them (each plan reads them afresh)
    calls = [(s, before, known(s.after), before | grammar.span_atoms(s.before))
             for s in segments if s.skill in new_skills for before in [known(s.before)]]
    clusters = [c for c in cluster_effects(calls, domain) if len(c.segments) >= MIN_CALLS]
    added = [new_operator(c, k, _failures(c, calls, domain), grammar, domain.fluent_predicates) for k, c in enumerate(clusters)]
    made = {a[0] for op in added for a in op.add}
    repaired = [never_worked(op, examples[op.name], grammar, made) if op.name in examples else op for op in repaired]
    used = {a[0] for op in repaired + added for a in op.pre + op.add + op.delete}
    predicates = dict(domain.predicates) | {n: s for n, s in grammar.signatures.items() if n in used}
    types = tuple(dict.fromkeys(domain.types + tuple(env_cls.object_types)))
    learned = Domain(f"{domain.name}-learned", types, predicates, tuple(repaired + added))
    return LearnedModel(learned, grammar, _samplers(env_cls, added, clusters), domain.operators)


def _model_examples(op: LiftedOperator, segments: list[Segment], domain: Domain, atoms) -> Examples:
    """The calls of `op`'s skill its model preconditions allowed, lifted: positive where its effects followed."""
    examples = Examples()
    for segment in (s for s in segments if s.skill == op.skill):
        for binding in model_bindings(op, segment, domain):
            after = segment.after.given
            worked = bind(op.add, binding) <= after and not bind(op.delete, binding) & after
            (examples.positive if worked else examples.negative).append(
                lift(atoms(segment.before), {o: v for v, o in binding.items()}))
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


def _samplers(env_cls: type[NoveltyEnv], operators: list[LiftedOperator], clusters: list[Cluster]) -> dict[str, Sampler]:
    skills, out = {s.name: s for s in env_cls.skills}, {}
    for op, cluster in zip(operators, clusters):
        spec = skills[op.skill]
        if spec.param_low < spec.param_high:
            calls = [(segment, binding.get(op.slot_param)) for segment, binding in cluster.segments]
            out[op.name] = fit_sampler(calls, spec.param_low, spec.param_high)
    return out

