"""Progress of slow host work (building tasks and plan tables) as plain lines on stderr: nothing for work
that ends within a few seconds, then a line every few seconds, which reads the same in a terminal and a log."""
from __future__ import annotations

import sys
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
