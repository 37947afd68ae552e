"""Double DQN for the bridge policy (the paper's learner): state, targets, minibatch updates, and the learner
contract's methods over them (learn/learner.py)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import struct

from envs_jax.base import BridgeObs, NoveltyEnv
from jaxbridge.core.config import ParamSamples, TrainConfig
from jaxbridge.core.learner_settings import DQNSettings, PolyakPer, TargetInit
from jaxbridge.core.observations import token_measured_entries
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.optim import clipped_adam
from jaxbridge.learn.q_bridge import (QNetwork, StateSplit, TaskPart, at_task, batch_input, best_candidate,
                                      candidate_skills, encode_action, input_rows, input_size, task_state_split,
                                      with_input_rows)
from jaxbridge.learn.replay import ReplayBuffer, add, init_buffer, sample_indices
from jaxbridge.learn.transitions import Transition, empty_transitions, for_buffer, successor_features


@struct.dataclass
class DQNState:
    """Everything one seed's double DQN needs to continue exactly where it stopped."""

    params: Any
    target_params: Any
    opt_state: Any
    buffer: ReplayBuffer
    key: jax.Array
    decisions: jax.Array  # int32: training bridge decisions so far (drives epsilon)
    updates: jax.Array  # int32: minibatch updates so far
    norm: Any = None  # with `normalise`: the networks' input and output scaling (QNetwork's "norm")

    @property
    def online(self) -> Any:
        """The online network's variables for `QNetwork.apply` (its parameters, and its scaling if any)."""
        return self.params if self.norm is None else {**self.params, "norm": self.norm}

    @property
    def target(self) -> Any:
        """The target network's variables: its parameters with the online network's scaling."""
        return self.target_params if self.norm is None else {**self.target_params, "norm": self.norm}


@dataclass(frozen=True)
class DQN:
    """The learner's static side, resolved once from a config (learn/setup.py): what every function
    below needs besides the learner state."""

    env: NoveltyEnv  # the training env: its capacity fixes the shapes
    config: TrainConfig
    net: QNetwork
    optimizer: optax.GradientTransformationExtraArgs  # built once; each update gets the hyperparameter leaves
    num_features: int  # the approach's observation width (object-centric features or the full state)
    # A wide observation's task-constant entries, split off (None: the buffer stores whole observations).
    split: StateSplit | None = None
    fit: Callable | None = None  # the cycle's fit to its targets (choose_fit); make_dqn sets it
    noise_entries: np.ndarray | None = None  # the stored entries feature noise perturbs (None: all)

    @property
    def stored_features(self) -> int:
        """The width of an observation in the replay buffer: with a split, only its varying entries."""
        return self.num_features if self.split is None else len(self.split.varying)

    @property
    def fit_rows(self) -> np.ndarray | None:
        """The inputs whose weights a fit trains (`learn`): all but a split observation's unfilled entries. Those
        are zero in every training state, so no gradient reaches their weights and Adam leaves them as they
        are; a fit without them computes the same function on fewer rows (Doorknobs' 2x2 training maps in
        its 5x5 full state: 457 of 2032). The target net's rows stay too: in training they multiply zeros.
        None: every input."""
        if self.split is None or not self.split.unfilled:
            return None
        actions = np.arange(self.split.width, input_size(self.env, self.num_features))
        return np.concatenate([self.split.filled, actions])

    def task_part(self, tasks: Any) -> TaskPart | None:
        """The task-constant entries of the training tasks `tasks` (the env's Task struct, [T]), for the
        buffer's transitions to index (their `task`), laid out for the network on `fit_rows`; None without
        a split."""
        if self.split is None:
            return None
        if tasks is None:
            raise ValueError("a learner with a task-constant split needs its training tasks")
        constant = np.array(self.split.constant)
        values = jax.vmap(lambda task: self.env.full_state(self.env.reset(task))[constant])(tasks)
        split = self.split if self.fit_rows is None else self.split.without_unfilled()
        return TaskPart(values=values, index=jnp.zeros((), jnp.int32), split=split)

    # The learner contract (learn/learner.QLearner), over the functions below.
    settings = DQNSettings  # declared a floor below (core/learner_settings.py), where configs resolve them

    @classmethod
    def create(cls, config: TrainConfig, env: NoveltyEnv, num_features: int, full_state: bool) -> "DQN":
        """With a full-state observation the buffer keeps only its entries that change within a task
        (`split_task_state`)."""
        split = task_state_split(env) if full_state and config.learner.split_task_state else None
        return make_dqn(config, env, num_features, split)

    @property
    def shares_network(self) -> bool:
        # The split approaches give a seed's network to the rollouts once (fast matrix products); the
        # others keep a copy per episode, the layout their published numbers were computed with.
        return self.split is not None

    def init(self, key: jax.Array) -> DQNState:
        return init_learner(self, key)

    def greedy(self, state: DQNState) -> Any:
        return state.online

    @property
    def hyper(self) -> Hyper:
        """Its config's leaves (traced in a cycle: the slot's), for the functions below."""
        return Hyper(**self.config.leaf_values())

    def observe(self, state: DQNState, transitions: Transition, valid: jax.Array) -> DQNState:
        """One transition per bridge decision into the replay buffer, episode after episode."""
        flat = lambda x: x.reshape((-1,) + x.shape[2:])
        return state.replace(buffer=add(state.buffer, jax.tree.map(flat, stored_transitions(self, transitions)),
                                        flat(valid)))

    def learn(self, state: DQNState, decisions: jax.Array, tasks: Any) -> tuple[DQNState, jax.Array, jax.Array]:
        return learn(self, self.hyper, state, decisions, tasks)

    def stored(self, state: DQNState) -> jax.Array:
        return state.buffer.size


def feature_noise_entries(config: TrainConfig, env: NoveltyEnv) -> np.ndarray | None:
    """The observation entries `feature_noise` perturbs: all (None), or of object tokens their measured
    entries alone unless `attention_kind_noise` (core.observations.token_measured_entries)."""
    tokens = get_approach(config.approach).controls.observation.tokens
    return token_measured_entries(env) if tokens and not config.tokens.attention_kind_noise else None


def make_dqn(config: TrainConfig, env: NoveltyEnv, num_features: int, split: StateSplit | None = None) -> DQN:
    net = get_approach(config.approach).q_network(config, env)
    return DQN(env, config, net, clipped_adam(), num_features, split, choose_fit(config), feature_noise_entries(config, env))


def stored_transitions(dqn: DQN, transitions: Transition) -> Transition:
    """A cycle's transitions [episodes, T] as the replay buffer keeps them (transitions.for_buffer): with a
    split, only the entries that change within the task, and the index of the episode's training task."""
    if dqn.split is not None:
        episodes, steps = transitions.reward.shape
        transitions = transitions.replace(
            features=transitions.features[..., np.array(dqn.split.varying)],
            task=jnp.broadcast_to(jnp.arange(episodes, dtype=jnp.int32)[:, None], (episodes, steps)))
    return for_buffer(transitions)


def empty_transition(dqn: DQN) -> Transition:
    """The replay buffer's item: a transition without next_features (transitions.for_buffer), with its
    training task's index when the observation is split."""
    item = empty_transitions((), dqn.stored_features, dqn.env.num_skills, dqn.config.counts_steps)
    return for_buffer(item.replace(task=None if dqn.split is None else jnp.int32(0)))


def init_learner(dqn: DQN, key: jax.Array) -> DQNState:
    """A fresh network, its target (a copy, or with `target_init` "apart" another draw), optimiser and
    empty replay buffer."""
    k_init, k_run = jax.random.split(key)
    env, num_features = dqn.env, dqn.num_features
    sample = jnp.zeros((1, input_size(env, num_features)), jnp.float32)
    variables = dqn.net.init(k_init, sample)
    params, norm = {"params": variables["params"]}, variables.get("norm")  # the scaling is not a parameter
    target = (jax.tree.map(jnp.copy, params) if dqn.config.learner.target_init is TargetInit.COPY
              else {"params": dqn.net.init(jax.random.fold_in(k_init, 1), sample)["params"]})
    return DQNState(params=params, target_params=target, opt_state=dqn.optimizer.init(params),
                    buffer=init_buffer(empty_transition(dqn), dqn.config.learner.buffer_capacity), key=k_run,
                    decisions=jnp.int32(0), updates=jnp.int32(0), norm=norm)


def td_targets(dqn: DQN, hyper: Hyper, params: Any, target_params: Any, batch: Transition, key: jax.Array,
               task: TaskPart | None = None) -> jax.Array:
    """Double DQN: the online net picks a* among the next state's applicable actions (n_target_sample
    parameter samples per skill), the target net values it; no bootstrapping past `done`. With a split,
    `task` holds the training tasks' constants and `batch.task` indexes them. `hyper`: the numeric
    hyperparameters (`Hyper.of(config)`, or a cycle's slot's)."""
    env, config, net = dqn.env, dqn.config, dqn.net
    skills = candidate_skills(env, config.learner.n_target_sample)
    keys = jax.random.split(key, batch.reward.shape[0])
    stratified = config.param_samples is ParamSamples.STRATIFIED
    best, _ = jax.vmap(lambda obs, k, i: best_candidate(env, net, params, obs, skills, k, at_task(task, i), stratified))(
        BridgeObs(batch.next_features, batch.next_num_ground), keys, batch.task)
    next_q = net.apply(target_params, batch_input(env, batch.next_features, best.skill, best.param,
                                                  at_task(task, batch.task)))
    if config.learner.clip_bootstrap:
        next_q = jnp.clip(next_q, 0.0, 1.0 + hyper.call_planner_bonus)
    if batch.steps is not None:  # semi-MDP: what follows the transition comes step_gamma^steps later
        late = config.step_gamma ** batch.steps.astype(jnp.float32)
        return batch.reward * late + jnp.where(batch.done, 0.0, hyper.gamma * late * next_q)
    # gamma inside the select: a traced gamma's product next to the sum is fused into a multiply-add,
    # a constant's is not (docs/DESIGN.md, "Hyperparameters as leaves"); this way both round it first.
    return batch.reward + jnp.where(batch.done, 0.0, hyper.gamma * next_q)


RELABEL_CHUNK = 1024


def relabel(dqn: DQN, hyper: Hyper, learner: DQNState, key: jax.Array, task: TaskPart | None = None) -> jax.Array:
    """float32[capacity]: TD targets of every stored transition, recomputed once per cycle with the
    current nets (as the authors' code does), in chunks up to the buffer's fill level."""
    buffer = learner.buffer
    chunks = -(-buffer.capacity // RELABEL_CHUNK)
    data = jax.tree.map(lambda x: jnp.pad(x, [(0, chunks * RELABEL_CHUNK - x.shape[0])] + [(0, 0)] * (x.ndim - 1))
                        .reshape((chunks, RELABEL_CHUNK) + x.shape[1:]), buffer.data)

    def chunk_targets(i, targets):
        batch = jax.tree.map(lambda x: x[i], data)
        slots = i * RELABEL_CHUNK + jnp.arange(RELABEL_CHUNK)
        batch = batch.replace(next_features=successor_features(buffer.data.features, slots))
        y = td_targets(dqn, hyper, learner.online, learner.target, batch, jax.random.fold_in(key, i), task)
        return targets.at[i].set(y)

    filled = (buffer.size + RELABEL_CHUNK - 1) // RELABEL_CHUNK
    targets = jax.lax.fori_loop(0, filled, chunk_targets, jnp.zeros((chunks, RELABEL_CHUNK), jnp.float32))
    return targets.reshape(-1)[: buffer.capacity]


def fit_scaling(dqn: DQN, buffer: ReplayBuffer, targets: jax.Array, task: TaskPart | None) -> dict:
    """The authors' min-max scaling of the stored transitions' inputs and their
    targets: shift = the minimum, scale = the range, at least 1; an empty buffer leaves it the identity."""
    stored = jnp.arange(buffer.capacity) < buffer.size
    data = buffer.data
    action = encode_action(dqn.env, data.skill, data.param)

    def bounds(x):  # per column over the stored rows
        return (jnp.min(jnp.where(stored[:, None], x, jnp.inf), axis=0),
                jnp.max(jnp.where(stored[:, None], x, -jnp.inf), axis=0))
    (low_f, high_f), (low_a, high_a) = bounds(data.features), bounds(action)
    if task is not None:  # a split observation: its task-constant entries are the training tasks' values
        split = task.split
        whole = lambda varying, constant: (jnp.zeros(split.width).at[np.array(split.varying)].set(varying)
                                           .at[np.array(split.constant)].set(constant))
        low_f, high_f = whole(low_f, jnp.min(task.values, axis=0)), whole(high_f, jnp.max(task.values, axis=0))
    low, high = jnp.concatenate([low_f, low_a]), jnp.concatenate([high_f, high_a])
    (y_low,), (y_high,) = bounds(targets[:, None])
    empty = buffer.size == 0
    return {"x_shift": jnp.where(empty, 0.0, low), "x_scale": jnp.where(empty, 1.0, jnp.maximum(high - low, 1.0)),
            "y_shift": jnp.where(empty, 0.0, y_low), "y_scale": jnp.where(empty, 1.0, jnp.maximum(y_high - y_low, 1.0))}


def minibatch_noise(key: jax.Array, updates: jax.Array, shape: tuple) -> jax.Array:
    """Standard normal noise for the minibatch features of the updates numbered `updates` [n]: [n, *shape],
    update u's own draw from the learner's `key` folded with u (a fresh draw per update). Drawn for a
    cycle's updates at once, the same numbers as one draw per update at a third less cost: threefry's
    lowering costs per call, and a draw per update was a fifth of Doorknobs' update."""
    return jax.vmap(lambda u: jax.random.normal(jax.random.fold_in(key, u), shape))(updates)


def noise_shape(shape: tuple, entries: np.ndarray | None) -> tuple:
    """The shape of the noise for features of `shape` perturbed at `entries` of their last axis (None: all)."""
    return shape if entries is None else shape[:-1] + (len(entries),)


def with_noise(features: jax.Array, noise: jax.Array, entries: np.ndarray | None) -> jax.Array:
    """`features` plus `noise` at `entries` of their last axis (None: everywhere). The noise is spread to the
    features' width by a gather from it and a zero (a scatter-add costs a third of an update on a CPU)."""
    if entries is None:
        return features + noise
    source = np.full(features.shape[-1], len(entries))
    source[entries] = np.arange(len(entries))
    padded = jnp.concatenate([noise, jnp.zeros(noise.shape[:-1] + (1,), noise.dtype)], -1)
    return features + jnp.take(padded, source, axis=-1)


def perturbed(features: jax.Array, scale: float, key: jax.Array, update: jax.Array,
              entries: np.ndarray | None) -> jax.Array:
    """`features` plus `scale` times update `update`'s own `minibatch_noise`, drawn for `entries` alone."""
    noise = minibatch_noise(key, update[None], noise_shape(features.shape, entries))[0]
    return with_noise(features, scale * noise, entries)


def update_step(dqn: DQN, hyper: Hyper, learner: DQNState, targets: jax.Array, index: jax.Array,
                task: TaskPart | None = None, noise: jax.Array | None = None) -> tuple[DQNState, jax.Array]:
    """One Adam step on the minibatch of (transition, target) at buffer slots `index`, then a polyak
    step of the target net. With `feature_noise`, the features are perturbed by `noise` (this update's
    `minibatch_noise`; drawn here if not given)."""
    env, config, net = dqn.env, dqn.config, dqn.net
    batch = jax.tree.map(lambda d: d[index], learner.buffer.data)
    features = batch.features
    if config.learner.feature_noise > 0:
        features = (perturbed(features, config.learner.feature_noise, learner.key, learner.updates, dqn.noise_entries)
                    if noise is None else with_noise(features, config.learner.feature_noise * noise, dqn.noise_entries))

    def loss_fn(params):
        variables = learner.replace(params=params).online
        q = net.apply(variables, batch_input(env, features, batch.skill, batch.param, at_task(task, batch.task)),
                      members=True)
        error = q - targets[index]
        if learner.norm is not None:  # the authors' loss is on the scaled targets
            error = error / learner.norm["y_scale"]
        return jnp.mean(error ** 2), jnp.max(jnp.abs(q))  # every member fits the targets

    (loss, q_abs_max), grads = jax.value_and_grad(loss_fn, has_aux=True)(learner.params)
    updates, opt_state = dqn.optimizer.update(grads, learner.opt_state, learner.params, max_norm=hyper.grad_clip,
                                             learning_rate=hyper.learning_rate)
    params = optax.apply_updates(learner.params, updates)
    target = learner.target_params
    if config.learner.polyak_per is PolyakPer.UPDATE:
        target = optax.incremental_update(params, target, config.learner.polyak_tau)
    learner = learner.replace(params=params, target_params=target, opt_state=opt_state,
                              updates=learner.updates + 1)
    return learner, (loss, q_abs_max)


def fit_until_no_better(dqn: DQN, hyper: Hyper, learner: DQNState, targets: jax.Array,
                        task: TaskPart | None) -> tuple[DQNState, jax.Array, jax.Array]:
    """The authors' fit: minibatch updates until `fit_patience` of them in a row
    found no lower minibatch loss, or `updates_per_cycle` were made, then the weights that scored the
    lowest loss are restored (those a minibatch was evaluated with, before its step). Each seed stops on
    its own (a while loop); none runs while the buffer is empty. Returns as `learn`."""
    config = dqn.config.learner

    def more(carry):
        learner, _, _, since_best, done, _, _ = carry
        return (learner.buffer.size > 0) & (done < config.updates_per_cycle) & (since_best < config.fit_patience)

    def update(carry):
        learner, best_params, best_loss, since_best, done, loss_sum, q_abs = carry
        key, k_sample = jax.random.split(learner.key)
        index = sample_indices(learner.buffer, k_sample, config.batch_size)
        updated, (loss, q_abs_max) = update_step(dqn, hyper, learner.replace(key=key), targets, index, task)
        better = loss < best_loss
        best_params = jax.tree.map(lambda p, b: jnp.where(better, p, b), learner.params, best_params)
        return (updated, best_params, jnp.where(better, loss, best_loss), jnp.where(better, 0, since_best + 1),
                done + 1, loss_sum + loss, jnp.maximum(q_abs, q_abs_max))

    start = (learner, learner.params, jnp.float32(jnp.inf), jnp.int32(0), jnp.int32(0), jnp.float32(0.0),
             jnp.float32(0.0))
    learner, best_params, _, _, done, loss_sum, q_abs = jax.lax.while_loop(more, update, start)
    return learner.replace(params=best_params), loss_sum / jnp.maximum(done, 1).astype(jnp.float32), q_abs


def minibatch_indices(config: TrainConfig, learner: DQNState) -> tuple[jax.Array, jax.Array]:
    """(the key after the updates, int32[updates_per_cycle, batch_size]: each update's buffer slots).

    Update u's slots come from the u-th key of a chain of splits, uniformly over the stored items. All
    are drawn before the updates: the same numbers as a split and a draw inside each update, but one
    vectorised draw instead of a thousand small ones (a fifth of an update's time on a CPU)."""
    def next_key(key, _):
        key, k_sample = jax.random.split(key)
        return key, k_sample

    key, sample_keys = jax.lax.scan(next_key, learner.key, None, length=config.learner.updates_per_cycle)
    return key, jax.vmap(lambda k: sample_indices(learner.buffer, k, config.learner.batch_size))(sample_keys)


def track_target(config: TrainConfig, learner: DQNState, decisions: jax.Array) -> DQNState:
    """The authors' polyak schedule: one soft update of the target towards the online net per training
    bridge decision, i.e. (1 - tau)^decisions of the old target is kept."""
    if config.learner.polyak_per is not PolyakPer.DECISION:
        return learner
    keep = (1.0 - config.learner.polyak_tau) ** decisions.astype(jnp.float32)
    target = jax.tree.map(lambda t, p: keep * t + (1.0 - keep) * p, learner.target_params, learner.params)
    return learner.replace(target_params=target)


def learn(dqn: DQN, hyper: Hyper, learner: DQNState, decisions: jax.Array,
          tasks: Any = None) -> tuple[DQNState, jax.Array, jax.Array]:
    """After a cycle's episodes (`decisions` training bridge decisions): track the target net, relabel
    the buffer, then `updates_per_cycle` minibatch updates (none while the buffer is empty), on the
    network's `fit_rows`. `tasks`: the training tasks the buffer's `task` indices refer to (needed with a
    split); `hyper`: the numeric hyperparameters (`Hyper.of(config)`, or a cycle's slot's).
    Returns the learner, the mean loss and the largest |Q| predicted in the minibatches."""
    config, rows = dqn.config, dqn.fit_rows
    task = dqn.task_part(tasks)
    whole = learner = track_target(config, learner, decisions)
    if rows is not None:  # the fit's network, optimiser moments and scaling on the filled inputs only
        learner = input_rows(learner, rows)
    key, k_relabel = jax.random.split(learner.key)
    targets = relabel(dqn, hyper, learner, k_relabel, task)  # with the previous cycle's scaling
    learner = learner.replace(key=key)
    if learner.norm is not None:
        learner = learner.replace(norm=fit_scaling(dqn, learner.buffer, targets, task))
    if config.learner.reset_optimizer:  # the authors' new Adam for every cycle's fit
        learner = learner.replace(opt_state=dqn.optimizer.init(learner.params))
    learner, loss, q_abs_max = dqn.fit(dqn, hyper, learner, targets, task)
    return (learner if rows is None else with_input_rows(whole, learner, rows)), loss, q_abs_max


def fixed_updates(dqn: DQN, hyper: Hyper, learner: DQNState, targets: jax.Array,
                  task: TaskPart | None) -> tuple[DQNState, jax.Array, jax.Array]:
    """Ours' fit: exactly `updates_per_cycle` minibatch updates (none take effect while the buffer is
    empty). Returns as `learn`."""
    buffer = learner.buffer  # read by every update, written by none: outside the loop's carry
    ready = buffer.size > 0  # nothing stored yet (no decision so far): no update takes effect

    def body(fitted, draws):
        index, noise = draws
        updated, (loss, q_abs_max) = update_step(dqn, hyper, fitted.replace(buffer=buffer), targets, index, task, noise)
        stats = (jnp.where(ready, loss, 0.0), jnp.where(ready, q_abs_max, 0.0))
        # Selecting per update rather than once after the scan: the same values, but XLA fuses the
        # update differently without it and the last bits change (the runs in docs/ would not reproduce).
        return jax.tree.map(lambda a, b: jnp.where(ready, a, b), updated.replace(buffer=None), fitted), stats

    config = dqn.config
    key, indices = minibatch_indices(config, learner)
    noise = (minibatch_noise(learner.key, learner.updates + jnp.arange(config.learner.updates_per_cycle),
                             noise_shape(indices.shape[1:] + (dqn.stored_features,), dqn.noise_entries))
             if config.learner.feature_noise > 0 else None)
    fitted, (losses, q_abs) = jax.lax.scan(body, learner.replace(buffer=None), (indices, noise))
    learner = fitted.replace(buffer=buffer, key=jnp.where(ready, key, learner.key))
    return learner, jnp.mean(losses), jnp.max(q_abs)


def no_updates(dqn: DQN, hyper: Hyper, learner: DQNState, targets: jax.Array,
               task: TaskPart | None) -> tuple[DQNState, jax.Array, jax.Array]:
    """`updates_per_cycle` 0: the learner as it is, zero loss and |Q|."""
    return learner, jnp.float32(0.0), jnp.float32(0.0)


def choose_fit(config: TrainConfig) -> Callable:
    """A cycle's fit to the relabelled targets, chosen once from the config: none, ours' fixed number of
    updates, or the authors' early-stopping fit (`fit_patience`)."""
    if config.learner.updates_per_cycle == 0:
        return no_updates
    return fit_until_no_better if config.learner.fit_patience else fixed_updates
