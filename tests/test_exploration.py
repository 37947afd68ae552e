"""The count bonus (learn/exploration.py, `count_bonus`): its formula on a hand-made episode, off it leaves
the learner (and so the compiled program) as it was, on it wraps every learner and resumes exactly."""
from __future__ import annotations

import jaxbridge
import jax.numpy as jnp
import numpy as np
import pytest
from run_helpers import trained_whole_and_resumed

from jaxbridge.learn import dqn, pqn
from jaxbridge.learn.exploration import (TABLE_SIZE, CountExploration, count_bonus, observation_slots,
                                         with_exploration)
from jaxbridge.learn.learner import check_learner
from jaxbridge.learn.setup import make_setup
from jaxbridge.learn.transitions import Transition
from jaxbridge.run.checkpoint import restore

SEQUENCE = "envs_jax.light_switch_door.sequence:LightSwitchSequence_k2"


def episode(next_features: list[list[float]], valid: list[bool], done: list[bool]) -> tuple[Transition, jnp.ndarray]:
    """One episode's transitions ([1, T]): the first decision sees features [0, 0]."""
    nxt = jnp.asarray([next_features], jnp.float32)
    features = jnp.concatenate([jnp.zeros((1, 1, 2)), nxt[:, :-1]], 1)
    steps = nxt.shape[1]
    return Transition(features=features, skill=jnp.zeros((1, steps), jnp.int32), param=jnp.zeros((1, steps)),
                      reward=jnp.zeros((1, steps)), done=jnp.asarray([done]), next_features=nxt,
                      next_num_ground=jnp.ones((1, steps, 2), jnp.int32)), jnp.asarray([valid])


def test_the_bonus_is_paid_once_per_episode_per_observation_and_shrinks_with_the_seeds_count():
    a, b, c = [1.0, 0.5], [1.0, 0.25], [0.0, 0.0]  # c: the episode's first observation
    transitions, valid = episode([a, b, a, c, b, a], [True, True, True, True, False, True], [False] * 5 + [True])
    slots = np.asarray(observation_slots(jnp.asarray([a, b, c])))
    assert len(set(slots.tolist())) == 3
    counts = jnp.zeros(TABLE_SIZE, jnp.int32).at[slots[1]].set(3)  # b reached 3 times in earlier cycles
    bonus, after = count_bonus(0.5, counts, transitions, valid)
    # a: new, the 1st visit; b: new, the 4th; a again, c (the start), a row that is no decision, the goal: 0
    np.testing.assert_allclose(np.asarray(bonus)[0], [0.5, 0.5 / 2, 0, 0, 0, 0], rtol=1e-6)
    assert [int(after[s]) for s in slots] == [2, 4, 1] and int(after.sum()) == 7  # every counted visit, repeats too
    later, _ = count_bonus(0.5, after, transitions, valid)
    np.testing.assert_allclose(np.asarray(later)[0, :2], [0.5 / np.sqrt(3), 0.5 / np.sqrt(5)], rtol=1e-6)


@pytest.mark.parametrize("learner", ["dqn", "pqn"])
def test_off_the_learner_is_the_plain_one_and_on_it_is_wrapped_and_keeps_the_contract(learner):
    plain = jaxbridge.make_config(SEQUENCE, learner=learner, num_seeds=1)
    setup = make_setup(plain)
    made = {"dqn": dqn.DQN, "pqn": pqn.PQN}[learner].create(plain, setup.train_env, 3, False)
    assert plain.learner.count_bonus == 0 and with_exploration(made, plain) is made  # the factory's own learner: today's program
    assert type(setup.learner) is type(made)
    on = make_setup(jaxbridge.make_config(SEQUENCE, learner=learner, num_seeds=1, count_bonus=0.1))
    assert isinstance(on.learner, CountExploration) and type(on.learner.inner) is type(made) and on.learner.scale == 0.1
    check_learner(on.learner, on.config)
    for approach in ("no_feature_selection", "maple_q", "no_callplanner"):  # every approach that learns
        config = jaxbridge.make_config(SEQUENCE, approach=approach, learner=learner, num_seeds=1, count_bonus=0.1)
        assert isinstance(make_setup(config).learner, CountExploration)


def test_with_the_bonus_a_run_checkpoints_its_counts_and_resumes_exactly(tmp_path):
    config = jaxbridge.make_config(SEQUENCE, num_seeds=1, cycles=2, episodes_per_cycle=2, num_test_tasks=2,
                                 updates_per_cycle=10, buffer_capacity=256, checkpoint_every=1, count_bonus=0.1)
    setup = make_setup(config)
    whole, crashed = trained_whole_and_resumed(setup, tmp_path, crash_at=2)
    assert (crashed / "metrics.csv").read_bytes() == (whole / "metrics.csv").read_bytes()
    state, _, _ = restore(crashed / "checkpoints", setup.init_learners())
    rewards = np.asarray(state.inner.buffer.data.reward)[0, :int(state.inner.buffer.size[0])]
    assert int(state.counts.sum()) > 0 and ((rewards > 0) & (rewards < 1)).any()  # bonuses stored, no goal's 1
