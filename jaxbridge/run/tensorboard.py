"""`train.py --tensorboard`: a run's per-cycle statistics as TensorBoard event files (tensorboardX), written
as the cycles complete, into `<run>/events/` (`tensorboard --logdir <experiment>` shows one run per
approach). metrics.csv stays the source of truth; these are for watching.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from jaxbridge.utils import stats

EVENTS_DIR = "events"
# Over seeds, per cycle: the solve rates with their mean, 95% interval and IQM; the rest as means.
RATES = {"test_solve_rate": "test/solve_rate", "train_success_rate": "train/success_rate"}
MEANS = {"loss": "learn/loss", "q_abs_max": "learn/q_abs_max", "epsilon": "learn/epsilon",
         "buffer_size": "learn/buffer_size", "train_decisions": "train/bridge_decisions"}


class CycleEvents:
    """The event file of one run; `cycle(c, metrics)` after each completed cycle, `close()` at the end."""

    def __init__(self, run_dir: Path, config: dict):
        from tensorboardX import SummaryWriter  # only when asked for: it loads protobuf

        self.writer = SummaryWriter(str(run_dir / EVENTS_DIR))
        self.writer.add_text("config", "```\n" + json.dumps(config, indent=2) + "\n```", 0)

    def cycle(self, cycle: int, metrics) -> None:
        """Log a completed cycle's CycleMetrics (numpy, one entry per seed) at step `cycle`."""
        for field, tag in RATES.items():
            described = stats.describe(np.asarray(getattr(metrics, field), np.float64)[:, None])
            for key in ("mean", "mean_low", "mean_high", "iqm"):
                self.writer.add_scalar(f"{tag}/{key}", float(described[key][0]), cycle)
        for field, tag in MEANS.items():
            self.writer.add_scalar(tag, float(np.mean(getattr(metrics, field))), cycle)
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()
