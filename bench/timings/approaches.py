"""Wall-clock of the paper's figure: every approach, 8 seeds x 100 cycles, through the real code path
(`train.py`'s driver, run files and checkpoints included), into a temporary directory.

    python -m bench.timings.approaches [--env light_switch_door] [--seeds 0-7] [--cycles 100] [--approaches all]
                               [--workers N] [--devices auto|N]

The layout is train.py's: approaches in --workers threads, each sharding its seeds over --devices
(default auto: one virtual CPU device per core).

Prints each approach's time and final numbers, a table of the seconds per approach, the total and the
process's peak RSS, and the ratio to the authors' compute for the
same figure (results.md: on the order of 100 CPU-hours for 6 approaches x 8 seeds).
"""
from __future__ import annotations

import json
import resource
import tempfile
import time
from pathlib import Path

import jax

from bench.command import CommandParser
import jaxbridge
from bench.timings.training import AUTHORS_WHOLE_RUN_S  # one seed-run of "ours", per env (results.md)
from jaxbridge.utils.cli import auto_or_positive_int


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door", seeds="0-7")
    parser.add_argument("--cycles", type=int, default=100, help="cycles (default: %(default)s)")
    parser.add_argument("--approaches", default="all", help="comma-separated approaches or all (default: all)")
    parser.add_argument("--workers", type=int, default=None, help="approaches at a time (default: one per core)")
    parser.add_argument("--devices", type=auto_or_positive_int, default="auto", help="as train.py (default: auto)")
    parser.add_argument("--keep", type=Path, default=None, help="write the experiment here instead of a temp dir")
    args = parser.parse_args()
    devices = jaxbridge.local_devices(args.devices)  # before JAX starts
    names = list(jaxbridge.APPROACHES) if args.approaches == "all" else args.approaches.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        out = args.keep or Path(tmp) / args.env
        start = time.perf_counter()
        summaries = jaxbridge.train(args.env, names, args.seed_list, args.cycles, out.parent, out.name, workers=args.workers,
                                    devices=devices).summaries
        total = time.perf_counter() - start
        results = (out / "results.md").read_text()
    kinds = "+".join(sorted({d.platform for d in devices}))
    print(f"jax {jax.__version__}, each approach's seeds over {len(devices)} {kinds} device(s)")
    print(f"{args.env}: {len(names)} approaches x {len(args.seed_list)} seeds x {args.cycles} cycles, "
          f"{args.workers or jaxbridge.default_workers(names)} at a time")
    for name, info in summaries.items():
        print(f"  {name:>20}: {info['elapsed_s']:7.1f} s   smooth test reward {info['smooth_reward_final']['mean']:.3f}")
    seed_runs, authors = len(names) * len(args.seed_list), AUTHORS_WHOLE_RUN_S[args.env]
    print(f"total: {total:.1f} s ({total / 60:.1f} min) for {seed_runs} seed-runs; "
          f"authors: ~{authors * seed_runs / 3600:,.0f} CPU-hours at {authors:,} s per seed-run "
          f"-> {authors * seed_runs / total:,.0f}x")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB on Linux -> GiB
    print("\n| " + " | ".join(summaries) + " | total | peak RSS |")
    print("|---" * (len(summaries) + 2) + "|")
    print("| " + " | ".join(f"{info['elapsed_s']:.1f}" for info in summaries.values())
          + f" | **{total:.1f} s ({total / 60:.1f} min)** | {peak:.2f} GiB |\n")
    print(results)
    print(json.dumps({"total_s": round(total, 1), "peak_rss_gib": round(peak, 2),
                      "per_approach_s": {k: v["elapsed_s"] for k, v in summaries.items()}}))


if __name__ == "__main__":
    main()
