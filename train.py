"""Train bridge policies for every seed at once and write a run directory.

    python train.py --env light_switch_door --num-seeds 8

The run directory (default runs/<env>) gets config.json, metrics.csv (one row per seed x cycle),
summary.json, curves.png (test and training smooth reward) and checkpoints/ (orbax, whole learner state),
which eval.py loads.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from envs_jax import ENVS
from jaxbridge.cli import UsageError, non_negative_int, positive_int, run_main
from jaxbridge.config import TrainConfig

DEFAULTS = TrainConfig()


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--env", default=DEFAULTS.env, choices=sorted(ENVS), help="environment (default: %(default)s)")
    p.add_argument("--num-seeds", type=positive_int, default=DEFAULTS.num_seeds,
                   help="seeds trained together, each with its own tasks and network (default: %(default)s)")
    p.add_argument("--first-seed", type=non_negative_int, default=DEFAULTS.first_seed,
                   help="seeds are first-seed .. first-seed+num-seeds-1 (default: %(default)s)")
    p.add_argument("--cycles", type=positive_int, default=DEFAULTS.cycles,
                   help="online learning cycles (default: %(default)s, the paper's)")
    p.add_argument("--episodes-per-cycle", type=positive_int, default=DEFAULTS.episodes_per_cycle,
                   help="training episodes per cycle (default: %(default)s, the paper's)")
    p.add_argument("--updates-per-cycle", type=non_negative_int, default=DEFAULTS.updates_per_cycle,
                   help="double-DQN minibatch updates per cycle (default: %(default)s)")
    p.add_argument("--batch-size", type=positive_int, default=DEFAULTS.batch_size,
                   help="minibatch size of the updates (default: %(default)s; the paper: 64)")
    p.add_argument("--call-planner-bonus", type=float, default=DEFAULTS.call_planner_bonus,
                   help="extra reward when CallPlanner reaches the goal (the authors' code: 0.5; default: %(default)s)")
    p.add_argument("--checkpoint-every", type=positive_int, default=DEFAULTS.checkpoint_every,
                   help="save the learner state every N cycles and at the end (default: %(default)s)")
    p.add_argument("--out", type=Path, default=Path("runs"), help="parent of run directories (default: %(default)s)")
    p.add_argument("--name", default=None, help="run directory name under --out (default: the env name)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing run directory of the same name")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (one summary line at the end)")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    from jaxbridge.runner import prepare_run_dir, train

    config = TrainConfig(env=args.env, num_seeds=args.num_seeds, first_seed=args.first_seed, cycles=args.cycles,
                         episodes_per_cycle=args.episodes_per_cycle, updates_per_cycle=args.updates_per_cycle,
                         batch_size=args.batch_size,
                         call_planner_bonus=args.call_planner_bonus, checkpoint_every=args.checkpoint_every)
    run_dir = args.out / (args.name or args.env)
    try:
        prepare_run_dir(run_dir, args.overwrite)
    except FileExistsError as err:
        raise UsageError(str(err)) from None
    except OSError as err:
        raise UsageError(f"cannot write run directory {run_dir}: {err.strerror}") from None
    info = train(config, run_dir, progress=not args.no_progress)
    at = info["test_solve_rate_at"]
    last = max(int(c) for c in at) if at else None
    print(f"done in {info['elapsed_s']:.0f} s -> {run_dir}/")
    print(f"mean test solve rate per cycle (last): {info['mean_test_solve_rate_per_cycle'][-1]:.2f}; "
          f"smooth reward at cycle {info['cycles']}: {info['smooth_reward_final']['mean']:.3f}"
          + (f"; at cycle {last}: {at[str(last)]['mean']:.2f}" if last else ""))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
