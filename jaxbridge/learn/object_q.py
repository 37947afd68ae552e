"""A Q-network that learns which object matters (issue 37): attention over the state's object tokens.

The paper selects the features by hand, those of the interactable object closest to the robot where it
got stuck, and names learning that selection as the first thing to try. Here the observation is every
object of the state as a token (`core.observations.object_tokens`: one-hot type, features, offsets
from the robot where it got stuck and now, interactable); the robot's token asks, by attention, which
interactable object to look at, and the Q-value is an MLP of (robot, attended object, action). Any
number of objects, in any order: the same parameters serve the training task's few and the test tasks'
many.
"""
from __future__ import annotations

from typing import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from jaxbridge.core.observations import token_slots
from jaxbridge.learn.q_bridge import SplitInput, UniformDense, members_scan, mlp, uniform_params


class KeyScores(nn.Module):
    """Each token's key (a dense layer of the token) dotted with the query, computed as the token dotted with
    the query taken back through the key's weights: (t W + b).q = t.(W q) + b.q, one vector per observation
    instead of a key per token, the same value up to float rounding (and the same parameters)."""

    features: int

    @nn.compact
    def __call__(self, tokens: jax.Array, query: jax.Array) -> jax.Array:
        kernel, bias = uniform_params(self, tokens.shape[-1], self.features)
        return jnp.einsum("...nd,...d->...n", tokens, query @ kernel.T) + (query @ bias)[..., None]


class ObjectAttention(nn.Module):
    """Tokens [..., N, D] (slot 0 the robot; `position`: the entries of the offset its distance reads; the
    last entry: interactable) -> (attended [..., D], weights [..., N]): the attention-weighted mean of the
    interactable objects' tokens, a soft version of the paper's one selected object. The logits are a
    preference for what the object is, bounded to +-`preference`, less a penalty per unit of distance
    (`near`, or learned from there): attention starts near the robot, as the paper's rule, and learns
    which kinds of object outweigh nearness, within the bound's reach."""

    keys: int  # the width of a token's key and the robot's query
    position: slice
    preference: float  # the token network's attention_preference (core/token_settings.py)
    fixed_penalty: bool  # its attention_fixed_penalty: the penalty stays at `near`
    log_scale: bool  # its attention_log_scale
    near: float = 16.0

    @nn.compact
    def __call__(self, tokens: jax.Array) -> tuple[jax.Array, jax.Array]:
        # The only per-object layer is the key, and it is folded into the query (KeyScores): every stored
        # transition's every object passes it at each update, so it is what attention costs. The values are
        # the tokens themselves; what the Q-network makes of the attended one is its first layer's work, as
        # for ours' selected features.
        query = UniformDense(self.keys, name="query")(tokens[..., 0, :])
        scores = KeyScores(self.keys, name="key")(tokens, query)
        distance = jnp.linalg.norm(tokens[..., self.position], axis=-1)
        penalty = jnp.float32(self.near) if self.fixed_penalty else jax.nn.softplus(
            self.param("near", lambda _: jnp.log(jnp.expm1(jnp.float32(self.near)))))
        # What an object is may move the attention by at most `preference` against its distance: learned on
        # the few objects of a training task, a wide preference overrides distance on the many of a test task.
        content = scores / jnp.sqrt(self.keys)
        logits = self.preference * jnp.tanh(content / self.preference) - penalty * distance
        candidate = tokens[..., -1] > 0.5
        if self.log_scale:  # a test task's many candidates keep the sharpness a training task's few taught
            logits = logits * jnp.log(jnp.maximum(candidate.sum(-1, keepdims=True), 2).astype(jnp.float32))
        # A large finite floor, not -inf: with nothing to look at, the softmax and its gradient stay finite.
        weights = jax.nn.softmax(jnp.where(candidate, logits, -1e9), axis=-1)
        weights = jnp.where(candidate.any(-1, keepdims=True), weights, 0.0)  # none to look at: zeros
        return jnp.einsum("...n,...nd->...d", weights, tokens), weights


class ObjectQMember(nn.Module):
    """One Q-function of object tokens: (robot's token, attended token, action) -> MLP -> scalar (a scan's step)."""

    token_width: int
    action_width: int  # one-hot over the skills and CallPlanner, and the parameter
    position: tuple[int, int]  # the token entries of the offset attention's distance reads
    hidden_sizes: Sequence[int]
    activation: str
    output_init: str
    layer_norm: bool
    preference: float
    robot_features: tuple[int, int] | None  # the robot token's feature entries the MLP leaves out (None: none)
    fixed_penalty: bool
    log_scale: bool

    def encoder(self, **kwargs) -> ObjectAttention:
        return ObjectAttention(max(self.hidden_sizes[0] // 4, 1), slice(*self.position), self.preference,
                               self.fixed_penalty, self.log_scale, **kwargs)

    def tokens(self, observation: jax.Array) -> jax.Array:
        return observation.reshape(observation.shape[:-1] + (-1, self.token_width))

    @nn.compact
    def __call__(self, carry: None, x: jax.Array | SplitInput) -> tuple[None, jax.Array]:
        observation, action = (x.observation, x.action) if isinstance(x, SplitInput) else (
            x[..., :-self.action_width], x[..., -self.action_width:])
        tokens = self.tokens(observation)
        attended, _ = self.encoder(name="attention")(tokens)
        robot = tokens[..., 0, :]
        if self.robot_features is not None:  # zeros in their place: the same layer shapes either way
            robot = robot.at[..., slice(*self.robot_features)].set(0.0)
        # The robot's token and the attended one: the first layer's share of them once per observation,
        # however many candidate actions.
        seen = jnp.concatenate([robot, attended], -1)
        return carry, mlp(SplitInput(seen, action), self.hidden_sizes, self.activation, self.output_init, self.layer_norm)


class ObjectQNetwork(nn.Module):
    """Q(object tokens, skill, param), taking the same inputs as QNetwork (a whole input [..., F + A] or a
    SplitInput), F any multiple of `token_width`; with `ensemble` > 1, members of their own (attention and
    MLP) whose value is their minimum, as QNetwork's."""

    token_width: int
    action_width: int
    position: tuple[int, int]
    preference: float
    robot_features: tuple[int, int] | None  # the robot's own features, left out of the MLP's input (None: none)
    fixed_penalty: bool  # the token network's attention_* settings, declared there
    log_scale: bool
    hidden_sizes: Sequence[int] = (32, 32)
    activation: str = "leaky_relu"
    output_init: str = "zero"
    layer_norm: bool = False
    ensemble: int = 1

    def fields(self) -> tuple:
        return (self.token_width, self.action_width, self.position, tuple(self.hidden_sizes), self.activation,
                self.output_init, self.layer_norm, self.preference, self.robot_features, self.fixed_penalty,
                self.log_scale)

    @nn.compact
    def __call__(self, x: jax.Array | SplitInput, members: bool = False) -> jax.Array:
        if self.ensemble == 1:
            q = ObjectQMember(*self.fields(), name="member")(None, x)[1][None]
        else:  # one after another, as QNetwork's members, for the same reasons
            _, q = members_scan(ObjectQMember, self.ensemble)(*self.fields(), name="members")(None, x)
        return q if members else jnp.min(q, axis=0)


def attention(net: ObjectQNetwork, variables, observation: jax.Array) -> jax.Array:
    """float32[..., T]: how much the robot attends to each token of `observation` (zero for the robot's and
    for objects no skill can act on now); of an ensemble, the first member's."""
    params = variables["params"]
    params = params["member"] if net.ensemble == 1 else jax.tree.map(lambda x: x[0], params["members"])
    member = ObjectQMember(*net.fields(), parent=None)
    return member.encoder(parent=None).apply({"params": params["attention"]}, member.tokens(observation))[1]


def slot_weights(env, net: ObjectQNetwork, q, features: jax.Array) -> np.ndarray:
    """float[T, B, N]: how much each episode's network (q: per-episode parameters [B, ...]) attends to each
    object slot of its observations (features [T, B, tokens]); zero for slots that are not tokens."""
    weights = np.asarray(jax.vmap(lambda q, f: attention(net, q, f), in_axes=(0, 1), out_axes=1)(q, features))
    slots = np.zeros(weights.shape[:-1] + (env.num_objects,), np.float32)
    slots[..., token_slots(env)] = weights
    return slots
