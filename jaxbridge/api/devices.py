"""The devices a training shards its seeds over."""
from __future__ import annotations

from jaxbridge.utils.errors import refusing


def local_devices(count: int | None = None) -> list:
    """The local devices to shard the seeds over: None = all of them (on a CPU-only machine one virtual CPU
    device per core, if JAX's backend has not started yet), else the first `count` (InputError if fewer
    exist). Call it before anything runs JAX for the CPU count to take effect."""
    from jaxbridge.learn.devices import select_devices

    with refusing():
        return select_devices(count)


def default_workers(approaches: list[str]) -> int:
    """How many approaches a training runs at the same time when `workers` is not given: one per CPU
    core, at most one per approach."""
    from jaxbridge.learn.devices import default_workers as workers

    return workers(approaches)
