"""The object-token Q-network's settings (learn/object_q.py), held by the run's config as `config.tokens`.

Only an approach whose bridge sees object tokens (the learned selector, ours_learned_selection) builds that
network and reads them; every learner that fits a Q-network builds it the same way, so they are the
network's, not a learner's.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

from jaxbridge.core.settings import Settings, setting


class AttentionDistance(enum.StrEnum):
    STALL = "stall"
    NOW = "now"


@dataclass(frozen=True)
class TokenSettings(Settings):
    attention_distance: AttentionDistance = setting(AttentionDistance.STALL, choices=AttentionDistance)
    """The distance that attention's penalty reads: each object's from the robot where it got stuck ("stall":
    chosen there, as the paper's rule chooses, and kept through the fix) or from the robot now ("now": it
    may drift to an object the fix walks past)."""
    attention_preference: float = setting(2.0, low=0, above=True)
    """How far, in logits, what an object is may move attention against its distance (a tanh bound). Learned
    on a training task's few objects, a wider bound lets a preference override nearness among a test task's
    many; a narrower one cannot pass over a nearer decoy (docs/design/selection.md)."""
    attention_robot_features: bool = False
    """The Q-network reads the robot's own features (Coffee's z, tilt, wrist and fingers) beside its token's
    type and displacement since the stall. Off (ours): it reads what the paper's rule gives, the chosen
    object and how far the robot has moved; attention's query reads the robot's whole token either way.
    Chosen on development seeds (docs/design/selection.md)."""
    attention_fixed_penalty: bool = True
    """Attention's penalty per unit of distance stays at its start (16), so that a preference passes over a
    nearer object only within its bound's reach (attention_preference / 16 squashed units). Off: the
    penalty is learned from there, and where it falls on the doors a preference passes over the fix's door
    to the next. Chosen on development seeds (docs/design/selection.md)."""
    attention_kind_noise: bool = False
    """The learner's `feature_noise` also perturbs each token's type one-hot and interactable flag. Off
    (ours): it perturbs what measures an object, its features and offsets, and what an object is stays
    exact (ours' features have no such entries). Chosen on development seeds (docs/design/selection.md)."""
    attention_log_scale: bool = False
    """Attention's logits times the log of the number of candidates (a scalable softmax), so that a test
    task's many objects do not spread what a training task's few sharpened. Tried on development seeds
    (docs/design/selection.md)."""
