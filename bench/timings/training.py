"""Wall-clock of the paper's protocol for our method: 8 seeds x 100 cycles, seeds over every device.

    python -m bench.timings.training [--env doorknobs] [--seeds 0-7] [--cycles 100] [--devices auto|N]
                             [--seed-block 1] [--approach ours[,plan_progress,...]]

Prints the time to build tasks and plans, the first cycle (mostly compilation), the steady-state
seconds per cycle, the total, and the ratio to the authors' run time of one seed (results.md: Light
Switch Door 17,572 s, Doorknobs 21,118 s; Coffee never finished, ~13,900 s of learning by cycle 100).
"""
from __future__ import annotations

import jaxbridge
import argparse
import dataclasses
import time

import jax
import numpy as np

from bench.command import CommandParser
from bench.records import authors_seed_run_s
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.grid import owner, parse_value
from jaxbridge.learn.devices import SeedMesh, describe, device_count_arg, select_devices
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import make_setup
from jaxbridge.run.model_repair import ModelRepair
from jaxbridge.utils import compile_cache

AUTHORS_WHOLE_RUN_S = authors_seed_run_s()  # one seed-run of the authors' "ours" (docs/results/authors_times.csv)


class TimedTraining:
    """One approach's training, timed a cycle at a time: its tasks and plans, placed learners and Cycle are
    built on creation (`build_s`); `step()` runs one cycle and records its seconds and test solve rates."""

    def __init__(self, config: TrainConfig, devices: list):
        start = time.perf_counter()
        self.config, self.setup = config, make_setup(config)
        self.seeds = SeedMesh(config.num_seeds, tuple(devices), config.seed_block)
        self.learners = self.seeds.place(self.setup.init_learners())
        self.cycle = Cycle(self.setup, self.seeds)
        # a model repair approach's relearning between cycles is part of its cycles' time, as in train.py
        self.repair = ModelRepair(self.setup, config.num_seeds) if self.setup.approach.repairs_model else None
        self.build_s = time.perf_counter() - start
        self.times, self.built, self.seed_rates = [], [], []

    def step(self) -> None:
        t0 = time.perf_counter()
        with compile_cache.record() as built:
            self.learners, metrics = self.cycle(self.learners)
            if self.repair is not None:
                self.repair.after_cycle(len(self.times) + 1, self.cycle)
        self.seed_rates.append(np.asarray(self.seeds.unpad(metrics).test_solve_rate))
        self.times.append(time.perf_counter() - t0)
        self.built.append((built.fresh, built.seconds))

    def result(self) -> dict:
        """The times (build, each cycle, their total), each cycle's programs compiled and seconds spent
        building programs ("built"), each cycle's mean test solve rate ("rates") and per seed ("seed_rates",
        float[seeds, cycles]), and the setup, seed layout and learners."""
        return {"build_s": self.build_s, "times": self.times, "built": self.built, "total_s": self.build_s + sum(self.times),
                "rates": [float(r.mean()) for r in self.seed_rates], "seed_rates": np.array(self.seed_rates).T,
                "setup": self.setup, "seeds": self.seeds, "learners": self.learners, "cycle": self.cycle}


def measure_cycles(config: TrainConfig, devices: list, cycles: int | None = None) -> dict:
    """Build `config`'s setup with the seeds over `devices` and run `cycles` cycles (default:
    config.cycles). Returns TimedTraining.result() with what JAX compiled in the first cycle ("first")
    and in the later ones ("later"; jaxbridge.utils.compile_cache.CompileEvents)."""
    run = TimedTraining(config, devices)
    with compile_cache.record() as first:
        run.step()
    with compile_cache.record() as later:  # the later cycles' compilations (none: the cycle compiles once)
        for _ in range((cycles or config.cycles) - 1):
            run.step()
    return {**run.result(), "first": first, "later": later}


def measure_interleaved(configs: dict[str, TrainConfig], devices: list, cycles: int) -> dict[str, dict]:
    """{name: TimedTraining.result()} of several trainings run a cycle of each in turn, so that a machine
    whose speed drifts slows them alike (their ratios are then measured in one run)."""
    runs = {name: TimedTraining(config, devices) for name, config in configs.items()}
    for _ in range(cycles):
        for run in runs.values():
            run.step()
    return {name: run.result() for name, run in runs.items()}


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


def overrides_parser(module: str, doc: str, env: str, seeds: str, cycles: int) -> CommandParser:
    """The parser of a command that trains seeds with config overrides (this timing, bench.probes.sweep and the
    probes built on it): --env, --seeds, --cycles and TrainConfig fields as name=value."""
    parser = CommandParser(module, doc, env=env, seeds=seeds)
    parser.add_argument("--cycles", type=int, default=cycles, help="cycles (default: %(default)s)")
    parser.add_argument("overrides", nargs="*", type=config_override,
                        help="TrainConfig fields as name=value, e.g. feature_noise=0 (booleans: true/false)")
    return parser


def with_overrides(config: TrainConfig, overrides: list[tuple[str, object]]) -> tuple[TrainConfig, dict]:
    """`config` with the (field, value) overrides applied, and those changes."""
    changes = dict(overrides)
    return dataclasses.replace(config, **changes), changes


def report(config: TrainConfig, run: dict) -> tuple[float, float, float, float]:
    """Print one approach's times; returns its steady-state (median), mean, and mean less building programs
    seconds per cycle after the first (a model repair approach's relearning cycles are in the means, not the
    median; the cycle it first plans with learned tables compiles its program again), and its mean over
    every cycle, the first's building included (the whole training's cycles, as train.py runs them)."""
    times, total = run["times"], run["total_s"]
    later = times[1:] or times
    built = run["built"][1:] or run["built"]
    steady, mean, whole = float(np.median(later)), float(np.mean(later)), float(np.mean(times))
    unbuilt = mean - sum(seconds for _, seconds in built) / len(later)
    per_seed_run = total / config.num_seeds
    print(f"{config.env}, {config.approach}: {config.num_seeds} seeds x {config.cycles} cycles, {config.learner.updates_per_cycle} updates/cycle, "
          f"batch {config.learner.batch_size}")
    print(f"tasks + plan tables: {run['build_s']:.1f} s; first cycle (with compilation): {times[0]:.1f} s; "
          f"steady state: {steady:.3f} s/cycle, mean {mean:.3f} s/cycle; later cycles built "
          f"{sum(n for n, _ in built)} program(s) in {sum(s for _, s in built):.1f} s, mean without them {unbuilt:.3f} s/cycle")
    print(f"total: {total:.1f} s; final mean test solve rate {run['rates'][-1]:.2f}")
    if config.env in AUTHORS_WHOLE_RUN_S:
        authors = AUTHORS_WHOLE_RUN_S[config.env]
        print(f"authors: {authors:,} s per seed-run; ours: {per_seed_run:.1f} s per seed-run "
              f"-> {authors / per_seed_run:,.0f}x")
    return steady, mean, unbuilt, whole


def main() -> None:
    parser = overrides_parser(__spec__.name, __doc__, "light_switch_door", "0-7", 100)
    parser.add_argument("--devices", type=device_count_arg, default="auto", help="as train.py (default: auto)")
    parser.add_argument("--seed-block", type=int, default=1, help="as train.py (default: %(default)s)")
    parser.add_argument("--approach", default="ours", help="which approach, or a comma-separated list trained a "
                        "cycle of each in turn, each one's steady-state cost then given as a ratio to the first's "
                        "(default: %(default)s)")
    args = parser.parse_args()
    seeds_over = select_devices(args.devices)
    print(f"jax {jax.__version__}, seeds over {describe(seeds_over)} device(s), seed block {args.seed_block}")
    configs = {approach: with_overrides(jaxbridge.make_config(args.env, seeds=args.seed_list, cycles=args.cycles,
                                                            seed_block=args.seed_block, approach=approach),
                                        args.overrides)[0] for approach in args.approach.split(",")}
    runs = measure_interleaved(configs, seeds_over, args.cycles)
    seconds = {approach: report(configs[approach], run) for approach, run in runs.items()}
    first = next(iter(seconds))
    for approach, (steady, mean, unbuilt, whole) in list(seconds.items())[1:]:
        print(f"{approach}: {steady / seconds[first][0]:.2f}x {first}'s steady-state seconds per cycle, "
              f"{mean / seconds[first][1]:.2f}x its mean, {unbuilt / seconds[first][2]:.2f}x its mean without building programs, "
              f"{whole / seconds[first][3]:.2f}x its mean over every cycle")


if __name__ == "__main__":
    main()
