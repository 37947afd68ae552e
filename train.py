"""Train bridge policies for every seed at once and write a run directory.

    python train.py --env light_switch_door --num-seeds 8
    python train.py --resume runs/light_switch_door      # continue after a crash or Ctrl-C

The run directory (default runs/<env>) gets config.json, metrics.csv (one row per seed x cycle),
summary.json, curves.png (test and training smooth reward) and checkpoints/ (orbax, whole learner state),
which eval.py loads. Exit codes: 0 done, 2 bad input, 3 numerical fault, 130 interrupted.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from envs_jax import ENVS
from jaxbridge.cli import UsageError, non_negative_int, positive_int, run_main
from jaxbridge.config import TrainConfig

DEFAULTS = TrainConfig()
# Flags that set the run's config; --resume takes the saved config instead.
CONFIG_FLAGS = {"env": "env", "num_seeds": "num_seeds", "first_seed": "first_seed", "cycles": "cycles",
                "episodes_per_cycle": "episodes_per_cycle", "updates_per_cycle": "updates_per_cycle",
                "batch_size": "batch_size", "call_planner_bonus": "call_planner_bonus",
                "checkpoint_every": "checkpoint_every"}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    d = DEFAULTS
    p.add_argument("--env", choices=sorted(ENVS), help=f"environment (default: {d.env})")
    p.add_argument("--num-seeds", type=positive_int,
                   help=f"seeds trained together, each with its own tasks and network (default: {d.num_seeds})")
    p.add_argument("--first-seed", type=non_negative_int,
                   help=f"seeds are first-seed .. first-seed+num-seeds-1 (default: {d.first_seed})")
    p.add_argument("--cycles", type=positive_int, help=f"online learning cycles (default: {d.cycles}, the paper's)")
    p.add_argument("--episodes-per-cycle", type=positive_int,
                   help=f"training episodes per cycle (default: {d.episodes_per_cycle}, the paper's)")
    p.add_argument("--updates-per-cycle", type=non_negative_int,
                   help=f"double-DQN minibatch updates per cycle (default: {d.updates_per_cycle})")
    p.add_argument("--batch-size", type=positive_int,
                   help=f"minibatch size of the updates (default: {d.batch_size}; the paper: 64)")
    p.add_argument("--call-planner-bonus", type=float,
                   help=f"extra reward when CallPlanner reaches the goal (the authors' code: 0.5; default: {d.call_planner_bonus})")
    p.add_argument("--checkpoint-every", type=positive_int,
                   help=f"save the learner state every N cycles and at the end (default: {d.checkpoint_every})")
    p.add_argument("--out", type=Path, default=Path("runs"), help="parent of run directories (default: %(default)s)")
    p.add_argument("--name", default=None, help="run directory name under --out (default: the env name)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing run directory of the same name")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR", default=None,
                   help="continue the run in RUN_DIR from its latest checkpoint, with its saved config")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (one summary line at the end)")
    return p.parse_args(argv)


def make_config(args) -> TrainConfig:
    given = {field: getattr(args, flag) for flag, field in CONFIG_FLAGS.items() if getattr(args, flag) is not None}
    config = TrainConfig(**given)
    if config.episodes_per_cycle * config.train_steps > config.buffer_capacity:
        raise UsageError(f"--episodes-per-cycle x {config.train_steps} steps must fit the replay buffer "
                         f"({config.buffer_capacity} transitions)")
    return config


def main(argv=None) -> int:
    args = parse_args(argv)
    from jaxbridge.checkpoint import CheckpointError
    from jaxbridge.runner import Interrupted, NumericalFault, load_config, prepare_run_dir, train

    if args.resume is not None:
        clashing = [f"--{flag.replace('_', '-')}" for flag in CONFIG_FLAGS if getattr(args, flag) is not None]
        clashing += [f for f, on in (("--overwrite", args.overwrite), ("--name", args.name)) if on]
        if clashing:
            raise UsageError(f"--resume continues a run with its saved config; drop {', '.join(clashing)}")
        run_dir = args.resume
        try:
            config = load_config(run_dir)
        except ValueError as err:
            raise UsageError(str(err)) from None
    else:
        config = make_config(args)
        run_dir = args.out / (args.name or config.env)
        try:
            prepare_run_dir(run_dir, args.overwrite)
        except FileExistsError as err:
            raise UsageError(str(err)) from None
        except OSError as err:
            raise UsageError(f"cannot write run directory {run_dir}: {err.strerror}") from None
    try:
        info = train(config, run_dir, progress=not args.no_progress, resume=args.resume is not None)
    except CheckpointError as err:
        raise UsageError(str(err)) from None
    except NumericalFault as err:
        print(f"error: {err}", file=sys.stderr)
        return 3
    except Interrupted as err:
        print(f"{err}; continue with: python train.py --resume {run_dir}", file=sys.stderr)
        return 130
    at = info["test_solve_rate_at"]
    last = max((int(c) for c in at), default=None)
    print(f"done in {info['elapsed_s']:.0f} s -> {run_dir}/")
    print(f"mean test solve rate at the last cycle: {info['mean_test_solve_rate_per_cycle'][-1]:.2f}; "
          f"smooth reward at cycle {info['cycles']}: {info['smooth_reward_final']['mean']:.3f}"
          + (f"; at cycle {last}: {at[str(last)]['mean']:.2f}" if last else ""))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
