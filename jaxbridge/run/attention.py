"""What a learned object selector looks at (issue 37): over a policy's greedy episodes, how often its most
attended object at a bridge decision is the one the env's fix acts on (`NoveltyEnv.oracle_object`)."""
from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np

from jaxbridge.core.tasks import TaskBatch
from jaxbridge.learn.object_q import ObjectQNetwork, slot_weights
from jaxbridge.run.evaluate import TrainedPolicy, batch_rollout


@dataclass(frozen=True)
class Attention:
    """Per seed: bridge decisions with an object to fix, and the fraction whose most attended object is it."""

    seeds: list[int]
    decisions: np.ndarray  # int[seeds]
    agreement: np.ndarray  # float[seeds]; NaN where a seed made no such decision

    @property
    def overall(self) -> float:
        """Over every such decision of every seed."""
        total = self.decisions.sum()
        return float(np.nansum(self.agreement * self.decisions) / total) if total else float("nan")


def attention_agreement(policy: TrainedPolicy, batch: TaskBatch, rollout_seed: int = 0) -> Attention:
    """Re-run `batch`'s greedy episodes recording each step; at every bridge decision compare the network's
    most attended object with the env's `oracle_object` of that state (decisions without one are left out)."""
    net = policy.setup.learner.net
    if not isinstance(net, ObjectQNetwork):
        raise ValueError(f"approach {policy.config.approach} selects no object by attention (ours_learned_selection does)")
    bridge, greedy, controls = policy.on(batch)
    _, records = batch_rollout(batch, bridge, greedy, rollout_seed, controls, record=True)  # evaluate's episodes
    oracle = np.asarray(jax.vmap(jax.vmap(batch.env.oracle_object))(records.env_state))  # [T, B]
    looked = slot_weights(batch.env, net, greedy.q, records.features).argmax(-1)  # [T, B]: each episode's own network
    counted = np.asarray(records.decided) & (oracle >= 0)
    seeds = list(dict.fromkeys(batch.seeds.tolist()))
    decisions = np.array([counted[:, batch.seeds == s].sum() for s in seeds])
    hits = np.array([(counted & (looked == oracle))[:, batch.seeds == s].sum() for s in seeds])
    return Attention(seeds, decisions, np.where(decisions > 0, hits / np.maximum(decisions, 1), np.nan))
