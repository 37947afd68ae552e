"""Wall-clock of the paper's protocol for our method: 8 seeds x 100 cycles, seeds over every device.

    python -m bench.training [--env doorknobs] [--num-seeds 8] [--cycles 100] [--devices auto|N]
                             [--seed-block 1] [--approach ours[,plan_progress,...]]

Prints the time to build tasks and plans, the first cycle (mostly compilation), the steady-state
seconds per cycle, the total, and the ratio to the authors' run time of one seed (results.md: Light
Switch Door 17,572 s, Doorknobs 21,118 s; Coffee never finished, ~13,900 s of learning by cycle 100).
"""
from __future__ import annotations

import argparse
import dataclasses
import time

import jax
import numpy as np

from bench.records import authors_seed_run_s
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.grid import owner, parse_value
from jaxbridge.learn.devices import SeedMesh, describe, device_count_arg, select_devices
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import make_setup

AUTHORS_WHOLE_RUN_S = authors_seed_run_s()  # one seed-run of the authors' "ours" (docs/results/authors_times.csv)


def measure_cycles(config: TrainConfig, devices: list, cycles: int | None = None) -> dict:
    """Build `config`'s setup with the seeds over `devices` and run `cycles` cycles (default:
    config.cycles). Returns the times (build, each cycle), what JAX compiled in the first cycle and in
    the later ones (jaxbridge.utils.compile_cache.CompileEvents), each cycle's mean test solve rate ("rates")
    and per seed ("seed_rates", float[seeds, cycles]), and the setup, seed layout and final
    learners (for further measurements)."""
    from jaxbridge.utils import compile_cache

    start = time.perf_counter()
    setup = make_setup(config)
    seeds = SeedMesh(config.num_seeds, tuple(devices), config.seed_block)
    learners = seeds.place(setup.init_learners())
    cycle = Cycle(setup, seeds)
    built = time.perf_counter()
    times, seed_rates = [], []

    def one(learners):
        t0 = time.perf_counter()
        learners, metrics = cycle(learners)
        seed_rates.append(np.asarray(seeds.unpad(metrics).test_solve_rate))
        times.append(time.perf_counter() - t0)
        return learners

    with compile_cache.record() as first:
        learners = one(learners)
    with compile_cache.record() as later:  # the later cycles' compilations (none: the cycle compiles once)
        for _ in range((cycles or config.cycles) - 1):
            learners = one(learners)
    return {"build_s": built - start, "times": times, "rates": [float(r.mean()) for r in seed_rates],
            "seed_rates": np.array(seed_rates).T, "first": first, "later": later,
            "total_s": time.perf_counter() - start, "setup": setup, "seeds": seeds, "learners": learners, "cycle": cycle}


def config_override(text: str) -> tuple[str, object]:
    """argparse type of a `name=value` TrainConfig override (a field of the config or of double DQN's
    settings), its value read as train.py --sweep reads it."""
    name, sep, value = text.partition("=")
    if not sep or owner(TrainConfig(), name) is None:
        raise argparse.ArgumentTypeError(f"expected a TrainConfig field as name=value, got {text!r}")
    try:
        return name, parse_value(name, value)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def with_overrides(config: TrainConfig, overrides: list[tuple[str, object]]) -> tuple[TrainConfig, dict]:
    """`config` with the (field, value) overrides applied, and those changes."""
    changes = dict(overrides)
    return dataclasses.replace(config, **changes), changes


def report(config: TrainConfig, run: dict) -> float:
    """Print one approach's times; returns its steady-state seconds per cycle."""
    times, total = run["times"], run["total_s"]
    steady = float(np.median(times[1:])) if len(times) > 1 else times[0]
    per_seed_run = total / config.num_seeds
    print(f"{config.env}, {config.approach}: {config.num_seeds} seeds x {config.cycles} cycles, {config.updates_per_cycle} updates/cycle, "
          f"batch {config.batch_size}")
    print(f"tasks + plan tables: {run['build_s']:.1f} s; first cycle (with compilation): {times[0]:.1f} s; "
          f"steady state: {steady:.3f} s/cycle")
    print(f"total: {total:.1f} s; final mean test solve rate {run['rates'][-1]:.2f}")
    if config.env in AUTHORS_WHOLE_RUN_S:
        authors = AUTHORS_WHOLE_RUN_S[config.env]
        print(f"authors: {authors:,} s per seed-run; ours: {per_seed_run:.1f} s per seed-run "
              f"-> {authors / per_seed_run:,.0f}x")
    return steady


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--num-seeds", type=int, default=8, help="seeds (default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=100, help="cycles (default: %(default)s)")
    parser.add_argument("--env", default="light_switch_door", help="environment (default: %(default)s)")
    parser.add_argument("--devices", type=device_count_arg, default="auto", help="as train.py (default: auto)")
    parser.add_argument("--seed-block", type=int, default=1, help="as train.py (default: %(default)s)")
    parser.add_argument("--approach", default="ours", help="which approach, or a comma-separated list measured one "
                        "after the other, each one's steady-state cost then given as a ratio to the first's "
                        "(default: %(default)s)")
    parser.add_argument("overrides", nargs="*", type=config_override,
                        help="TrainConfig fields as name=value, e.g. feature_noise=0")
    args = parser.parse_args()
    seeds_over = select_devices(args.devices)
    print(f"jax {jax.__version__}, seeds over {describe(seeds_over)} device(s), seed block {args.seed_block}")
    steady = {}
    for approach in args.approach.split(","):
        config, _ = with_overrides(TrainConfig.for_env(args.env, num_seeds=args.num_seeds, cycles=args.cycles,
                                                       seed_block=args.seed_block, approach=approach), args.overrides)
        steady[approach] = report(config, measure_cycles(config, seeds_over))
    first = next(iter(steady))
    for approach, seconds in list(steady.items())[1:]:
        print(f"{approach}: {seconds / steady[first]:.2f}x {first}'s steady-state seconds per cycle")


if __name__ == "__main__":
    main()
