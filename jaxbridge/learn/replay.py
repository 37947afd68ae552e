"""A per-seed FIFO replay buffer on the device, with masked inserts.

Own code rather than brax's UniformSamplingQueue: importing brax.training pulls in the MuJoCo stack,
its queue flattens every field to one float32 matrix (ints round-trip through float32), its size checks
run in Python (not under jit), and it has no masked insert, which is what a scan that only sometimes
makes a transition needs. See docs/DESIGN.md.
"""
from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from flax import struct


@struct.dataclass
class ReplayBuffer:
    data: Any  # pytree, leading axis = capacity
    size: jax.Array  # int32: items stored (<= capacity)
    insert_at: jax.Array  # int32: next slot to write (oldest item once full)

    @property
    def capacity(self) -> int:
        return jax.tree.leaves(self.data)[0].shape[0]


def init_buffer(example: Any, capacity: int) -> ReplayBuffer:
    data = jax.tree.map(lambda x: jnp.zeros((capacity,) + jnp.shape(x), jnp.asarray(x).dtype), example)
    return ReplayBuffer(data=data, size=jnp.int32(0), insert_at=jnp.int32(0))


def add(buffer: ReplayBuffer, items: Any, mask: jax.Array) -> ReplayBuffer:
    """Append the items whose mask is set (in order), overwriting the oldest once full.

    At most `capacity` items may be added at once."""
    capacity = buffer.capacity
    offset = jnp.cumsum(mask) - 1
    slot = jnp.where(mask, (buffer.insert_at + offset) % capacity, capacity)  # `capacity` = dropped
    data = jax.tree.map(lambda d, x: d.at[slot].set(x, mode="drop"), buffer.data, items)
    count = jnp.sum(mask, dtype=jnp.int32)
    return ReplayBuffer(data=data, size=jnp.minimum(buffer.size + count, capacity),
                        insert_at=(buffer.insert_at + count) % capacity)


def sample_indices(buffer: ReplayBuffer, key: jax.Array, batch_size: int) -> jax.Array:
    """int32[batch_size]: slots drawn uniformly with replacement from the stored items (slot 0 if the
    buffer is empty)."""
    return jax.random.randint(key, (batch_size,), 0, jnp.maximum(buffer.size, 1))
