"""What a training takes from its caller and reports back, passed down the layers as one value (the API,
the experiment, each program, the loop)."""
from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable


@dataclass(frozen=True)
class RunHooks:
    progress: bool = True
    """A progress display on stderr (a bar in a terminal, plain lines in a log)."""
    stop: threading.Event | None = None
    """Set from another thread (Ctrl-C, a caller): every run checkpoints after its current cycle and stops."""
    on_cycle: Callable[[], None] | None = None
    """Called after each completed cycle of any run."""
    tensorboard: bool = False
    """Also log each cycle to TensorBoard event files (run/tensorboard.py)."""
    devices: list | None = None
    """Shard the seeds over these devices (default: the first local device); an experiment splits them
    between its programs."""
    display: Any = None
    """A progress display shared with the experiment's other programs (set by the experiment); else the
    run's own."""
    widen: Callable[[Callable[[int], bool]], list] | None = None
    """After a cycle, more devices for the run (set by the experiment: run/scheduling.py)."""
