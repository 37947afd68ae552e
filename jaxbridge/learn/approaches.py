"""The paper's six approaches, each a configuration of the same machinery (the authors' code).

An approach is which bridge acts when the plan is stuck (the learned Q bridge, a random one, or none),
which parts of the meta-policy it uses (`Controls`: planner, CallPlanner, feature selection) and
whether it learns. Everything else (envs, planner tables, rollout, transitions, double DQN, metrics) is
shared, so a difference in results is the approach's defining difference and nothing more.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

from envs_jax.base import NoveltyEnv
from jaxbridge.core.bridges import Bridge, PurePlanningBridge, RandomBridge
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.episode import Controls, observation_size
from jaxbridge.core.learner_settings import Normalise
from jaxbridge.core.observations import (CLOSEST_OBJECT, FEATURES, FULL_STATE, OBJECT_TOKENS, robot_features,
                                         token_position, token_width)
from jaxbridge.core.signatures import signature_members, signature_shape
from jaxbridge.core.token_settings import AttentionDistance
from jaxbridge.learn.object_q import ObjectQNetwork
from jaxbridge.learn.q_bridge import QBridge, QNetwork
from jaxbridge.learn.signature_q import SignatureQNetwork


class BridgeKind(enum.Enum):
    """Which bridge acts when the plan is stuck."""

    Q = "q"  # the learned Q bridge
    RANDOM = "random"  # a uniformly random choice
    NONE = "none"  # none: the planner re-plans
    LOW_LEVEL = "low_level"  # a brax agent emitting raw actions (learn/low_level; trained by run/low_level_runs)


@dataclass(frozen=True)
class Approach:
    name: str
    label: str  # as in the paper's figures
    bridge: BridgeKind
    controls: Controls = Controls()
    description: str = ""
    algorithm: str = ""  # the low-level baselines' brax trainer ("ppo" or "sac")
    per_signature: bool = False  # a Q-network of its own per failure signature (learn/signature_q.py)
    repairs_model: bool = False  # the planner plans with a model learned from the cycles' skill calls (run/model_repair.py)
    given_predicates: bool = False  # that model over the env's declared novelty predicates, none invented

    def check_env(self, env_cls: type[NoveltyEnv]) -> None:
        """ValueError where the env lacks what the approach reads: a model learner, the env's object view;
        the given predicates, the env's declaration of them."""
        if self.repairs_model and not env_cls.object_types:
            raise ValueError(f"{self.name} learns the planner's model from the object view; {env_cls.name} has none")
        if self.given_predicates and not env_cls.novelty_predicates:
            raise ValueError(f"{self.name} learns over the env's novelty_predicates; {env_cls.name} declares none")

    @property
    def learns(self) -> bool:
        return self.bridge in (BridgeKind.Q, BridgeKind.LOW_LEVEL)

    @property
    def low_level(self) -> bool:
        return self.bridge is BridgeKind.LOW_LEVEL

    def make_bridge(self, env: NoveltyEnv, net: QNetwork, n_sample: int,
                    explore_ground_operators: bool = False, stratified: bool = True) -> Bridge:
        """The approach's bridge (equal arguments give equal bridges: one compiled rollout serves them);
        `explore_ground_operators`: random draws over ground operators (RandomBridge); `stratified`: the
        greedy argmax's parameter samples (q_bridge.sample_candidates)."""
        if self.bridge is BridgeKind.Q:
            return QBridge(env, net, n_sample, explore_ground_operators, stratified)
        if self.bridge is BridgeKind.RANDOM:
            return RandomBridge(env, explore_ground_operators)
        return PurePlanningBridge(env)

    def q_network(self, config: TrainConfig, env: NoveltyEnv) -> QNetwork | ObjectQNetwork | SignatureQNetwork:
        """The Q-network its bridge fits, with `config`'s learner's widths: over the observation vector, over
        object tokens (learned selection, with `config.tokens`), or one per failure signature."""
        s, tokens = config.learner, config.tokens
        if (self.controls.observation.tokens or self.per_signature) and s.normalise is not Normalise.NONE:
            what = "object tokens" if self.controls.observation.tokens else "inputs"
            raise ValueError(f"approach {self.name} does not scale its {what}: no normalise")
        if self.per_signature:
            return SignatureQNetwork(signature_shape(env), signature_members(env), env.num_skills + 2, s.hidden_sizes,
                                     s.activation, s.output_init, ensemble=s.q_ensemble)
        if not self.controls.observation.tokens:
            return QNetwork(s.hidden_sizes, s.q_ensemble, s.activation, s.output_init,
                            normalise=s.normalise is Normalise.MINMAX)
        at_stall = tokens.attention_distance is AttentionDistance.STALL
        left_out = None if tokens.attention_robot_features else robot_features(env)
        return ObjectQNetwork(token_width(env), env.num_skills + 2, token_position(env, at_stall),
                              tokens.attention_preference, left_out, tokens.attention_fixed_penalty,
                              tokens.attention_log_scale, s.hidden_sizes, s.activation, s.output_init,
                              ensemble=s.q_ensemble)

    def observation_size(self, env: NoveltyEnv) -> int:
        """The width of what its bridge sees on `env`."""
        return observation_size(env, self.controls)


APPROACHES = {a.name: a for a in (
    Approach("ours", "ours", BridgeKind.Q, Controls(),
             "bridge policy learning: object-centric features, CallPlanner"),
    Approach("no_feature_selection", "no feature selection", BridgeKind.Q, Controls(observation=FULL_STATE),
             "the bridge sees every object's raw features, padded to the env's largest task"),
    Approach("no_callplanner", "no CallPlanner", BridgeKind.Q, Controls(call_planner=False),
             "no CallPlanner action: once stuck, the bridge keeps control for the episode"),
    Approach("random", "random bridge", BridgeKind.RANDOM, Controls(),
             "a uniformly random applicable action (CallPlanner included) whenever stuck; no learning"),
    Approach("pure_planning", "pure planning", BridgeKind.NONE, Controls(),
             "the planner alone, re-planning whenever stuck; no learning"),
    Approach("maple_q", "Maple Q (pure RL)", BridgeKind.Q, Controls(planner=False, call_planner=False, observation=FULL_STATE),
             "pure RL, no planner: full state, actions grounded on each task's objects"),
)}


# The baseline the paper argues from but never ran (issue 22): low-level continuous RL from the stuck
# state with brax's agents on ours' features; variants add a CallPlanner action dimension, or see the
# full state instead. Not among "all".
LOW_LEVEL = {a.name: a for a in (
    Approach(f"low_level_{algorithm}{suffix}", f"low-level {algorithm.upper()}{label}", BridgeKind.LOW_LEVEL,
             Controls(call_planner=suffix == "_callplanner", low_level=True,
                      observation=FULL_STATE if suffix == "_full_state" else FEATURES),
             f"brax {algorithm.upper()} from the stuck state on the env's raw actions{what}", algorithm)
    for algorithm in ("ppo", "sac")
    for suffix, label, what in (("", "", ""),
                                ("_callplanner", " + CallPlanner", "; one more action dimension hands control to the planner"),
                                ("_full_state", ", full state", "; it sees every object's raw features")))}

# The comparison the paper says it lacks (issue 38; docs/design/approaches.md, "Plan repair"): the bridge's reward
# comes from the plan it got stuck in (RAPid-Learn style: a cost per step, a reward on reaching a later
# state of that plan, which ends its problem), with no CallPlanner; then the plan resumes from the
# state reached, or the planner replans. Not among "all".
PLAN_REPAIR = {a.name: a for a in (
    Approach("plan_progress", "plan progress", BridgeKind.Q, Controls(call_planner=False, plan_progress=True, resume_plan=True),
             "rewarded for reaching a later state of the stuck plan, which then resumes there; no CallPlanner"),
    Approach("plan_progress_replan", "plan progress, replanning", BridgeKind.Q,
             Controls(call_planner=False, plan_progress=True),
             "rewarded for reaching a later state of the stuck plan; then the planner replans; no CallPlanner"),
)}

# The paper's first open question (issue 37): a bridge that learns which object matters instead of
# being shown the closest one's features (learn/object_q.py), and the paper's rule as one function of
# the object view, the same for every env, to compare it with. Not among "all".
SELECTION = {a.name: a for a in (
    Approach("ours_closest_object", "ours, closest object", BridgeKind.Q, Controls(observation=CLOSEST_OBJECT),
             "ours with the paper's selection read off the object view: the interactable object closest to the "
             "robot where it got stuck"),
    Approach("ours_learned_selection", "ours, learned selection", BridgeKind.Q, Controls(observation=OBJECT_TOKENS),
             "ours with every object of the state as a token, attention choosing which matters; no hand-made selection"),
)}

# The paper's second limitation (issue 54): where several kinds of novelty stall the planner, a bridge per
# failure signature (the stalled operator's skill, the type of the object it stalled at), each fitted
# only to its own signature's transitions, and one network that sees the signature beside ours' features.
# Not among "all" (an env adds them to its defaults: Multi Novelty).
SIGNATURE = {a.name: a for a in (
    Approach("ours_per_signature", "ours, a bridge per signature", BridgeKind.Q, Controls(signature=True),
             "ours with a Q-network of its own per failure signature (stalled operator's skill, object type)",
             per_signature=True),
    Approach("ours_signature_conditioned", "ours, signature-conditioned", BridgeKind.Q, Controls(signature=True),
             "ours with one Q-network that sees the failure signature as one-hots beside the features"),
)}

# The bridge's experience into the planner's model (issue 76; docs/design/model_learning.md): ours, and
# between cycles the planner's model relearned from the recent skill calls (its stalls, the bridge's
# fixes), so that its plans compose fixes and the bridge acts only where they stall. Not among "all".
MODEL_REPAIR = {a.name: a for a in (
    Approach("ours_model_repair", "ours, model repair", BridgeKind.Q, Controls(),
             "ours with the planner's model repaired and extended from the skill calls of the cycles so far",
             repairs_model=True),
    Approach("ours_model_repair_given", "ours, model repair, given predicates", BridgeKind.Q, Controls(),
             "ours_model_repair over the env's declared novelty predicates (what perception would report), none "
             "invented: the upper bound of what the operators can learn", repairs_model=True, given_predicates=True),
)}

KNOWN = {**APPROACHES, **LOW_LEVEL, **PLAN_REPAIR, **SELECTION, **SIGNATURE, **MODEL_REPAIR}


def get_approach(name: str) -> Approach:
    if name not in KNOWN:
        raise ValueError(f"unknown approach {name!r}; choose from {', '.join(KNOWN)}")
    return KNOWN[name]
