"""Which devices an experiment's programs train on. Programs start on a share of the devices each, the
costliest first; once no program waits for a share, a running program takes the shares the finished
ones gave back at its next cycle boundary (`DevicePool.spare`), when the cycles it has left save more
than the recompile costs (`worth_widening`). The per-seed program is the same on any number of devices
(learn/devices.py), so where a seed ran changes none of its numbers, only the wall time; the learned
selector's is not yet, so its programs are never widened (run/experiments.py)."""
from __future__ import annotations

import threading
import time


def worth_widening(per_device: int, per_device_wider: int, cycles_left: int, cycle_s: float, compile_s: float) -> bool:
    """Whether a program should shard its seeds over more devices, `per_device` seeds one after another on
    each before and `per_device_wider` after: the seconds its cycles left save exceed twice its compile
    seconds (the wider program compiles again, with every device it holds waiting)."""
    saved = cycles_left * cycle_s * (1 - per_device_wider / per_device)
    return per_device_wider < per_device and saved > 2 * compile_s


class DevicePool:
    """The shares of the devices that an experiment's `programs` train on: `take` one to start (waiting
    for one to come back if none is free), `give_back` them at the end; `spare` hands the free shares to
    a running program once no program is left to start. Counts each device's busy seconds."""

    def __init__(self, shares: list, programs: int, clock=time.perf_counter):
        self._free, self._waiting, self._clock = list(shares), programs, clock
        self._changed = threading.Condition()
        self._start, self._since = clock(), {}
        self.busy_s = {_name(d): 0.0 for share in shares for d in share or []}

    def take(self) -> list:
        """A share for a program about to start: [share]."""
        with self._changed:
            self._changed.wait_for(lambda: self._free)
            self._waiting -= 1
            return self._lease([self._free.pop(0)])

    def spare(self, wanted) -> list:
        """The free shares, if no program is left to start and `wanted(their device count)` says yes;
        else []."""
        with self._changed:
            count = sum(len(share or []) for share in self._free)
            if self._waiting or not count or None in self._free or not wanted(count):
                return []
            taken, self._free = self._free, []
            return self._lease(taken)

    def give_back(self, shares: list) -> None:
        with self._changed:
            now = self._clock()
            for d in (d for share in shares for d in share or []):
                self.busy_s[_name(d)] += now - self._since.pop(_name(d))
            self._free.extend(shares)
            self._changed.notify_all()

    def _lease(self, shares: list) -> list:
        now = self._clock()
        self._since.update({_name(d): now for share in shares for d in share or []})
        return shares

    def record(self) -> dict:
        """The wall seconds so far and each device's busy seconds (for the experiment's schedule.json)."""
        return {"wall_s": round(self._clock() - self._start, 1),
                "busy_s": {name: round(s, 1) for name, s in self.busy_s.items()}}


def _name(device) -> str:
    return f"{device.platform}:{device.id}"
