"""The benchmark suite: one table of the figures that matter, per env, and bench/results.json to compare
runs.

    python -m bench.timings.table [--quick] [--devices auto|N] [--envs all|ENV,...] [--out bench/results.json]

Per env (light_switch_door, doorknobs, coffee, each with its own training defaults), in a fresh process
each (so that its peak memory is its own):
  * meta-policy env steps/s, planner + oracle bridge on 1 device: 1 seed x 1 test task, and 8 seeds x 10
    test tasks (bench.timings.meta_policy; median of --repeats rollouts, steps that episodes really take);
  * the training cycle of 8 seeds with the env's defaults, seeds over --devices (bench.timings.training): seconds
    of tasks + plan tables, compile seconds of the first cycle (tracing + lowering + XLA, from
    jax.monitoring), steady-state seconds per cycle (median of --cycles cycles after the first), and how
    many programs the later cycles compiled (0: the cycle compiles once);
  * double-DQN minibatch updates/s, 8 seeds x the env's updates per cycle on the same layout
    (bench.timings.updates; median of --repeats calls);
  * peak resident memory of the process (ru_maxrss) and its growth over the process after `import jax`;
    on a GPU also the device's peak bytes in use.
The persistent compilation cache is off here, so every compile figure is a cold compile (and the cycle
is never cached anyway: it holds a host callback, see jaxbridge/utils/compile_cache.py).
"""
from __future__ import annotations

import jaxbridge
import argparse
import datetime
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from bench.command import CommandParser
from bench.records import BENCH, ENVS, ROOT, git_commit


def rss_mib() -> float:
    """Peak resident set size of this process so far (Linux reports KiB, macOS bytes)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (2 ** 20 if sys.platform == "darwin" else 2 ** 10)


def measure_env(env: str, devices_arg, cycles: int, repeats: int, update_repeats: int) -> dict:
    """Every figure of one env, in this process (which should not have measured anything else)."""
    from jaxbridge.learn.devices import describe, device_count_arg, select_devices
    devices = select_devices(device_count_arg(devices_arg))
    from jaxbridge.utils import compile_cache
    compile_cache.enable(False)
    import jax

    from bench.timings.meta_policy import cases, measure
    from bench.timings.training import measure_cycles
    from bench.timings.updates import measure_updates
    from envs_jax import env_class

    base = rss_mib()
    out = {"env": env, "devices": describe(devices), "rss_base_mib": round(base, 1)}
    start = time.perf_counter()
    meta = {}
    for name, batch in cases(env_class(env), full=False).items():
        r = measure(batch, repeats)
        meta[name] = {k: round(v, 4) if isinstance(v, float) else v for k, v in r.items()}
    out["meta_policy"] = {"device": describe(jax.local_devices()[:1]), "cases": meta,
                          "seconds": round(time.perf_counter() - start, 1)}
    out["rss_after_meta_policy_mib"] = round(rss_mib(), 1)

    config = jaxbridge.make_config(env, num_seeds=8)
    run = measure_cycles(config, devices, cycles=cycles + 1)
    first, later = run["first"], run["later"]
    out["cycle"] = {"num_seeds": 8, "updates_per_cycle": config.learner.updates_per_cycle, "batch_size": config.learner.batch_size,
                    "build_s": round(run["build_s"], 2), "first_cycle_s": round(run["times"][0], 2),
                    "compile_s": round(first.trace_s + first.lower_s + first.compile_s, 2),
                    "compile_events": first.as_dict(), "measured_cycles": cycles,
                    "steady_s_per_cycle": round(statistics.median(run["times"][1:]), 4),
                    "cycle_times_s": [round(t, 4) for t in run["times"]],
                    "programs_compiled_after_first_cycle": later.compiles, "traces_after_first_cycle": later.traces,
                    "mean_test_solve_rate": run["rates"]}
    out["rss_after_cycles_mib"] = round(rss_mib(), 1)

    r = measure_updates(run["setup"], run["seeds"], run["learners"], config.learner.updates_per_cycle, update_repeats)
    out["updates"] = {k: round(v, 4) if isinstance(v, float) else v for k, v in r.items()}
    out["rss_peak_mib"] = round(rss_mib(), 1)
    out["rss_growth_mib"] = round(rss_mib() - base, 1)
    stats = jax.local_devices()[0].memory_stats() or {}
    out["device_peak_bytes"] = stats.get("peak_bytes_in_use")
    out["seconds"] = round(time.perf_counter() - start, 1)
    return out


def in_fresh_process(env: str, args) -> dict:
    cmd = [sys.executable, "-m", "bench.timings.table", "--child", env, "--devices", str(args.devices),
           "--cycles", str(args.cycles), "--repeats", str(args.repeats), "--update-repeats", str(args.update_repeats)]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        raise SystemExit(f"bench: {env} failed (exit {proc.returncode})")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--quick", action="store_true",
                        help="fewer repetitions (2 measured cycles, 5 rollouts, 2 update calls) for a smoke test")
    parser.add_argument("--devices", default="auto", metavar="auto|N",
                        help="devices of the training cycle and the updates, as train.py (default: %(default)s)")
    parser.add_argument("--envs", default="all", help="comma-separated envs or all (default: all)")
    parser.add_argument("--cycles", type=int, default=None, help="measured cycles after the compiling one (default: 4)")
    parser.add_argument("--repeats", type=int, default=None, help="timed rollouts per meta-policy case (default: 20)")
    parser.add_argument("--update-repeats", type=int, default=None, help="timed update calls (default: 3)")
    parser.add_argument("--out", type=Path, default=BENCH, help="JSON results (default: %(default)s)")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    from jaxbridge.utils.cli import auto_or_positive_int
    auto_or_positive_int(args.devices)  # refuses a bad value; the text goes on to the child and the record
    quick = args.quick
    args.cycles = args.cycles or (2 if quick else 4)
    args.repeats = args.repeats or (5 if quick else 20)
    args.update_repeats = args.update_repeats or (2 if quick else 3)
    if args.child:
        print(json.dumps(measure_env(args.child, args.devices, args.cycles, args.repeats, args.update_repeats)))
        return 0
    envs = list(ENVS) if args.envs == "all" else args.envs.split(",")
    unknown = [e for e in envs if e not in ENVS]
    if unknown:
        parser.error(f"unknown env {', '.join(unknown)}; choose from {', '.join(ENVS)}")
    import jax
    start = time.perf_counter()
    results = {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"), "commit": git_commit(),
               "jax": jax.__version__,
               "python": platform.python_version(), "machine": platform.machine(), "cpu_cores": os.cpu_count(),
               "load_before": [round(x, 2) for x in os.getloadavg()], "quick": quick,
               "settings": {"measured_cycles": args.cycles, "rollout_repeats": args.repeats,
                            "update_repeats": args.update_repeats, "devices": args.devices,
                            "persistent_compile_cache": False},
               "envs": {}}
    for env in envs:
        print(f"{env} ...", file=sys.stderr, flush=True)
        results["envs"][env] = in_fresh_process(env, args)
    results["load_after"] = [round(x, 2) for x in os.getloadavg()]
    results["total_s"] = round(time.perf_counter() - start, 1)
    first = next(iter(results["envs"].values()))
    print(f"jax {results['jax']}, {results['date']}, {results['cpu_cores']} cores, load {results['load_before'][0]} -> "
          f"{results['load_after'][0]}; meta-policy on 1 {first['meta_policy']['device'].split()[-1]} device, "
          f"cycle and updates over {first['devices']} device(s); {args.cycles} measured cycles")
    from bench.pages.performance import bench_rows  # imports jax: only once every child has measured
    print(bench_rows(results))
    print(f"total {results['total_s']:.0f} s -> {args.out}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
