"""The PDDL reader: every built-in env's planner model round-trips through strips.py's writer, skills and
slots included, and malformed or foreign PDDL is refused with one PDDLError line."""
import dataclasses
import re

import pytest
from pyperplan.pddl.parser import Parser

from envs_jax import BUILTIN, KNOBS, VARIANTS, WORLDS, env_class
from planner.pddl import PDDLError, read_domain, read_problem
from planner.strips import domain_pddl, problem_pddl

ENVS = BUILTIN + VARIANTS + KNOBS + WORLDS


def planner_problem(name: str):
    """The planner problem of the env's first training task, at the capacity that task needs."""
    cls = env_class(name)
    spec = cls.train_task(0)
    return cls.for_tasks([spec]).planner_problem(spec)


LSD = planner_problem("light_switch_door")
LSD_DOMAIN, LSD_PROBLEM = domain_pddl(LSD.domain), problem_pddl(LSD)


@pytest.mark.parametrize("name", ENVS)
def test_every_builtin_model_round_trips(name):
    problem = planner_problem(name)
    domain = read_domain(domain_pddl(problem.domain))
    assert domain == problem.domain and domain_pddl(domain) == domain_pddl(problem.domain)
    assert [(op.skill, op.slot_param) for op in domain.operators] == \
        [(op.skill, op.slot_param) for op in problem.domain.operators]
    again = read_problem(problem_pddl(problem), domain)
    assert again == problem and problem_pddl(again) == problem_pddl(problem)


@pytest.mark.parametrize("name", ENVS)
def test_the_skill_comments_leave_pddl_that_pyperplan_reads(name, tmp_path):
    problem = planner_problem(name)
    (tmp_path / "d.pddl").write_text(domain_pddl(problem.domain))
    (tmp_path / "p.pddl").write_text(problem_pddl(problem))
    parser = Parser(str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl"))
    parsed = parser.parse_domain()
    parser.parse_problem(parsed)
    assert sorted(parsed.actions) == sorted(op.name.lower() for op in problem.domain.operators)


def test_a_domain_without_skill_comments_runs_each_action_by_its_own_name():
    foreign = re.sub(r";[^\n]*", "; written elsewhere", LSD_DOMAIN)
    domain = read_domain(foreign)
    assert domain == dataclasses.replace(LSD.domain, operators=tuple(
        dataclasses.replace(op, skill=op.name, slot_param=None) for op in LSD.domain.operators))


def test_the_reader_takes_the_usual_spellings_of_the_subset():
    text = """; a hand-written domain
    (DEFINE (DOMAIN tiny) (:REQUIREMENTS :STRIPS :TYPING)
      (:types cell robot - object)
      (:predicates (At ?r - robot ?c - cell) (Next ?a ?b - cell) (Done))
      (:action Go ; skill: Walk slot: ?to
        :parameters (?r - robot ?from ?to - cell)
        :precondition (AND (At ?r ?from) (Next ?from ?to))
        :effect (AND (At ?r ?to) (NOT (At ?r ?from))))
      (:action Finish :parameters () :precondition (At ?r ?c) :effect (Done)))"""
    with pytest.raises(PDDLError, match=r"action Finish.*unknown variable \?r in At"):
        read_domain(text)
    domain = read_domain(text.replace("(:action Finish :parameters ()", "(:action Finish :parameters (?r - robot ?c - cell)"))
    go, finish = domain.operators
    assert domain.types == ("cell", "robot") and domain.predicates["Next"] == ("cell", "cell")
    assert go.params == (("?r", "robot"), ("?from", "cell"), ("?to", "cell"))
    assert (go.skill, go.slot_param, go.delete) == ("Walk", "?to", (("At", "?r", "?from"),))
    assert (finish.pre, finish.add, finish.skill) == ((("At", "?r", "?c"),), (("Done",),), "Finish")
    problem = read_problem("(define (problem p) (:domain tiny) (:objects a b - cell bot - robot)"
                           " (:init (At bot a) (Next a b)) (:goal (At bot b)))", domain)
    assert problem.objects == {"a": "cell", "b": "cell", "bot": "robot"}
    assert (problem.static, problem.init) == ({("Next", "a", "b")}, {("At", "bot", "a")})
    assert problem.goal == {("At", "bot", "b")}


BAD_DOMAINS = [  # (old, new) in LSD's domain text, and what the message must say
    (None, "unbalanced '(' opened on line 1"),
    (("(:types", "(:types)) (:types"), "unbalanced ')'"),
    ((":typing", ":typing :conditional-effects"), "requirement :conditional-effects is not supported"),
    ((":typing", ":typing :numeric-fluents"), "requirement :numeric-fluents is not supported"),
    (("(Adjacent ?cur ?tgt)", "(Near ?cur ?tgt)"), "action MoveRobot, line 8: undeclared predicate Near"),
    (("?tgt - cell)", "?tgt - room)"), "action MoveRobot: undeclared type room"),
    (("(LightOn ?light)", "(LightOn ?light ?cell)"), "action TurnOnLight, line 14: LightOn takes 1 argument(s), got 2"),
    (("(LightOff ?light))\n    :effect (and (LightOn", "(not (LightOn ?light)))\n    :effect (and (LightOn"),
     "action TurnOnLight, line 13: (not ...) is not supported here"),
    (("(and (LightOn ?light)", "(and (when (LightOff ?light) (LightOn ?light))"), "action TurnOnLight, line 14: (when ...)"),
    (("(Adjacent ?cur ?tgt)", "(Adjacent ?robot ?tgt)"), "action MoveRobot, line 8: Adjacent wants a cell, got ?robot - robot"),
    (("slot: ?tgt", "slot: ?elsewhere"), "action MoveRobot, line 6: slot ?elsewhere is not a parameter"),
    (("robot cell light)", "robot cell light - thing)"), "type hierarchies are not supported (parent type thing)"),
    (("(:types", "(:constants x - cell) (:types"), "section :constants is not supported"),
    (("(domain light-switch-door)", "(problem light-switch-door)"), "expected (define (domain NAME) ...)"),
    ((":precondition", ":pre"), "action MoveRobot: unexpected or repeated :pre"),
]


@pytest.mark.parametrize("change, message", BAD_DOMAINS, ids=[m for _, m in BAD_DOMAINS])
def test_malformed_or_foreign_domains_are_refused_in_one_line(change, message):
    text = LSD_DOMAIN[:-2] if change is None else LSD_DOMAIN.replace(*change, 1)
    assert text != LSD_DOMAIN
    with pytest.raises(PDDLError) as refused:
        read_domain(text)
    assert message in str(refused.value) and "\n" not in str(refused.value)
    assert str(refused.value).startswith("domain")


BAD_PROBLEMS = [
    (("(:domain light-switch-door)", "(:domain coffee)"), "problem task: written for domain coffee, not light-switch-door"),
    (("(LightOff light)", "(LightOff lamp)"), "problem task, :init, line 3: unknown object lamp in LightOff"),
    (("(LightOn light)", "(LightOn cell0)"), "problem task, :goal, line 4: LightOn wants a light, got cell0 - cell"),
    (("robby - robot", "robby - android"), "problem task, :objects: undeclared type android"),
    (("robby - robot", "robby - robot robby - robot"), "problem task: an object is declared twice"),
    (("(:goal (and", "(:goal (or"), "problem task, :goal, line 4: (or ...) is not supported here"),
    (("(:init", "(:init (= (total-cost) 0)"), "(= ...) is not supported here"),
    (("(:goal", "(:metric minimize (total-cost)) (:goal"), "section :metric is not supported"),
]


@pytest.mark.parametrize("change, message", BAD_PROBLEMS, ids=[m for _, m in BAD_PROBLEMS])
def test_malformed_or_foreign_problems_are_refused_in_one_line(change, message):
    text = LSD_PROBLEM.replace(*change, 1)
    assert text != LSD_PROBLEM
    with pytest.raises(PDDLError) as refused:
        read_problem(text, LSD.domain)
    assert message in str(refused.value) and "\n" not in str(refused.value)


def test_no_damage_to_the_text_escapes_as_anything_but_pddlerror():
    """Cut the texts short anywhere and drop any one token: the reader answers or refuses, never crashes."""
    tokens = list(re.finditer(r"[()]|[^\s()]+", LSD_DOMAIN))
    damaged = [LSD_DOMAIN[:k] for k in range(0, len(LSD_DOMAIN), 5)]
    damaged += [LSD_DOMAIN[:t.start()] + LSD_DOMAIN[t.end():] for t in tokens]
    for text in damaged:
        try:
            read_domain(text)
        except PDDLError as refused:
            assert "\n" not in str(refused)
    for k in range(0, len(LSD_PROBLEM), 5):
        with pytest.raises(PDDLError):
            read_problem(LSD_PROBLEM[:k], LSD.domain)
