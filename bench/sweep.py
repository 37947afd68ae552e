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
from jaxbridge.online import build_experiment, init_learners, make_cycle


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="light_switch_door", help="environment (default: %(default)s)")
    parser.add_argument("--num-seeds", type=int, default=16, help="seeds (default: %(default)s)")
    parser.add_argument("--first-seed", type=int, default=8, help="first seed (default: %(default)s)")
    parser.add_argument("--cycles", type=int, default=40, help="cycles (default: %(default)s)")
    parser.add_argument("--save", help="also save the rates, float[seeds, cycles], to this .npy file")
    parser.add_argument("overrides", nargs="*", help="TrainConfig fields as name=value")
    args = parser.parse_args()
    config = TrainConfig.for_env(args.env, num_seeds=args.num_seeds, first_seed=args.first_seed, cycles=args.cycles)
    changes = {}
    for item in args.overrides:
        name, value = item.split("=", 1)
        changes[name] = type(getattr(config, name))(value)
    config = dataclasses.replace(config, **changes)
    start = time.perf_counter()
    experiment = build_experiment(config)
    learners, cycle = init_learners(experiment), make_cycle(experiment)
    rates = []
    for _ in range(config.cycles):
        learners, metrics = cycle(learners)
        rates.append(np.asarray(metrics.test_solve_rate))
    rates = np.array(rates).T
    if args.save:
        np.save(args.save, rates)
    for seed, row in zip(config.seeds, rates):
        print(f"{seed:>3} " + "".join(str(min(9, int(r * 10))) for r in row))
    mean = rates.mean(0)
    print(f"overrides {changes or 'none'}: {time.perf_counter() - start:.0f} s; mean every 5 cycles "
          f"{mean[4::5].round(2).tolist()}; min mean from cycle 30: {mean[29:].min():.3f}; "
          f"seeds >= 0.9 at the last cycle: {(rates[:, -1] >= 0.9).sum()}/{len(rates)}")


if __name__ == "__main__":
    main()
