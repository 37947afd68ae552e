"""Motion without a sampling planner in the loop: visibility roadmaps among rectangles.

The host precomputes, once per task, a few waypoints per region (e.g. the corners of the clutter grown by
a little more than the robot radius, and the goal) and every waypoint's shortest collision-free distance
to the goal along straight, collision-free edges. On device, the robot then moves from wherever it is
toward the waypoint it can see (straight segment clear of every obstacle by the robot radius) that
minimises distance-to-waypoint + waypoint-cost, at most `max_step` per step. That sum drops by a full step
every step, so the walk reaches the goal, and every step stays on a segment checked to be collision-free.
When the goal itself is visible, the robot simply goes straight to it.
"""
from __future__ import annotations

import operator
from functools import reduce

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax import geometry


def visible(p: jax.Array, nodes: jax.Array, rects: jax.Array, mask: jax.Array, clearance) -> jax.Array:
    """bool[K]: which of `nodes` (float32[K, 2]) the robot at p can reach in a straight line that keeps
    more than `clearance` from every masked-in rectangle (float32[N, 5], bool[N])."""
    # Every rectangle against every waypoint in one elementwise program (one trace of the test, not one
    # per rectangle), its rows combined with `&`: XLA:CPU vectorises that over the waypoints, but not a
    # fused reduction over the short rectangle axis (3-4x slower).
    clears = geometry.segment_clears_rect(p, nodes, rects[:, None], clearance) | ~mask[:, None]  # [N, K]
    return reduce(operator.and_, clears)


def costs_to_goal(edges: np.ndarray, nodes: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Host: shortest path lengths to node `goal` over the allowed directed edges (Bellman-Ford).

    edges: bool[..., K, K], edges[i, j] = the robot may go straight from node i to node j;
    nodes: float32[..., K, 2]; goal: int[...]. Returns float32[..., K], inf where the goal is out of reach.
    """
    length = np.linalg.norm(nodes[..., :, None, :] - nodes[..., None, :, :], axis=-1)
    weight = np.where(edges, length, np.inf)
    k = nodes.shape[-2]
    cost = np.where(np.arange(k) == goal[..., None], 0.0, np.inf)
    for _ in range(k - 1):
        cost = np.minimum(cost, np.min(weight + cost[..., None, :], axis=-1))
    return cost.astype(np.float32)


def pursue(p: jax.Array, nodes: jax.Array, cost: jax.Array, seen: jax.Array, max_step: float):
    """Device: the step toward the best visible waypoint and the resulting cost-to-goal from p.

    Returns (float32[2] step of norm <= max_step, zero if no waypoint with a finite cost is visible;
    float32 cost-to-goal of p, inf if none)."""
    dist = jnp.sqrt((nodes[:, 0] - p[0]) ** 2 + (nodes[:, 1] - p[1]) ** 2)  # not norm: see geometry
    total = jnp.where(seen, dist + cost, jnp.inf)
    # At a waypoint, going on via the next one costs the same as "going" to this one: break the tie.
    best = jnp.argmin(total + jnp.where(dist < 1e-4, 1e-3, 0.0))
    delta = nodes[best] - p
    scale = jnp.minimum(1.0, max_step / jnp.maximum(dist[best], 1e-12))
    reachable = jnp.isfinite(total[best])
    return jnp.where(reachable, delta * scale, 0.0), total[best]
