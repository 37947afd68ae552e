"""PQN (Gallici et al. 2024, "Simplifying Deep Temporal Difference Learning") as the bridge's learner.

No replay buffer and no target network: each cycle's own decisions are the data. The Q-network has a
LayerNorm before each hidden activation (what keeps TD learning stable without a target network), the
targets are Q(lambda) returns computed once per cycle with the current network, and the network takes
`pqn_epochs` passes over the decisions in `pqn_minibatches` shuffled minibatches. Exploration is the
cycle's epsilon-greedy over the seed's parallel episodes, as for double DQN; CallPlanner, feature selection
and the approaches are the same. It implements the learner contract (learn/learner.py).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import struct

from envs_jax.base import BridgeObs, NoveltyEnv
from jaxbridge.core.config import ParamSamples, TrainConfig
from jaxbridge.core.learner_settings import Normalise, PQNSettings
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.dqn import feature_noise_entries, perturbed
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.optim import clipped_adam
from jaxbridge.learn.q_bridge import QNetwork, batch_input, best_candidate, candidate_skills, input_size
from jaxbridge.learn.transitions import Transition, empty_transitions


@struct.dataclass
class PQNState:
    """One seed's PQN: its network, Adam, and the last cycle's decisions (overwritten every cycle)."""

    params: Any
    opt_state: Any
    key: jax.Array
    decisions: jax.Array  # int32: training bridge decisions so far (drives epsilon)
    updates: jax.Array  # int32: minibatch updates so far
    batch: Transition  # the cycle's transitions, [episodes, steps]
    valid: jax.Array  # bool[episodes, steps]: the rows that are bridge decisions


@dataclass(frozen=True)
class PQN:
    env: NoveltyEnv  # the training env: its capacity fixes the shapes
    config: TrainConfig
    net: QNetwork  # with LayerNorm
    optimizer: optax.GradientTransformationExtraArgs
    num_features: int
    noise_entries: np.ndarray | None = None  # the observation entries feature noise perturbs (None: all)
    shares_network: bool = True  # one copy of the network for a rollout's episodes
    settings = PQNSettings  # declared a floor below (core/learner_settings.py), where configs resolve them

    @classmethod
    def create(cls, config: TrainConfig, env: NoveltyEnv, num_features: int, full_state: bool) -> "PQN":
        """Double DQN's network with LayerNorm; the same optimiser."""
        if config.learner.normalise is not Normalise.NONE:
            raise ValueError("learner pqn does not support normalise (set by the config or its preset)")
        net = replace(get_approach(config.approach).q_network(config, env), layer_norm=True)
        return cls(env, config, net, clipped_adam(), num_features,
                   feature_noise_entries(config, env))

    def init(self, key: jax.Array) -> PQNState:
        k_init, k_run = jax.random.split(key)
        params = self.net.init(k_init, jnp.zeros((1, input_size(self.env, self.num_features)), jnp.float32))
        shape = (self.config.episodes_per_cycle, self.config.train_steps)
        batch = empty_transitions(shape, self.num_features, self.env.num_skills, self.config.counts_steps)
        return PQNState(params=params, opt_state=self.optimizer.init(params), key=k_run, decisions=jnp.int32(0),
                        updates=jnp.int32(0), batch=batch, valid=jnp.zeros(shape, bool))

    def greedy(self, state: PQNState) -> Any:
        return state.params

    def observe(self, state: PQNState, transitions: Transition, valid: jax.Array) -> PQNState:
        return state.replace(batch=transitions.replace(task=None), valid=valid)

    def stored(self, state: PQNState) -> jax.Array:
        return state.valid.sum(dtype=jnp.int32)

    def lambda_returns(self, hyper: Hyper, params: Any, batch: Transition, valid: jax.Array,
                       key: jax.Array) -> jax.Array:
        """float32[episodes, steps]: each decision's Q(lambda) return, backwards through its episode's
        decisions: r + gamma ((1 - lambda) max_a Q(s', a) + lambda G'), G' the next decision's return;
        nothing past `done`; with a step discount, reward and future both step_gamma^steps later (as
        double DQN's targets). The max is over the next state's applicable candidates (n_target_sample
        parameter samples per skill), by the current network."""
        config, env = self.config, self.env
        skills = candidate_skills(env, config.learner.n_target_sample)
        stratified = config.param_samples is ParamSamples.STRATIFIED
        keys = jax.random.split(key, valid.size).reshape(valid.shape)
        best_q = lambda obs, k: best_candidate(env, self.net, params, obs, skills, k, stratified=stratified)[1]
        next_q = jax.vmap(jax.vmap(best_q))(BridgeObs(batch.next_features, batch.next_num_ground), keys)
        next_q = jnp.where(jnp.isfinite(next_q), next_q, 0.0)  # -inf: nothing applicable (only after `done`)
        if config.learner.clip_bootstrap:
            next_q = jnp.clip(next_q, 0.0, 1.0 + hyper.call_planner_bonus)

        late = (jnp.ones_like(batch.reward) if batch.steps is None
                else config.step_gamma ** batch.steps.astype(jnp.float32))

        def backwards(later, row):
            reward, done, q, decided, discount = row
            future = hyper.gamma * discount * ((1.0 - hyper.q_lambda) * q + hyper.q_lambda * later)
            g = reward * discount + jnp.where(done, 0.0, future)
            return jnp.where(decided, g, later), g

        def episode(rows):
            _, returns = jax.lax.scan(backwards, jnp.float32(0.0), rows, reverse=True)
            return returns
        return jax.vmap(episode)((batch.reward, batch.done, next_q, valid, late))

    def minibatch_step(self, hyper: Hyper, state: PQNState, batch: Transition, targets: jax.Array,
                       weight: jax.Array) -> tuple[PQNState, tuple[jax.Array, jax.Array, jax.Array]]:
        """One Adam step on the weighted squared error of a minibatch; none where it holds no decision."""
        env, net, noise = self.env, self.net, self.config.learner.feature_noise
        features = batch.features
        if noise > 0:  # as double DQN's (QSettings.feature_noise): a fresh draw per update
            features = perturbed(features, noise, state.key, state.updates, self.noise_entries)

        def loss_fn(params):
            q = net.apply(params, batch_input(env, features, batch.skill, batch.param), members=True)
            loss = jnp.sum(weight * (q - targets) ** 2) / jnp.maximum(weight.sum(), 1.0) / q.shape[0]
            return loss, jnp.max(jnp.where(weight > 0, jnp.abs(q), 0.0))

        (loss, q_abs_max), grads = jax.value_and_grad(loss_fn, has_aux=True)(state.params)
        updates, opt_state = self.optimizer.update(grads, state.opt_state, state.params, max_norm=hyper.grad_clip,
                                                   learning_rate=hyper.learning_rate)
        updated = state.replace(params=optax.apply_updates(state.params, updates), opt_state=opt_state,
                                updates=state.updates + 1)
        some = weight.sum() > 0
        return jax.tree.map(lambda a, b: jnp.where(some, a, b), updated, state), (loss, q_abs_max, some)

    def learn(self, state: PQNState, decisions: jax.Array, tasks: Any) -> tuple[PQNState, jax.Array, jax.Array]:
        """Q(lambda) targets for the cycle's decisions, then `pqn_epochs` shuffled passes over them."""
        config, hyper = self.config, Hyper(**self.config.leaf_values())  # traced in a cycle: the slot's
        key, k_targets, k_epochs = jax.random.split(state.key, 3)
        if config.learner.reset_optimizer:
            state = state.replace(opt_state=self.optimizer.init(state.params))
        flat = lambda x: x.reshape((-1,) + x.shape[2:])
        targets = flat(self.lambda_returns(hyper, state.params, state.batch, state.valid, k_targets))
        batch, valid = jax.tree.map(flat, state.batch), flat(state.valid)
        rows, parts = valid.shape[0], config.learner.pqn_minibatches
        size = -(-rows // parts)

        def epoch(state, k):
            # The decisions first, shuffled, then the rest; minibatch m takes every parts-th of them from
            # m, so each minibatch holds about a parts-th of the decisions.
            order = jnp.argsort(jnp.where(valid, jax.random.uniform(k, (rows,)), 2.0))
            order = jnp.pad(order, (0, size * parts - rows), constant_values=rows).reshape(size, parts).T
            picked = jnp.minimum(order, rows - 1)  # the padding reads a real row, weighted 0
            weight = jnp.where(order < rows, valid[picked], False).astype(jnp.float32)
            minibatches = (jax.tree.map(lambda x: x[picked], batch), targets[picked], weight)  # each [parts, size, ...]
            return jax.lax.scan(lambda state, part: self.minibatch_step(hyper, state, *part), state, minibatches)

        state, (losses, q_abs, ran) = jax.lax.scan(epoch, state, jax.random.split(k_epochs, config.learner.pqn_epochs))
        ran = ran.astype(jnp.float32)
        loss = jnp.sum(losses * ran) / jnp.maximum(ran.sum(), 1.0)
        return state.replace(key=key), loss, jnp.max(q_abs * ran)

