"""The learner contract: what a seed's cycle (learn/online.py) needs of whatever fits the bridge's Q-function.

The cycle runs the meta-policy's training episodes with the learner's greedy network and epsilon-greedy
exploration, turns each episode's records into one transition per bridge decision (learn/transitions.py),
hands them to the learner, lets it learn, and tests its greedy network. A learner is the static side,
made from the config (a frozen dataclass, hashable); in a cycle it is made again from each slot's settings,
their leaves traced (learn/setup.Setup.learner_for), so it reads its hyperparameters from its settings and
a sweep's every setting trains at its own values. Its
state is a pytree that the cycle carries, checkpoints and restores. Double DQN (learn/dqn.py) and PQN
(learn/pqn.py) are the built-in ones; docs/NEW_LEARNER.md shows how to add one, and `check_learner`
checks one as `check_env` checks an env.
"""
from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import NoveltyEnv
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.q_bridge import QNetwork, input_size
from jaxbridge.learn.transitions import Transition, empty_transitions


class LearnerContractError(ValueError):
    """A learner that breaks the contract: the message names the method and what was expected."""


@runtime_checkable
class QLearner(Protocol):
    """What a seed's cycle needs of a learner. `state` is the learner's pytree (a flax struct dataclass):
    it must have `key` (a PRNG key the cycle splits and replaces) and `decisions` (int32, the training
    bridge decisions so far, which the cycle adds to and the exploration schedule reads). Its hyperparameters
    are its settings' (`config.learner`): in a cycle, each slot's learner is made from that slot's values."""

    env: NoveltyEnv  # the training env: its capacity fixes the shapes
    net: QNetwork  # the Q-function the bridge calls: net.apply(greedy(state), input) -> Q
    num_features: int  # the width of the bridge's observation (the approach's)

    @property
    def shares_network(self) -> bool:
        """True: a rollout's episodes share one copy of the network (one matrix product for all of them);
        False: each episode gets its own copy (the same numbers up to the order of float sums)."""

    def init(self, key: jax.Array) -> Any:
        """A fresh state for one seed."""

    def greedy(self, state: Any) -> Any:
        """The network variables the bridge acts with (greedily at test time, epsilon-greedily in training)."""

    def observe(self, state: Any, transitions: Transition, valid: jax.Array) -> Any:
        """Take a cycle's transitions, [episodes_per_cycle, train_steps] (one row per env step of each training
        episode; `valid` marks the rows that are bridge decisions): store them, or keep them for `learn`."""

    def learn(self, state: Any, decisions: jax.Array, tasks: Any) -> tuple[Any, jax.Array, jax.Array]:
        """Learn after a cycle's episodes (`decisions` of them this cycle; `tasks`: the training tasks).
        Returns (state, mean loss, largest |Q| predicted), both float32 scalars."""

    def stored(self, state: Any) -> jax.Array:
        """int32: the transitions it holds (the metrics' buffer_size)."""


def epsilon(hyper: Hyper | TrainConfig, decisions: jax.Array) -> jax.Array:
    """The exploration rate of every learner's training episodes: linear annealing per training bridge
    decision, floored at epsilon_end."""
    return jnp.maximum(hyper.epsilon_end, hyper.epsilon_start - hyper.epsilon_decay * decisions)


def _expect(ok: bool, where: str, expected: str, got: Any) -> None:
    if not ok:
        raise LearnerContractError(f"{where}: expected {expected}, got {got}")


def _shapes(tree: Any) -> Any:
    return jax.tree.map(lambda x: (x.shape, x.dtype), tree)


def _calls(where: str, fn, *args) -> Any:
    """jax.eval_shape(fn, *args) (nothing is computed), any error reported as a contract error of `where`."""
    try:
        return jax.eval_shape(fn, *args)
    except LearnerContractError:
        raise
    except Exception as err:  # noqa: BLE001: whatever a plug-in raises becomes one line naming the method
        raise LearnerContractError(f"{where}: raised {type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}") from err


def example_transitions(learner: QLearner, config: TrainConfig) -> tuple[Transition, jax.Array]:
    """Transitions of the shapes a cycle of `config` hands `observe`: [episodes_per_cycle, train_steps], every
    other row a decision, with their step counts where a step discount is on."""
    episodes, steps = config.episodes_per_cycle, config.train_steps
    transitions = empty_transitions((episodes, steps), learner.num_features, learner.env.num_skills, config.counts_steps)
    return transitions, jnp.asarray(np.arange(steps)[None, :] % 2 == 0).repeat(episodes, 0)


def check_learner(learner: QLearner, config: TrainConfig, tasks: Any = None) -> QLearner:
    """Check a learner made for `config` against the contract without computing anything (abstract shapes);
    returns it. LearnerContractError names the first method that breaks it. `tasks`: one seed's training
    tasks, as `learn` gets them."""
    name = type(learner).__name__
    for attribute in ("env", "net", "num_features", "shares_network", "init", "greedy", "observe", "learn", "stored"):
        _expect(hasattr(learner, attribute), name, f"an attribute {attribute!r} (learn/learner.QLearner)", "none")
    try:
        hash(learner)
    except TypeError:
        raise LearnerContractError(f"{name}: expected a hashable learner (a frozen dataclass), got an unhashable one") from None
    state = _calls(f"{name}.init", learner.init, jax.random.key(0))
    for field in ("key", "decisions"):
        _expect(hasattr(state, field), f"{name}.init", f"a state with a {field!r} field", type(state).__name__)
    _expect(jax.dtypes.issubdtype(state.key.dtype, jax.dtypes.prng_key), f"{name}.init", "state.key a PRNG key",
            state.key.dtype)
    _expect(state.decisions.shape == () and state.decisions.dtype == jnp.int32, f"{name}.init",
            "state.decisions an int32 scalar", _shapes(state.decisions))
    candidates = jnp.zeros((4, input_size(learner.env, learner.num_features)), jnp.float32)
    q = _calls(f"{name}.greedy", lambda s: learner.net.apply(learner.greedy(s), candidates), state)
    _expect(q.shape == (4,), f"{name}.greedy", "variables for net.apply giving one Q per input row", _shapes(q))
    transitions, valid = example_transitions(learner, config)
    observed = _calls(f"{name}.observe", learner.observe, state, transitions, valid)
    _expect(_shapes(observed) == _shapes(state), f"{name}.observe", "a state of init's shapes and dtypes",
            "another (a state's shapes must not change: the cycle is a scan)")
    learned = _calls(f"{name}.learn", lambda s: learner.learn(s, jnp.int32(3), tasks), observed)
    _expect(isinstance(learned, tuple) and len(learned) == 3, f"{name}.learn", "(state, loss, q_abs_max)", type(learned))
    _expect(_shapes(learned[0]) == _shapes(state), f"{name}.learn", "a state of init's shapes and dtypes", "another")
    for label, value in zip(("loss", "q_abs_max"), learned[1:]):
        _expect(value.shape == () and value.dtype == jnp.float32, f"{name}.learn", f"{label} a float32 scalar", _shapes(value))
    stored = _calls(f"{name}.stored", learner.stored, state)
    _expect(stored.shape == () and jnp.issubdtype(stored.dtype, jnp.integer), f"{name}.stored", "an integer scalar",
            _shapes(stored))
    return learner
