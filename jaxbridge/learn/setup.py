"""A run's config with everything it names resolved once (`Setup`): the env class, the training and test
envs, the approach, the learner (its Q-network and optimiser), and (built on first use) the seeds' task
batches."""
from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax import NoveltyEnv, env_class
from jaxbridge.core.bridges import Bridge
from jaxbridge.core.config import ParamSamples, TrainConfig
from jaxbridge.core.episode import Controls
from jaxbridge.core.learner_settings import learner_class
from jaxbridge.core.tasks import TaskBatch, evaluation_batch, evaluation_specs, make_batch, training_specs
from jaxbridge.learn.approaches import Approach, get_approach
from jaxbridge.learn.exploration import with_exploration
from jaxbridge.learn.learner import QLearner
from jaxbridge.learn.q_bridge import QBridgeParams
from jaxbridge.utils.progress import SlowWork


@dataclass(frozen=True)
class Setup:
    """The static side of a run, resolved from its config: nothing below looks a name up again."""

    config: TrainConfig
    env_cls: type[NoveltyEnv]
    approach: Approach
    train_env: NoveltyEnv  # sized to the seeds' training tasks (the learners' shapes follow it), with the config's quirks
    test_env: NoveltyEnv  # sized to the seeds' test tasks, with the config's quirks
    learner: QLearner  # network, optimiser and observation width, on the training env (learn/learner.py)

    @cached_property
    def train(self) -> TaskBatch:
        """Each seed's `train_tasks`, one per episode of a cycle, seed-major (built on first use)."""
        return task_batches(self)[0]

    @cached_property
    def test(self) -> TaskBatch:
        """Each seed's test tasks, seed-major (built on first use)."""
        return task_batches(self)[1]

    @property
    def controls(self) -> Controls:
        """The meta-policy's parts: the approach's, with the config's loop guard."""
        return dataclasses.replace(self.approach.controls, loop_guard=self.config.loop_guard)

    def bridge(self, env: NoveltyEnv) -> Bridge:
        """The approach's bridge on `env` (equal arguments give equal bridges: one compilation)."""
        config = self.config
        return self.approach.make_bridge(env, self.learner.net, config.n_sample, config.explore_ground_operators,
                                         config.param_samples is ParamSamples.STRATIFIED)

    def learner_for(self, slot: TrainConfig) -> QLearner:
        """The learner of a slot of this setup's program, made from its settings `slot` (in a cycle, the
        config with the slot's traced leaves: `with_leaves`), so that it reads its own slot's wherever it
        reads a leaf."""
        return make_learner(slot, self.approach, self.train_env)

    def init_learners(self, setting: TrainConfig | None = None) -> Any:
        """One learner state per seed, stacked on a leading seed axis; seed s starts from jax.random.key(s).
        `setting`: a config of this setup's program (default its own), whose learner makes them, so that an
        `init` that reads a leaf reads that setting's. A low-level baseline's are brax's (normalizer, policy)
        parameters (learn/low_level.py)."""
        if self.approach.low_level:
            from jaxbridge.learn.low_level import init_policies  # brax: imported only when used
            return init_policies(self)
        own = setting in (None, self.config)
        learner = self.learner if own else make_learner(setting, self.approach, self.train_env)
        return jax.jit(jax.vmap(learner.init))(seed_keys(self.config))  # one program, not op by op

    def greedy_policy(self, env: NoveltyEnv, states: Any, owner: np.ndarray) -> tuple[Bridge, Any, Controls]:
        """The approach's greedy bridge on `env`, its per-episode parameters (episode i acts with seed owner[i]'s
        of the seeds' learner `states`) and its controls: what a test rollout of a batch of `env` runs."""
        if self.approach.low_level:
            from jaxbridge.learn.low_level import policy_bridge
            bridge, controls = policy_bridge(env, self.approach)
            return bridge, jax.tree.map(lambda x: x[owner], states), controls
        return self.bridge(env), self.episode_params(states, owner, np.zeros(len(owner), np.float32)), self.controls

    def episode_params(self, states: Any, owner: np.ndarray, eps: jax.Array) -> QBridgeParams:
        """Q-bridge parameters for a batch of episodes: episode i acts with seed owner[i]'s greedy network (of
        the seeds' learner `states`) and exploration rate eps[i] (zeros: greedy)."""
        return QBridgeParams(q=jax.tree.map(lambda x: x[owner], jax.vmap(self.learner.greedy)(states)), epsilon=eps)


def seed_keys(config: TrainConfig) -> jax.Array:
    """The seeds' starting keys as a run of `config` uses them: seed s starts from jax.random.key(s)."""
    return jnp.stack([jax.random.key(s) for s in config.seeds])


def make_setup(config: TrainConfig, env_cls: type[NoveltyEnv] | None = None) -> Setup:
    """Resolve `config` (its env by name unless `env_cls` is given, its approach)."""
    env_cls = env_cls or env_class(config.env)
    approach = get_approach(config.approach)
    approach.check_env(env_cls)
    train_env = training_env(config, env_cls, config.seeds)
    test_env = env_cls.for_tasks(evaluation_specs(env_cls, config.seeds, config.num_test_tasks, config.test_protocol)[0]
                                 ).with_quirks(config.env_quirks)
    return Setup(config, env_cls, approach, train_env, test_env, make_learner(config, approach, train_env))


def training_env(config: TrainConfig, env_cls: type[NoveltyEnv], seeds: list[int]) -> NoveltyEnv:
    """The env sized to `seeds`' training tasks, with the config's quirks: the learners' shapes follow it."""
    return env_cls.for_tasks(training_specs(env_cls, seeds, config.episodes_per_cycle)[0]).with_quirks(config.env_quirks)


def make_learner(config: TrainConfig, approach: Approach, train_env: NoveltyEnv) -> QLearner:
    """The learner `config` names, for the approach's observation on the training env, with its exploration."""
    learner = learner_class(config.learner.name).create(config, train_env, approach.observation_size(train_env),
                                                        approach.controls.observation.whole_state)
    return with_exploration(learner, config)


_TASKS_LOCK = threading.Lock()


@lru_cache(maxsize=4)
def _build_tasks(env_cls: type[NoveltyEnv], seeds: tuple[int, ...], episodes: int, train_steps: int,
                 num_test_tasks: int, test_protocol: str) -> tuple[TaskBatch, TaskBatch]:
    train_specs, train_owner = training_specs(env_cls, seeds, episodes)
    train = make_batch(env_cls, train_specs, train_owner, horizons=[train_steps] * len(train_specs),
                       progress=SlowWork(f"{env_cls.name}: training tasks and plan tables"))
    return train, evaluation_batch(env_cls, list(seeds), num_test_tasks, protocol=test_protocol,
                                   progress=SlowWork(f"{env_cls.name}: test tasks and plan tables"))


def task_batches(setup: Setup) -> tuple[TaskBatch, TaskBatch]:
    """The seeds' training batch (each seed's `train_tasks`, one per episode of a cycle) and test batch.

    Built once per process for equal settings and shared read-only: every approach of an experiment
    trains and tests on the same tasks, and their host-side build (plan tables, roadmaps) takes seconds.
    The lock makes a second worker wait for the first's build rather than repeat it; the tasks' host
    planners are then shared too, their caches filling with the entries either worker would compute."""
    config = setup.config
    with _TASKS_LOCK:
        return _build_tasks(setup.env_cls, tuple(config.seeds), config.episodes_per_cycle, config.train_steps,
                            config.num_test_tasks, config.test_protocol)
