"""The low-level baselines (issue 22): the brax view of an env from its stuck state, the meta-policy with a
low-level bridge, and train.py running them beside ours."""
import csv
import os
from dataclasses import dataclass

import chex
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from run_helpers import train

from bench.probes.low_level import main as low_level_table

from envs_jax import env_class
from envs_jax.base import BridgeAction, BridgeObs
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.tasks import evaluation_batch, make_batch
from jaxbridge.learn.brax_env import BridgeEnv, low_level_controls, scaled_choice
from jaxbridge.learn.low_level import PolicyBridge, _networks
from jaxbridge.utils.compile_cache import CacheJanitor

from brax.envs.wrappers.training import wrap  # noqa: E402 -- after brax_env, which imports brax quietly
from brax.training.acme import running_statistics, specs


def adapter(env_name: str, call_planner: bool, seed: int = 0, full_state: bool = False) -> BridgeEnv:
    cls = env_class(env_name)
    batch = make_batch(cls, [cls.train_task(seed)], [seed], horizons=[100])
    return BridgeEnv(batch.env, batch.arrays, call_planner, full_state)


def squashed(env, action) -> np.ndarray:
    """The agent's [-1, 1] action that scales to the raw `action` (the inverse of scaled_choice's map)."""
    low, high = env.action_bounds()
    return 2 * (np.asarray(action, np.float32) - low) / (high - low) - 1


# Every env with CallPlanner (its step runs the planner's stretch); without it, the plain step, on one env:
# the Doorknobs and Coffee programs take 20-40 s each to compile.
# The wrappers are the env's adapter's alone: Light Switch Door without the CallPlanner dimension (its is
# stepped directly by the oracle action sequence below), Coffee with it; Doorknobs' adapter resets to its
# stuck state in the full-state test below.
@pytest.mark.parametrize("env_name, call_planner", [("light_switch_door", False), ("coffee", True)])
def test_the_adapter_meets_brax_expectations_under_its_training_wrappers(env_name, call_planner):
    view = adapter(env_name, call_planner)
    env = view.env
    assert view.action_size == env.action_dim + call_planner
    assert view.observation_size == env.num_features
    low, high = env.action_bounds()
    assert low.shape == high.shape == (env.action_dim,) and np.all(low < high)
    state = jax.eval_shape(view.reset, jax.random.PRNGKey(0))  # its shapes; its values under the wrappers below
    chex.assert_shape(state.obs, (view.observation_size,))
    chex.assert_shape([state.reward, state.done], ())
    # brax's own wrappers (vmap, episode length, auto-reset) step it on a batch
    wrapped = wrap(view, episode_length=100)
    batch = jax.jit(wrapped.reset)(jax.random.split(jax.random.PRNGKey(1), 3))
    assert not batch.done.any()  # the training task's planner gets stuck before its goal
    stepped = jax.jit(wrapped.step)(batch, jnp.zeros((3, view.action_size)))
    chex.assert_shape(stepped.obs, (3, view.observation_size))
    chex.assert_shape([stepped.reward, stepped.done], (3,))
    chex.assert_trees_all_equal_shapes_and_dtypes(stepped.pipeline_state, batch.pipeline_state)


def test_the_full_state_variant_observes_the_full_state_of_the_stuck_state():
    view = adapter("doorknobs", call_planner=False, full_state=True)
    state = view.reset(jax.random.PRNGKey(0))
    assert view.observation_size == view.env.full_state_size
    stuck = jax.tree.map(lambda x: x[0], state.pipeline_state.episodes.env_state)
    np.testing.assert_array_equal(state.obs, view.env.full_state(stuck))
    assert not np.array_equal(state.obs, np.asarray(view.env.full_state(view.env.reset(
        jax.tree.map(lambda x: x[0], view.task.tasks)))))  # the planner moved the robot before it got stuck


def lsd_oracle(features) -> np.ndarray:
    """The oracle's fix as raw Light Switch Door actions: set the door's move key, then its turn key, then
    hand control back (the last entry, the CallPlanner dimension)."""
    has, move_key, move_target, turn_key, turn_target = (float(x) for x in features)
    if has and abs(move_key - move_target) > 0.1:
        return np.array([0, 0, move_target - move_key, 0, -1], np.float32)
    if has and abs(turn_key - turn_target) > 0.1:
        return np.array([0, 0, 0, turn_target - turn_key, -1], np.float32)
    return np.array([0, 0, 0, 0, 1], np.float32)


@pytest.mark.parametrize("seed", [0, 3])
def test_an_oracle_low_level_action_sequence_from_the_stuck_state_reaches_the_goal_with_reward_1(seed):
    view = adapter("light_switch_door", call_planner=True, seed=seed)
    env, step = view.env, jax.jit(view.step)
    state = view.reset(jax.random.PRNGKey(0))
    assert float(state.obs[0]) == 1.0  # stuck at a closed door
    rewards, env_steps = [], [int(state.pipeline_state.episodes.t[0])]
    while not state.done:
        raw = lsd_oracle(state.obs)
        state = step(state, jnp.asarray(np.concatenate([squashed(env, raw[:4]), raw[4:]])))
        rewards.append(float(state.reward))
        env_steps.append(int(state.pipeline_state.episodes.t[0]))
        assert len(rewards) < 30
    assert rewards[-1] == 1.0 and sum(rewards) == 1.0
    # a key step is one env step; CallPlanner's step covers the planner's whole stretch after it
    jumps = np.diff(env_steps)
    assert set(jumps[:2]) == {1} and jumps[-1] > 1
    # without the CallPlanner dimension the same keys open the door but nothing turns the light on
    view = adapter("light_switch_door", call_planner=False, seed=seed)
    state = view.reset(jax.random.PRNGKey(0))
    for _ in range(3):
        state = jax.jit(view.step)(state, jnp.asarray(squashed(env, lsd_oracle(state.obs)[:4])))
    assert float(state.reward) == 0.0 and not state.done


@dataclass(frozen=True)
class LowLevelOracle:
    """lsd_oracle as a low-level bridge of the meta-policy."""

    env: object

    def __call__(self, params, obs, key) -> BridgeAction:
        has, move_key, move_target, turn_key, turn_target = (obs.features[i] for i in range(5))
        move_off = (has > 0.5) & (jnp.abs(move_key - move_target) > 0.1)
        turn_off = (has > 0.5) & (jnp.abs(turn_key - turn_target) > 0.1)
        raw = jnp.stack([0.0, 0.0, jnp.where(move_off, move_target - move_key, 0.0),
                         jnp.where(move_off | ~turn_off, 0.0, turn_target - turn_key)])
        low, high = (jnp.asarray(b) for b in self.env.action_bounds())
        call = jnp.where(move_off | turn_off, -1.0, 1.0)
        return scaled_choice(self.env, jnp.append(2 * (raw - low) / (high - low) - 1, call),
                             obs.num_ground[-1] > 0, call_planner=True)


def test_the_meta_policy_with_a_low_level_bridge_applies_its_raw_actions_on_the_test_tasks():
    batch = evaluation_batch(env_class("light_switch_door"), [0], 10)
    keys = jax.random.split(jax.random.key(0), batch.size)
    oracle = lambda call_planner: MetaPolicy(batch.env, LowLevelOracle(batch.env), None,
                                             low_level_controls(call_planner=call_planner))
    result, records = rollout(oracle(True), batch.arrays, keys, batch.max_steps, record=True)
    assert np.asarray(result.success).all()
    # the bridge decides at every step it controls (no skill runs on): one decision per bridge step
    decided, bridge = np.asarray(records.decided), (np.asarray(records.actor) == 1) & np.asarray(records.live)
    assert decided[bridge].all() and np.asarray(result.bridge_decisions).sum() == decided.sum()
    # the same bridge without CallPlanner fixes the first door and is then stuck with the light off
    result, _ = rollout(oracle(False), batch.arrays, keys, batch.max_steps)
    assert not np.asarray(result.success).any()


def test_a_policy_bridge_acts_by_its_networks_mode_within_the_env_bounds():
    env = env_class("doorknobs").for_tasks([env_class("doorknobs").train_task(0)])
    nets = _networks("ppo", env.num_features, env.action_dim)
    normalizer = running_statistics.init_state(specs.Array((env.num_features,), jnp.float32))
    policy = nets.policy_network.init(jax.random.PRNGKey(0))
    params = (normalizer, policy)
    bridge = PolicyBridge(env, "ppo", False, env.num_features)
    obs = BridgeObs(features=jnp.linspace(-3, 3, env.num_features), num_ground=jnp.ones(env.num_skills + 1, jnp.int32))
    choice = bridge(params, obs, jax.random.key(0))
    low, high = env.action_bounds()
    assert int(choice.skill) == 0 and np.all(low <= choice.action) and np.all(choice.action <= high)
    logits = nets.policy_network.apply(normalizer, policy, obs.features)
    expected = low + (np.tanh(np.asarray(logits[:env.action_dim])) + 1) / 2 * (high - low)
    np.testing.assert_allclose(choice.action, expected, rtol=1e-5, atol=1e-6)


def test_train_runs_ours_and_low_level_baselines_into_one_table_eval_and_resume(tmp_path, capsys, eval_main):
    # One low-level approach beside ours, one seed: each seed's brax trainer compiles anew (~20 s), so a
    # second approach or seed would double the test's cost for the same code path (the adapter's step
    # without CallPlanner is tested above).
    proc = train("--env", "light_switch_door", "--approaches", "ours,low_level_ppo_callplanner",
                 "--num-seeds", "1", "--cycles", "3", "--no-progress", "--out", str(tmp_path), "--name", "ll", timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "warp" not in proc.stdout + proc.stderr  # brax's optional backends stay quiet
    experiment = tmp_path / "ll"
    table = (experiment / "results.md").read_text()
    assert table.count("| ours | 1 |") == 2 and table.count("| low-level PPO + CallPlanner | 1 |") == 2
    metrics = lambda run: list(csv.DictReader((experiment / run / "metrics.csv").open()))
    rows = metrics("low_level_ppo_callplanner")
    assert [(r["seed"], r["cycle"]) for r in rows] == [("0", c) for c in "123"]
    # the paper's budget: 5 episodes x 100 agent steps (a planner's stretch after CallPlanner is one)
    assert all(int(r["train_env_steps"]) == 500 for r in rows)
    # eval.py loads the last policy and finds the seed's last test solve rate again
    assert eval_main([str(experiment), "--approach", "low_level_ppo_callplanner"]) == 0
    out = capsys.readouterr().out
    last = {r["seed"]: float(r["test_solve_rate"]) for r in rows if r["cycle"] == "3"}
    row = next(line.split() for line in out.splitlines() if line.split()[:1] == ["0"])
    assert float(row[-6]) == last["0"]  # solve rate, then steps, calls, stuck, decisions, misses
    # --resume keeps finished low-level runs as they are
    before = (experiment / "low_level_ppo_callplanner" / "metrics.csv").read_bytes()
    resumed = train("--resume", str(experiment), "--no-progress", timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert (experiment / "low_level_ppo_callplanner" / "metrics.csv").read_bytes() == before
    # bench.probes.low_level's table: training steps per seed so far, and who ever solved a test task
    low_level_table([str(experiment)])
    out = capsys.readouterr().out
    solved = int(any(float(r["test_solve_rate"]) > 0 for r in rows))
    row = next(line for line in out.splitlines() if line.startswith("| low-level PPO + CallPlanner | 0 |"))
    assert row.split(" | ")[2] == "1,500" and row.endswith(f"| {solved}/1 |")
    ours = next(line for line in out.splitlines() if line.startswith("| ours | 0 |"))
    steps = sum(int(r["train_env_steps"]) for r in metrics("ours"))
    assert ours.split(" | ")[2] == f"{steps:,.0f}"


def fake_process(root, maps: int, resident_pages: int):
    """A /proc/self of `maps` mappings and `resident_pages` resident pages, under `root`."""
    root.mkdir(exist_ok=True)
    (root / "maps").write_text("mapping\n" * maps)
    (root / "statm").write_text(f"999 {resident_pages} 0 0 0 0 0\n")


@pytest.mark.parametrize("maps, grown_pages, cleared", [(10, 5, False), (60, 5, True), (10, 50, True), (None, 0, True)])
def test_the_cache_janitor_clears_only_when_maps_or_memory_run_short(tmp_path, maps, grown_pages, cleared):
    """Between low-level seeds: clearing makes every other approach's program trace again, so it waits
    until the process holds half the kernel's maps or has grown past its allowance (or cannot tell)."""
    page = os.sysconf("SC_PAGE_SIZE")
    proc, limit = tmp_path / "self", tmp_path / "max_map_count"
    limit.write_text("100\n")
    fake_process(proc, 10, 100)
    janitor = CacheJanitor(max_growth=20 * page, proc=proc, map_limit=limit)
    if maps is None:
        (proc / "maps").unlink()
    else:
        fake_process(proc, maps, 100 + grown_pages)
    program = jax.jit(lambda x: x + 1)
    program(jnp.ones(3))
    assert janitor() == cleared
    assert program._cache_size() == (0 if cleared else 1)
