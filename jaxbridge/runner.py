"""The host side of training: the loop over cycles, progress display, run files and checkpoints."""
from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import jax
import numpy as np
from tqdm import tqdm

from jaxbridge import artifacts, checkpoint
from jaxbridge.config import TrainConfig
from jaxbridge.online import CycleMetrics, Experiment, build_experiment, init_learners, make_cycle


def prepare_run_dir(run_dir: Path, overwrite: bool) -> None:
    """Create the run directory; refuse to touch an existing non-empty one unless asked to."""
    if run_dir.exists() and any(run_dir.iterdir()):
        if not overwrite:
            raise FileExistsError(f"run directory {run_dir} already exists (pass --overwrite to replace it)")
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)


def train(config: TrainConfig, run_dir: Path, progress: bool = True, log=print) -> dict:
    """Run every cycle of `config`, writing the run files and checkpoints into `run_dir`."""
    start = time.perf_counter()
    experiment = build_experiment(config)
    learners = init_learners(experiment)
    cycle = make_cycle(experiment)
    artifacts.write_atomic(run_dir / "config.json", json.dumps(config.to_dict(), indent=2) + "\n")
    history: list[CycleMetrics] = []
    bar = tqdm(total=config.cycles, desc=f"{config.env} x{config.num_seeds} seeds", unit="cycle",
               disable=not progress, dynamic_ncols=True)
    for c in range(1, config.cycles + 1):
        learners, metrics = cycle(learners)
        metrics = jax.tree.map(np.asarray, metrics)
        history.append(metrics)
        bar.set_postfix(test=f"{metrics.test_solve_rate.mean():.2f}", train=f"{metrics.train_success_rate.mean():.2f}",
                        eps=f"{metrics.epsilon.mean():.2f}")
        bar.update()
        if c % config.checkpoint_every == 0 or c == config.cycles:
            checkpoint.save(run_dir / "checkpoints", c, learners, {"cycle": c, "config": config.to_dict()})
    bar.close()
    info = artifacts.write_run_files(run_dir, config.to_dict(), history, config.seeds,
                                     time.perf_counter() - start)
    return info


def load_learners(run_dir: Path) -> tuple[TrainConfig, Experiment, object, int]:
    """Rebuild a run's experiment and restore its latest learner state."""
    config = TrainConfig.from_dict(json.loads((run_dir / "config.json").read_text()))
    experiment = build_experiment(config)
    learners, record, step = checkpoint.restore(run_dir / "checkpoints", init_learners(experiment))
    return config, experiment, learners, step
