"""The online learning loop: per cycle, training episodes, double-DQN updates, greedy test evaluation.

One jitted `cycle` runs a whole cycle for every seed at once: the episodes of all seeds form one batch
of the meta-policy rollout (the planner's table lookups, the bridge's decisions and the env steps of
every seed and episode advance together), the learner updates are `vmap`ped over seeds. A host loop
over cycles drives progress, logging and checkpoints; nothing inside a cycle touches the host.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from envs_jax import env_class
from jaxbridge.approaches import Approach, get_approach
from jaxbridge.config import TrainConfig
from jaxbridge.dqn import Learner, epsilon, init_learner, learn, q_network
from jaxbridge.meta_policy import rollout
from jaxbridge.q_bridge import QBridgeParams, QNetwork
from jaxbridge.replay import add
from jaxbridge.tasks import TaskBatch, evaluation_batch, make_batch
from jaxbridge.transitions import episode_transitions


@struct.dataclass
class CycleMetrics:
    """One cycle's numbers, one entry per seed."""

    test_solve_rate: jax.Array
    train_success_rate: jax.Array
    train_env_steps: jax.Array
    train_decisions: jax.Array  # bridge decisions in this cycle's training episodes
    test_env_steps: jax.Array
    epsilon: jax.Array  # during this cycle's training episodes
    loss: jax.Array  # mean TD loss of this cycle's updates
    q_abs_max: jax.Array  # largest |Q| predicted in this cycle's updates (a non-finite value stops a run)
    buffer_size: jax.Array
    table_misses: jax.Array  # planner lookups answered by the host planner (train + test)


@dataclass
class Experiment:
    """The static side of a run: config, tasks of every seed, the network and the bridge."""

    config: TrainConfig
    approach: Approach
    train: TaskBatch  # seed-major: episodes_per_cycle copies of each seed's training task
    test: TaskBatch  # seed-major: each seed's test tasks
    net: QNetwork
    train_bridge: Callable
    test_bridge: Callable

    @property
    def env(self):
        return self.test.env


def build_experiment(config: TrainConfig) -> Experiment:
    env_cls = env_class(config.env)
    seeds = config.seeds
    train_specs = [env_cls.train_task(s) for s in seeds for _ in range(config.episodes_per_cycle)]
    train_owner = [s for s in seeds for _ in range(config.episodes_per_cycle)]
    train = make_batch(env_cls, train_specs, train_owner, horizons=[config.train_steps] * len(train_specs))
    test = evaluation_batch(env_cls, seeds, config.num_test_tasks)
    net = q_network(config)
    approach = get_approach(config.approach)
    return Experiment(config, approach, train, test, net, approach.make_bridge(train.env, net, config.n_sample),
                      approach.make_bridge(test.env, net, config.n_sample))


def init_learners(experiment: Experiment) -> Learner:
    """One learner per seed, stacked on a leading seed axis; seed s starts from jax.random.key(s)."""
    keys = jnp.stack([jax.random.key(s) for s in experiment.config.seeds])
    return jax.vmap(partial(init_learner, experiment.train.env, experiment.config))(keys)


def episode_params(learners: Learner, owner: np.ndarray, eps: jax.Array) -> QBridgeParams:
    """Bridge parameters for a batch of episodes: each episode gets its seed's network (owner[i] is the
    seed index of episode i) and exploration rate eps[i] (zeros for the greedy bridge)."""
    return QBridgeParams(q=jax.tree.map(lambda x: x[owner], learners.params), epsilon=eps)


def make_cycle(experiment: Experiment) -> Callable[[Learner], tuple[Learner, CycleMetrics]]:
    config, train, test = experiment.config, experiment.train, experiment.test
    approach, controls = experiment.approach, experiment.approach.controls
    seeds, episodes, num_tests = config.num_seeds, config.episodes_per_cycle, config.num_test_tasks
    train_owner = np.repeat(np.arange(seeds), episodes)
    test_owner = np.repeat(np.arange(seeds), num_tests)
    call_planner = train.env.num_skills

    def cycle(learners: Learner, train_tasks, train_tables, train_horizons, test_tasks, test_tables,
              test_horizons) -> tuple[Learner, CycleMetrics]:
        keys = jax.vmap(lambda k: jax.random.split(k, 4))(learners.key)
        k_next, k_train, k_learn, k_test = (keys[:, i] for i in range(4))

        # 1. Training episodes, epsilon-greedy, on every seed's training task.
        eps = epsilon(config, learners.decisions)
        explore = episode_params(learners, train_owner, eps[train_owner])
        episode_keys = jax.vmap(lambda k: jax.random.split(k, episodes))(k_train).reshape(-1)
        result, records = rollout(train.env, experiment.train_bridge, explore, train_tasks, train_tables,
                                  train_horizons, episode_keys, config.train_steps, record=approach.learns,
                                  controls=controls)
        decisions = result.bridge_decisions.reshape(seeds, episodes).sum(1)

        if approach.learns:
            # 2. One transition per bridge decision into each seed's replay buffer.
            transitions, valid = jax.vmap(episode_transitions, in_axes=(1, 0, None, None))(
                records, result.success, call_planner, config.call_planner_bonus)
            by_seed = lambda x: x.reshape((seeds, -1) + x.shape[2:])
            buffers = jax.vmap(add)(learners.buffer, jax.tree.map(by_seed, transitions), by_seed(valid))
            learners = learners.replace(buffer=buffers, decisions=learners.decisions + decisions, key=k_learn)

            # 3. Double-DQN updates, every seed its own.
            learners, loss, q_abs_max = jax.vmap(partial(learn, train.env, config))(learners, decisions)
        else:  # random bridge, pure planning: nothing to learn, the same act-and-test loop
            learners = learners.replace(decisions=learners.decisions + decisions)
            eps = jnp.full_like(eps, 1.0 if approach.bridge == "random" else 0.0)
            loss = q_abs_max = jnp.zeros(seeds, jnp.float32)
        learners = learners.replace(key=k_next)

        # 4. Greedy evaluation on every seed's test tasks.
        greedy = episode_params(learners, test_owner, jnp.zeros(len(test_owner), jnp.float32))
        test_keys = jax.vmap(lambda k: jax.random.split(k, num_tests))(k_test).reshape(-1)
        tested, _ = rollout(test.env, experiment.test_bridge, greedy, test_tasks, test_tables, test_horizons,
                            test_keys, test.max_steps, controls=controls)

        per_seed = lambda x, n: x.reshape(seeds, n)
        metrics = CycleMetrics(
            test_solve_rate=per_seed(tested.success, num_tests).mean(1),
            train_success_rate=per_seed(result.success, episodes).mean(1),
            train_env_steps=per_seed(result.steps, episodes).sum(1),
            train_decisions=decisions,
            test_env_steps=per_seed(tested.steps, num_tests).sum(1),
            epsilon=eps, loss=loss, q_abs_max=q_abs_max, buffer_size=learners.buffer.size,
            table_misses=per_seed(result.table_misses, episodes).sum(1)
            + per_seed(tested.table_misses, num_tests).sum(1))
        return learners, metrics

    # No buffer donation: the state before a cycle must stay valid, so that Ctrl-C or a numerical fault
    # during a cycle can still checkpoint the last good one.
    jitted = jax.jit(cycle)
    return lambda learners: jitted(learners, train.tasks, train.tables, train.horizons, test.tasks,
                                   test.tables, test.horizons)


def smooth(rates: np.ndarray, window: int = 25) -> np.ndarray:
    """The paper's smooth reward (reference/results.md): the value at cycle c (1-based) is the sum of
    the rates of cycles c-25 .. c-1 divided by 25, so it ramps up from 0 over the first 25 cycles and
    excludes cycle c itself. rates: [..., cycles] -> [..., cycles]."""
    cumulative = np.concatenate([np.zeros(rates.shape[:-1] + (1,)), np.cumsum(rates, axis=-1)], axis=-1)
    before = np.arange(rates.shape[-1])  # cycles completed before cycle c = c - 1
    return (cumulative[..., before] - cumulative[..., np.maximum(before - window, 0)]) / window
