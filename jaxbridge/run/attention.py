"""What a learned object selector looks at (issue 37): over a policy's greedy episodes, how often its most
attended object at a bridge decision is the one the env's fix acts on (`NoveltyEnv.oracle_object`), and
where it looks instead: the distance rank of what it attends to among the objects a skill can act on."""
from __future__ import annotations

from dataclasses import dataclass

import jax
import numpy as np

from jaxbridge.core.tasks import TaskBatch
from jaxbridge.learn.object_q import ObjectQNetwork, slot_weights
from jaxbridge.run.evaluate import TrainedPolicy, batch_rollout

RANKS = 4  # distance ranks told apart (the nearest, 2nd, 3rd); farther ones share the last


@dataclass(frozen=True)
class Attention:
    """Per seed: bridge decisions with an object to fix, the fraction whose most attended object is it, the
    fraction where it is the nearest candidate (the paper's rule's premise), and the seed's solve rate; over
    every seed, the decisions that looked elsewhere by the distance rank of what they looked at."""

    seeds: list[int]
    decisions: np.ndarray  # int[seeds]
    agreement: np.ndarray  # float[seeds]; NaN where a seed made no such decision
    nearest: np.ndarray  # float[seeds]: the fix's object the nearest candidate; NaN as agreement
    solve_rate: np.ndarray  # float[seeds]: of the seed's episodes
    missed_rank: np.ndarray  # int[RANKS]: misses looking at the nearest, 2nd, 3rd, farther candidate
    by_action: dict[str, tuple[int, int]]  # the action chosen (a skill, or CallPlanner): (hits, decisions)

    @property
    def overall(self) -> float:
        """Over every such decision of every seed."""
        return self._over_decisions(self.agreement)

    def per_seed(self) -> str:
        """eval.py --attention's first line (bench.studies.selection reads it back): each seed's agreement."""
        return "attention on the fix's object, per seed: " + ", ".join(
            f"{s} {a:.2f} of {n}" for s, a, n in zip(self.seeds, self.agreement, self.decisions)) + f"; all {self.overall:.2f}"

    def diagnosis(self) -> str:
        """eval.py --attention's second line: the premise, where misses looked, and the seeds that look right
        but fail (what the network does with the object, not which it picks)."""
        near = self._over_decisions(self.nearest)
        ranks = ", ".join(f"{name} {n}" for name, n in zip(("nearest", "2nd", "3rd", "farther"), self.missed_rank))
        right_but_failing = [s for s, a, r in zip(self.seeds, self.agreement, self.solve_rate) if a >= 0.9 and r < 0.5]
        actions = ", ".join(f"{name} {hits / n:.2f} of {n}" for name, (hits, n) in self.by_action.items() if n)
        return (f"the fix's object is the nearest candidate at {near:.2f} of them; the misses looked at the "
                f"{ranks} (by distance); seeds attending to it at 0.9 or more but solving under 0.5: "
                + (", ".join(map(str, right_but_failing)) or "none") + f"; by the action chosen: {actions}")

    def _over_decisions(self, per_seed: np.ndarray) -> float:
        """A per-seed fraction of decisions as the fraction of every seed's decisions together."""
        total = self.decisions.sum()
        return float(np.nansum(per_seed * self.decisions) / total) if total else float("nan")


def attention_agreement(policy: TrainedPolicy, batch: TaskBatch, rollout_seed: int = 0) -> Attention:
    """Re-run `batch`'s greedy episodes recording each step; at every bridge decision compare the network's
    most attended object with the env's `oracle_object` of that state (decisions without one are left out)."""
    net = policy.setup.learner.net
    if not isinstance(net, ObjectQNetwork):
        raise ValueError(f"approach {policy.config.approach} selects no object by attention (ours_learned_selection does)")
    bridge, greedy, controls = policy.on(batch)
    result, records = batch_rollout(batch, bridge, greedy, rollout_seed, controls, record=True)  # evaluate's episodes
    env = batch.env
    oracle = np.asarray(jax.vmap(jax.vmap(env.oracle_object))(records.env_state))  # [T, B]
    looked = slot_weights(env, net, greedy.q, records.features).argmax(-1)  # [T, B]: each episode's own network
    rank = distance_rank(env, records.env_state)  # [T, B, N]
    counted = np.asarray(records.decided) & (oracle >= 0)
    at = lambda ranks, slot: np.take_along_axis(ranks, np.maximum(slot, 0)[..., None], -1)[..., 0]
    hit, nearest = looked == oracle, at(rank, oracle) == 0
    missed = counted & ~hit
    seeds = list(dict.fromkeys(batch.seeds.tolist()))
    per_seed = lambda x: np.array([(counted & x)[:, batch.seeds == s].sum() for s in seeds])
    decisions = per_seed(counted)
    fraction = lambda x: np.where(decisions > 0, per_seed(x) / np.maximum(decisions, 1), np.nan)
    # Which decisions read the fix's object matters where only some actions need it (a skill with no object)
    chosen = np.asarray(records.skill)
    by_action = {}
    for k, name in enumerate(env.skill_names + ("CallPlanner",)):  # CallPlanner is skill num_skills
        taken = counted & (chosen == k)
        by_action[name] = (int((taken & hit).sum()), int(taken.sum()))
    return Attention(seeds, decisions, fraction(hit), fraction(nearest),
                     np.array([np.asarray(result.success)[batch.seeds == s].mean() for s in seeds]),
                     np.bincount(np.minimum(at(rank, looked)[missed], RANKS - 1), minlength=RANKS), by_action)


def distance_rank(env, states) -> np.ndarray:
    """int[T, B, N]: each slot's rank by distance to the robot among the objects a skill can act on (0: the
    nearest; ties by slot); RANKS for the others."""
    objects = jax.vmap(jax.vmap(env.objects))(states)
    position, candidate = np.asarray(objects.position), np.asarray(objects.interactable)
    distance = np.where(candidate, np.linalg.norm(position - position[..., :1, :], axis=-1), np.inf)
    rank = np.argsort(np.argsort(distance, axis=-1, kind="stable"), axis=-1, kind="stable")
    return np.where(candidate, rank, RANKS)
