"""Failure signatures (issue 54): the meta-policy passes each stall's (stalled operator's skill, type of the
object it stalled at) to the bridge; a network per signature is its members alone, each learning only
from its own signature's transitions; the approaches built on them are registered and leave the others'
observations as they were."""
import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.light_switch_door.env import LightSwitchDoor
from envs_jax.multi_novelty.env import FUSE, LIGHT, MOVE, MultiNovelty
from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.episode import Controls, observation_size
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.signatures import (num_signatures, planner_skills, signature_features, signature_index,
                                       signature_members, signature_shape, signature_width)
from jaxbridge.core.tasks import evaluation_specs, make_batch
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.q_bridge import QNetwork, SplitInput, encode_action
from jaxbridge.learn.signature_q import SignatureQNetwork

DOOR, LIGHT_TYPE = (list(MultiNovelty.object_types).index(kind) for kind in ("door", "light"))


def test_signatures_are_the_planners_skills_by_the_object_types_each_with_none():
    env = MultiNovelty.for_tasks([MultiNovelty.train_task(0)])
    assert planner_skills(env).tolist() == [MOVE, LIGHT]  # FetchKey, LiftLatch, PushDoor, ReplaceFuse: the bridge's
    assert signature_shape(env) == (3, len(env.object_types) + 1) and num_signatures(env) == 3 * 6
    start = env.reset(env.task_arrays(MultiNovelty.train_task(0)))
    state = start.replace(robot_x=start.task.num_cells - jnp.float32(0.5))  # at the light
    for skill, part in ((MOVE, 0), (LIGHT, 1), (FUSE, 2), (-1, 2)):  # a skill the planner never runs: none
        one_hots = np.asarray(signature_features(env, jnp.int32(skill), state))
        assert one_hots.shape == (signature_width(env),) and one_hots.sum() == 2
        assert int(signature_index(jnp.asarray(one_hots), signature_shape(env))) == part * 6 + LIGHT_TYPE
    assert observation_size(env, Controls(signature=True)) == env.num_features + signature_width(env)
    members = signature_members(env)  # the env declares its two: a network each, and one for the rest
    assert members[0 * 6 + DOOR] == 0 and members[1 * 6 + LIGHT_TYPE] == 1 and sorted(set(members)) == [0, 1, 2]
    assert observation_size(env, Controls()) == env.num_features


def test_the_bridge_sees_the_stalled_operator_and_the_object_of_each_stall():
    """The oracle on held-out tasks (every kind, doors with both locks): at every decision the signature is
    its stall's, MoveRobot at a door for either lock (the signature cannot tell them apart, by design) and
    TurnOnLight at the light for the fuse; it stays while the bridge keeps control (the card's cell shows
    no door)."""
    specs, _ = evaluation_specs(MultiNovelty, [0, 1], 4, "held_out")
    batch = make_batch(MultiNovelty, specs, [0] * len(specs))
    env = batch.env
    _, records = rollout(MetaPolicy(env, make_bridge("oracle", env), None, Controls(signature=True)), batch.arrays,
                         jax.random.split(jax.random.key(0), batch.size), batch.max_steps, record=True)
    decided = np.asarray(records.decided & records.live)
    features = np.asarray(records.features)[decided]
    ids = np.asarray(signature_index(jnp.asarray(features[:, env.num_features:]), signature_shape(env)))
    at_door, at_card, at_latch, at_fuse = (features[:, i] > 0.5 for i in (0, 1, 2, 5))
    stalled = np.asarray(records.stuck)[decided]
    door_id, fuse_id = 0 * 6 + DOOR, 1 * 6 + LIGHT_TYPE
    assert (ids[at_door] == door_id).all() and (ids[at_fuse] == fuse_id).all()
    assert (stalled & at_card).sum() > 0 and (stalled & at_latch).sum() > 0
    assert set(ids.tolist()) == {door_id, fuse_id}
    assert (~at_door & ~at_fuse).sum() > 0  # decisions away from the stall (the card fetched) keep its signature


def member_inputs(key, env, rows):
    """Random observations with random signatures, and actions: (whole inputs, features, signature ids, actions)."""
    k_f, k_s, k_t, k_a, k_p = jax.random.split(key, 5)
    shape = signature_shape(env)
    skill, kind = jax.random.randint(k_s, (rows,), 0, shape[0]), jax.random.randint(k_t, (rows,), 0, shape[1])
    features = jax.random.uniform(k_f, (rows, env.num_features))
    one_hots = jnp.concatenate([jax.nn.one_hot(skill, shape[0]), jax.nn.one_hot(kind, shape[1])], -1)
    action = encode_action(env, jax.random.randint(k_a, (rows,), 0, env.num_skills + 1), jax.random.uniform(k_p, (rows,)))
    whole = jnp.concatenate([features, one_hots, action], -1)
    return whole, features, skill * shape[1] + kind, action


def test_a_network_per_signature_is_its_members_and_each_learns_only_from_its_own_transitions():
    env = LightSwitchDoor.for_tasks([LightSwitchDoor.train_task(0)])
    members = signature_members(env)  # undeclared: a network per signature
    assert members == tuple(range(num_signatures(env)))
    net = SignatureQNetwork(signature_shape(env), members, env.num_skills + 2, output_init="uniform")
    whole, features, ids, action = member_inputs(jax.random.key(1), env, 12)
    variables = net.init(jax.random.key(0), whole[:1])
    members = variables["params"]["members"]
    plain = QNetwork(output_init="uniform")
    alone = jax.vmap(lambda params, x: plain.apply({"params": params}, x))(
        jax.tree.map(lambda p: p[ids], members), jnp.concatenate([features, action], -1))
    np.testing.assert_allclose(net.apply(variables, whole), alone, rtol=1e-6, atol=1e-6)
    # one observation's candidates, as the greedy argmax gives them (q_bridge.best_candidate): its member's
    observed = whole[0, :-action.shape[-1]]
    each = jnp.concatenate([jnp.broadcast_to(observed, (12, observed.shape[0])), action], -1)
    np.testing.assert_allclose(net.apply(variables, SplitInput(observed, action)), net.apply(variables, each),
                               rtol=1e-6, atol=1e-6)

    mine = ids == ids[0]
    grads = jax.grad(lambda p: jnp.sum(jnp.where(mine, net.apply({"params": p}, whole), 0.0)))(variables["params"])
    moved = np.any([np.asarray(g != 0).reshape(num_signatures(env), -1).any(-1) for g in jax.tree.leaves(grads)], 0)
    assert moved[int(ids[0])] and moved.sum() == 1


def test_the_signature_approaches_see_ours_features_and_the_signature():
    env = MultiNovelty.for_tasks([MultiNovelty.train_task(0)])
    for name, per_signature in (("ours_per_signature", True), ("ours_signature_conditioned", False)):
        approach = get_approach(name)
        assert approach.controls == Controls(signature=True) and approach.per_signature == per_signature
        assert approach.observation_size(env) == get_approach("ours").observation_size(env) + signature_width(env)
