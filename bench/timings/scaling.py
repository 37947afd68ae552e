"""Seconds of our method's training as the seed count grows: for each count, the time to build the
seeds' tasks and plan tables (host), the first cycle (mostly compilation), the steady-state seconds per
cycle, and the projected paper protocol (100 cycles) against the authors' run time per seed-run.

    python -m bench.timings.scaling [--env light_switch_door] [--seed-counts 8,64,256,1024] [--seed-block auto,1,...]
                            [--cycles 3] [--devices auto|N] [--json PATH]

--seed-block auto vmaps all of a device's seeds as one block (what a GPU needs); an integer fixes the
block width (1: one seed after another, the CPU default of train.py); a list measures each, per seed
count. Each line is printed as soon as
it is measured, and --json is rewritten after each, so a run cut short keeps what it measured.
"""
from __future__ import annotations

import jaxbridge
import json
from pathlib import Path

import numpy as np

from bench.command import CommandParser
from bench.timings.training import AUTHORS_WHOLE_RUN_S


def _peak_bytes(devices) -> int | None:
    """The devices' peak memory in use since the process started (GPU/TPU; None where not reported)."""
    stats = [d.memory_stats() for d in devices]
    peaks = [s.get("peak_bytes_in_use") for s in stats if s]
    return max(peaks) if peaks else None


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door")
    parser.add_argument("--seed-counts", default="8,64,256,1024",
                        help="seed counts, each from seed 0, comma-separated (default: %(default)s)")
    parser.add_argument("--seed-block", default="auto", help="auto (a device's seeds in one block) or N, or a "
                                                               "comma-separated list of them (default: auto)")
    parser.add_argument("--cycles", type=int, default=3, help="cycles timed per seed count, the first compiles "
                                                              "(default: %(default)s)")
    parser.add_argument("--devices", default="auto", help="as train.py (default: auto)")
    parser.add_argument("--json", type=Path, default=None, help="also write the rows to this JSON file")
    args = parser.parse_args()

    from jaxbridge.learn.devices import describe, device_count_arg, select_devices
    devices = select_devices(device_count_arg(args.devices))  # before JAX starts
    import jax
    from bench.timings.training import measure_cycles

    print(f"jax {jax.__version__}, {describe(devices)} device(s): {devices[0].device_kind}", flush=True)
    print(f"{'seeds':>6} {'block':>6} {'build s':>8} {'first s':>8} {'s/cycle':>8} {'100 cycles s':>13} "
          f"{'s/seed-run':>11} {'x authors':>10}", flush=True)
    rows = []
    counts = [int(n) for n in args.seed_counts.split(",")]
    blocks = args.seed_block.split(",")
    for num_seeds, block in ((n, b) for n in counts for b in blocks):
        per_device = -(-num_seeds // len(devices))
        block = per_device if block == "auto" else int(block)
        config = jaxbridge.make_config(args.env, num_seeds=num_seeds, cycles=args.cycles, seed_block=block)
        run = measure_cycles(config, devices)
        times = run["times"]
        steady = float(np.median(times[1:])) if len(times) > 1 else times[0]
        projected = run["build_s"] + times[0] + 99 * steady
        per_seed_run = projected / num_seeds
        row = {"env": config.env, "seeds": num_seeds, "block": block, "devices": describe(devices),
               "device_kind": devices[0].device_kind, "build_s": run["build_s"], "first_cycle_s": times[0],
               "steady_s_per_cycle": steady, "projected_100_cycles_s": projected,
               "s_per_seed_run": per_seed_run, "x_authors": AUTHORS_WHOLE_RUN_S[config.env] / per_seed_run,
               "jax": jax.__version__, "peak_device_bytes_so_far": _peak_bytes(devices)}
        rows.append(row)
        print(f"{num_seeds:>6} {block:>6} {row['build_s']:>8.1f} {times[0]:>8.1f} {steady:>8.3f} {projected:>13.1f} "
              f"{per_seed_run:>11.2f} {row['x_authors']:>10,.0f}"
              + (f"  (peak device memory so far {row['peak_device_bytes_so_far'] / 2**30:.1f} GiB)"
                 if row["peak_device_bytes_so_far"] else ""), flush=True)
        del run
        if args.json:
            args.json.write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
