"""The seed axis over devices: which devices (`--devices auto|N`), the mesh over them, padding the
seeds to a multiple of the device count, and the program each device runs on its block of seeds.

Each device runs a *per-seed* program (`lax.map` over its seeds, `optimization_barrier`s at the edges),
not a `vmap`, because XLA compiles the same math differently for other batch shapes and the last bits
would then depend on the device count; `seed_block` B > 1 vmaps blocks of B seeds for GPUs, and the
numbers then depend on B only. Padded slots skip the work and are dropped (docs/DESIGN.md, "Seeds over
devices").
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass, field
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from jaxbridge.utils.distributed import multi_process

AXIS = "seeds"
CPU_FLAG = "xla_force_host_platform_device_count"


def device_count_arg(text: str) -> int | None:
    """argparse type of --devices: a positive integer, or None for "auto" (every device)."""
    from jaxbridge.utils.cli import auto_or_positive_int
    return auto_or_positive_int(text)


def cpu_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _backend_started() -> bool:
    try:
        from jax._src import xla_bridge
        return xla_bridge.backends_are_initialized()
    except (ImportError, AttributeError):
        return True  # cannot tell: do not touch the config


def configure_cpu_devices(request: int | None = None) -> None:
    """On CPU, the virtual device count (None, "auto": one per core), if the backend has not started yet
    and XLA_FLAGS does not set it; nothing otherwise."""
    if not _backend_started() and CPU_FLAG not in os.environ.get("XLA_FLAGS", ""):
        jax.config.update("jax_num_cpu_devices", cpu_cores() if request is None else int(request))


def select_devices(request: int | None = None) -> list:
    """The local devices to shard the seeds over: None ("auto") = all of them, else the first `request`.

    On CPU, JAX has one device unless told otherwise before its backend starts: this sets
    `jax_num_cpu_devices` (auto: one per core) if the backend has not started yet and XLA_FLAGS does
    not already set --xla_force_host_platform_device_count. Other platforms (GPU, TPU) are unaffected.
    Raises ValueError if fewer than `request` devices exist. With several processes (utils/distributed.py)
    every process's devices: `request` then counts each process's own."""
    configure_cpu_devices(request)
    devices = jax.local_devices()
    if multi_process():
        per_process = len(devices) if request is None else request
        if per_process > len(devices):
            raise ValueError(f"--devices {request}: process {jax.process_index()} has only {len(devices)} device(s)")
        of = lambda p: sorted((d for d in jax.devices() if d.process_index == p), key=lambda d: d.id)
        return [d for p in range(jax.process_count()) for d in of(p)[:per_process]]
    if request is None:
        return devices
    if request > len(devices):
        kind = devices[0].platform.upper()
        hint = (" (CPU devices are fixed when JAX starts; this process started it with fewer)"
                if kind == "CPU" else "")
        raise ValueError(f"--devices {request}: only {len(devices)} {kind} device(s) here{hint}")
    return devices[:request]


def default_workers(approaches: list[str]) -> int:
    """Approaches trained at the same time by default: one per CPU core, at most one per approach."""
    return max(1, min(len(approaches), os.cpu_count() or 1))


def split_devices(devices: list | None, workers: int) -> list:
    """One share of `devices` per worker (approach trained at the same time): as even as possible, every
    device in one share; with fewer devices than workers, every worker gets all of them (None stays None:
    the default device)."""
    if not devices or len(devices) < workers:
        return [devices] * workers
    return [devices[i::workers] for i in range(workers)]


def describe(devices) -> str:
    """E.g. "2 cpu"."""
    kinds = sorted({d.platform for d in devices})
    return f"{len(devices)} {'+'.join(kinds)}"


def is_prng_key(x) -> bool:
    return jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key)


def _key_data(x):
    """A PRNG key array's raw uint32 words (other arrays as they are): what crosses processes."""
    return jax.random.key_data(x) if is_prng_key(x) else x


# Whole pytrees in one compiled program each: leaf by leaf, every leaf's shape compiled its own op, a
# fixed start-up cost of every run and evaluation.
@functools.partial(jax.jit, static_argnums=1)
def _repeat_last(tree: Any, extra: int) -> Any:
    return jax.tree.map(lambda x: jnp.concatenate([x, jnp.repeat(x[-1:], extra, axis=0)]), tree)


@functools.partial(jax.jit, static_argnums=1)
def _leading(tree: Any, n: int) -> Any:
    return jax.tree.map(lambda x: x[:n], tree)


@dataclass(frozen=True)
class SeedMesh:
    """`num_seeds` seeds laid out over `devices`: seed i lives in slot i; slots num_seeds..padded-1
    pad the seed axis to a multiple of the device count."""

    num_seeds: int
    devices: tuple = field(default_factory=lambda: tuple(jax.local_devices()[:1]))
    block: int = 1  # seeds vmapped together on a device (TrainConfig.seed_block)

    def __post_init__(self):
        if self.block < 1:
            raise ValueError(f"seed block must be at least 1, got {self.block}")

    @property
    def num_devices(self) -> int:
        return len(self.devices)

    @property
    def padded(self) -> int:
        width = self.num_devices * self.block
        return -(-self.num_seeds // width) * width

    @property
    def mesh(self) -> Mesh:
        return Mesh(np.asarray(self.devices), (AXIS,))

    @property
    def sharding(self) -> NamedSharding:
        return NamedSharding(self.mesh, PartitionSpec(AXIS))

    def pad(self, tree: Any) -> Any:
        """Leading axis num_seeds -> padded, by repeating the last seed."""
        extra = self.padded - self.num_seeds
        return _repeat_last(tree, extra) if extra else tree

    @property
    def spans_processes(self) -> bool:
        return len({d.process_index for d in self.devices}) > 1

    def place(self, tree: Any) -> Any:
        """Pad a per-seed pytree and shard its seed axis over the devices (across processes, each
        process, holding the whole tree, hands over the slots of its own devices)."""
        return self._put(self.pad(tree))

    def _put(self, tree: Any) -> Any:
        if not self.spans_processes:
            # Split from host memory: splitting a device array over several devices compiles a slicing
            # program per leaf shape (tens of milliseconds each, dozens per run); keys stay as they are.
            if len(self.devices) > 1:
                tree = jax.tree.map(lambda x: x if is_prng_key(x) else np.asarray(x), tree)
            return jax.device_put(tree, self.sharding)

        def put(x):  # every process holds all of x; each hands over its own devices' slots
            host = np.asarray(_key_data(x))
            placed = jax.make_array_from_callback(host.shape, self.sharding, lambda index: host[index])
            return jax.random.wrap_key_data(placed, impl=jax.random.key_impl(x)) if is_prng_key(x) else placed
        return jax.tree.map(put, tree)

    def unpad(self, tree: Any) -> Any:
        """The real seeds of a placed pytree, on one device (the layout checkpoints use, whatever the
        device count); across processes, gathered into every process's memory."""
        if self.spans_processes:
            from jax.experimental import multihost_utils

            def gather(x):
                host = np.asarray(multihost_utils.process_allgather(_key_data(x), tiled=True))[: self.num_seeds]
                return jax.random.wrap_key_data(host, impl=jax.random.key_impl(x)) if is_prng_key(x) else host
            return jax.tree.map(gather, tree)
        return _leading(jax.device_put(tree, jax.local_devices()[0]), self.num_seeds)

    def real(self) -> jax.Array:
        """bool[padded], placed: which slots hold a real seed."""
        return self._put(np.arange(self.padded) < self.num_seeds)

    def map_seeds(self, fn: Callable) -> Callable:
        """`fn(state, *inputs) -> (state, out)` for one seed, lifted to every seed: the returned
        function takes (real, states, *inputs), each with a leading padded seed axis sharded over the
        devices, and returns (states, outs) likewise. Padded slots return their state unchanged and
        zero outputs. The per-seed (per-block) computation compiles to the same code for any device
        count."""

        def one_seed(args):
            is_real, state, inputs = args

            def run(state, inputs):
                state, inputs = jax.lax.optimization_barrier((state, inputs))
                return jax.lax.optimization_barrier(fn(state, *inputs))

            def skip(state, inputs):
                out = jax.eval_shape(fn, state, *inputs)[1]
                return state, jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), out)

            return jax.lax.cond(is_real, run, skip, state, inputs)

        block = self.block

        def per_device(real, states, *inputs):
            if block == 1:
                return jax.lax.map(one_seed, (real, states, inputs))
            blocks = jax.tree.map(lambda x: x.reshape((-1, block) + x.shape[1:]), (real, states, inputs))
            out = jax.lax.map(jax.vmap(one_seed), blocks)
            return jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), out)

        spec = PartitionSpec(AXIS)
        return jax.shard_map(per_device, mesh=self.mesh, in_specs=spec, out_specs=spec, check_vma=False)
