"""One bridge per failure signature (issue 54): a Q-network of its own for each (stalled operator's
skill, type of the object it stalled at), the RAPid-Learn-style answer to the paper's second limitation.

The observation ends with the signature's two one-hots (`core/signatures.signature_features`); they
pick the member, which sees the rest of the observation and the action, as ours' network does. The
members are one stacked parameter pytree indexed by the member id (their number is static: one per
signature the env declares and one for the rest, `core/signatures.signature_members`), so a seed's
networks are one array per layer, and a minibatch's gradient reaches each member only through its own
signature's transitions.
"""
from __future__ import annotations

from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from jaxbridge.core.signatures import signature_index
from jaxbridge.learn.q_bridge import QNetwork, SplitInput


class SignatureQNetwork(nn.Module):
    """Q(features ++ signature one-hots, skill, param) = member[signature](features, skill, param), each
    member a QNetwork (its ensemble, if any, inside it). Takes QNetwork's inputs: a whole input [..., F + S
    + A] or a SplitInput, whose action's leading axes are the observation's, or none (one observation and
    its candidates, as the greedy argmax gives them: then only its member runs)."""

    shape: tuple[int, int]  # (stalled skills, object types), each with "none": core/signatures.signature_shape
    members: tuple[int, ...]  # the member of each signature id: core/signatures.signature_members
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
        features = observation[..., :-width]
        index = jnp.asarray(self.members, jnp.int32)[signature_index(observation[..., -width:], self.shape)]
        member = self.member()
        sample = SplitInput(jnp.zeros(features.shape[-1]), jnp.zeros(self.action_width))
        stacked = self.param("members", lambda key: jax.vmap(lambda k: member.init(k, sample)["params"])(
            jax.random.split(key, max(self.members) + 1)))

        q = lambda params, x: member.apply({"params": params}, x, members)
        if not index.shape:  # one observation: its member alone, its first layer's share once for the candidates
            return q(jax.tree.map(lambda p: p[index], stacked), SplitInput(features, action))
        # A batch of observations (a minibatch, relabelling's targets): every member on every row, each row
        # then takes its own member's value, so no other member's parameters get a gradient from it. Dense
        # products of the few members cost less than gathering a member's parameters per row.
        whole = jnp.concatenate([features, jnp.broadcast_to(action, features.shape[:-1] + action.shape[-1:])], -1)
        values = jax.vmap(q, in_axes=(0, None))(stacked, whole)  # [members, (ensemble,) *lead]
        return jnp.take_along_axis(values, jnp.broadcast_to(index, values.shape[1:])[None], axis=0)[0]
