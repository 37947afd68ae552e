"""The repair approach's host side (learn/approaches.MODEL_REPAIR): each slot's skill calls so far, the model
learned from them, and its tasks planned with that model.

After a cycle, every slot's training episodes are cut into segments (the planner's stalls and the
bridge's fixes among them) and the most recent `KEPT_SEGMENTS` kept. After cycles 1, 2, 4, 8, ... each
slot's model is learned again from them where the bridge acted in the slot's training since its model was
last learned (kept only where its planner alone solves at least as many of the slot's training tasks as
the model before it) and its training and test tasks are planned with it
(learn/model/device.py): a doubling schedule, so early cycles get a model from their first fixes while a
long run relearns only log2(cycles) times.

Beside each checkpoint a run keeps what it resumes from, `model_repair/<cycle>.pkl` (its slots' segments,
models and host planners' answers, which are its tables' rows), and its seeds' latest learned domains as
PDDL, `models/seed<N>.pddl`, and how many operators each seed's model had learned after each cycle,
`learned_operators.csv`.
"""
from __future__ import annotations

import pickle
from pathlib import Path

import jax
import numpy as np

from jaxbridge.core.tasks import TaskArrays, TaskBatch
from jaxbridge.learn.model.device import Capacities, LearnedPlanner, model_batch
from jaxbridge.learn.model.execute import run_planner_alone
from jaxbridge.learn.model.model import LearnedModel, learn_model
from jaxbridge.learn.model.segments import Segment, segments_from_records
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import Setup
from jaxbridge.run import checkpoint
from jaxbridge.run.checkpoint import CheckpointError
from jaxbridge.utils.files import write_atomic
from jaxbridge.utils.progress import SlowWork

LEARNED_CSV = "learned_operators.csv"  # per seed and cycle, the learned operators of the seed's model after it
KEPT_SEGMENTS = 5000  # per slot: about a few cycles of a paper env's training episodes


def relearns_after(cycle: int) -> bool:
    """Whether the models are learned again after `cycle` (1, 2, 4, 8, ...)."""
    return cycle & (cycle - 1) == 0


class ModelRepair:
    """Per slot (run-major: slot i is seed i % num_seeds), its segments and its learned model."""

    def __init__(self, setup: Setup, slots: int):
        self.setup = setup
        self.segments: list[list[Segment]] = [[] for _ in range(slots)]
        self.models: list[LearnedModel | None] = [None] * slots
        self.planners: dict = {}  # (slot, spec, env) -> its host planner (learn/model/device.model_batch)
        self.least = Capacities()  # every planned batch's so far: tables never shrink, so no cycle recompiles for it
        self.tabled = -1  # the planners' answers the cycle's tables hold (-1: none of theirs yet)
        self.learned: list[list[int]] = []  # per cycle, each slot's learned operators after it
        self.bridged = [False] * slots  # the bridge acted in the slot's training since its model was learned

    def after_cycle(self, cycle_number: int, cycle: Cycle) -> None:
        """Keep the cycle's segments; on the schedule, relearn every slot's model; retask `cycle` where that
        changed a model or the host planners answered states its tables lack."""
        records = jax.tree.map(np.asarray, cycle.seeds.unpad(cycle.records))
        for slot, kept in enumerate(self.segments):
            specs, _ = self.seed_tasks(self.setup.train, slot)
            new = segments_from_records(self.setup.train.env, specs, jax.tree.map(lambda x: x[slot], records))
            kept += new
            del kept[:-KEPT_SEGMENTS]
            self.bridged[slot] |= any(segment.by_bridge for segment in new)
        due = self.due(cycle_number)
        if due:
            progress = SlowWork(f"{self.setup.config.env}: planner models learned after cycle {cycle_number}")
            for done, slot in enumerate(due, 1):
                learned = learn_model(self.setup.env_cls, self.segments[slot], given=self.setup.approach.given_predicates)
                self.models[slot], self.bridged[slot] = self.kept_model(slot, learned), False
                progress(done, len(due))
            self.tabled = -1
        self.learned.append([len(model.learned_operators) if model else 0 for model in self.models])
        if self.tabled != sum(len(planner.cache) for planner in self.planners.values()):
            self.retask(cycle)

    def due(self, cycle_number: int) -> list[int]:
        """The slots to learn again after `cycle_number`: on the schedule, those with calls to learn from and
        no model yet, or bridge calls since their model was learned (plans that needed no bridge teach
        nothing new)."""
        if not relearns_after(cycle_number):
            return []
        return [slot for slot, kept in enumerate(self.segments) if kept and (self.models[slot] is None or self.bridged[slot])]

    def seed_tasks(self, batch: TaskBatch, slot: int) -> tuple[list, np.ndarray]:
        """The specs and horizons of `batch` (seed-major) that belong to the slot's seed."""
        per_seed = batch.size // self.setup.config.num_seeds
        first = (slot % self.setup.config.num_seeds) * per_seed
        return batch.specs[first:first + per_seed], np.asarray(batch.horizons)[first:first + per_seed]

    def kept_model(self, slot: int, learned: LearnedModel) -> LearnedModel:
        """`learned`, unless its planner alone solves fewer of the slot's training tasks than the slot's
        current model's does (a model relearned from more calls can draw a worse threshold; only training
        tasks decide, never test tasks)."""
        current = self.models[slot]
        if current is None:
            return learned
        tasks = dict(zip(*self.seed_tasks(self.setup.train, slot)))
        env = self.setup.train.env
        solved = lambda model: sum(run_planner_alone(env, model, spec, int(h)).success for spec, h in tasks.items())
        return current if solved(current) > solved(learned) else learned

    def retask(self, cycle: Cycle) -> None:
        """`cycle`'s tasks planned with the slots' models, once every slot has one; its tables then hold every
        state the host planners answered so far."""
        if all(model is not None for model in self.models):
            cycle.retask(self.planned(self.setup.train), self.planned(self.setup.test))
            self.tabled = sum(len(planner.cache) for planner in self.planners.values())

    def planned(self, batch: TaskBatch) -> TaskArrays:
        """Every slot's tasks of `batch` (seed-major) planned with its model: TaskArrays [slots, n, ...]."""
        slots = range(len(self.models))
        owner, specs, horizons = [], [], []
        for slot in slots:
            mine, their_horizons = self.seed_tasks(batch, slot)
            owner, specs, horizons = owner + [slot] * len(mine), specs + list(mine), horizons + their_horizons.tolist()
        planned = model_batch(batch.env, specs, owner, dict(enumerate(self.models)), horizons, self.planners, self.least)
        self.least = self.least.at_least(Capacities.of(planned.arrays.tables))
        return jax.tree.map(lambda x: np.reshape(np.asarray(x), (len(slots), -1) + x.shape[1:]), planned.arrays)

    def save(self, run_dirs: list[Path], seeds: list[int], cycle_number: int) -> None:
        """Each run's slots' segments and models beside its checkpoint of `cycle_number` (older ones whose
        checkpoint is gone are deleted), and its seeds' latest domains as PDDL."""
        for i, run_dir in enumerate(run_dirs):
            mine = slice(i * len(seeds), (i + 1) * len(seeds))
            caches = [(slot - mine.start, spec, env, planner.cache) for (slot, spec, env), planner in self.planners.items()
                      if mine.start <= slot < mine.stop]
            state = {"segments": self.segments[mine], "models": self.models[mine], "caches": caches,
                     "learned": [counts[mine] for counts in self.learned], "bridged": self.bridged[mine]}
            for folder in ("model_repair", "models"):
                (run_dir / folder).mkdir(exist_ok=True)
            write_atomic(run_dir / "model_repair" / f"{cycle_number}.pkl", pickle.dumps(state))
            kept = set(checkpoint.sealed_steps(run_dir / "checkpoints")) | {cycle_number}
            for old in (run_dir / "model_repair").glob("*.pkl"):
                if old.stem.isdigit() and int(old.stem) not in kept:
                    old.unlink()
            for seed, model in zip(seeds, self.models[mine]):
                if model is not None:
                    write_atomic(run_dir / "models" / f"seed{seed}.pddl", model.pddl())
            rows = [f"{seed},{c},{n}" for c, counts in enumerate(state["learned"], 1) for seed, n in zip(seeds, counts)]
            write_atomic(run_dir / LEARNED_CSV, "\n".join(["seed,cycle,learned_operators", *rows]) + "\n")

    def restore(self, run_dirs: list[Path], cycle_number: int, cycle: Cycle) -> None:
        """The state saved beside cycle `cycle_number`'s checkpoints, and `cycle` retasked with its models."""
        self.segments, self.models, caches, learned, self.bridged = [], [], [], [], []
        for run_dir in run_dirs:
            state = pickle.loads((run_dir / "model_repair" / f"{cycle_number}.pkl").read_bytes())
            caches += [(len(self.models) + slot, *rest) for slot, *rest in state["caches"]]
            self.segments += state["segments"]
            self.models += state["models"]
            self.bridged += state["bridged"]
            learned.append(state["learned"])
        self.learned = [sum(counts, []) for counts in zip(*learned)]  # each cycle's counts, every run's slots
        for slot, spec, env, cache in caches:  # the planners' answers as they were: the tables' rows
            self.planners[slot, spec, env] = LearnedPlanner.of(env, spec, self.models[slot], cache)
        self.retask(cycle)


def load_models(run_dir: Path, cycle: int, seeds: list[int]) -> dict[int, LearnedModel]:
    """A repair run's models, by seed, as they were after `cycle` (a checkpoint's cycle)."""
    path = Path(run_dir) / "model_repair" / f"{cycle}.pkl"
    if not path.is_file():
        raise CheckpointError(f"{path} is missing: the run's learned models after cycle {cycle}")
    return dict(zip(seeds, pickle.loads(path.read_bytes())["models"]))


def planned_with(batch: TaskBatch, models: dict[int, LearnedModel]) -> TaskBatch:
    """`batch`'s tasks planned with their seeds' learned models."""
    return model_batch(batch.env, batch.specs, batch.seeds.tolist(), models, np.asarray(batch.horizons).tolist())
