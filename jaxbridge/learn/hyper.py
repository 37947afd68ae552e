"""The numeric hyperparameters that change no shape and no program, as pytree leaves (`Hyper`).

A cycle takes them as an input with a leading slot axis, like the seeds' tasks, so one compiled cycle
serves every setting of a sweep (`train.py --sweep`): a slot's numbers are those of a plain run with its
setting, because a plain run passes its one setting the same way. Which fields these are is
`config.LEAF_FIELDS`; everything else in the config is static (shapes, programs, switches).
"""
from __future__ import annotations

import jax
import numpy as np
from flax import struct

from jaxbridge.core.config import LEAF_FIELDS, TrainConfig


@struct.dataclass
class Hyper:
    """float32 scalars (or [slots] arrays), one per name in LEAF_FIELDS (documented in TrainConfig)."""

    learning_rate: jax.Array
    gamma: jax.Array
    grad_clip: jax.Array
    call_planner_bonus: jax.Array
    epsilon_start: jax.Array
    epsilon_end: jax.Array
    epsilon_decay: jax.Array
    q_lambda: jax.Array

    @classmethod
    def of(cls, config: TrainConfig) -> "Hyper":
        return cls(**{name: np.float32(getattr(config, name)) for name in LEAF_FIELDS})


assert tuple(Hyper.__dataclass_fields__) == LEAF_FIELDS, "Hyper's fields are config.LEAF_FIELDS, in order"
