"""Ctrl-C for train.py, as requests rather than exceptions: an exception raised wherever the main thread
happens to be (inside XLA, inside orbax's threads) could tear a save apart or abort the process.

* The first Ctrl-C asks every run to stop after its current cycle and checkpoint it; during start-up
  and compilation, before any cycle of this process has finished, it exits at once (nothing to save).
* A second one is acknowledged and waits: the checkpoint being written is finished.
* A third exits at once. A checkpoint cut short has no manifest and is skipped on resume, and every run
  file is written atomically, so nothing on disk is left half-written.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Callable

EXIT_INTERRUPTED = 130


class Interrupts:
    """Installs the SIGINT handler; `stop` is what the runs watch, `trained` what they set after a cycle."""

    def __init__(self, on_exit: Callable[[], None] = lambda: None):
        self.stop, self.trained = threading.Event(), threading.Event()
        self.presses, self._on_exit = 0, on_exit
        self._previous = signal.signal(signal.SIGINT, self._handle)

    def _handle(self, signum, frame) -> None:
        self.presses += 1
        if not self.trained.is_set():
            self._exit("interrupted during start-up: nothing was trained in this run, nothing was saved")
        elif self.presses == 1:
            self.stop.set()
            print("\nCtrl-C: stopping after the current cycle and saving its checkpoint "
                  "(Ctrl-C twice more quits at once)", file=sys.stderr, flush=True)
        elif self.presses == 2:
            print("\nCtrl-C: still finishing the checkpoint, please wait (once more quits at once; "
                  "the last complete checkpoint stays)", file=sys.stderr, flush=True)
        else:
            self._exit("interrupted: quit at once; resume from the last complete checkpoint")

    def _exit(self, message: str) -> None:
        print(f"\n{message}", file=sys.stderr, flush=True)
        self._on_exit()
        os._exit(EXIT_INTERRUPTED)  # no unwinding through XLA's or orbax's threads

    def restore(self) -> None:
        signal.signal(signal.SIGINT, self._previous)


def run_watched(work: Callable[[], object]) -> object:
    """`work()` in a worker thread while the main thread stays free for the signal handler (a long XLA
    call in the main thread would hold a Ctrl-C until it returns); its result, or its exception."""
    outcome: dict = {}

    def target():
        try:
            outcome["value"] = work()
        except BaseException as err:  # noqa: BLE001 -- re-raised in the main thread below
            outcome["error"] = err

    thread = threading.Thread(target=target, name="train", daemon=True)
    thread.start()
    while thread.is_alive():
        thread.join(0.2)
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]
