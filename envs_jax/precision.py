"""Float64 tolerance windows as float32 bounds.

The authors' envs keep keys and knob rotations in float64 (sums of float32 actions) and test them against
`target +- tolerance` in float64; ours are float32 on device. A float32 value x passes their test exactly
when float32 lo <= x <= hi, with lo and hi the float64 window's ends rounded inward to float32: so
float32(0.6) = 0.60000002 leaves a door with target 0.5 closed, as theirs does.
"""
from __future__ import annotations

import numpy as np


def float32_window(target, tolerance: float, inclusive: bool) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) float32 arrays shaped like `target`: the float32 values x with target - tolerance <= x <=
    target + tolerance in float64 (strict inequalities when not `inclusive`), as lo <= x <= hi."""
    target = np.asarray(target, np.float64)
    low, high = target - tolerance, target + tolerance
    lo, hi = low.astype(np.float32), high.astype(np.float32)
    # Rounding to nearest may land outside (or, when strict, on) the float64 end: step one float32 in.
    lo_out = (lo < low) if inclusive else (lo <= low)
    hi_out = (hi > high) if inclusive else (hi >= high)
    lo = np.where(lo_out, np.nextafter(lo, np.float32(np.inf)), lo).astype(np.float32)
    hi = np.where(hi_out, np.nextafter(hi, np.float32(-np.inf)), hi).astype(np.float32)
    return lo, hi
