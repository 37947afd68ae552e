"""Learning-reliability sweep: train many seeds at once with config overrides and print one row of
test solve rates per seed (digit = floor(10 x rate), 9 = 0.9-1.0) and a summary over seeds (the
evidence of docs/TUNING.md).

    python -m bench.probes.sweep --seeds 8-23 --cycles 40 batch_size=64 polyak_per=decision
"""
from __future__ import annotations

import time

import numpy as np

import jaxbridge
from bench.timings.training import measure_cycles, overrides_parser, with_overrides
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.devices import select_devices
from jaxbridge.learn.setup import Setup

# Issue #19's reliability bars: the mean from cycle 40 on, and every single seed from cycle 50 on.
LATE_MEAN, SEED_FLOOR = 0.95, 0.8


def swept_config(args) -> tuple[TrainConfig, dict]:
    """The env's config for the chosen seeds and cycles with the overrides applied, and the overrides."""
    config = jaxbridge.make_config(args.env, seeds=args.seed_list, cycles=args.cycles)
    return with_overrides(config, args.overrides)


def train_seeds(config: TrainConfig) -> tuple[Setup, object, np.ndarray]:
    """Train every seed of `config` over every device (as train.py; results do not depend on it), without
    run files. Returns the setup, the final learners (one device) and the test solve rates
    float[seeds, cycles]."""
    run = measure_cycles(config, select_devices())
    return run["setup"], run["seeds"].unpad(run["learners"]), run["seed_rates"]


def print_digits(seeds: list[int], rates: np.ndarray) -> None:
    for seed, row in zip(seeds, rates):
        print(f"{seed:>3} " + "".join(str(min(9, int(r * 10))) for r in row))


def main() -> None:
    parser = overrides_parser(__spec__.name, __doc__, "light_switch_door", "8-23", 40)
    parser.add_argument("--save", help="also save the rates, float[seeds, cycles], to this .npy file")
    parser.add_argument("--bar", type=float, default=0.95,
                        help="a threshold on the mean test solve rate: the cycles from 50 on at or above it, and "
                             "from which cycle the mean stays at or above it (Coffee's authors' tasks: 0.837, 0.9 x "
                             "the oracle's ceiling) (default: %(default)s)")
    args = parser.parse_args()
    config, changes = swept_config(args)
    start = time.perf_counter()
    _, _, rates = train_seeds(config)
    if args.save:
        np.save(args.save, rates)
    print_digits(config.seeds, rates)
    mean = rates.mean(0)
    print(f"overrides {changes or 'none'}: {time.perf_counter() - start:.0f} s; mean every 5 cycles "
          f"{mean[4::5].round(2).tolist()}; min mean from cycle 30: "
          f"{f'{mean[29:].min():.3f}' if len(mean) >= 30 else 'n/a'}; "
          f"seeds >= 0.9 at the last cycle: {(rates[:, -1] >= 0.9).sum()}/{len(rates)}")
    print(reliability(rates, args.bar))


def reliability(rates: np.ndarray, bar: float) -> str:
    """How reliably the seeds hold what they learned (rates: float[seeds, cycles]): the lowest mean test
    solve rate from cycle 40 on and the cycles there below LATE_MEAN; the seed-cycles from cycle 50 on
    below SEED_FLOOR; the lowest mean from cycle 50, the cycles there with a mean >= `bar`, and the
    first cycle from which the mean stays >= `bar`."""
    mean, late = rates.mean(0), rates[:, 49:]
    if len(mean) < 50:
        return "reliability: needs 50 cycles or more"
    below = np.flatnonzero(mean < bar)
    holds_from = 1 if len(below) == 0 else (below[-1] + 2 if below[-1] + 1 < len(mean) else None)
    return (f"reliability: lowest mean from cycle 40 {mean[39:].min():.3f}; cycles from 40 with mean < {LATE_MEAN}: "
            f"{(mean[39:] < LATE_MEAN).sum()}; seed-cycles below {SEED_FLOOR} from cycle 50: "
            f"{(late < SEED_FLOOR).sum()}/{late.size}; lowest mean from cycle 50 {mean[49:].min():.3f}; cycles from "
            f"50 with mean >= {bar}: {(mean[49:] >= bar).sum()}/{len(mean) - 49}; mean stays >= {bar} from cycle "
            f"{holds_from if holds_from is not None else 'never'}; mean over cycles 50-{len(mean)} {mean[49:].mean():.3f}")

if __name__ == "__main__":
    main()
