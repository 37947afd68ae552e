"""The planner's model learned from experience (jaxbridge/learn/model/, docs/design/model_learning.md):
record a seed's training episodes as segments, learn the repaired model from them, plan with it alone.

    segments = jaxbridge.record_segments("multi_novelty", seed=0)
    model = jaxbridge.learn_model("multi_novelty", segments)
    print(model.pddl())                                             # the repaired domain
    jaxbridge.plan_alone(model, "multi_novelty", seed=0, protocol="held_out").solve_rate
"""
from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np

from jaxbridge.api.envs import EnvLike, check_test_protocol, load_env
from jaxbridge.api.config import default_test_protocol
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.tasks import make_batch, test_specs, train_specs
from jaxbridge.learn.model.execute import PlannedEpisode, run_planner_alone
from jaxbridge.learn.model.model import LearnedModel, learn_model as _learn
from jaxbridge.learn.model.segments import Segment, segments_from_records
from jaxbridge.run.evaluate import batch_rollout
from jaxbridge.utils.errors import InputError, refusing


def record_segments(env: EnvLike, seed: int, episodes: int = 20, rollouts: int = 3, bridge: str = "random") -> list[Segment]:
    """The skill calls of `rollouts` passes over the seed's `episodes` training tasks, the meta-policy
    acting with a hand-made bridge ("random": what a bridge explores before it has learned anything)."""
    env_cls = load_env(env)
    if episodes < 1 or rollouts < 1:
        raise InputError(f"episodes and rollouts: positive counts, got {episodes} and {rollouts}")
    specs = train_specs(env_cls, seed, episodes)
    batch = make_batch(env_cls, specs, [seed] * len(specs), horizons=[s.horizon for s in specs])
    with refusing():
        acting = make_bridge(bridge, batch.env)
    segments = []
    for rollout_seed in range(rollouts):
        _, records = batch_rollout(batch, acting, None, rollout_seed, record=True)
        segments += segments_from_records(batch.env, specs, jax.tree.map(np.asarray, records))
    return segments


def learn_model(env: EnvLike, segments: list[Segment], given: bool = False) -> LearnedModel:
    """The env's planner model repaired where its operators stalled and extended with the operators and
    samplers the segments show, over predicates invented from the object view, or with `given` over the
    novelty predicates the env declares (`NoveltyEnv.novelty_predicates`; InputError where it has none)."""
    if not segments:
        raise InputError("learn_model: no segments to learn from")
    return _learn(load_env(env), segments, given)


@dataclass(frozen=True)
class PlannedEpisodes:
    """`plan_alone`'s episodes, one per task."""

    specs: list
    episodes: list[PlannedEpisode]

    @property
    def solve_rate(self) -> float:
        return float(np.mean([e.success for e in self.episodes]))


def plan_alone(model: LearnedModel, env: EnvLike, seed: int, num_tasks: int = 10, protocol: str | None = None,
               specs: list | None = None, novelties: int | None = None) -> PlannedEpisodes:
    """The learned model's planner alone (no bridge: a skill that changes nothing is a failure) on the
    seed's test tasks of `protocol` (default: train.py's), on `specs`, or with `novelties` on tasks of the
    env's generalisation sweep with that many novelty instances (drawn from `seed`, the sweep's horizons)."""
    env_cls, horizon = load_env(env), (lambda spec: spec.horizon)
    if novelties is not None:
        sweep = env_cls.novelty_sweep
        if sweep is None or novelties not in sweep.counts:
            raise InputError(f"novelties: {env_cls.name}'s sweep has counts {sweep.counts if sweep else 'none'}, got {novelties}")
        rng = np.random.default_rng(seed)
        specs, horizon = [sweep.task(rng, novelties) for _ in range(num_tasks)], sweep.horizon
    elif specs is None:
        protocol = protocol or default_test_protocol(env_cls)
        check_test_protocol(env_cls, protocol)
        specs = test_specs(env_cls, seed, num_tasks, protocol)
    return PlannedEpisodes(list(specs), [run_planner_alone(env_cls.for_tasks([s]), model, s, horizon(s)) for s in specs])
