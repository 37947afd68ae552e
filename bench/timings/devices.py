"""Seconds per training cycle with the seeds on 1 device vs sharded over N, measured in one process
(cycles of the two layouts interleaved, so machine noise hits both alike), and a check that both
layouts give bit-identical metrics and parameters.

    python -m bench.timings.devices [--seeds 0-7] [--cycles 8] [--devices 2] [--seed-block 1]

On a CPU-only machine the N devices are virtual CPU devices (one per core is what train.py's
`--devices auto` uses).
"""
from __future__ import annotations

import jaxbridge
import time

import jax
import numpy as np

from bench.command import CommandParser


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door", seeds="0-7")
    parser.add_argument("--cycles", type=int, default=8, help="cycles per layout, the first one compiles (default: %(default)s)")
    parser.add_argument("--devices", type=int, default=2, help="devices of the sharded layout (default: %(default)s)")
    parser.add_argument("--seed-block", type=int, default=1, help="as train.py (default: %(default)s)")
    args = parser.parse_args()

    from jaxbridge.learn.devices import SeedMesh, select_devices
    devices = select_devices(args.devices)  # before JAX starts: virtual CPU devices
    from jaxbridge.learn.online import Cycle
    from jaxbridge.learn.setup import make_setup

    config = jaxbridge.make_config(args.env, seeds=args.seed_list, seed_block=args.seed_block)
    setup = make_setup(config)
    layouts = {}
    for n in (1, args.devices):
        seeds = SeedMesh(config.num_seeds, tuple(devices[:n]), config.seed_block)
        layouts[n] = {"seeds": seeds, "cycle": Cycle(setup, seeds),
                      "learners": seeds.place(setup.init_learners()), "times": [], "metrics": []}
    for _ in range(args.cycles):
        for layout in layouts.values():
            t0 = time.perf_counter()
            layout["learners"], metrics = layout["cycle"](layout["learners"])
            jax.block_until_ready(layout["learners"])
            layout["times"].append(time.perf_counter() - t0)
            layout["metrics"].append([np.asarray(x)[: config.num_seeds] for x in jax.tree.leaves(metrics)])
    print(f"jax {jax.__version__}, devices: {devices}")
    print(f"{config.env}: {config.num_seeds} seeds, {config.learner.updates_per_cycle} updates/cycle, batch {config.learner.batch_size}, "
          f"seed block {config.seed_block}")
    for n, layout in layouts.items():
        print(f"{n} device(s): first cycle (with compilation) {layout['times'][0]:.1f} s; steady state "
              f"{np.median(layout['times'][1:]):.3f} s/cycle (median of {len(layout['times']) - 1})")
    one, many = layouts[1], layouts[args.devices]
    print(f"speed-up {args.devices} vs 1 device: {np.median(one['times'][1:]) / np.median(many['times'][1:]):.2f}x")
    leaves = lambda layout: [np.asarray(x) for x in jax.tree.leaves(layout["seeds"].unpad(layout["learners"]).params)]
    same = (all(np.array_equal(a, b) for ma, mb in zip(one["metrics"], many["metrics"]) for a, b in zip(ma, mb))
            and all(np.array_equal(a, b) for a, b in zip(leaves(one), leaves(many))))
    print(f"bit-identical metrics and parameters: {same}")


if __name__ == "__main__":
    main()
