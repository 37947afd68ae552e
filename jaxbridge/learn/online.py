"""The online learning loop: per cycle, training episodes, the learner's updates, greedy test evaluation.

One jitted `cycle` runs a whole cycle for every seed: the seed axis is sharded over the devices and
each device runs the same per-seed cycle on its seeds one after another (learn/devices.py says why
not a `vmap`: bit-identical numbers whatever the device count). Within a seed, its episodes form one
batch of the meta-policy rollout (the planner's table lookups, the bridge's decisions and the env steps
of every episode advance together). A host loop over cycles drives progress, logging and checkpoints;
nothing inside a cycle touches the host.
"""
from __future__ import annotations

from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from jaxbridge.core.config import TrainConfig
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import TaskArrays
from jaxbridge.learn.approaches import BridgeKind
from jaxbridge.learn.devices import SeedMesh
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.learner import QLearner, epsilon
from jaxbridge.learn.q_bridge import QBridgeParams
from jaxbridge.learn.setup import Setup, seed_keys
from jaxbridge.learn.transitions import episode_transitions


@struct.dataclass
class CycleMetrics:
    """One cycle's numbers, one entry per seed."""

    test_solve_rate: jax.Array
    train_success_rate: jax.Array
    train_env_steps: jax.Array
    train_decisions: jax.Array  # bridge decisions in this cycle's training episodes
    test_env_steps: jax.Array
    test_decisions: jax.Array  # bridge decisions per test task (a repaired model needs fewer)
    epsilon: jax.Array  # during this cycle's training episodes
    loss: jax.Array  # mean TD loss of this cycle's updates
    q_abs_max: jax.Array  # largest |Q| predicted in this cycle's updates (a non-finite value stops a run)
    buffer_size: jax.Array
    table_misses: jax.Array  # planner lookups answered by the host planner (train + test)


def _repeat(params, n: int):
    """One seed's network for each of n episodes."""
    return jax.tree.map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), params)


def bridge_params(learning: QLearner, params: Any, eps: jax.Array, n: int) -> QBridgeParams:
    """The Q bridge's parameters for n episodes of one seed: its network `params` given once (a learner
    whose rollouts share it) or a copy per episode, with the exploration rate `eps`."""
    if learning.shares_network:
        return QBridgeParams(q=params, epsilon=eps)
    return QBridgeParams(q=_repeat(params, n), epsilon=jnp.full(n, eps, jnp.float32))


def _by_seed(tree, seeds: int):
    """Seed-major batch [seeds * n, ...] -> [seeds, n, ...], in host memory (an eager reshape of a device
    array compiles a program per leaf shape)."""
    return jax.tree.map(lambda x: np.reshape(np.asarray(x), (seeds, -1) + x.shape[1:]), tree)


def make_seed_cycle(setup: Setup, host_planner: bool = True) -> Callable:
    """One seed's cycle: (learner state, its training TaskArrays, its test TaskArrays, its Hyper) -> (learner
    state, (CycleMetrics of scalars, the training episodes' StepRecords where the approach repairs its model
    from them, else None)), against the learner contract (learn/learner.py). The same computation for every
    seed and setting. Without `host_planner` its rollouts leave states missing from the plan tables
    unplanned (meta_policy.rollout): exact only where the metrics report no table miss."""
    config, approach, test = setup.config, setup.approach, setup.test
    controls = setup.controls
    train_env, test_env = setup.train_env, setup.test_env  # the task batches' envs, with the config's quirks
    train_bridge, test_bridge = setup.bridge(train_env), setup.bridge(test_env)
    episodes, num_tests = config.episodes_per_cycle, config.num_test_tasks
    call_planner = train_env.num_skills
    shared = setup.learner.shares_network  # one copy of the seed's network for its episodes, or one each
    config.check_buffer_fits()

    def seed_cycle(learner: Any, train_tasks: TaskArrays, test_tasks: TaskArrays,
                   hyper: Hyper) -> tuple[Any, CycleMetrics]:
        k_next, k_train, k_learn, k_test = jax.random.split(learner.key, 4)
        slot = config.with_leaves(hyper.values)  # the slot's settings, every leaf its traced value
        learning = setup.learner_for(slot)

        # 1. Training episodes, epsilon-greedy, on the seed's training task.
        eps = epsilon(slot, learner.decisions)
        explore = bridge_params(learning, learning.greedy(learner), eps, episodes)
        result, records = rollout(MetaPolicy(train_env, train_bridge, explore, controls, shared), train_tasks,
                                  jax.random.split(k_train, episodes), config.train_steps, record=approach.learns,
                                  host_planner=host_planner)
        decisions = result.bridge_decisions.sum()

        if approach.learns:
            # 2. One transition per bridge decision, to the learner.
            transitions, valid = jax.vmap(episode_transitions, in_axes=(1, 0, None, None, None, None))(
                records, result.success, call_planner, slot.call_planner_bonus, config.counts_steps,
                controls.plan_progress)
            learner = learning.observe(learner, transitions, valid)
            learner = learner.replace(decisions=learner.decisions + decisions, key=k_learn)

            # 3. The learner's updates.
            learner, loss, q_abs_max = learning.learn(learner, decisions, train_tasks.tasks)
        else:  # random bridge, pure planning: nothing to learn, the same act-and-test loop
            learner = learner.replace(decisions=learner.decisions + decisions)
            eps = jnp.float32(1.0 if approach.bridge is BridgeKind.RANDOM else 0.0)
            loss = q_abs_max = jnp.float32(0.0)
        learner = learner.replace(key=k_next)

        # 4. Greedy evaluation on the seed's test tasks.
        greedy = bridge_params(learning, learning.greedy(learner), jnp.float32(0.0), num_tests)
        tested, _ = rollout(MetaPolicy(test_env, test_bridge, greedy, controls, shared), test_tasks,
                            jax.random.split(k_test, num_tests), test.max_steps, host_planner=host_planner)

        metrics = CycleMetrics(
            test_solve_rate=tested.success.mean(), train_success_rate=result.success.mean(),
            train_env_steps=result.steps.sum(), train_decisions=decisions, test_env_steps=tested.steps.sum(),
            test_decisions=tested.bridge_decisions.mean(),
            epsilon=eps, loss=loss, q_abs_max=q_abs_max, buffer_size=learning.stored(learner),
            table_misses=result.table_misses.sum() + tested.table_misses.sum())
        return learner, (metrics, records if approach.repairs_model else None)

    return seed_cycle


class Cycle:
    """One jitted cycle of every slot: `cycle(learners) -> (learners, metrics)`.

    A slot is a (setting, seed) pair, setting-major: `settings` are configs that differ from
    `setup.config` only in their leaf hyperparameters (declared `leaf=True`, core/settings.py; default: that config
    alone), and each passes its values to its seeds' slots as leaves (learn/hyper.py), so one program
    serves them all. Learner states and metrics carry the placed slot axis of `seeds` (padded to a multiple of
    the device count and sharded over the devices: `seeds.place(...)`, `seeds.unpad(...)`). Each device
    runs the per-seed cycle on its slots one after another (learn/devices.py), so the numbers depend
    neither on the device count nor on the other settings."""

    def __init__(self, setup: Setup, seeds: SeedMesh | None = None, settings: list[TrainConfig] | None = None):
        config, settings = setup.config, settings or [setup.config]
        slots = len(settings) * config.num_seeds
        self.seeds = seeds or SeedMesh(slots, block=config.seed_block)
        assert (self.seeds.num_seeds, self.seeds.block) == (slots, config.seed_block)
        tasks = _by_seed((setup.train.arrays, setup.test.arrays), config.num_seeds)
        if len(settings) > 1:  # every setting trains and tests on the seeds' tasks
            tasks = jax.tree.map(lambda x: np.concatenate([x] * len(settings)), tasks)
        self._hypers = jax.tree.map(lambda *v: np.repeat(np.stack(v), config.num_seeds), *map(Hyper.of, settings))
        self._inputs = self.seeds.place((*tasks, self._hypers))
        self.repairs_model = setup.approach.repairs_model
        self.records = None  # the last cycle's training StepRecords [slots, T, episodes] (repairs_model)
        self._real = self.seeds.real()
        # No buffer donation: the state before a cycle must stay valid, so that Ctrl-C or a numerical
        # fault during a cycle can still checkpoint the last good one (and a cycle can be run again).
        # out_shardings: the learners come back laid out as they went in. Left to XLA, a 1-device mesh
        # returns some leaves replicated (PartitionSpec()) instead of split over the seed axis: the same
        # memory, but a different jit cache key, so the second cycle compiled the whole program again.
        self._compile = lambda host_planner: jax.jit(self.seeds.map_seeds(make_seed_cycle(setup, host_planner)),
                                                     out_shardings=self.seeds.sharding)
        # First without the host planner: a program without host callbacks, which JAX's persistent cache
        # keeps, so a later process (a resumed run, the next experiment) need not compile it again.
        self._tables_only = self._compile(False)
        self._with_host = None  # compiled on the first cycle that meets a state missing from a table

    def retask(self, train: TaskArrays, test: TaskArrays) -> None:
        """Every slot's training and test tasks from now on (leading axis: slots), e.g. planned with a
        model learned since: the program compiles again where their shapes changed."""
        self._inputs = self.seeds.place((train, test, self._hypers))

    def run(self, learners: Any, host_planner: bool) -> tuple[Any, tuple[CycleMetrics, Any]]:
        """One cycle by one of the two programs (traceable): without the host planner, exact only where
        the metrics report no table miss; or with it."""
        if host_planner and self._with_host is None:
            self._with_host = self._compile(True)
        program = self._with_host if host_planner else self._tables_only
        return program(self._real, learners, *self._inputs)

    def __call__(self, learners: Any) -> tuple[Any, CycleMetrics]:
        if not self.repairs_model:  # a learned model's plans leave its table at once: straight to the host
            updated, (metrics, _) = self.run(learners, host_planner=False)
            if not np.asarray(self.seeds.unpad(metrics.table_misses)).any():
                return updated, metrics
        # Some episode needed the host planner: the same cycle again from the same state, with it (every
        # process sees the same gathered metrics, so all take this branch together).
        updated, (metrics, self.records) = self.run(learners, host_planner=True)
        return updated, metrics


@struct.dataclass
class TrainOutput:
    """What `make_train`'s function returns: every seed's final learner and every cycle's metrics."""

    learners: Any  # leading axis: seeds
    metrics: CycleMetrics  # each field [seeds, cycles]


def make_train(setup: Setup) -> Callable[..., TrainOutput]:
    """The whole online-learning run of `setup` as one pure function (PureJaxRL's shape):
    `train(keys=None, hyper=None) -> TrainOutput`, every cycle of every seed, no files and no host work.

    `keys`: one per seed (default `seed_keys(config)`, a plain run's); `hyper`: the numeric hyperparameters
    as leaves (default `Hyper.of(config)`). jit it, or vmap it over keys or over `Hyper` leaves: the runs
    of a vmap go one after another. Each seed runs its cycles as a plain run's cycle does (the same
    per-seed program, seeds one after another), so the metrics are the run's where no plan-table lookup
    misses: the rollouts do not call the host planner, so a missed lookup leaves that episode unplanned,
    and `metrics.table_misses` counts them."""
    config = setup.config
    if setup.approach.low_level:
        raise ValueError(f"{config.approach}: the low-level baselines train with brax's own loop, not make_train")
    if setup.approach.repairs_model:
        raise ValueError(f"{config.approach}: its model is relearned on the host between cycles, not in make_train")
    seed_cycle = make_seed_cycle(setup, host_planner=False)
    tasks = _by_seed((setup.train.arrays, setup.test.arrays), config.num_seeds)
    init = jax.vmap(setup.learner.init)

    def one_seed(args):
        learner, train_tasks, test_tasks, hyper = args

        def cycle(learner, _):  # the barriers keep the per-seed program the one a plain run compiles
            learner, inputs = jax.lax.optimization_barrier((learner, (train_tasks, test_tasks, hyper)))
            learner, (metrics, _) = jax.lax.optimization_barrier(seed_cycle(learner, *inputs))
            return learner, metrics

        return jax.lax.scan(cycle, learner, None, length=config.cycles)

    @jax.custom_batching.custom_vmap
    def run(keys: jax.Array, hyper: Hyper) -> TrainOutput:
        hypers = jax.tree.map(lambda x: jnp.broadcast_to(jnp.float32(x), (config.num_seeds,)), hyper)
        learners, metrics = jax.lax.map(one_seed, (init(keys), *tasks, hypers))
        return TrainOutput(learners=learners, metrics=metrics)

    @run.def_vmap
    def one_run_after_another(axis_size: int, in_batched: list, keys: jax.Array, hyper: Hyper):
        # vmap over runs (keys, settings) runs them one after another, each by the plain run's program, as
        # train.py --sweep does: batching their ops would let XLA sum in other orders, and a last-bit
        # difference can flip a greedy choice cycles later.
        keys, hyper = (jax.tree.map(lambda x, b: x if b else jnp.broadcast_to(x, (axis_size,) + x.shape), arg, batched)
                       for arg, batched in zip((keys, hyper), in_batched))
        out = jax.lax.map(lambda args: run(*args), (keys, hyper))
        return out, jax.tree.map(lambda _: True, out)

    def train(keys: jax.Array | None = None, hyper: Hyper | None = None) -> TrainOutput:
        return run(seed_keys(config) if keys is None else keys, Hyper.of(config) if hyper is None else hyper)

    return train
