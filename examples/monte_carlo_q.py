"""A learner of your own, written against the learner contract only (docs/NEW_LEARNER.md): Monte Carlo Q.

Each cycle it fits the bridge's Q-network to the discounted returns of the decisions of its last `memory`
cycles (no bootstrapping, no target network) by `epochs` full-batch Adam steps. Simple, and weaker than
double DQN: a return is one episode's luck. Train it with

    python train.py --env light_switch_door --approaches ours --learner examples.monte_carlo_q:MonteCarloQ \
        --set memory=10 --sweep epochs=20,50
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import optax
from flax import struct

from envs_jax import NoveltyEnv
from jaxbridge import TrainConfig
from jaxbridge.core.learner_settings import QSettings
from jaxbridge.core.settings import made, setting
from jaxbridge.learn.q_bridge import QNetwork, encode, input_size
from jaxbridge.learn.transitions import Transition


@struct.dataclass
class MonteCarloState:
    params: Any
    opt_state: Any
    key: jax.Array  # the cycle splits and replaces it
    decisions: jax.Array  # the cycle counts the training decisions here
    cycles: jax.Array  # cycles observed: the oldest cycle's rows are overwritten next
    inputs: jax.Array  # the last `memory` cycles' rows as network inputs, [memory * episodes * steps, input]
    returns: jax.Array  # their discounted returns
    valid: jax.Array  # which rows are decisions


def discounted_returns(transitions: Transition, valid: jax.Array, gamma: jax.Array) -> jax.Array:
    """Backwards through one episode's rows: a decision's return is its reward plus gamma times the next
    decision's return, unless it was done."""
    def backwards(later, row):
        reward, done, decided = row
        g = reward + jnp.where(done, 0.0, gamma * later)
        return jnp.where(decided, g, later), g
    return jax.lax.scan(backwards, jnp.float32(0.0), (transitions.reward, transitions.done, valid), reverse=True)[1]


@dataclass(frozen=True)
class MonteCarloQ(QSettings):
    """The learner, its fields its settings: its own two beside the Q-network's and Adam's (QSettings:
    hidden_sizes, learning_rate, gamma, ...), then the parts `create` adds."""

    epochs: int = setting(50, low=1)
    """Full-batch Adam steps per cycle."""
    memory: int = setting(20, low=1)
    """Cycles of decisions kept: the oldest cycle's are overwritten by the next."""
    env: NoveltyEnv = made()
    net: QNetwork = made()
    num_features: int = made()
    rows: int = made()  # episodes_per_cycle x train_steps: the rows a cycle hands `observe`
    shares_network = True

    @classmethod
    def create(cls, config: TrainConfig, env: NoveltyEnv, num_features: int, full_state: bool) -> MonteCarloQ:
        """The run's learner: `config.learner` (these settings) with the parts made for the approach's observation
        (`full_state` needs nothing different here)."""
        return config.learner.with_parts(env=env, net=QNetwork(config.learner.hidden_sizes), num_features=num_features,
                                         rows=config.episodes_per_cycle * config.train_steps)

    @property
    def adam(self) -> optax.GradientTransformation:
        return optax.adam(self.learning_rate)  # in a cycle, the slot's learning rate (a traced leaf)

    def init(self, key: jax.Array) -> MonteCarloState:
        k_init, k_run = jax.random.split(key)
        width = input_size(self.env, self.num_features)
        params = self.net.init(k_init, jnp.zeros((1, width), jnp.float32))
        rows = self.memory * self.rows
        return MonteCarloState(params=params, opt_state=self.adam.init(params), key=k_run,
                               decisions=jnp.int32(0), cycles=jnp.int32(0), inputs=jnp.zeros((rows, width), jnp.float32),
                               returns=jnp.zeros(rows, jnp.float32), valid=jnp.zeros(rows, bool))

    def greedy(self, state: MonteCarloState) -> Any:
        return state.params

    def observe(self, state: MonteCarloState, transitions: Transition, valid: jax.Array) -> MonteCarloState:
        returns = jax.vmap(discounted_returns, in_axes=(0, 0, None))(transitions, valid, self.gamma)
        inputs = encode(self.env, transitions.features, transitions.skill, transitions.param)
        at = (state.cycles % self.memory) * self.rows
        put = lambda memory, new: jax.lax.dynamic_update_slice_in_dim(
            memory, new.reshape((self.rows,) + memory.shape[1:]), at, 0)
        return state.replace(inputs=put(state.inputs, inputs), returns=put(state.returns, returns),
                             valid=put(state.valid, valid), cycles=state.cycles + 1)

    def learn(self, state: MonteCarloState, decisions: jax.Array, tasks: Any):
        weight = state.valid.astype(jnp.float32)

        def loss_fn(params):
            q = self.net.apply(params, state.inputs)
            return jnp.sum(weight * (q - state.returns) ** 2) / jnp.maximum(weight.sum(), 1.0), jnp.max(jnp.abs(q) * weight)

        def step(carry, _):
            params, opt_state = carry
            (loss, q_abs), grads = jax.value_and_grad(loss_fn, has_aux=True)(params)
            updates, opt_state = self.adam.update(grads, opt_state)
            params = optax.apply_updates(params, updates)
            return (params, opt_state), (loss, q_abs)

        (params, opt_state), (losses, q_abs) = jax.lax.scan(step, (state.params, state.opt_state), None,
                                                           length=self.epochs)
        return state.replace(params=params, opt_state=opt_state), losses.mean(), q_abs.max()

    def stored(self, state: MonteCarloState) -> jax.Array:
        return state.valid.sum(dtype=jnp.int32)

