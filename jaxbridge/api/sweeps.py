"""The generalisation sweep from Python: trained bridges on tasks with 1, 2, ... novelty instances."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from jaxbridge.api.policies import Policy, run_directory, runs_in
from jaxbridge.learn.approaches import KNOWN
from jaxbridge.run.comparison import run_labels
from jaxbridge.run.sweep import SweepResult, evaluate_sweep, sweep_csv, sweep_markdown
from jaxbridge.viz.figures import plot_sweep
from jaxbridge.utils.errors import InputError, refusing
from jaxbridge.utils.files import write_atomic

SWEEP_TASKS = 10  # tasks per count, met by every seed


@dataclass(frozen=True)
class NoveltySweep:
    """What `sweep_novelties` returns: solve rates per line, seed and count, and their table and figure."""

    result: SweepResult  # .solve_rate[label]: float[seeds, counts] (NaN where the line cannot see the tasks)
    cycles: str  # the checkpoints' cycles, e.g. "cycle 100"

    @property
    def title(self) -> str:
        r = self.result
        return (f"{r.env}: greedy bridges ({self.cycles}) on {r.tasks_per_count} tasks per count, "
                f"{r.counted} 1..{max(r.counts)}")

    def markdown(self) -> str:
        """Solve rate per count (rows) and line (columns): mean [95% bootstrap CI] over seeds, and why a
        line is n/a where one is."""
        unseen = [label for label, rate in self.result.solve_rate.items() if np.isnan(rate).any()]
        note = (f"\nn/a ({', '.join(unseen)}): the full state an approach sees is sized to the largest test task; "
                f"larger tasks do not fit its input.\n" if unseen else "")
        return sweep_markdown(self.result) + note

    def write(self, out_dir: str | Path) -> Path:
        """sweep_novelties.png, .md and .csv into `out_dir`; the PNG's path."""
        out = Path(out_dir)
        try:
            write_atomic(out / "sweep_novelties.png", plot_sweep(self.result, self.title))
            write_atomic(out / "sweep_novelties.md", f"# {self.title}\n\nTest solve rate, mean [95% bootstrap CI] "
                         "over seeds (each seed's: the .csv).\n\n" + self.markdown())
            write_atomic(out / "sweep_novelties.csv", sweep_csv(self.result))
        except OSError as err:
            raise InputError(f"cannot write to {out}: {err.strerror or err}") from None
        return out / "sweep_novelties.png"


def sweep_lines(runs: list[str | Path], approach: str | None = None) -> dict[str, Path]:
    """The sweep's lines {label: run directory}: every run of a lone experiment directory (unless
    `approach` picks one), else one line per run given."""
    runs = [Path(r) for r in runs]
    if len(runs) == 1 and approach is None and (runs[0] / "experiment.json").is_file():
        held = runs_in(runs[0])
        if not held:
            raise InputError(f"{runs[0]} holds no runs yet")
        order = [name for a in KNOWN for name in held if name.partition("@")[0] == a]  # with sweeps' settings
        return {label: runs[0] / name for name, label in run_labels(order).items()}
    return {str(given): run_directory(given, approach) for given in runs}


def sweep_novelties(lines: Mapping[str, str | Path | Policy], tasks_per_count: int = SWEEP_TASKS,
                    sweep_seed: int = 0, rollout_seed: int = 0, progress: Callable[[str], None] = lambda label: None,
                    planner_alone: bool = False, max_memory: float | None = None) -> NoveltySweep:
    """Each line's policy (a Policy or a run directory) greedily on the env's sweep tasks: for each count of
    novelty instances (`env.novelty_sweep`), `tasks_per_count` tasks drawn from `sweep_seed`, the same for
    every seed and line; with `planner_alone`, each repair run's learned planner with no bridge
    (`Policy.alone`), its seeds in groups that fit `max_memory` GiB (default: what is available).
    `progress(label)` is called as each line starts."""
    policies = {label: p if isinstance(p, Policy) else Policy(p) for label, p in lines.items()}
    if planner_alone:
        policies = {label: p.alone() for label, p in policies.items()}
    with refusing():  # runs of several envs, an env without a sweep
        result = evaluate_sweep({label: p.trained for label, p in policies.items()}, tasks_per_count, sweep_seed,
                                rollout_seed, progress, None if max_memory is None else int(max_memory * 2**30))
    return NoveltySweep(result, ", ".join(sorted({f"cycle {p.cycle}" for p in policies.values()})))
