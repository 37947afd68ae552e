"""Doorknobs' motion without a sampling planner: the robot follows its room's precomputed roadmap
(docs/design/envs.md, "Doorknobs choices") toward a doorway, seeing only the waypoints in its line of sight."""
from __future__ import annotations

import jax
import jax.numpy as jnp

from envs_jax.doorknobs import maps, roadmap
from envs_jax.doorknobs.maps import ACTION_MAGNITUDE, CLEARANCE, GOAL_NODES, SIDE_NORMAL


def sight(state, room: jax.Array) -> tuple[jax.Array, jax.Array]:
    """The room's roadmap waypoints float32[K, 2] and which of them the robot sees, bool[K]: the
    hot part of motion, the same whichever doorway the robot heads for."""
    rects, mask = maps.route_obstacles(state.task, room, state.door_open, state.robot)
    nodes = state.task.nodes[room]
    return nodes, roadmap.visible(state.robot, nodes, rects, mask, CLEARANCE)


def leads(state, nodes: jax.Array, seen: jax.Array, side: jax.Array) -> jax.Array:
    """bool[K]: the seen waypoints the robot may head for on its way to the doorway on `side`: its
    goal only from its entry cone."""
    goal = GOAL_NODES + side
    cone = maps.in_entry_cone(state.robot, nodes[goal], jnp.asarray(SIDE_NORMAL)[side])
    return seen & ((jnp.arange(nodes.shape[0]) != goal) | cone)


def route(state, room: jax.Array, side: jax.Array) -> jax.Array:
    """MoveToDoor's next step toward the doorway on `side` of `room` (zero: no path). Follows the
    task's precomputed roadmap from wherever the robot is."""
    nodes, seen = sight(state, room)
    step, _ = roadmap.pursue(state.robot, nodes, state.task.node_cost[room, side],
                             leads(state, nodes, seen, side), ACTION_MAGNITUDE)
    return step
