"""2-D geometry for rectangles, circles and segments, as pure jnp functions (jit/vmap friendly).

A rectangle is a float32[..., 5] array (x, y, width, height, theta): (x, y) is the anchor, the lower-left
corner before rotation, and the rectangle is rotated counter-clockwise by theta about its anchor. This is
the authors' `Rectangle` convention (walls, clutter and doors in Doorknobs). Points are float32[..., 2].
All functions broadcast over leading axes; "touching" counts as intersecting (closed sets).
"""
from __future__ import annotations

import jax.numpy as jnp

X, Y, WIDTH, HEIGHT, THETA = range(5)


def rect(x, y, width, height, theta=0.0) -> jnp.ndarray:
    return jnp.stack(jnp.broadcast_arrays(*(jnp.asarray(v, jnp.float32) for v in
                                            (x, y, width, height, theta))), axis=-1)


def to_local(p: jnp.ndarray, r: jnp.ndarray) -> jnp.ndarray:
    """Points in the rectangle's frame, where it is the box [0, width] x [0, height]."""
    d = p - r[..., :2]
    c, s = jnp.cos(r[..., THETA]), jnp.sin(r[..., THETA])
    return jnp.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)


def corners(r: jnp.ndarray, pad: float | jnp.ndarray = 0.0) -> jnp.ndarray:
    """float32[..., 4, 2]: the corners (counter-clockwise from the anchor) of the rectangle grown by
    `pad` on every side."""
    lo, w, h = -pad, r[..., WIDTH] + pad, r[..., HEIGHT] + pad
    local_x = jnp.stack(jnp.broadcast_arrays(lo, w, w, lo), axis=-1)
    local_y = jnp.stack(jnp.broadcast_arrays(lo, lo, h, h), axis=-1)
    c, s = jnp.cos(r[..., THETA])[..., None], jnp.sin(r[..., THETA])[..., None]
    return jnp.stack([r[..., X, None] + c * local_x - s * local_y,
                      r[..., Y, None] + s * local_x + c * local_y], axis=-1)


def _box_distance(q: jnp.ndarray, size: jnp.ndarray) -> jnp.ndarray:
    """Distance from local points q to the box [0, size]; 0 inside."""
    return jnp.linalg.norm(q - jnp.clip(q, 0.0, size), axis=-1)


def point_rect_distance(p: jnp.ndarray, r: jnp.ndarray) -> jnp.ndarray:
    return _box_distance(to_local(p, r), r[..., WIDTH:THETA])


def circle_hits_rect(centre: jnp.ndarray, radius, r: jnp.ndarray) -> jnp.ndarray:
    return point_rect_distance(centre, r) <= radius


def point_segment_distance(p: jnp.ndarray, a: jnp.ndarray, b: jnp.ndarray) -> jnp.ndarray:
    d = b - a
    t = jnp.clip(jnp.sum((p - a) * d, -1) / jnp.maximum(jnp.sum(d * d, -1), 1e-20), 0.0, 1.0)
    return jnp.linalg.norm(p - (a + t[..., None] * d), axis=-1)


def segment_rect_distance(a: jnp.ndarray, b: jnp.ndarray, r: jnp.ndarray) -> jnp.ndarray:
    """Distance between the segment a-b and the rectangle (0 if they intersect): how close a circle
    swept along the segment comes to the rectangle."""
    qa, qb = to_local(a, r), to_local(b, r)
    size = r[..., WIDTH:THETA]
    # Do they intersect? Clip the segment against both slabs of the box (Liang-Barsky).
    d = qb - qa
    flat = jnp.abs(d) < 1e-12
    safe = jnp.where(flat, 1.0, d)
    t_lo, t_hi = (0.0 - qa) / safe, (size - qa) / safe
    enter = jnp.where(flat, jnp.where((qa >= 0) & (qa <= size), -jnp.inf, jnp.inf), jnp.minimum(t_lo, t_hi))
    leave = jnp.where(flat, jnp.where((qa >= 0) & (qa <= size), jnp.inf, -jnp.inf), jnp.maximum(t_lo, t_hi))
    crosses = jnp.maximum(0.0, jnp.max(enter, -1)) <= jnp.minimum(1.0, jnp.min(leave, -1))
    # Disjoint convex sets: the closest pair involves an endpoint or a box corner.
    box = corners(rect(0.0, 0.0, size[..., 0], size[..., 1]))
    to_corners = point_segment_distance(box, qa[..., None, :], qb[..., None, :])
    gap = jnp.minimum(jnp.minimum(_box_distance(qa, size), _box_distance(qb, size)), jnp.min(to_corners, -1))
    return jnp.where(crosses, 0.0, gap)


def rects_overlap(r1: jnp.ndarray, r2: jnp.ndarray) -> jnp.ndarray:
    """Separating-axis test for two rotated rectangles (touching counts)."""
    c1, c2 = corners(r1), corners(r2)
    axes = jnp.concatenate([c1[..., 1:3, :] - c1[..., 0:2, :], c2[..., 1:3, :] - c2[..., 0:2, :]], axis=-2)
    p1 = jnp.einsum("...kd,...jd->...kj", axes, c1)
    p2 = jnp.einsum("...kd,...jd->...kj", axes, c2)
    apart = (jnp.max(p1, -1) < jnp.min(p2, -1)) | (jnp.max(p2, -1) < jnp.min(p1, -1))
    return ~jnp.any(apart, -1)
