"""The authors' float64 door tests, on device in float32 and int32.

The authors' envs keep keys and knob rotations in float64 (sums of float32 actions) and test them against
`target +- tolerance` in float64; ours run in JAX's 32-bit types. Two ways to get their verdicts:

- `float32_window`: for a float32 value, the window's float64 ends rounded inward to float32 (Doorknobs'
  knob rotations, which still accumulate in float32).
- `ExactKey` and `exact_window`: a value in [0, 1] kept exactly, so that a sum of float32 actions is their
  float64 sum (Light Switch Door's keys).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct


def float32_window(target, tolerance: float, inclusive: bool) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) float32 arrays shaped like `target`: the float32 values x with target - tolerance <= x <=
    target + tolerance in float64 (strict inequalities when not `inclusive`), as lo <= x <= hi.

    So float32(0.6) = 0.60000002 leaves a door with target 0.5 closed, as theirs does."""
    target = np.asarray(target, np.float64)
    low, high = target - tolerance, target + tolerance
    lo, hi = low.astype(np.float32), high.astype(np.float32)
    # Rounding to nearest may land outside (or, when strict, on) the float64 end: step one float32 in.
    lo_out = (lo < low) if inclusive else (lo <= low)
    hi_out = (hi > high) if inclusive else (hi >= high)
    lo = np.where(lo_out, np.nextafter(lo, np.float32(np.inf)), lo).astype(np.float32)
    hi = np.where(hi_out, np.nextafter(hi, np.float32(-np.inf)), hi).astype(np.float32)
    return lo, hi


FINE_BITS = 29  # a key counts 2^-24ths (coarse) and 2^-53rds (fine): 2^-24 = 2^29 * 2^-53
FINE_MASK = (1 << FINE_BITS) - 1
COARSE_ONE = 1 << 24  # 1.0 in coarse units
COARSE_UNIT, FINE_UNIT = 2.0 ** -24, 2.0 ** -53


@struct.dataclass
class ExactKey:
    """Numbers kept exactly on the grid of multiples of 2^-53: coarse * 2^-24 + fine * 2^-53, two int32
    arrays with 0 <= fine < 2^29 (so the pair orders as the number does).

    Why this grid: float64 holds every multiple of 2^-53 in [0, 1], so the authors' `clip(key + action,
    0, 1)` in float64 never rounds while the actions are multiples of 2^-53, as every float32 of magnitude
    at least 2^-30 is: their key is this one. A smaller action is rounded to the grid here, where float64
    rounds the sum instead (or, for a key under 0.5, keeps more of it)."""

    coarse: jax.Array  # int32
    fine: jax.Array  # int32 in [0, 2^29)

    @staticmethod
    def zeros(shape) -> "ExactKey":
        return ExactKey(jnp.zeros(shape, jnp.int32), jnp.zeros(shape, jnp.int32))

    @staticmethod
    def of(value: jax.Array) -> "ExactKey":
        """float32 values (|value| < 128) on the grid; those under 2^-30 in magnitude are rounded to it."""
        scaled = jnp.asarray(value, jnp.float32) * jnp.float32(2.0 ** 24)
        coarse = scaled.astype(jnp.int32)  # towards zero; the fraction left is exact in float32
        fine = jnp.round((scaled - coarse.astype(jnp.float32)) * jnp.float32(2.0 ** FINE_BITS))
        return _carried(coarse, fine.astype(jnp.int32))

    def __add__(self, other: "ExactKey") -> "ExactKey":
        return _carried(self.coarse + other.coarse, self.fine + other.fine)

    def __lt__(self, other: "ExactKey") -> jax.Array:
        # self - other < 0: the fine difference, in (-2^29, 2^29), borrows one coarse unit when negative.
        return self.coarse + ((self.fine - other.fine) >> FINE_BITS) < other.coarse

    def __getitem__(self, index) -> "ExactKey":
        return ExactKey(self.coarse[index], self.fine[index])

    def add_clipped(self, action: jax.Array, where: jax.Array) -> "ExactKey":
        """clip(key + action, 0, 1) where `where` holds, else the key (keys in [0, 1]; action and where
        broadcast against them). An action beyond +-1 clips the key as +-1 does."""
        total = self + ExactKey.of(jnp.clip(action, -1.0, 1.0))
        outside = (total.coarse < 0) | (total.coarse >= COARSE_ONE)
        return ExactKey(jnp.where(where, jnp.clip(total.coarse, 0, COARSE_ONE), self.coarse),
                        jnp.where(where, jnp.where(outside, 0, total.fine), self.fine))

    def to_float32(self) -> jax.Array:
        """The float32 nearest the key (ties to even), as numpy's float32 of the float64 key."""
        # Keys under 2^-22 fit an int32 in 2^-53 units, which converts to float32 in one rounding.
        small = ((self.coarse << FINE_BITS) | self.fine).astype(jnp.float32) * jnp.float32(FINE_UNIT)
        # Above, the float32 spacing is 2^-46 or more: fine's last 6 bits can only break a tie, so they
        # fold into one sticky bit (round to odd) and two exact float32 terms add with one rounding.
        sticky = jnp.where((self.fine & 63) != 0, 32, 0)
        fine = ((self.fine & ~63) | sticky).astype(jnp.float32) * jnp.float32(FINE_UNIT)
        large = self.coarse.astype(jnp.float32) * jnp.float32(COARSE_UNIT) + fine
        return jnp.where(self.coarse < 4, small, large)


def _carried(coarse: jax.Array, fine: jax.Array) -> ExactKey:
    """(coarse, fine) with fine brought into [0, 2^29), its whole 2^29s (or borrows) carried into coarse."""
    return ExactKey(coarse + (fine >> FINE_BITS), fine & FINE_MASK)


@struct.dataclass
class ExactWindow:
    """The keys lo <= key <= hi."""

    lo: ExactKey
    hi: ExactKey

    def contains(self, key: ExactKey) -> jax.Array:
        return ~(key < self.lo) & ~(self.hi < key)


def exact_window(target, tolerance: float) -> ExactWindow:
    """The grid keys that pass the authors' float64 test target - tolerance <= key <= target + tolerance,
    shaped like `target` (host arrays)."""
    target = np.asarray(target, np.float64)
    lo = np.ceil((target - tolerance) / FINE_UNIT).astype(np.int64)  # dividing by 2^-53 is exact
    hi = np.floor((target + tolerance) / FINE_UNIT).astype(np.int64)
    return ExactWindow(_host_key(lo), _host_key(hi))


def _host_key(units: np.ndarray) -> ExactKey:
    """An ExactKey of whole 2^-53 units (int64)."""
    return ExactKey((units >> FINE_BITS).astype(np.int32), (units & FINE_MASK).astype(np.int32))
