"""Experiments: several approaches trained on the same env and seeds, one run directory each, then
compared (the paper's figure and tables).

The approaches run concurrently in worker threads (a jitted cycle releases the GIL), which split the
devices between them; one progress bar counts every cycle. Neither changes any number
(docs/DESIGN.md, Host loop; docs/PERFORMANCE.md for the times).
"""
from __future__ import annotations

import dataclasses
import json
import queue
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from pathlib import Path


from envs_jax import env_class
from jaxbridge.core.config import TrainConfig
from jaxbridge.learn.approaches import get_approach
from jaxbridge.learn.devices import default_workers, split_devices
from jaxbridge.learn.setup import make_setup
from jaxbridge.run import checkpoint, comparison, rundir
from jaxbridge.run.runner import Interrupted, train
from jaxbridge.utils.files import WriteError, write_atomic
from jaxbridge.utils.progress import cycle_progress

EXPERIMENT_FILE = "experiment.json"
# Seconds per approach in `python -m bench.approaches` (Light Switch Door, 8 seeds, 2 at a time): the
# longest start first, so the workers finish close together.
COST = {"maple_q": 200, "no_feature_selection": 172, "no_callplanner": 172, "ours": 111, "random": 20,
        "pure_planning": 15}


def is_experiment_dir(path: Path) -> bool:
    return (path / EXPERIMENT_FILE).is_file()


def load_experiment(experiment_dir: Path) -> tuple[TrainConfig, list[str]]:
    """The base config and approach list of an experiment directory."""
    try:
        data = json.loads((experiment_dir / EXPERIMENT_FILE).read_text())
        return TrainConfig.from_dict(data["config"]), list(data["approaches"])
    except (OSError, KeyError, TypeError, json.JSONDecodeError) as err:
        raise ValueError(f"{experiment_dir / EXPERIMENT_FILE} is not a valid experiment file: {err}") from None


def check_resumable(experiment_dir: Path, approaches: list[str]) -> None:
    """Refuse (CheckpointError) to resume an experiment an approach of which has results but no checkpoint
    left: resuming would silently train it again from scratch."""
    for name in approaches:
        run_dir = experiment_dir / name
        if (run_dir / "metrics.csv").is_file() and not checkpoint.sealed_steps(run_dir / "checkpoints"):
            raise checkpoint.CheckpointError(f"{run_dir} has results but no complete checkpoint to resume from; "
                                             f"start the experiment over with --overwrite")


def train_approaches(config: TrainConfig, approaches: list[str], experiment_dir: Path, progress: bool = True,
                     resume: bool = False, workers: int | None = None, devices: list | None = None,
                     replaced: Path | None = None, stop: threading.Event | None = None,
                     trained: threading.Event | None = None, tensorboard: bool = False) -> dict[str, dict]:
    """Train every approach (run directory `experiment_dir/<approach>`), `workers` at a time, then write
    the comparison files (figure, results.md, results.csv), also after a fault or Ctrl-C for the
    approaches that have files. With `resume`, finished approaches are kept, started ones continue
    from their checkpoint and the others start. `replaced`: the run this one replaces, moved aside, deleted
    once this one's experiment file is written. `stop` (set by another thread) stops every approach after
    its current cycle, checkpointed; `trained` is set after any cycle completes; `tensorboard`: event files
    per approach (run/tensorboard.py). Returns each approach's summary, in list order."""
    if resume:
        check_resumable(experiment_dir, approaches)
    else:
        write_atomic(experiment_dir / EXPERIMENT_FILE, json.dumps(
            {"config": config.to_dict(), "approaches": approaches}, indent=2) + "\n")
        rundir.discard(replaced)
    workers = workers or default_workers(approaches)
    env_cls = env_class(config.env)  # resolved once for every approach
    bar = cycle_progress(config.cycles * len(approaches), f"{config.env} x{config.num_seeds} seeds, "
                         f"{len(approaches)} approaches", progress)
    stop = stop or threading.Event()
    device_shares = queue.SimpleQueue()  # a worker takes a share of the devices per approach, then returns it
    for share in split_devices(devices, min(workers, len(approaches))):
        device_shares.put(share)

    def run(name: str) -> dict:
        if stop.is_set():  # interrupted before this approach's turn
            raise Interrupted(0)
        run_dir = experiment_dir / name
        started = (run_dir / "checkpoints").is_dir() and bool(checkpoint.sealed_steps(run_dir / "checkpoints"))
        if not started:
            rundir.fresh(run_dir)
        share = device_shares.get()
        try:
            return train(make_setup(dataclasses.replace(config, approach=name), env_cls), run_dir, resume=started,
                         bar=bar, stop=stop, devices=share, trained=trained, tensorboard=tensorboard)
        finally:
            device_shares.put(share)

    order, unwritable = sorted(approaches, key=lambda a: -COST.get(a, 0)), False
    try:
        with ThreadPoolExecutor(workers, thread_name_prefix="approach") as pool:
            futures = {name: pool.submit(run, name) for name in order}
            try:
                # Wake up now and then: the OS may deliver Ctrl-C's SIGINT to a worker thread, and Python
                # only runs the handler (raising KeyboardInterrupt here) when the main thread runs.
                pending = set(futures.values())
                while pending:
                    done, pending = wait(pending, timeout=0.2, return_when=FIRST_EXCEPTION)
                    if any(f.exception() is not None for f in done):
                        break
            except KeyboardInterrupt:
                pass
            stop.set()  # after Ctrl-C or a fault: every running approach checkpoints and stops
            wait(futures.values())
        errors = [f.exception() for f in futures.values() if f.exception() is not None]
        faults = [e for e in errors if not isinstance(e, Interrupted)]
        if faults:
            raise faults[0]
        if errors:
            cycles = ", ".join(f"{n} {futures[n].exception().cycle}" for n in approaches
                               if isinstance(futures[n].exception(), Interrupted))
            raise Interrupted(-1, f"interrupted; checkpoints saved ({cycles} cycles done)")
        return {name: futures[name].result() for name in approaches}
    except WriteError:
        unwritable = True
        raise
    finally:
        bar.close()
        done = [a for a in approaches if (experiment_dir / a / "metrics.csv").is_file()]
        if done and not unwritable:
            comparison.write_comparison(experiment_dir, config.env, [get_approach(a) for a in done])
