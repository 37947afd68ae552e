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

    def __init__(self, total: int, desc: str, initial: int = 0, step: float = 0.05, every: float = 30.0, eta=None):
        self.total, self.desc, self.n, self.start_n, self.eta = total, desc, initial, initial, eta
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
        left = (self.eta() if self.eta else elapsed / done * (self.total - self.n) if done else None)
        eta = f", ETA {left:.0f} s" if left is not None and self.n < self.total else ""
        print(f"{self.desc}: {self.n}/{self.total} cycles ({100 * self.n / max(1, self.total):.0f}%), "
              f"{elapsed:.0f} s{eta}{'; ' + self.postfix if self.postfix else ''}", file=sys.stderr, flush=True)
        self.last_n, self.last_time = self.n, now

    def close(self) -> None:
        pass


def cycle_progress(total: int, desc: str, enabled: bool = True, initial: int = 0, eta=None):
    """A progress display over `total` cycles: tqdm's bar in a terminal, LogProgress lines otherwise
    (a log file would get every bar frame on one line), nothing when not `enabled`. `eta()`: the
    seconds left, where the caller knows better than the overall rate (shown in tqdm's postfix)."""
    if enabled and not sys.stderr.isatty():
        return LogProgress(total, desc, initial, eta=eta)
    from tqdm import tqdm
    own_eta = {} if eta is None else {"bar_format": "{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]"}
    return tqdm(total=total, initial=initial, desc=desc, unit="cycle", disable=not enabled, dynamic_ncols=True, **own_eta)


class ExperimentProgress:
    """One display for an experiment's programs, each updating it through `for_program(name)`, with the
    time left from each program's own pace (its recent seconds per cycle, the first, compiling cycle
    left out): the programs' seconds left shared by the `workers`, and at least the longest one's."""

    def __init__(self, cycles: dict[str, int], desc: str, workers: int, enabled: bool = True):
        self.left, self.workers, self.times = dict(cycles), workers, {name: [] for name in cycles}
        self.lock = threading.Lock()
        self.display = cycle_progress(sum(cycles.values()), desc, enabled, eta=self.eta)

    def for_program(self, name: str) -> "ProgramProgress":
        return ProgramProgress(self, name)

    def advance(self, name: str, n: int) -> None:
        """`n` cycles of program `name` done: one just trained, or more at once (restored, or finished before)."""
        with self.lock:
            self.left[name] -= n
            if n == 1:  # the first stamp ends the compiling cycle: the gaps after it are the pace
                self.times[name] = (self.times[name] + [time.perf_counter()])[-10:]
        self.display.update(n)

    def pace(self, name: str) -> float | None:
        times = self.times[name]
        return (times[-1] - times[0]) / (len(times) - 1) if len(times) >= 2 else None

    def eta(self) -> float | None:
        with self.lock:
            paces = {name: self.pace(name) for name in self.left}
            known = [p for p in paces.values() if p is not None]
            if not known:
                return None
            left = {name: n * (paces[name] if paces[name] is not None else sum(known) / len(known))
                    for name, n in self.left.items()}
        return max(max(left.values()), sum(left.values()) / self.workers)

    def set_postfix(self, **values) -> None:
        left = self.eta()
        self.display.set_postfix(**values, **({} if left is None or isinstance(self.display, LogProgress)
                                              else {"eta": f"{left:.0f}s"}))

    def close(self) -> None:
        self.display.close()


class ProgramProgress:
    """The display as one program of an experiment sees it (tqdm's update / set_postfix / close)."""

    def __init__(self, shared: ExperimentProgress, name: str):
        self.shared, self.name = shared, name

    def update(self, n: int = 1) -> None:
        if n:
            self.shared.advance(self.name, n)

    def set_postfix(self, **values) -> None:
        self.shared.set_postfix(**values)

    def close(self) -> None:
        pass
