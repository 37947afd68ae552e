"""One bridge per failure signature (issue 54): a Q-network of its own for each (stalled operator's
skill, type of the object it stalled at), the RAPid-Learn-style answer to the paper's second limitation.

The observation ends with the signature's two one-hots (`core/signatures.signature_features`); they
pick the member, which sees the rest of the observation and the action, as ours' network does. The
members are one stacked parameter pytree indexed by the signature id (their number is static: the env's
planner skills x object types, each with "none"), so a seed's networks are one array per layer, and a
minibatch's gradient reaches each member only through its own signature's transitions.
"""
from __future__ import annotations

import math
from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from jaxbridge.core.signatures import signature_index
from jaxbridge.learn.q_bridge import QNetwork, SplitInput


class SignatureQNetwork(nn.Module):
    """Q(features ++ signature one-hots, skill, param) = member[signature](features, skill, param), each
    member a QNetwork (its ensemble, if any, inside it). Takes QNetwork's inputs: a whole input [..., F + S
    + A] or a SplitInput, whose action's leading axes start with the observation's (one observation and
    its candidates, or one action per observation)."""

    shape: tuple[int, int]  # (stalled skills, object types), each with "none": core/signatures.signature_shape
    action_width: int  # one-hot over the skills and CallPlanner, and the parameter
    hidden_sizes: Sequence[int] = (32, 32)
    activation: str = "leaky_relu"
    output_init: str = "zero"
    layer_norm: bool = False
    ensemble: int = 1
    # Candidates come as a SplitInput (q_bridge.best_candidate): one member per observation, not per candidate.
    split_candidates = True

    def member(self) -> QNetwork:
        return QNetwork(self.hidden_sizes, self.ensemble, self.activation, self.output_init,
                        layer_norm=self.layer_norm, parent=None)

    @nn.compact
    def __call__(self, x: jax.Array | SplitInput, members: bool = False) -> jax.Array:
        observation, action = (x.observation, x.action) if isinstance(x, SplitInput) else (
            x[..., :-self.action_width], x[..., -self.action_width:])
        width = sum(self.shape)
        features, index = observation[..., :-width], signature_index(observation[..., -width:], self.shape)
        member = self.member()
        sample = SplitInput(jnp.zeros(features.shape[-1]), jnp.zeros(self.action_width))
        count = self.shape[0] * self.shape[1]
        stacked = self.param("members", lambda key: jax.vmap(lambda k: member.init(k, sample)["params"])(
            jax.random.split(key, count)))

        def q(params, features, action):  # one observation (and its candidates) with its member
            return member.apply({"params": params}, SplitInput(features, action), members)

        lead = index.shape
        if not lead:
            return q(jax.tree.map(lambda p: p[index], stacked), features, action)
        rows = math.prod(lead)
        action = jnp.broadcast_to(action, lead + action.shape[len(lead):])
        flat = lambda a: a.reshape((rows,) + a.shape[len(lead):])
        values = jax.vmap(q)(jax.tree.map(lambda p: p[flat(index)], stacked), flat(features), flat(action))
        if members:  # [rows, ensemble, ...] -> [ensemble, *lead, ...]
            values = jnp.moveaxis(values, 1, 0)
            return values.reshape(values.shape[:1] + lead + values.shape[2:])
        return values.reshape(lead + values.shape[1:])
