"""Progress on stderr: of slow host work (building tasks and plan tables) as plain lines, nothing for work
that ends within a few seconds; of training cycles as tqdm's bar in a terminal and as plain lines in a log."""
from __future__ import annotations

import sys
import threading
import time


class SlowWork:
    """`report(done, total)` after each item; prints "WHAT: done/total (s)" once `after` seconds have
    passed, then at most every `every` seconds, and at the end if it printed anything."""

    def __init__(self, what: str, after: float = 3.0, every: float = 5.0):
        self.what, self.after, self.every = what, after, every
        self.start, self.last = time.perf_counter(), None

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        due = now - self.start >= self.after if self.last is None else now - self.last >= self.every
        if due or (done == total and self.last is not None):
            print(f"{self.what}: {done}/{total} ({now - self.start:.0f} s)", file=sys.stderr, flush=True)
            self.last = now


class LogProgress:
    """tqdm's `update`/`set_postfix`/`close` as plain lines for a log file (stderr not a terminal): one
    line every `step` of the total or `every` seconds, whichever comes first, and one at the end:

        doorknobs x8 seeds, 6 approaches: 120/600 cycles (20%), 95 s, ETA 380 s; last=ours 20, test=0.95
    """

    def __init__(self, total: int, desc: str, initial: int = 0, step: float = 0.05, every: float = 30.0):
        self.total, self.desc, self.n, self.start_n = total, desc, initial, initial
        self.step, self.every, self.postfix = max(1, round(step * total)), every, ""
        self.start = self.last_time = time.perf_counter()
        self.last_n, self.lock = initial, threading.Lock()

    def set_postfix(self, **values) -> None:
        self.postfix = ", ".join(f"{k}={v}" for k, v in values.items())

    def update(self, n: int = 1) -> None:
        with self.lock:
            self.n += n
            now = time.perf_counter()
            if self.n - self.last_n >= self.step or now - self.last_time >= self.every or self.n >= self.total:
                self._line(now)

    def _line(self, now: float) -> None:
        elapsed, done = now - self.start, self.n - self.start_n
        eta = f", ETA {elapsed / done * (self.total - self.n):.0f} s" if 0 < done and self.n < self.total else ""
        print(f"{self.desc}: {self.n}/{self.total} cycles ({100 * self.n / max(1, self.total):.0f}%), "
              f"{elapsed:.0f} s{eta}{'; ' + self.postfix if self.postfix else ''}", file=sys.stderr, flush=True)
        self.last_n, self.last_time = self.n, now

    def close(self) -> None:
        pass


def cycle_progress(total: int, desc: str, enabled: bool = True, initial: int = 0):
    """A progress display over `total` cycles: tqdm's bar in a terminal, LogProgress lines otherwise
    (a log file would get every bar frame on one line), nothing when not `enabled`."""
    if enabled and not sys.stderr.isatty():
        return LogProgress(total, desc, initial)
    from tqdm import tqdm
    return tqdm(total=total, initial=initial, desc=desc, unit="cycle", disable=not enabled, dynamic_ncols=True)
