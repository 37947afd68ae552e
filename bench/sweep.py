"""Learning-reliability sweep: train many seeds at once with config overrides and print one row of
test solve rates per seed (digit = floor(10 x rate), 9 = 0.9-1.0) and the summary used in
docs/RESULTS.md.

    python -m bench.sweep --num-seeds 16 --first-seed 8 --cycles 40 batch_size=64 polyak_per=decision
"""
from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from jaxbridge.config import TrainConfig
from jaxbridge.devices import SeedMesh, select_devices
from jaxbridge.online import build_experiment, init_learners, make_cycle


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="light_switch_door", help="environment (default: %(default)s)")
    parser.add_argument("--num-seeds", type=int, default=16, help="seeds (default: %(default)s)")
    parser.add_argument("--first-seed", type=int, default=8, help="first seed (default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=40, help="cycles (default: %(default)s)")
    parser.add_argument("overrides", nargs="*", help="TrainConfig fields as name=value (booleans: True/False)")
    args = parser.parse_args()
    devices = select_devices("auto")  # as train.py: the seeds over every core; results do not depend on it
    config = TrainConfig.for_env(args.env, num_seeds=args.num_seeds, first_seed=args.first_seed, cycles=args.cycles)
    changes = {}
    for item in args.overrides:
        name, value = item.split("=", 1)
        kind = type(getattr(config, name))
        changes[name] = value == "True" if kind is bool else kind(value)
    config = dataclasses.replace(config, **changes)
    start = time.perf_counter()
    experiment = build_experiment(config)
    seeds = SeedMesh(config.num_seeds, tuple(devices))
    learners, cycle = seeds.place(init_learners(experiment)), make_cycle(experiment, seeds)
    rates = []
    for _ in range(config.cycles):
        learners, metrics = cycle(learners)
        rates.append(np.asarray(seeds.unpad(metrics).test_solve_rate))
    rates = np.array(rates).T
    for seed, row in zip(config.seeds, rates):
        print(f"{seed:>3} " + "".join(str(min(9, int(r * 10))) for r in row))
    mean = rates.mean(0)
    print(f"overrides {changes or 'none'}: {time.perf_counter() - start:.0f} s; mean every 5 cycles "
          f"{mean[4::5].round(2).tolist()}; min mean from cycle 30: {mean[29:].min():.3f}; "
          f"seeds >= 0.9 at the last cycle: {(rates[:, -1] >= 0.9).sum()}/{len(rates)}")


if __name__ == "__main__":
    main()
