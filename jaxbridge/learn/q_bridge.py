"""The learned bridge: a Q-function over (object-centric features, skill, parameter), as in MapleQ.

Q input = features(s) ++ one_hot(skill over the env's skills + CallPlanner) ++ [param]. The greedy
action is the argmax over every applicable skill with `n_sample` parameters drawn from its sampler
(one for skills whose sampler is a constant) and CallPlanner when applicable. Training explores
epsilon-greedily with the random bridge.
"""
from __future__ import annotations

import functools
import threading
from dataclasses import dataclass
from typing import Any, Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv, tree_where
from jaxbridge.core.bridges import RandomBridge


@dataclass(frozen=True)
class StateSplit:
    """Which entries of a wide observation change within a task (`varying`), which the task fixes
    (`constant`) and which pad it for tasks larger than the env's (`unfilled`: zero in all its states, so
    the buffer does not store them and a fit leaves their weights out): positions in the observation, in
    order. Static: one compilation per split."""

    varying: tuple[int, ...]
    constant: tuple[int, ...]
    unfilled: tuple[int, ...] = ()

    @property
    def width(self) -> int:
        return len(self.varying) + len(self.constant) + len(self.unfilled)

    @property
    def filled(self) -> np.ndarray:
        """The positions of the varying entries, then of the constant ones."""
        return np.array(self.varying + self.constant, int)

    def without_unfilled(self) -> StateSplit:
        """The split of the observation cut to its `filled` entries, in their order: each part one run of
        positions, which the first layer slices (`take_rows`)."""
        varying = len(self.varying)
        return StateSplit(tuple(range(varying)), tuple(range(varying, varying + len(self.constant))))


def task_state_split(env: NoveltyEnv) -> StateSplit | None:
    """The env's full state as varying, task-constant and unfilled entries (None if every entry varies
    and is filled). An entry this env's tasks never fill is unfilled whether or not larger tasks vary it."""
    every = np.arange(env.full_state_size)
    varying, filled = np.isin(every, env.full_state_varying), np.isin(every, env.full_state_filled)
    if (varying & filled).all():
        return None
    positions = lambda mask: tuple(map(int, np.flatnonzero(mask)))
    return StateSplit(positions(varying & filled), positions(~varying & filled), positions(~filled))


@struct.dataclass
class TaskPart:
    """The task-constant entries of an observation given once per task: `values` [T, K] for T tasks and,
    per observation, `index` (int32, broadcastable to the observation's leading axes) into them. The
    first layer then multiplies each task's constants once, not once per transition or candidate."""

    values: jax.Array
    index: jax.Array
    split: StateSplit = struct.field(pytree_node=False)


def at_task(task: TaskPart | None, index: jax.Array | None) -> TaskPart | None:
    """`task` for observations of the training tasks at `index` (None without a split)."""
    return None if task is None else task.replace(index=index)


@struct.dataclass
class SplitInput:
    """A network input given as its parts: `observation` [..., F] and `action` [..., A], the
    observation's leading axes broadcastable to the action's (one observation, many candidate actions),
    and optionally `task`: then `observation` holds only the entries that vary within a task and the
    rest come from the task's constants. The first layer computes each part's share once; same
    parameters as for the whole input [..., F (+ K) + A], same function up to float rounding."""

    observation: jax.Array
    action: jax.Array
    task: TaskPart | None = None

    @property
    def width(self) -> int:
        observed = self.task.split.width if self.task is not None else self.observation.shape[-1]
        return observed + self.action.shape[-1]


class UniformDense(nn.Module):
    """Dense layer initialised as PyTorch's nn.Linear (the authors' network): weights and biases
    uniform in +-scale/sqrt(fan_in)."""

    features: int
    scale: float = 1.0

    @nn.compact
    def __call__(self, x: jax.Array | SplitInput) -> jax.Array:
        split = isinstance(x, SplitInput)
        fan_in = x.width if split else x.shape[-1]
        kernel, bias = uniform_params(self, fan_in, self.features, self.scale)
        if not split:
            return x @ kernel + bias
        action_share = x.action @ kernel[fan_in - x.action.shape[-1]:] + bias
        if x.task is None:
            return x.observation @ kernel[:x.observation.shape[-1]] + action_share
        rows = x.task.split
        task_share = (x.task.values @ take_rows(kernel, rows.constant))[x.task.index]  # once per task, then gathered
        return task_share + x.observation @ take_rows(kernel, rows.varying) + action_share


def uniform_params(module: nn.Module, fan_in: int, features: int, scale: float = 1.0) -> tuple[jax.Array, jax.Array]:
    """A dense layer's kernel [fan_in, features] and bias, declared in `module` (inside its compact call) and
    initialised as PyTorch's nn.Linear: uniform in +-scale/sqrt(fan_in)."""
    bound = scale / np.sqrt(fan_in)
    init = lambda key, shape: jax.random.uniform(key, shape, jnp.float32, -bound, bound)
    return module.param("kernel", init, (fan_in, features)), module.param("bias", init, (features,))


def take_rows(x: jax.Array, positions: tuple[int, ...]) -> jax.Array:
    """x[positions]: a slice where the positions are one ascending run (a gather otherwise, dearer on CPU,
    and so is its gradient's scatter)."""
    if len(positions) and np.all(np.diff(positions) == 1):
        return x[positions[0]:positions[-1] + 1]
    return x[np.array(positions)]


LEAKY_SLOPE = 0.01
ACTIVATIONS = {"leaky_relu": lambda x: nn.leaky_relu(x, LEAKY_SLOPE), "relu": nn.relu}


OUTPUT_SCALES = {"zero": 0.0, "uniform": 1.0}  # TrainConfig.output_init -> the output layer's init bound


def mlp(x: jax.Array | SplitInput, hidden_sizes: Sequence[int], activation: str, output_init: str,
        layer_norm: bool = False) -> jax.Array:
    """Hidden layers of `hidden_sizes`, then a scalar output (inside a compact module)."""
    for size in hidden_sizes:
        x = UniformDense(size)(x)
        x = ACTIVATIONS[activation](nn.LayerNorm()(x) if layer_norm else x)
    return UniformDense(1, scale=OUTPUT_SCALES[output_init])(x)[..., 0]


class _Member(nn.Module):
    hidden_sizes: Sequence[int]
    activation: str
    output_init: str
    layer_norm: bool

    @nn.compact
    def __call__(self, carry: None, x: jax.Array | SplitInput) -> tuple[None, jax.Array]:
        return carry, mlp(x, self.hidden_sizes, self.activation, self.output_init, self.layer_norm)


_SCAN_LOCK = threading.Lock()


def members_scan(member: type[nn.Module], length: int) -> type[nn.Module]:
    """`member` as an ensemble of `length`, one member after another (a scan over their stacked parameters,
    unrolled: a loop's own overhead was 40% of two members' forward and backward pass on a CPU). Built once
    per (member, length) under a lock: flax builds the scanned class from the member's dataclass fields,
    and two approaches' programs traced at once in worker threads raced on them."""
    with _SCAN_LOCK:
        return _members_scan(member, length)


@functools.cache
def _members_scan(member: type[nn.Module], length: int) -> type[nn.Module]:
    return nn.scan(member, variable_axes={"params": 0}, split_rngs={"params": True}, in_axes=nn.broadcast,
                   length=length, unroll=length)


def scaled_input(x: jax.Array | SplitInput, shift: jax.Array, scale: jax.Array) -> jax.Array | SplitInput:
    """(x - shift) / scale per entry of the whole input [I] (a SplitInput's parts each by their rows)."""
    if not isinstance(x, SplitInput):
        return (x - shift) / scale
    part = lambda values, rows: (values - shift[rows]) / scale[rows]
    actions = np.arange(x.width - x.action.shape[-1], x.width)
    if x.task is None:
        return x.replace(observation=part(x.observation, np.arange(x.observation.shape[-1])),
                         action=part(x.action, actions))
    rows = x.task.split
    return x.replace(observation=part(x.observation, np.array(rows.varying)), action=part(x.action, actions),
                     task=x.task.replace(values=part(x.task.values, np.array(rows.constant))))


class QNetwork(nn.Module):
    """MLP with leaky-ReLU hidden layers and a scalar output; optionally an ensemble of such MLPs whose
    value is their minimum (clipped double Q).

    Departures from the authors' ReLU network (docs/design/learning.md): the leaky slope keeps units
    alive under mostly-zero targets, the output layer starts at zero (so the untrained Q is 0; theirs
    starts uniform as PyTorch's default, `output_init`),
    and with `ensemble` > 1 members fitted to the same targets give their minimum, in the argmax and the
    targets alike, so the argmax over sampled parameters does not pick one member's upward error."""

    hidden_sizes: Sequence[int] = (32, 32)
    ensemble: int = 1
    activation: str = "leaky_relu"  # of the hidden units: ACTIVATIONS
    output_init: str = "zero"  # the output layer's initialisation: OUTPUT_SCALES
    # The authors' min-max scaling: the "norm" collection holds x_shift, x_scale [input] and y_shift,
    # y_scale (learn/dqn.py fits them every cycle; they are not trained).
    normalise: bool = False
    layer_norm: bool = False  # a LayerNorm before each hidden activation (PQN's network: learn/pqn.py)

    @nn.compact
    def __call__(self, x: jax.Array | SplitInput, members: bool = False) -> jax.Array:
        """Q of x[..., input] (or of a SplitInput): [...], or every member's, [ensemble, ...], with
        `members`."""
        if self.normalise:
            width = x.width if isinstance(x, SplitInput) else x.shape[-1]
            norm = {name: self.variable("norm", name, init, shape).value for name, init, shape in (
                ("x_shift", jnp.zeros, (width,)), ("x_scale", jnp.ones, (width,)),
                ("y_shift", jnp.zeros, ()), ("y_scale", jnp.ones, ()))}
            x = scaled_input(x, norm["x_shift"], norm["x_scale"])
            q = QNetwork(self.hidden_sizes, self.ensemble, self.activation, self.output_init,
                         layer_norm=self.layer_norm, name="net")(x, members)
            return q * norm["y_scale"] + norm["y_shift"]
        if self.ensemble == 1:  # the plain network, parameters laid out as before ensembles existed
            q = mlp(x, self.hidden_sizes, self.activation, self.output_init, self.layer_norm)[None]
        else:
            # Members one after another, not vmapped: a member axis inside the per-seed program made XLA
            # compile the gradient differently with the number of devices (docs/RELIABILITY.md); each
            # member alone compiles as the plain network.
            scanned = members_scan(_Member, self.ensemble)
            _, q = scanned(self.hidden_sizes, self.activation, self.output_init, self.layer_norm)(None, x)
        return q if members else jnp.min(q, axis=0)


FIRST_LAYER = "UniformDense_0"  # flax names an mlp's layers in order: the first takes the input


def _input_axis(path: tuple) -> int | None:
    """The axis of the input in a leaf of QNetwork variables at tree `path`: the first layer's kernel rows
    (-2), the input scaling's entries (-1); None for a leaf without one."""
    names = [getattr(key, "key", None) for key in path]
    if names[-1] == "kernel" and FIRST_LAYER in names:
        return -2
    return -1 if names[-1] in ("x_shift", "x_scale") else None


def input_rows(tree: Any, rows: np.ndarray) -> Any:
    """`tree` (QNetwork variables, or a state holding them: a learner's, an optimiser's moments) with each
    input-sized leaf cut to the inputs `rows`: the variables of the same network on those inputs alone."""
    def cut(path, leaf):
        axis = _input_axis(path)
        return leaf if axis is None else jnp.take(leaf, rows, axis=axis)
    return jax.tree_util.tree_map_with_path(cut, tree)


def with_input_rows(tree: Any, cut: Any, rows: np.ndarray) -> Any:
    """`tree` updated from `cut` (what `input_rows(tree, rows)` became): the inputs `rows` of each input-sized
    leaf and every other leaf from `cut`, the other inputs' entries as they were."""
    def put(path, leaf, part):
        axis = _input_axis(path)
        if axis is None:
            return part
        return leaf.at[(..., rows, slice(None)) if axis == -2 else (..., rows)].set(part)
    return jax.tree_util.tree_map_with_path(put, tree, cut)


def input_size(env: NoveltyEnv, num_features: int) -> int:
    """Observation ++ one-hot over the skills and CallPlanner ++ one parameter."""
    return num_features + env.num_skills + 1 + 1


def encode_action(env: NoveltyEnv, skill: jax.Array, param: jax.Array) -> jax.Array:
    """The action's part of the Q-network input: one_hot(skill) ++ [param]; broadcasts."""
    shape = jnp.broadcast_shapes(skill.shape, param.shape)
    one_hot = jax.nn.one_hot(skill, env.num_skills + 1)
    return jnp.concatenate([jnp.broadcast_to(one_hot, shape + one_hot.shape[-1:]),
                            jnp.broadcast_to(param, shape)[..., None]], axis=-1)


def encode(env: NoveltyEnv, features: jax.Array, skill: jax.Array, param: jax.Array) -> jax.Array:
    """The Q-network input for (features, skill, param); broadcasts over leading axes."""
    action = encode_action(env, skill, param)
    shape = jnp.broadcast_shapes(features.shape[:-1], action.shape[:-1])
    return jnp.concatenate([jnp.broadcast_to(features, shape + features.shape[-1:]),
                            jnp.broadcast_to(action, shape + action.shape[-1:])], axis=-1)


# Observations at least this wide (the full-state ablations) enter the candidates' Q as a SplitInput: their
# first-layer share is computed once per decision. Narrower features stay whole (docs/design/learning.md).
SPLIT_FROM_FEATURES = 32


def candidates_input(env: NoveltyEnv, features: jax.Array, skill: jax.Array, param: jax.Array,
                     task: TaskPart | None = None, split: bool = False) -> jax.Array | SplitInput:
    """The Q-network input for one observation `features` [F] (its varying entries, with `task`) and
    candidates (skill, param) [C]; `split`: as a SplitInput whatever its width (a network that asks)."""
    if split or task is not None or features.shape[-1] >= SPLIT_FROM_FEATURES:
        return SplitInput(features, encode_action(env, skill, param), task)
    return encode(env, features, skill, param)


def batch_input(env: NoveltyEnv, features: jax.Array, skill: jax.Array, param: jax.Array,
                task: TaskPart | None = None) -> jax.Array | SplitInput:
    """The Q-network input for a batch of (features, skill, param) [B]: whole, or split by `task`."""
    if task is None:
        return encode(env, features, skill, param)
    return SplitInput(features, encode_action(env, skill, param), task)


def candidate_skills(env: NoveltyEnv, n_sample: int) -> np.ndarray:
    """Static list of candidate skills: n_sample copies of each skill with a uniform sampler, one of
    each constant-parameter skill, then CallPlanner."""
    counts = [n_sample if s.param_low != s.param_high else 1 for s in env.skills]
    return np.array(sum(([k] * c for k, c in enumerate(counts)), []) + [env.num_skills], np.int32)


def sample_candidates(env: NoveltyEnv, skills: np.ndarray, key: jax.Array, stratified: bool = True) -> jax.Array:
    """float32[C]: a parameter for each candidate from its skill's sampler (0 for CallPlanner).

    Stratified: the j-th of a skill's n candidates is uniform in the j-th n-quantile of the sampler's
    range. Each sample is still uniform over the range when its stratum is picked at random, but the n
    samples cover the range evenly, so a narrow good interval (a door key's +-0.1) is never missed by
    chance. Without `stratified`, the n samples are independent (the authors')."""
    _, first, counts = np.unique(skills, return_index=True, return_counts=True)
    stratum = np.arange(len(skills)) - np.repeat(first, counts)
    size = np.repeat(counts, counts)
    u = (stratum + jax.random.uniform(key, skills.shape)) / size if stratified else jax.random.uniform(key, skills.shape)
    is_env_skill = skills < env.num_skills
    return jnp.where(is_env_skill, env.param_from_uniform(np.minimum(skills, env.num_skills - 1), u), 0.0)


def best_candidate(env: NoveltyEnv, net: QNetwork, q_params: Any, obs: BridgeObs, skills: np.ndarray, key: jax.Array,
                   task: TaskPart | None = None, stratified: bool = True) -> tuple[BridgeAction, jax.Array]:
    """argmax over the candidates applicable in `obs` of Q(features, skill, param); also returns the max Q."""
    params = sample_candidates(env, skills, key, stratified)
    split = getattr(net, "split_candidates", False)  # e.g. a network per failure signature: one per observation
    q = net.apply(q_params, candidates_input(env, obs.features, jnp.asarray(skills), params, task, split))
    q = jnp.where(obs.num_ground[skills] > 0, q, -jnp.inf)
    best = jnp.argmax(q)
    return BridgeAction(skill=jnp.asarray(skills)[best], param=params[best]), q[best]


@struct.dataclass
class QBridgeParams:
    q: Any  # network parameters
    epsilon: jax.Array  # float32: exploration rate (0 = greedy)


@dataclass(frozen=True)
class QBridge:
    """Epsilon-greedy Q bridge; with epsilon 0 it is the greedy bridge used at test time. Training explores
    with the random bridge."""

    env: NoveltyEnv
    net: QNetwork
    n_sample: int
    explore_ground_operators: bool = False  # epsilon's draw: over ground operators, not skills (RandomBridge)
    stratified: bool = True  # the candidates' parameters: stratified, or independent (sample_candidates)

    def __call__(self, params: QBridgeParams, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        k_explore, k_random, k_greedy = jax.random.split(key, 3)
        skills = candidate_skills(self.env, self.n_sample)
        greedy, _ = best_candidate(self.env, self.net, params.q, obs, skills, k_greedy, stratified=self.stratified)
        explore = jax.random.uniform(k_explore) < params.epsilon
        random = RandomBridge(self.env, self.explore_ground_operators)(None, obs, k_random)
        return tree_where(explore, random, greedy)
