"""The learned object selector (issue 37): its network reads any number of objects in any order, looks only
at objects a skill can act on, and the approach trains, checkpoints and evaluates as every other."""
import jaxbridge
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from envs_jax import env_class
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.observations import object_tokens, robot_features, token_slots, token_width
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.object_q import attention
from jaxbridge.learn.q_bridge import encode
from run_helpers import cli_in_process, train

ENV = env_class("light_switch_door")
SELECTOR = get_approach("ours_learned_selection")


def lsd_state(cells: int, doors: tuple[int, ...], robot_x: float):
    """An LSD env and a state of its one task with the robot at `robot_x`."""
    spec = ENV.sized_task(np.random.default_rng(0), cells, len(doors)).__class__(cells, doors)
    env = ENV.for_tasks([spec])
    return env, env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec))).replace(robot_x=jnp.float32(robot_x))


def lsd(cells: int, doors: tuple[int, ...], robot_cell: int, stuck_cell: int | None = None):
    """An LSD env and the object tokens of a state of one task with the robot in `robot_cell`, stuck in
    `stuck_cell` (there by default)."""
    env, state = lsd_state(cells, doors, robot_cell + 0.5)
    stuck_state = state.replace(robot_x=jnp.float32((robot_cell if stuck_cell is None else stuck_cell) + 0.5))
    return env, object_tokens(env, state, stuck_state)


def network(env, **settings):
    net = SELECTOR.q_network(TrainConfig(approach="ours_learned_selection", **settings), env)

    width = len(token_slots(env)) * token_width(env)
    x = encode(env, jnp.zeros(width), jnp.int32(0), jnp.float32(0.5))
    params = net.init(jax.random.key(0), x)
    # a non-zero output layer, so that the Q-values say something (it starts at zero)
    return net, jax.tree.map(lambda p: p + 0.1 * jax.random.normal(jax.random.key(1), p.shape), params)


def q_values(env, net, params, tokens):
    skills, param = jnp.arange(env.num_skills + 1), jnp.full(env.num_skills + 1, 0.5)
    return np.asarray(net.apply(params, encode(env, tokens, skills, param)))


def test_tokens_hold_each_real_object_and_mark_what_can_be_acted_on():
    env, tokens = lsd(6, (1, 3), robot_cell=3)
    assert list(token_slots(env)) == [0, 1, 8, 9]  # the robot, the light and the doors: cells are never acted on
    rows = np.asarray(tokens).reshape(-1, token_width(env))
    types, interactable, x = rows[:, :4].argmax(1), rows[:, -1], rows[:, 12]
    assert list(types) == [0, 1, 3, 3] and not rows[0, 4:].any()  # the robot first: no features, at itself
    assert list(np.flatnonzero(interactable)) == [1, 2, 3]
    assert rows[3, 4:9].tolist() == [0.0, 0.0, 0.5, 0.0, 0.75] and x[3] == 0.0  # door 1's keys and targets, here
    assert x[2] == pytest.approx(-2 / 3) and x[1] == pytest.approx(2 / 3)  # door 0 two cells back, the light two ahead
    np.testing.assert_array_equal(rows[:, 9:12], rows[:, 12:15])  # stuck here: the offsets then are those now


def test_tokens_keep_each_object_where_it_was_from_the_stuck_robot_and_say_how_far_it_moved():
    env, tokens = lsd(6, (1, 3), robot_cell=1, stuck_cell=3)
    _, stuck_here = lsd(6, (1, 3), robot_cell=3)
    rows, then = (np.asarray(t).reshape(-1, token_width(env)) for t in (tokens, stuck_here))
    np.testing.assert_array_equal(rows[1:, 9:12], then[1:, 9:12])  # the objects' offsets at the stall
    assert rows[0, 9] == pytest.approx(-2 / 3) and rows[0, 12] == 0.0  # the robot: two cells back since
    assert rows[3, 12] == pytest.approx(2 / 3) and rows[3, 9] == 0.0  # door 1 two cells ahead now, here then


@pytest.mark.parametrize("distance, nearest", [("stall", 2), ("now", 3)])
def test_attention_reads_the_distance_it_is_set_to(distance, nearest):
    """Stuck beside door 0 (cell 1), the robot has walked to door 1 (cell 5): each distance has its nearest."""
    env, tokens = lsd(8, (1, 5), robot_cell=5, stuck_cell=1)
    net, params = network(env, attention_distance=distance)
    weights = np.asarray(attention(net, params, tokens))
    assert weights.argmax() == nearest and weights[nearest] > 0.9


@pytest.mark.parametrize("read", [False, True])
def test_the_q_network_reads_the_robots_own_features_only_when_asked(read):
    """Coffee's robot has features (z, tilt, wrist, fingers): with only the jug to look at, so that attention
    cannot move, Q changes with them only under attention_robot_features; it reads the jug either way."""
    coffee = env_class("coffee")
    spec = coffee.train_task(0)
    env = coffee.for_tasks([spec])
    state = env.reset(jax.tree.map(jnp.asarray, env.task_arrays(spec)))
    rows = np.asarray(object_tokens(env, state, state)).reshape(-1, token_width(env)).copy()
    rows[2:, -1] = 0.0  # the jug (token 1) the one object a skill can act on
    net, params = network(env, attention_robot_features=read)
    q = q_values(env, net, params, jnp.asarray(rows.reshape(-1)))
    features = slice(*robot_features(env))
    assert (features.start, features.stop) == (4, 8) and robot_features(ENV) is None  # LSD's robot has none
    moved, turned = rows.copy(), rows.copy()
    moved[0, features] += 0.5  # the robot's own features
    turned[1, features.start] += 0.5  # the jug's rotation
    assert not np.allclose(q_values(env, net, params, jnp.asarray(turned.reshape(-1))), q)
    assert np.allclose(q_values(env, net, params, jnp.asarray(moved.reshape(-1))), q) != read


def test_a_fixed_penalty_is_the_learned_ones_start_without_a_parameter():
    from flax import traverse_util
    env, tokens = lsd(8, (1, 3, 5), robot_cell=3)
    net, params = network(env, attention_fixed_penalty=False)
    flat = traverse_util.flatten_dict(params)
    at_start = {k: jnp.log(jnp.expm1(jnp.float32(16.0))) if k[-1] == "near" else v for k, v in flat.items()}
    fixed, _ = network(env, attention_fixed_penalty=True)
    without = traverse_util.unflatten_dict({k: v for k, v in flat.items() if k[-1] != "near"})
    assert len(at_start) == len(flat) > len(traverse_util.flatten_dict(without))
    expected = np.asarray(attention(net, traverse_util.unflatten_dict(at_start), tokens))
    np.testing.assert_allclose(np.asarray(attention(fixed, without, tokens)), expected, rtol=1e-5, atol=1e-7)
    assert not np.allclose(np.asarray(attention(net, params, tokens)), expected)  # a learned one moves


@pytest.mark.parametrize("kind_noise", [False, True])
def test_a_learned_selectors_feature_noise_leaves_what_an_object_is_exact_unless_asked(kind_noise):
    """Feature noise on object tokens perturbs each token's features and offsets; its type's one-hot and its
    interactable flag stay exact (drawn only for the entries it perturbs), unless `attention_kind_noise`."""
    from jaxbridge.learn import dqn
    config = jaxbridge.make_config("coffee", approach="ours_learned_selection", feature_noise=0.1,
                                 attention_kind_noise=kind_noise)
    env = env_class("coffee")()
    learning = dqn.make_dqn(config, env, len(token_slots(env)) * token_width(env))
    features = jnp.zeros((4, learning.stored_features))
    perturbed = dqn.perturbed(features, 0.1, jax.random.key(0), jnp.int32(0), learning.noise_entries)
    tokens = np.asarray(perturbed).reshape(4, len(token_slots(env)), token_width(env))
    kinds = len(env.object_types)
    assert np.all(tokens[..., kinds:-1] != 0)  # features and both offsets
    assert np.all(tokens[..., :kinds] != 0) == np.all(tokens[..., -1] != 0) == kind_noise
    drawn = dqn.noise_shape(features.shape, learning.noise_entries)[-1]
    assert drawn == (tokens[0].size if kind_noise else tokens[0, :, kinds:-1].size)


def test_log_scaled_attention_sharpens_with_the_number_of_candidates():
    """The logits times log n: the softmax of log n times the unscaled log-weights, on 2 and on 6 candidates."""
    for doors in ((1,), (1, 3, 5, 7, 9)):
        env, tokens = lsd(12, doors, robot_cell=3)
        net, params = network(env)
        scaled, _ = network(env, attention_log_scale=True)
        plain, sharp = (np.asarray(attention(n, params, tokens)) for n in (net, scaled))
        on = plain > 0
        n = on.sum()
        expected = np.exp(np.log(n) * np.log(plain[on]))
        np.testing.assert_allclose(sharp[on], expected / expected.sum(), rtol=1e-4, atol=1e-6)
        assert (sharp[on].max() > plain[on].max()) == (n > 2)  # log 2 < 1 softens; more candidates sharpen


def test_the_network_reads_any_number_of_objects_in_any_order():
    env, tokens = lsd(6, (1, 3), robot_cell=3)
    net, params = network(env)
    q = q_values(env, net, params, tokens)
    width = token_width(env)
    rows = tokens.reshape(-1, width)
    order = np.r_[0, np.random.default_rng(1).permutation(np.arange(1, len(token_slots(env))))]
    np.testing.assert_allclose(q_values(env, net, params, rows[order].reshape(-1)), q, rtol=1e-5, atol=1e-6)
    padded = jnp.concatenate([tokens, jnp.zeros(5 * width)])  # five more empty slots: a larger env's padding
    np.testing.assert_allclose(q_values(env, net, params, padded), q, rtol=1e-5, atol=1e-6)
    bigger, more = lsd(12, (1, 3, 7, 9), robot_cell=3)  # a larger task: the same parameters apply
    assert q_values(bigger, net, params, more).shape == q.shape and np.isfinite(q_values(bigger, net, params, more)).all()


def test_attention_goes_only_to_objects_a_skill_can_act_on():
    env, tokens = lsd(6, (1, 3), robot_cell=3)
    net, params = network(env)
    weights = np.asarray(attention(net, params, tokens))
    assert weights.shape == (4,) and weights.sum() == pytest.approx(1.0)  # tokens: the robot, the light, 2 doors
    assert weights[0] == 0.0 and (weights[1:] > 0).all()


def test_distance_ranks_order_only_what_a_skill_can_act_on():
    from jaxbridge.run.attention import RANKS, distance_rank

    env, state = lsd_state(8, (1, 5), robot_x=4.2)
    states = jax.tree.map(lambda x: x[None, None], state)  # [T=1, B=1]
    rank = distance_rank(env, states)[0, 0]
    light, doors = 1, token_slots(env)[2:]  # at x 4.2: door 5 at 5.5, door 1 at 1.5, the light at 7.5
    assert (rank[doors[1]], rank[doors[0]], rank[light]) == (0, 1, 2)
    assert (np.delete(rank, [light, *doors]) == RANKS).all()  # the robot and the cells are never candidates


def test_an_ensemble_is_members_of_their_own_whose_minimum_is_the_value():
    env, tokens = lsd(6, (1, 3), robot_cell=3)
    net = SELECTOR.q_network(TrainConfig(approach="ours_learned_selection", q_ensemble=2, output_init="uniform"), env)
    x = encode(env, tokens, jnp.arange(env.num_skills + 1), jnp.full(env.num_skills + 1, 0.5))
    params = net.init(jax.random.key(0), x)
    members = np.asarray(net.apply(params, x, members=True))
    assert members.shape == (2, env.num_skills + 1) and not np.allclose(members[0], members[1])
    np.testing.assert_array_equal(np.asarray(net.apply(params, x)), members.min(0))
    assert np.asarray(attention(net, params, tokens)).sum() == pytest.approx(1.0)


def test_the_approach_refuses_what_its_network_does_not_have():
    with pytest.raises(ValueError, match="does not scale its object tokens: no normalise"):
        SELECTOR.q_network(TrainConfig(approach="ours_learned_selection", normalise="minmax"), ENV())


def test_the_learned_selector_trains_from_the_command_line_and_reports_what_it_looks_at(tmp_path):
    """LSD, 2 seeds x 4 cycles: the run's files, its checkpoints evaluated (the latest, and cycle 1's, kept by
    --keep-cycles), and eval.py --attention's line."""
    trained = train("--approaches", "ours_learned_selection", "--num-seeds", "2", "--cycles", "4",
                    "--checkpoint-every", "1", "--keep-cycles", "1", "--out", str(tmp_path), "--no-progress")
    assert trained.returncode == 0, trained.stderr
    experiment = tmp_path / "light_switch_door"
    looked = cli_in_process("eval.py", str(experiment), "--approach", "ours_learned_selection", "--attention")
    assert looked.returncode == 0, looked.stderr
    line, diagnosis = looked.stdout.splitlines()[-2:]
    assert line.startswith("attention on the fix's object, per seed: 0 ") and "; all " in line
    assert diagnosis.startswith("the fix's object is the nearest candidate at ") and "misses looked at the" in diagnosis
    # the same decisions by the action chosen (a skill's name or CallPlanner): their counts add up to them all
    by_action = re.findall(r"(\w+) [\d.]+ of (\d+)", diagnosis.partition("; by the action chosen: ")[2])
    names = {skill.name for skill in env_class("light_switch_door").skills} | {"CallPlanner"}
    assert by_action and {name for name, _ in by_action} <= names
    assert sum(int(n) for _, n in by_action) == sum(int(n) for n in re.findall(r" of (\d+)", line))
    early = cli_in_process("eval.py", str(experiment), "--approach", "ours_learned_selection", "--attention",
                           "--cycle", "1")
    assert early.returncode == 0 and "cycle 1" in early.stdout and early.stdout.splitlines()[-2].startswith("attention on")
    gone = cli_in_process("eval.py", str(experiment), "--approach", "ours_learned_selection", "--cycle", "2")
    assert gone.returncode == 2 and "no complete checkpoint for step 2" in gone.stderr  # neither kept nor latest two
    refused = cli_in_process("eval.py", str(experiment / "ours_learned_selection"), str(experiment / "ours_learned_selection"),
                  "--attention")
    assert refused.returncode == 2 and "--attention reports on one RUN's evaluation" in refused.stderr
    # --render shades what it attends to: the re-run episode carries, at each bridge decision, weights over
    # the object slots a skill may act on that sum to one, and nothing elsewhere; the picture draws them.
    import jaxbridge
    from jaxbridge.viz.render import render_episode, trace_episodes
    policy = jaxbridge.load(experiment, "ours_learned_selection")
    batch = policy.tasks(seeds=[0], num_tasks=2)
    bridge, params, controls = policy.on(batch)
    trace = trace_episodes(batch, bridge, params, [0], 0, controls)[0]
    env = batch.env
    decided = trace.decided.astype(bool)
    assert trace.attention.shape == (trace.steps, env.num_objects) and decided.any()
    np.testing.assert_allclose(trace.attention[decided].sum(-1), 1.0, rtol=1e-5)
    assert not trace.attention[~decided].any() and not trace.attention[:, ~np.isin(np.arange(env.num_objects), env.candidate_slots)].any()
    assert list(trace.object_type[:2]) == [0, 1] and render_episode(env, trace).startswith(b"\x89PNG")
    from matplotlib.figure import Figure
    from envs_jax.drawing import attention_marks
    ax = Figure().add_subplot()
    assert len(attention_marks(ax, env.drawer(), env, trace, trace.steps)) == 1 and len(ax.collections) == 1
    assert not attention_marks(Figure().add_subplot(), env.drawer(), env, trace, 0)  # nothing decided yet
