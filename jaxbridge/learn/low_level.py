"""The low-level baselines (issue 22): brax's PPO and SAC on each seed's training task from its stuck state
(learn/brax_env.BridgeEnv), evaluated after every cycle's worth of agent steps by the meta-policy with the
agent's deterministic policy as a low-level bridge, on the same test tasks as every other approach.

brax's trainers are not vmappable over seeds, so seeds train one after another. A cycle is ours' env
steps per cycle (episodes_per_cycle x train_steps) times `low_level_budget`, counted in agent steps (an
agent step is one env step, or a planner's whole stretch after CallPlanner: the agents get at least
ours' env steps).
"""
from __future__ import annotations

import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Callable

import jax
import jax.numpy as jnp

from envs_jax.base import BridgeAction, BridgeObs, NoveltyEnv
from jaxbridge.core.meta_policy import Controls, MetaPolicy, observation_size, rollout
from jaxbridge.core.tasks import TaskArrays
from jaxbridge.learn.brax_env import BridgeEnv, agent_action_size, scaled_choice

from brax.training.acme import running_statistics, specs  # after brax_env, which imports brax quietly
from brax.training.agents.ppo import networks as ppo_networks
from brax.training.agents.ppo import train as ppo
from brax.training.agents.sac import checkpoint as sac_checkpoint
from brax.training.agents.sac import networks as sac_networks
from brax.training.agents.sac import train as sac


def _device_put_replicated(tree, devices):
    """jax 0.10 removed `jax.device_put_replicated`, which brax 0.14's trainers call to give their
    pmapped state its device axis; the trainers here run on one device (max_devices_per_host=1)."""
    if len(devices) != 1:
        raise ValueError("the low-level baselines train on one device")
    return jax.tree.map(lambda x: jax.device_put(jnp.asarray(x)[None], devices[0]), tree)


if not hasattr(jax, "device_put_replicated"):  # the attribute raises on jax 0.10; brax looks it up at call time
    jax.device_put_replicated = _device_put_replicated


@lru_cache(maxsize=None)
def _networks(algorithm: str, obs_size: int, action_size: int):
    """brax's default networks of `algorithm`, built once per shape (the trainers build equal ones)."""
    make = {"ppo": ppo_networks.make_ppo_networks, "sac": sac_networks.make_sac_networks}[algorithm]
    return make(obs_size, action_size, preprocess_observations_fn=running_statistics.normalize)


@dataclass(frozen=True)
class PolicyBridge:
    """A trained agent as a low-level bridge: its deterministic action (the mode of brax's tanh-normal),
    scaled to the env's bounds; params are brax's (normalizer, policy) pair."""

    env: NoveltyEnv
    algorithm: str
    call_planner: bool
    obs_size: int

    def __call__(self, params, obs: BridgeObs, key: jax.Array) -> BridgeAction:
        nets = _networks(self.algorithm, self.obs_size, agent_action_size(self.env, self.call_planner))
        logits = nets.policy_network.apply(params[0], params[1], obs.features)
        squashed = nets.parametric_action_distribution.mode(logits)
        return scaled_choice(self.env, squashed, obs.num_ground[-1] > 0, self.call_planner)


def init_policies(setup) -> tuple:
    """Freshly initialised (normalizer, policy) params of the setup's agent, stacked over its seeds: the
    shapes a low-level run's checkpoint restores into."""
    approach = setup.approach
    obs_size = observation_size(setup.train_env, approach.controls)
    nets = _networks(approach.algorithm, obs_size, agent_action_size(setup.train_env, approach.controls.call_planner))
    one = lambda seed: (running_statistics.init_state(specs.Array((obs_size,), jnp.float32)),
                        nets.policy_network.init(jax.random.PRNGKey(seed)))
    return jax.tree.map(lambda *x: jnp.stack(x), *[one(s) for s in setup.config.seeds])


@dataclass(frozen=True)
class Budget:
    """One seed's training: `cycles` evaluation points, `steps_per_cycle` agent steps between them."""

    cycles: int
    steps_per_cycle: int
    episode_length: int  # agent steps at most per episode (the task horizon: each is >= 1 env step)

    @property
    def total(self) -> int:
        return self.cycles * self.steps_per_cycle


def train_ppo(adapter: BridgeEnv, budget: Budget, seed: int, on_cycle: Callable) -> None:
    """brax PPO, five episodes at a time (ours' episodes per cycle), one update of 4 epochs x 5 minibatches
    per 500 agent steps; `on_cycle(step, params)` after each cycle's steps."""
    def after_cycle(step, _make_policy, params):  # brax also calls it before training (step 0): skipped
        if step > 0:
            on_cycle(step, (params[0], params[1]))  # (normalizer, policy); the value net is not kept

    ppo.train(adapter, num_timesteps=budget.total, num_evals=budget.cycles + 1, run_evals=False,
              episode_length=budget.episode_length, num_envs=5, unroll_length=10, batch_size=10,
              num_minibatches=5, num_updates_per_batch=4, learning_rate=3e-4, entropy_cost=1e-2,
              discounting=0.99, normalize_observations=True, max_devices_per_host=1, seed=seed,
              policy_params_fn=after_cycle)


def train_sac(adapter: BridgeEnv, budget: Budget, seed: int, on_cycle: Callable) -> None:
    """brax SAC, five episodes at a time, one gradient step per five agent steps, rewards scaled by 100:
    with a reward of 1 the entropy bonus of staying in an episode outweighs ending it at the goal, and
    the greedy policy unlearns (Doorknobs + CallPlanner, tuning seeds 0-1: test solve rate 0.0 at
    scales 1 and 10, 0.8-1.0 at 100). Its per-cycle policies come back through brax's checkpoints (its
    only per-cycle output of parameters)."""
    with tempfile.TemporaryDirectory() as logdir:
        sac.train(adapter, num_timesteps=budget.total, num_evals=budget.cycles + 1,
                  episode_length=budget.episode_length, num_envs=5, num_eval_envs=1, batch_size=128,
                  min_replay_size=128, max_replay_size=min(budget.total, 100_000),
                  learning_rate=3e-4, discounting=0.99, reward_scaling=100.0, normalize_observations=True,
                  max_devices_per_host=1, seed=seed, checkpoint_logdir=logdir)
        for path in sorted(Path(logdir).iterdir(), key=lambda p: int(p.name)):
            on_cycle(int(path.name), tuple(sac_checkpoint.load(path))[:2])


TRAINERS = {"ppo": train_ppo, "sac": train_sac}


def policy_bridge(env: NoveltyEnv, approach) -> tuple[PolicyBridge, Controls]:
    """A low-level approach's trained agent as the meta-policy's bridge on `env`, with its controls."""
    controls = approach.controls  # a low-level approach's controls are the brax view's
    return PolicyBridge(env, approach.algorithm, controls.call_planner, observation_size(env, controls)), controls


def evaluate(env: NoveltyEnv, approach, params, arrays: TaskArrays, keys: jax.Array, max_steps: int):
    """EpisodeResult of the greedy low-level policy on `arrays`' episodes (planner until stuck, then it)."""
    bridge, controls = policy_bridge(env, approach)
    result, _ = rollout(MetaPolicy(env, bridge, params, controls, shared_params=True), arrays, keys, max_steps)
    return result
