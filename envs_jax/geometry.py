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


def _local(p: jnp.ndarray, r: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The point's (x, y) in the rectangle's frame, where it is the box [0, width] x [0, height]."""
    dx, dy = p[..., 0] - r[..., X], p[..., 1] - r[..., Y]
    c, s = jnp.cos(r[..., THETA]), jnp.sin(r[..., THETA])
    return c * dx + s * dy, c * dy - s * dx


def corners(r: jnp.ndarray, pad: float | jnp.ndarray = 0.0) -> jnp.ndarray:
    """float32[..., 4, 2]: the corners (counter-clockwise from the anchor) of the rectangle grown by
    `pad` on every side."""
    lo, w, h = -pad, r[..., WIDTH] + pad, r[..., HEIGHT] + pad
    local_x = jnp.stack(jnp.broadcast_arrays(lo, w, w, lo), axis=-1)
    local_y = jnp.stack(jnp.broadcast_arrays(lo, lo, h, h), axis=-1)
    c, s = jnp.cos(r[..., THETA])[..., None], jnp.sin(r[..., THETA])[..., None]
    return jnp.stack([r[..., X, None] + c * local_x - s * local_y,
                      r[..., Y, None] + s * local_x + c * local_y], axis=-1)


# Points are handled by component, not as a trailing axis of 2: XLA:CPU fuses a reduction over a tiny
# axis (jnp.linalg.norm) into a loop it does not vectorise.
def _box_distance(qx: jnp.ndarray, qy: jnp.ndarray, width: jnp.ndarray, height: jnp.ndarray) -> jnp.ndarray:
    """Distance from local points to the box [0, width] x [0, height]; 0 inside."""
    gx, gy = jnp.maximum(jnp.maximum(-qx, qx - width), 0.0), jnp.maximum(jnp.maximum(-qy, qy - height), 0.0)
    return jnp.sqrt(gx * gx + gy * gy)


def point_rect_distance(p: jnp.ndarray, r: jnp.ndarray) -> jnp.ndarray:
    return _box_distance(*_local(p, r), r[..., WIDTH], r[..., HEIGHT])


def circle_hits_rect(centre: jnp.ndarray, radius, r: jnp.ndarray) -> jnp.ndarray:
    return point_rect_distance(centre, r) <= radius


def circle_hits_upright_rect(centre: jnp.ndarray, radius, r: jnp.ndarray) -> jnp.ndarray:
    """`circle_hits_rect` for a rectangle known to have theta = 0 (no trigonometry)."""
    qx, qy = centre[..., 0] - r[..., X], centre[..., 1] - r[..., Y]
    return _box_distance(qx, qy, r[..., WIDTH], r[..., HEIGHT]) <= radius


def segment_clears_rect(a: jnp.ndarray, b: jnp.ndarray, r: jnp.ndarray, clearance) -> jnp.ndarray:
    """The segment a-b keeps more than `clearance` from the rectangle: a circle of radius < clearance
    moves from a to b without touching it. Exact, with no division and no square root per pair.

    The rectangle grown by `clearance` is the union of two crossed boxes (grown along one axis each)
    and four discs at its corners; the segment misses it if it misses each. A box by separating axes
    (the box's two and the segment's normal); a disc if the segment's line passes it by, or its nearest
    point is an endpoint (then outside the grown rectangle, checked once for all corners)."""
    c, s = jnp.cos(r[..., THETA]), jnp.sin(r[..., THETA])
    half_w, half_h = 0.5 * r[..., WIDTH], 0.5 * r[..., HEIGHT]
    centre_x, centre_y = r[..., X] + c * half_w - s * half_h, r[..., Y] + s * half_w + c * half_h
    # The segment's midpoint m and half-extent h, in the box's frame with its centre as origin.
    mx = 0.5 * (a[..., 0] + b[..., 0]) - centre_x
    my = 0.5 * (a[..., 1] + b[..., 1]) - centre_y
    hx, hy = 0.5 * (b[..., 0] - a[..., 0]), 0.5 * (b[..., 1] - a[..., 1])
    mx, my = c * mx + s * my, c * my - s * mx
    hx, hy = c * hx + s * hy, c * hy - s * hx
    ax, ay, amx, amy = jnp.abs(hx), jnp.abs(hy), jnp.abs(mx), jnp.abs(my)
    m_cross_h = mx * hy - my * hx

    def misses_box(ex, ey):
        return (amx > ex + ax) | (amy > ey + ay) | (jnp.abs(m_cross_h) > ex * ay + ey * ax)

    def endpoint_clear(px, py):  # outside the grown rectangle
        dx, dy = jnp.maximum(jnp.abs(px) - half_w, 0.0), jnp.maximum(jnp.abs(py) - half_h, 0.0)
        return dx * dx + dy * dy > clearance * clearance

    clear = (misses_box(half_w + clearance, half_h) & misses_box(half_w, half_h + clearance)
             & endpoint_clear(mx - hx, my - hy) & endpoint_clear(mx + hx, my + hy))
    length2 = hx * hx + hy * hy
    m_dot_h = mx * hx + my * hy
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            # Corner k = (sx half_w, sy half_h): its projection onto the segment (along h, from m) and
            # its offset across the segment's line, both times |h|.
            along = sx * half_w * hx + sy * half_h * hy - m_dot_h
            across = sx * half_w * hy - sy * half_h * hx - m_cross_h
            passes = (jnp.abs(along) >= length2) | (across * across > clearance * clearance * length2)
            clear = clear & passes
    return clear


def rects_overlap(r1: jnp.ndarray, r2: jnp.ndarray) -> jnp.ndarray:
    """Separating-axis test for two rotated rectangles (touching counts)."""
    c1, c2 = corners(r1), corners(r2)
    axes = jnp.concatenate([c1[..., 1:3, :] - c1[..., 0:2, :], c2[..., 1:3, :] - c2[..., 0:2, :]], axis=-2)
    p1 = jnp.einsum("...kd,...jd->...kj", axes, c1)
    p2 = jnp.einsum("...kd,...jd->...kj", axes, c2)
    apart = (jnp.max(p1, -1) < jnp.min(p2, -1)) | (jnp.max(p2, -1) < jnp.min(p1, -1))
    return ~jnp.any(apart, -1)
