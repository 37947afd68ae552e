"""Train the paper's approaches for every seed at once and write an experiment directory.

    python train.py --env light_switch_door --num-seeds 8         # all six approaches: the paper's figure
    python train.py --env light_switch_door --approaches ours     # just our method
    python train.py --resume runs/light_switch_door               # continue after a crash or Ctrl-C
    python train.py --env examples.locked_box:LockedBox --num-seeds 2 --cycles 3   # an env of your own

Approaches: ours (bridge policy learning), no_feature_selection, no_callplanner, random (random bridge),
pure_planning, maple_q (pure RL); see jaxbridge/learn/approaches.py.

The experiment directory (default runs/<env>) gets curves.png (per approach: the test solve rate per cycle
and the test and training smooth reward; mean, 95% CI and min-max bands over seeds), results.md and results.csv (test solve rate at cycles
10/25/50/100 and the final smooth reward), and one run directory per approach with config.json,
metrics.csv (one row per seed x cycle), summary.json, curves.png and checkpoints/ (orbax, whole learner
state), which eval.py loads. Exit codes: 0 done, 2 bad input, 3 numerical fault, 4 cannot write (no
space, read-only, permission; the last complete checkpoint stays), 130 interrupted (docs/RELIABILITY.md).

Devices: the seeds are sharded over --devices local devices (all GPUs, or on a CPU-only machine one
virtual CPU device per core), each device training its share of the seeds; a run may resume on another
count. The numbers are bit-identical whatever the device count. --seed-block B computes B seeds side by
side on each device (what a GPU needs); the numbers then depend on B, still not on the device count.
See docs/PERFORMANCE.md.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import jaxbridge
from jaxbridge.utils import compile_cache, distributed
from jaxbridge.utils.cli import (ArgumentParser, add_field_flags, auto_or_positive_int, names_from, positive_float,
                                 positive_int, run_main)
from jaxbridge.utils.interrupts import EXIT_INTERRUPTED, Interrupts, run_watched

EXIT_NUMERICAL, EXIT_CANNOT_WRITE = 3, 4
DEFAULTS = jaxbridge.TrainConfig()
# The default learner's settings that have a flag of their own; the others, and other learners': --set.
LEARNER_FLAGS = ("updates_per_cycle", "batch_size")
# The config's fields without a flag of their own: --approaches names them; the token network's settings: --set.
NO_FLAG = ("approach", "tokens")
# The flags that set the run's config, named as their settings; --resume takes the saved config instead.
SETTINGS = {field.name for field in dataclasses.fields(jaxbridge.TrainConfig)} | set(LEARNER_FLAGS)


def chosen_learner(argv) -> tuple[str | None, str | None]:
    """The --learner and --preset given, read before the whole parse: --help lists that learner's settings."""
    early = argparse.ArgumentParser(add_help=False)
    add_field_flags(early, jaxbridge.TrainConfig, only=("learner", "preset"))
    known, _ = early.parse_known_args(argv)
    return known.learner, known.preset


def parse_args(argv):
    p = ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
                       epilog=jaxbridge.settings_help(*chosen_learner(argv)))
    p.add_argument("--approaches", type=names_from(jaxbridge.ALL_APPROACHES, "approach"), default=None, metavar="LIST",
                   help="comma-separated approaches to train, or all (the six and what the env's default adds; default: "
                        f"the paper's figure for the env: the six, {', '.join(jaxbridge.APPROACHES)}; doorknobs: all but "
                        "no_feature_selection, as the paper's Doorknobs figure; multi_novelty: ours, the learned selector, the "
                        "per-signature bridges and the baselines but Maple Q; by name only: "
                        f"{', '.join([*jaxbridge.SELECTION, *jaxbridge.SIGNATURE, *jaxbridge.PLAN_REPAIR, *jaxbridge.LOW_LEVEL])})")
    p.add_argument("--set", action="append", default=None, metavar="NAME=VALUE",
                   help="set a setting of the run or of its learner by name (listed below), e.g. --set batch_size=64 "
                        "--set hidden_sizes=64x64; repeat for more (default: the preset's values)")
    p.add_argument("--sweep", action="append", default=None, metavar="KEY=V1,V2,...",
                   help="train every approach at each of these values of a hyperparameter (repeat for a grid: "
                        "the cartesian product), each setting its own run directory approach@KEY=V,... with a row "
                        "in results.md and a line in curves.png. KEY: a setting of the run or of its learner (listed "
                        "below); settings that differ only in [leaf] ones share one compiled program (seeds x settings "
                        "side by side), other keys (n_sample, hidden_sizes as 64x64, ...) compile one per value. Each "
                        "run's numbers are a plain run's (default: none)")
    p.add_argument("--out", type=Path, default=Path("runs"), help="parent of run directories (default: %(default)s)")
    p.add_argument("--name", default=None, help="experiment directory name under --out (default: the env name)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing experiment directory of the same name")
    p.add_argument("--resume", type=Path, metavar="DIR", default=None,
                   help="continue the experiment (or single approach's run) in DIR from its latest checkpoints, "
                        "with its saved config")
    p.add_argument("--workers", type=positive_int, default=None,
                   help="approaches trained at the same time, in threads (default: one per CPU core, at most one "
                        "per approach); they split the devices between them; results do not depend on it")
    p.add_argument("--devices", type=auto_or_positive_int, default="auto", metavar="auto|N",
                   help="shard the seeds over N local devices: auto = all GPUs/TPUs, or on a CPU-only machine one "
                        "virtual CPU device per core (set before JAX starts; XLA_FLAGS="
                        "--xla_force_host_platform_device_count=K takes precedence). Seeds need not divide evenly. "
                        "Results do not depend on it (default: %(default)s)")
    p.add_argument("--max-memory", type=positive_float, default=None, metavar="GIB",
                   help="refuse a run whose memory estimate (learner states, replay buffers, tasks and plan tables) "
                        "exceeds this many GiB (default: the memory available when it starts)")
    p.add_argument("--debug", action="store_true", help="show the tracebacks and orbax's messages behind an error")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (one summary line at the end)")
    p.add_argument("--tensorboard", action="store_true",
                   help="also write TensorBoard event files (tensorboardX) into each approach's run directory, "
                        "events/, as cycles complete: per cycle the mean, 95%% CI and IQM over seeds of the test and "
                        "training solve rates, the loss, epsilon, buffer size, and the config as text "
                        "(tensorboard --logdir RUN); metrics.csv stays the source of truth (default: off)")
    p.add_argument("--no-compile-cache", action="store_true", help=compile_cache.HELP)
    add_setting_flags(p)
    distributed.add_flags(p)
    return p.parse_args(argv)


def add_setting_flags(p) -> None:
    """A flag per setting, made from its declaration (jaxbridge.TrainConfig's fields and LEARNER_FLAGS)."""
    d, run = DEFAULTS, p.add_argument_group("settings of the run", "  each sets the TrainConfig field of its name "
                                           "(help(jaxbridge.TrainConfig));\n  one not given takes the preset's value "
                                           "for the env, else the default shown.\n  envs: " + ", ".join(jaxbridge.env_names())
                                           + "\n  presets: " + "; ".join(f"{k}: {v}" for k, v in jaxbridge.PRESETS.items()))
    add_field_flags(run, jaxbridge.TrainConfig, skip=NO_FLAG)
    add_field_flags(p.add_argument_group(f"settings of learner {d.learner.name} with flags (the others, and other "
                                         "learners': --set, listed below)"), type(d.learner), only=LEARNER_FLAGS)


def given_settings(args) -> dict:
    """{setting: value} of the setting flags given (one not given is left to the preset and the defaults)."""
    return {name: value for name, value in vars(args).items() if name in SETTINGS and value is not None}


def main(argv=None) -> int:
    args = parse_args(argv)
    distributed.initialize_from(args)  # before anything starts JAX
    devices = jaxbridge.local_devices(args.devices)
    compile_cache.enable(not args.no_compile_cache)  # before anything compiles
    start, given = time.perf_counter(), given_settings(args)
    interrupts = Interrupts(on_exit=jaxbridge.release_locks)
    options = dict(workers=args.workers, devices=devices, progress=not args.no_progress, tensorboard=args.tensorboard)
    if args.resume is not None:
        clashing = [f"--{flag.replace('_', '-')}" for flag in given]
        clashing += [f"--{flag}" for flag in ("overwrite", "name", "approaches", "sweep", "set") if getattr(args, flag)]
        if clashing:
            raise jaxbridge.InputError(f"--resume continues a run with its saved config; drop {', '.join(clashing)}")
        training = jaxbridge.prepare_resume(args.resume, **options)
    else:
        training = jaxbridge.prepare(approaches=args.approaches, out=args.out, name=args.name, overwrite=args.overwrite,
                                     sweep=args.sweep, max_memory=args.max_memory, settings=args.set, **options, **given)
        if distributed.is_primary():  # stdout, as the closing summary: stderr carries progress and errors
            print(training.describe(), flush=True)
    try:
        experiment = run_watched(lambda: training.run(interrupts.stop, interrupts.trained, debug=args.debug))
    except jaxbridge.NumericalFault as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_NUMERICAL
    except jaxbridge.Interrupted as err:
        print(f"{err}; continue with: python train.py --resume {training.run_dir}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except jaxbridge.WriteError as err:
        if args.debug:
            raise
        held = training.last_checkpoints()
        print(f"error: {err}; stopped, " + (f"the last complete checkpoints are {held}; once it can write, continue with: "
              f"python train.py --resume {training.run_dir}" if held else "before any checkpoint was complete"),
              file=sys.stderr, flush=True)
        os._exit(EXIT_CANNOT_WRITE)  # at once: orbax's unfinished writes would report at interpreter exit
    finally:
        interrupts.restore()
    if distributed.is_primary():  # process 0 reports for a multi-process run
        print(f"done in {time.perf_counter() - start:.0f} s -> {training.run_dir}/"
              + ("  (figure: curves.png, tables: results.md)" if training.is_experiment else ""))
        print(experiment.report())
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
