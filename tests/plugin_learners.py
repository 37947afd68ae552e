"""Learners that break the contract, each in one way, for the refusal tests (the example learner of
docs/NEW_LEARNER.md is examples/monte_carlo_q.py)."""
from dataclasses import dataclass

import jax
import jax.numpy as jnp

from examples.monte_carlo_q import MonteCarloQ


@dataclass(frozen=True)
class GrowingState(MonteCarloQ):
    """observe keeps only the decisions, so the state's shape would change from cycle to cycle."""

    def observe(self, state, transitions, valid):
        state = super().observe(state, transitions, valid)
        return state.replace(returns=state.returns[:-1])


@dataclass(frozen=True)
class VectorLoss(MonteCarloQ):
    """learn returns the loss of every epoch instead of their mean."""

    def learn(self, state, decisions, tasks):
        state, loss, q_abs = super().learn(state, decisions, tasks)
        return state, jnp.full(3, loss), q_abs


@dataclass(frozen=True)
class LeafInInit(MonteCarloQ):
    """init scales the network by the learning rate: a leaf read in init (a sweep's settings start apart)."""

    def init(self, key):
        state = super().init(key)
        return state.replace(params=jax.tree.map(lambda p: p * self.learning_rate, state.params))
