"""The model learner (jaxbridge/learn/model/): known operators recovered from synthetic segments, and Multi
Novelty's repaired model, learned from seed 0's exploration over invented and over its declared (given)
predicates, planning what no training task held."""
from __future__ import annotations

import numpy as np
import pytest

import jaxbridge
from envs_jax.base import SkillSpec
from envs_jax.multi_novelty import MultiNovelty
from envs_jax.multi_novelty.tasks import BOTH, task_of
from jaxbridge.learn.model.model import learn_model
from jaxbridge.learn.model.planning import plan
from jaxbridge.learn.model.samplers import Sampler
from jaxbridge.learn.model.segments import Segment, View
from planner import Domain, LiftedOperator, read_domain

CELLS, GATE_CELL, PUSH_WINDOW = 4, 1, 0.1


class GateRow:
    """What the learner reads of an env class, for a row of cells with a gate in cell 1: the model knows
    moves only; a move right out of the gate's cell needs the gate open, and PushGate opens it when the
    robot is there and pushes within 0.1 of the gate's weight."""

    name = "gate_row"
    object_types = {"robot": (), "cell": (), "gate": ("open", "weight")}
    skills = (SkillSpec("MoveRobot"), SkillSpec("PushGate", 0.0, 1.0))
    novelty_predicates = ()  # none declared: the given setting refuses it
    domain = Domain("gate-row", ("robot", "cell", "gate"), {"RobotInCell": ("robot", "cell"), "Adjacent": ("cell", "cell")}, (
        LiftedOperator("MoveRobot", (("?robot", "robot"), ("?cur", "cell"), ("?tgt", "cell")),
                       (("Adjacent", "?cur", "?tgt"), ("RobotInCell", "?robot", "?cur")), (("RobotInCell", "?robot", "?tgt"),),
                       (("RobotInCell", "?robot", "?cur"),), "MoveRobot", "?tgt"),
        LiftedOperator("PushGate", (("?robot", "robot"), ("?gate", "gate")), (), (), (), "PushGate", "?gate")))


def _view(cell: int, gate_open: bool, weight: float, gate_x: float = GATE_CELL + 0.5) -> View:
    names = ("robby", *(f"cell{i}" for i in range(CELLS)), "gate0")
    features = np.zeros((len(names), 2), np.float32)
    features[-1] = (gate_open, weight)
    position = np.zeros((len(names), 3), np.float32)
    position[:, 0] = [cell + 0.5, *(np.arange(CELLS) + 0.5), gate_x]
    adjacent = {("Adjacent", f"cell{i}", f"cell{j}") for i in range(CELLS) for j in (i - 1, i + 1) if 0 <= j < CELLS}
    return View(names, ("robot",) + ("cell",) * CELLS + ("gate",), features, position,
                frozenset({("RobotInCell", "robby", f"cell{cell}")} | adjacent))


def _gate_row_segments(rng: np.random.Generator, calls: int = 300, _view=_view) -> list[Segment]:
    segments = []
    for _ in range(calls):
        cell, gate_open, weight = int(rng.integers(CELLS)), bool(rng.random() < 0.3), float(rng.uniform(0.2, 0.8))
        if rng.random() < 0.6:
            target = int(np.clip(cell + rng.choice([-1, 1]), 0, CELLS - 1))
            blocked = target > cell == GATE_CELL and not gate_open
            after = _view(cell if blocked else target, gate_open, weight)
            segments.append(Segment("MoveRobot", f"cell{target}", 0.0, True, _view(cell, gate_open, weight), after))
        else:
            push = float(rng.random())
            opens = cell == GATE_CELL and abs(push - weight) <= PUSH_WINDOW
            segments.append(Segment("PushGate", "gate0", push, True, _view(cell, gate_open, weight),
                                    _view(cell, gate_open or opens, weight)))
    return segments


def test_the_learner_recovers_a_gates_precondition_its_opening_operator_and_its_push():
    model = learn_model(GateRow, _gate_row_segments(np.random.default_rng(0)))
    moves = {op.name: set(op.pre) - set(GateRow.domain.operators[0].pre) for op in model.domain.operators if op.skill == "MoveRobot"}
    # a move left needs nothing more; any other move an open gate (none: vacuously) where it starts
    assert {frozenset(extra) for extra in moves.values()} == {frozenset({("before_cell_cell", "?tgt", "?cur")}),
                                                              frozenset({("cell_all_gate_open", "?cur")})}
    (push,) = [op for op in model.domain.operators if op.skill == "PushGate"]
    variables = dict((t, v) for v, t in push.params)
    gate, cell, robot = variables["gate"], variables["cell"], variables["robot"]
    assert {("gate_not_open", gate), ("RobotInCell", robot, cell), ("same_place_cell_gate", cell, gate)} <= set(push.pre)
    assert {("gate_open", gate), ("cell_all_gate_open", cell)} <= set(push.add) and ("gate_not_open", gate) in push.delete
    args = ("gate0", f"cell{GATE_CELL}", "robby")
    for weight in (0.3, 0.5, 0.7):  # the push follows the gate's weight, inside the opening window
        assert abs(model.samplers[push.name](_view(GATE_CELL, False, weight), "gate0", args) - weight) < PUSH_WINDOW / 2


def test_the_gate_rows_model_plans_past_a_closed_gate_and_its_pddl_reads_back():
    model = learn_model(GateRow, _gate_row_segments(np.random.default_rng(1)))
    found = plan(model, _view(0, False, 0.5), frozenset({("RobotInCell", "robby", f"cell{CELLS - 1}")}))
    assert [op.skill for op in found] == ["MoveRobot", "PushGate", "MoveRobot", "MoveRobot"]
    read = read_domain(model.pddl())
    assert {op.name: (set(op.pre), set(op.add), set(op.delete), op.skill, op.slot_param) for op in read.operators} == \
        {op.name: (set(op.pre), set(op.add), set(op.delete), op.skill, op.slot_param) for op in model.domain.operators}


class EdgeGateRow(GateRow):
    """GateRow with its gate at its cell's right edge, where no cell is, and two more atoms of the model's:
    the static GateInCell and Facing(robot, gate), which holds while the robot is in the gate's cell and
    which the model's FaceGate makes from anywhere (as Doorknobs' model lets a robot step from doorway to
    doorway past a closed door)."""

    skills = GateRow.skills + (SkillSpec("FaceGate"),)
    domain = Domain("edge-gate-row", GateRow.domain.types,
                    GateRow.domain.predicates | {"GateInCell": ("gate", "cell"), "Facing": ("robot", "gate")},
                    GateRow.domain.operators + (LiftedOperator("FaceGate", (("?robot", "robot"), ("?gate", "gate")), (),
                                                               (("Facing", "?robot", "?gate"),), (), "FaceGate", "?gate"),))


def _edge_view(cell: int, gate_open: bool, weight: float, facing: bool | None = None) -> View:
    view = _view(cell, gate_open, weight, gate_x=GATE_CELL + 0.95)
    facing = cell == GATE_CELL if facing is None else facing
    given = view.given | {("GateInCell", "gate0", f"cell{GATE_CELL}")} | ({("Facing", "robby", "gate0")} if facing else set())
    return View(view.names, view.types, view.features, view.position, given)


def test_a_learned_push_needs_the_gate_it_faces_in_the_cell_it_stands_in_as_the_model_relates_the_robots_places():
    model = learn_model(EdgeGateRow, _gate_row_segments(np.random.default_rng(0), _view=_edge_view))
    (push,) = [op for op in model.domain.operators if op.skill == "PushGate"]
    variables = dict((t, v) for v, t in push.params)
    assert ("GateInCell", variables["gate"], variables["cell"]) in push.pre
    # facing the gate from cell 0 (the model's FaceGate allows it): walk into its cell first, then push
    found = plan(model, _edge_view(0, False, 0.5, facing=True), frozenset({("gate_open", "gate0")}))
    assert [(op.skill, op.slot_object) for op in found] == [("MoveRobot", f"cell{GATE_CELL}"), ("PushGate", "gate0")]


def test_a_sampler_with_no_link_to_its_slot_reads_the_object_its_ground_operator_names():
    # a robot-slot skill whose parameter follows a gate's first feature: of two gates, the operator's own
    sampler = Sampler((1.0, 0.0, 0.0), 0.0, 1.0, input_type="gate")
    view = View(("robby", "gate0", "gate1"), ("robot", "gate", "gate"), np.array([[0, 0], [0.2, 0], [0.7, 0]], np.float32),
                np.zeros((3, 3), np.float32), frozenset())
    assert sampler.input_object(view, "robby", ("robby", "gate1")) == "gate1"
    assert sampler(view, "robby", ("robby", "gate1")) == pytest.approx(0.7)


DIAL_WINDOW = 0.1


class DialRow:
    """A row of cells with a gate in cell 1 that opens while its dial is within 0.1 of the gate's own
    target (each task draws one): the model knows moves, and TurnDial only as touching the gate, where it
    sets the dial to its parameter."""

    object_types = {"robot": (), "cell": (), "gate": ("dial", "target")}
    skills = (SkillSpec("MoveRobot"), SkillSpec("TurnDial", 0.0, 1.0))
    domain = Domain("dial-row", ("robot", "cell", "gate"), {
        "RobotInCell": ("robot", "cell"), "Adjacent": ("cell", "cell"), "GateInCell": ("gate", "cell"), "Touched": ("gate",)}, (
        GateRow.domain.operators[0],
        LiftedOperator("TurnDial", (("?robot", "robot"), ("?cell", "cell"), ("?gate", "gate")),
                       (("GateInCell", "?gate", "?cell"), ("RobotInCell", "?robot", "?cell")), (("Touched", "?gate"),), (),
                       "TurnDial", "?gate")))


def _dial_view(cell: int, dial: float, target: float, touched: bool) -> View:
    view = _view(cell, False, 0.0)
    features = view.features.copy()
    features[-1] = (dial, target)
    given = view.given | {("GateInCell", "gate0", f"cell{GATE_CELL}")} | ({("Touched", "gate0")} if touched else set())
    return View(view.names, view.types, features, view.position, frozenset(given))


def _dial_row_segments(rng: np.random.Generator, calls: int = 400) -> list[Segment]:
    segments = []
    for _ in range(calls):
        cell = GATE_CELL if rng.random() < 0.5 else int(rng.integers(CELLS))
        dial, target, touched = float(rng.random()), float(rng.uniform(0.3, 0.7)), bool(rng.random() < 0.5)
        before = _dial_view(cell, dial, target, touched)
        if rng.random() < 0.5:
            goal = int(np.clip(cell + rng.choice([-1, 1]), 0, CELLS - 1))
            blocked = goal > cell == GATE_CELL and abs(dial - target) > DIAL_WINDOW
            segments.append(Segment("MoveRobot", f"cell{goal}", 0.0, True, before,
                                    _dial_view(cell if blocked else goal, dial, target, touched)))
        else:
            turn = float(rng.random())
            after = _dial_view(cell, turn, target, True) if cell == GATE_CELL else before
            segments.append(Segment("TurnDial", "gate0", turn, True, before, after))
    return segments


@pytest.fixture(scope="module")
def dial_row_model():
    return learn_model(DialRow, _dial_row_segments(np.random.default_rng(2)))


def test_a_move_out_of_the_gates_cell_needs_its_dial_within_a_band_of_its_target_read_off_the_stalls(dial_row_model):
    grammar = dial_row_model.grammar
    needs = {a[0] for op in dial_row_model.domain.operators if op.skill == "MoveRobot" for a in op.pre} - set(DialRow.domain.predicates)
    bands = [p.unary for p in grammar.all_at if p.name in needs]
    # one predicate, the dial's distance to the gate's own target, with a width at the window's edge
    assert [(b.feature_name, b.other_name, b.above) for b in bands] == [("dial", "target", False)]
    assert 0.08 < bands[0].threshold < 0.12


def test_turning_the_dial_a_skill_the_model_knows_learns_the_effect_a_move_needs_and_where_to_turn(dial_row_model):
    band = next(a[0] for op in dial_row_model.domain.operators if op.skill == "MoveRobot" for a in op.pre
                if a[0].startswith("cell_all_gate"))
    turns = [op for op in dial_row_model.learned_operators if op.skill == "TurnDial" and any(a[0] == band for a in op.add)]
    # the model's effect stays: made, or (a dial turned again) already there
    assert turns and all(("Touched", op.slot_param) in op.add + op.pre for op in turns)
    found = plan(dial_row_model, _dial_view(0, 0.0, 0.5, False), frozenset({("RobotInCell", "robby", f"cell{CELLS - 1}")}))
    assert [op.skill for op in found] == ["MoveRobot", "TurnDial", "MoveRobot", "MoveRobot"]
    sampler = dial_row_model.samplers[found[1].name]
    for target in (0.35, 0.5, 0.65):  # the turn follows the gate's target
        assert abs(sampler(_dial_view(GATE_CELL, 0.0, target, False), "gate0", found[1].args) - target) < DIAL_WINDOW / 2


@pytest.fixture(scope="module")
def multi_novelty_segments():
    return jaxbridge.record_segments("multi_novelty", seed=0)


@pytest.fixture(scope="module")
def multi_novelty_model(multi_novelty_segments):
    return jaxbridge.learn_model("multi_novelty", multi_novelty_segments)


def _both_locks_task():
    return task_of(np.random.default_rng(7), 10, (BOTH,))  # one door, keycard and latched: no training task holds one


def test_multi_noveltys_model_from_seed_0s_exploration_opens_a_door_with_both_locks_without_a_bridge(multi_novelty_model):
    run = jaxbridge.plan_alone(multi_novelty_model, "multi_novelty", seed=0, specs=[_both_locks_task()])
    (episode,) = run.episodes
    assert episode.success, episode
    skills = [name.split("(")[0].rsplit("_", 1)[0] for name in episode.operators]
    assert {"FetchKey", "LiftLatch", "PushDoor", "ReplaceFuse", "TurnOnLight"} <= set(skills)


def test_with_the_given_predicates_the_model_reads_only_multi_noveltys_declared_ones_and_still_opens_both_locks(
        multi_novelty_segments):
    model = jaxbridge.learn_model("multi_novelty", multi_novelty_segments, given=True)
    declared = {"door_not_keycard_or_card_held", "door_not_latched_or_released", "door_latch_up", "door_not_latch_up",
                "key_held", "key_not_held", "light_fuse_ok", "light_not_fuse_ok"}  # each literal with its other side
    assert {p.name for p in model.grammar.unary} == declared
    # nothing else invented: a predicate the env's model lacks is a declared one, a relation, or one quantified
    structure = {p.name for p in model.grammar.relations + model.grammar.all_at + model.grammar.spans}
    assert set(model.domain.predicates) - set(MultiNovelty.domain.predicates) <= declared | structure
    assert all(p.unary.name in declared for p in model.grammar.all_at + model.grammar.spans)
    (episode,) = jaxbridge.plan_alone(model, "multi_novelty", seed=0, specs=[_both_locks_task()]).episodes
    assert episode.success, episode


def test_the_model_api_refuses_what_it_cannot_learn_from():
    with pytest.raises(jaxbridge.InputError, match="no segments"):
        jaxbridge.learn_model("multi_novelty", [])
    with pytest.raises(jaxbridge.InputError, match="gate_row declares no novelty predicates"):
        learn_model(GateRow, _gate_row_segments(np.random.default_rng(0), calls=1), given=True)
    with pytest.raises(jaxbridge.InputError, match="positive counts"):
        jaxbridge.record_segments("multi_novelty", seed=0, episodes=0)


def test_planning_alone_on_the_sweep_takes_the_sweeps_tasks_and_refuses_a_count_it_lacks(multi_novelty_model):
    largest = jaxbridge.load_env("multi_novelty").novelty_sweep.counts[-1]
    run = jaxbridge.plan_alone(multi_novelty_model, "multi_novelty", seed=0, num_tasks=1, novelties=largest)
    assert [spec.instances for spec in run.specs] == [largest]
    with pytest.raises(jaxbridge.InputError, match="sweep has counts"):
        jaxbridge.plan_alone(multi_novelty_model, "multi_novelty", seed=0, novelties=largest + 1)
