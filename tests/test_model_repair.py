"""The repair approach (learn/approaches.MODEL_REPAIR): a learned model's plan tables on the device
(learn/model/device.py, core/learned_atoms.py) and its host side between cycles (run/model_repair.py)."""
from __future__ import annotations

import dataclasses

import chex
import jax
import numpy as np
import pytest

import jaxbridge
from envs_jax.multi_novelty.env import MultiNovelty
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.learned_atoms import invented_holds
from jaxbridge.core import tasks
from jaxbridge.learn.model.device import Capacities, model_batch
from jaxbridge.learn.model.segments import TaskReader
from jaxbridge.learn.online import make_train
from jaxbridge.learn.setup import make_setup
from jaxbridge.run.evaluate import TrainedPolicy, batch_rollout, run_bridge
from jaxbridge.run.memory import MODEL_TABLE_COPIES, RUNTIME_BYTES, TooBig, model_batches_fit, tree_bytes
from jaxbridge.run.model_repair import LEARNED_CSV, ModelRepair
from jaxbridge.run.runner import Interrupted, train
from jaxbridge.run.sweep import seed_groups, sweep_batch
from run_helpers import cli_in_process
from planner import read_domain

BOTH_LOCKS = "held_out"  # Multi Novelty's protocol of doors with both locks, which no training task holds


def _interrupt_at_cycle_4(cycle: int, learners):
    if cycle == 4:
        raise KeyboardInterrupt
    return learners


@pytest.fixture(scope="module")
def model():
    return jaxbridge.learn_model("multi_novelty", jaxbridge.record_segments("multi_novelty", seed=0, episodes=10, rollouts=2))


@pytest.fixture(scope="module")
def planned(model):
    specs = tasks.test_specs(MultiNovelty, 0, 3, BOTH_LOCKS)
    return model_batch(MultiNovelty.for_tasks(specs), specs, [0] * len(specs), {0: model})


def test_the_device_reads_the_invented_atoms_the_grammar_reads(model, planned):
    """Every invented atom of a task, evaluated on the device from the object view, holds exactly where
    the learner's grammar says it does, along whole episodes (doors opening, keys carried)."""
    _, records = batch_rollout(planned, make_bridge("none", planned.env), record=True)
    env, records = planned.env, jax.tree.map(np.asarray, records)
    compared = 0
    for b, (spec, compiled) in enumerate(zip(planned.specs, planned.compiled)):
        task, reader = compiled.planner.task, TaskReader(env, spec)
        table = jax.tree.map(lambda x: x[b], planned.arrays.tables.model)
        for t in np.flatnonzero(records.live[:, b])[::5]:
            state = jax.tree.map(lambda x: x[t, b], records.env_state)
            objects = jax.tree.map(np.asarray, env.objects(state))
            view = reader.view(objects.type_id, objects.features, objects.position, np.asarray(env.abstract(state)))
            device = np.asarray(invented_holds(table, env.objects(state)))[:len(task.invented)]
            assert {a for a, holds in zip(task.invented, device) if holds} == set(task.invented) & model.grammar.atoms(view)
            compared += 1
    assert compared > 10


def test_the_learned_models_tables_take_doors_with_both_locks_to_the_goal_on_the_device(model, planned):
    """The meta-policy with the learned model's tables and no bridge solves what the env's model cannot, the
    same step for step at a run's larger capacities (a later model may be smaller: the tables keep theirs)."""
    none = make_bridge("none", planned.env)
    repaired = run_bridge(planned, none)
    assert repaired.success.all() and (repaired.stuck_events == 0).all()
    larger = Capacities.of(planned.arrays.tables)
    larger = Capacities(2 * larger.atoms, 2 * larger.predicates, 2 * larger.operators, 2 * larger.rows)
    padded = model_batch(planned.env, planned.specs, [0] * len(planned.specs), {0: model}, least=larger)
    assert Capacities.of(padded.arrays.tables) == larger
    chex.assert_trees_all_equal(run_bridge(padded, none), repaired)
    own = tasks.evaluation_batch(MultiNovelty, [0], len(planned.specs), protocol=BOTH_LOCKS)
    assert not run_bridge(own, none).success.any()


def test_a_repair_run_relearns_writes_its_domains_and_resumes_exactly(tmp_path):
    """Four cycles straight, and three, Ctrl-C, then a resumed one: the same metrics (the fourth cycle plans
    with the model learned after the second, its host planner fresh after the resume and not after the
    third cycle's questions); the seed's domain as PDDL that reads back; the run evaluated
    with its model, whose planner alone takes doors with both locks to the goal."""
    config = jaxbridge.make_config("multi_novelty", approach="ours_model_repair", num_seeds=1, cycles=4,
                                   episodes_per_cycle=4, num_test_tasks=3, updates_per_cycle=2, checkpoint_every=1)
    for run in ("straight", "halted"):
        (tmp_path / run).mkdir()
    train(make_setup(config), tmp_path / "straight")
    with pytest.raises(Interrupted):
        train(make_setup(config), tmp_path / "halted", fault_injection=_interrupt_at_cycle_4)
    train(make_setup(config), tmp_path / "halted", resume=True)
    for written in ("metrics.csv", LEARNED_CSV):
        assert (tmp_path / "halted" / written).read_text() == (tmp_path / "straight" / written).read_text()
    learned = [int(row.split(",")[2]) for row in (tmp_path / "straight" / LEARNED_CSV).read_text().splitlines()[1:]]
    assert len(learned) == 4 and learned[-1] > 0  # seed 0's learned operators after each cycle
    domain = read_domain((tmp_path / "straight" / "models" / "seed0.pddl").read_text())
    assert any(op.name.startswith("MoveRobot_") for op in domain.operators)  # the move, repaired
    policy = jaxbridge.load(tmp_path / "straight")  # evaluated with the model it planned with at its last cycle
    assert policy.tasks().arrays.tables.model is not None
    assert policy.planner_alone(test_protocol=BOTH_LOCKS).success.all()
    written = (tmp_path / "straight" / "models" / "seed0.pddl").read_text()
    unrepaired = tmp_path / "unrepaired.pddl"  # the learned domain with its learned operators taken out
    head, *actions = written.rstrip().removesuffix(")").split("  (:action")  # define's closing paren put back below
    unrepaired.write_text(head + "".join("  (:action" + a for a in actions if not a.split()[0].split("_")[-1].isdigit()) + ")")
    assert not jaxbridge.load(tmp_path / "straight", domain=unrepaired).planner_alone(test_protocol=BOTH_LOCKS).success.any()
    for bad, why in ((written.replace("(:action", "(:acton", 1), "not supported"),
                     (written.replace("RobotInCell", "RobotAt"), "predicate RobotAt is not defined here")):
        (tmp_path / "bad.pddl").write_text(bad)
        refused = cli_in_process("eval.py", str(tmp_path / "straight"), "--domain", str(tmp_path / "bad.pddl"), "--planner-alone")
        assert refused.returncode == 2 and why in refused.stderr and len(refused.stderr.strip().splitlines()) == 1
    policy.trained = dataclasses.replace(policy.trained, models=None)
    with pytest.raises(jaxbridge.InputError, match="learns no planner model"):
        policy.planner_alone()
    with pytest.raises(ValueError, match="relearned on the host between cycles"):
        make_train(make_setup(config))


def test_the_given_predicates_approach_is_refused_for_an_env_that_declares_none():
    """Locked Box (examples/) declares no novelty predicates: the approach that learns over them is refused
    before any work, and the invented one is not."""
    from examples.locked_box import LockedBox

    config = jaxbridge.make_config(LockedBox, approach="ours_model_repair_given", num_seeds=1)
    with pytest.raises(ValueError, match="declares none"):
        make_setup(config, LockedBox)
    make_setup(dataclasses.replace(config, approach="ours_model_repair"), LockedBox)


def test_a_relearned_model_that_solves_fewer_training_tasks_is_not_kept(model):
    """Between two models of a slot the keeper takes the new one unless its planner alone solves fewer of the
    seed's training tasks: the env's own operators (no repair) do not replace the learned model, and the
    learned model replaces them."""
    config = jaxbridge.make_config("multi_novelty", approach="ours_model_repair", num_seeds=1, episodes_per_cycle=2,
                                   num_test_tasks=2)
    repair = ModelRepair(make_setup(config), slots=1)
    unrepaired = dataclasses.replace(model, domain=dataclasses.replace(model.domain, operators=model.base_operators))
    assert repair.kept_model(0, unrepaired) is unrepaired  # a slot's first model is kept as it is
    repair.models[0] = model
    assert repair.kept_model(0, unrepaired) is model
    repair.models[0] = unrepaired
    assert repair.kept_model(0, model) is model


def test_a_slot_is_learned_again_on_the_schedule_only_after_its_bridge_acted(model):
    """Relearning after cycles 1, 2, 4, 8, ...: a slot with no model yet, or with bridge calls since its
    model was learned; not a slot whose plans needed no bridge, nor off the schedule."""
    config = jaxbridge.make_config("multi_novelty", approach="ours_model_repair", num_seeds=2, episodes_per_cycle=2,
                                   num_test_tasks=2)
    repair = ModelRepair(make_setup(config), slots=2)
    repair.segments = [jaxbridge.record_segments("multi_novelty", seed=0, episodes=2, rollouts=1), []]
    assert repair.due(1) == [0] and repair.due(3) == []  # slot 1 has no calls to learn from
    repair.models[0] = model
    assert repair.due(4) == []
    repair.bridged[0] = True
    assert repair.due(4) == [0] and repair.due(6) == []


def test_a_sweep_evaluates_a_repair_runs_seeds_in_groups_that_fit_its_memory(model):
    """Learned tables are per seed and large: a sweep sizes its groups of seeds from the first seed's planned
    batch and the memory allowed, and refuses in one line when not even one seed's fits, as an evaluation
    refuses a planned batch its memory cannot hold."""
    specs = tasks.test_specs(MultiNovelty, 0, 3, BOTH_LOCKS)
    policy = TrainedPolicy(setup=None, step=0, learners=None, models={seed: model for seed in (0, 1, 2)})
    one_seed = policy.planned(sweep_batch(MultiNovelty, specs, [0]))
    per_seed = MODEL_TABLE_COPIES * tree_bytes(one_seed.arrays)
    assert seed_groups(policy, MultiNovelty, specs, [0, 1, 2], None) == [[0, 1, 2]]  # this machine's memory holds all
    assert seed_groups(policy, MultiNovelty, specs, [0, 1, 2], RUNTIME_BYTES + 2 * per_seed) == [[0, 1], [2]]
    with pytest.raises(TooBig, match="--sweep-tasks"):
        seed_groups(policy, MultiNovelty, specs, [0, 1, 2], RUNTIME_BYTES + per_seed // 2)
    with pytest.raises(TooBig, match="--num-tasks"):
        model_batches_fit(one_seed, RUNTIME_BYTES + per_seed // 2)
    unplanned = dataclasses.replace(policy, models=None)
    assert seed_groups(unplanned, MultiNovelty, specs, [0, 1, 2], RUNTIME_BYTES) == [[0, 1, 2]]
