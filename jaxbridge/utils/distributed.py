"""Several processes (hosts) as one run, through `jax.distributed` (JAX's own coordination service).

Every process runs the same command; `initialize` joins them before JAX's backend starts, after which
`jax.devices()` lists every process's devices and one jitted program spans them. Each process computes
the slots on its own devices; process 0 (`is_primary`) alone writes run files and checkpoints, from
metrics and states every process gathers (learn/devices.SeedMesh). On CPU the cross-process transfers go
through gloo, which jaxlib ships.
"""
from __future__ import annotations

import argparse

import jax

from jaxbridge.utils.cli import non_negative_int, positive_int
from jaxbridge.utils.errors import InputError


def initialize(coordinator: str | None = None, num_processes: int | None = None, process_id: int | None = None) -> None:
    """Join the run's processes: coordinator "host:port" (process 0 listens there), their number and this
    one's id; all None: detect them from a cluster's environment (SLURM, Open MPI, Kubernetes, TPU pods, as
    `jax.distributed.initialize` does). Must come before anything starts JAX's backend."""
    jax.config.update("jax_cpu_collectives_implementation", "gloo")  # only read by CPU backends
    jax.distributed.initialize(coordinator_address=coordinator, num_processes=num_processes, process_id=process_id)


def add_flags(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("several processes or hosts (jax.distributed; docs/PERFORMANCE.md, "
                                      "\"Several processes or hosts\")")
    group.add_argument("--coordinator", metavar="HOST:PORT", default=None,
                       help="join a run of --num-processes processes, each started with the same flags and its own "
                            "--process-id; process 0 listens at HOST:PORT and alone writes the files (default: one "
                            "process)")
    group.add_argument("--num-processes", type=positive_int, default=None, help="with --coordinator: how many processes")
    group.add_argument("--process-id", type=non_negative_int, default=None,
                       help="with --coordinator: this process's id, 0 .. num-processes - 1")
    group.add_argument("--distributed", action="store_true",
                       help="join a multi-process run whose coordinator, size and id jax.distributed reads from the "
                            "cluster's environment (SLURM, Open MPI, Kubernetes) instead of the three flags above")


def initialize_from(args: argparse.Namespace) -> None:
    """`initialize` as the flags of `add_flags` say (nothing without them); InputError if they clash."""
    manual = (args.coordinator, args.num_processes, args.process_id)
    if args.distributed and any(v is not None for v in manual):
        raise InputError("--distributed detects the cluster; drop --coordinator, --num-processes and --process-id")
    if any(v is not None for v in manual) and not all(v is not None for v in manual):
        raise InputError("--coordinator, --num-processes and --process-id go together")
    if args.process_id is not None and args.process_id >= args.num_processes:
        raise InputError(f"--process-id {args.process_id} must be below --num-processes {args.num_processes}")
    if args.distributed or args.coordinator is not None:
        initialize(args.coordinator, args.num_processes, args.process_id)


def is_primary() -> bool:
    """Whether this process writes the run's files (process 0; the only one without jax.distributed)."""
    return jax.process_index() == 0


def multi_process() -> bool:
    return jax.process_count() > 1


def sync_processes(name: str) -> None:
    """Wait until every process of a multi-process run gets here (at once in a single process)."""
    if multi_process():
        from jax.experimental import multihost_utils
        multihost_utils.sync_global_devices(name)
