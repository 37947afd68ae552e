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


class CycleTimes:
    """A program's cycle seconds, for `worth_widening`: its first since it compiled, and its last. The
    last counts only once it ran whole with the spare devices idle: on a CPU a one-device
    program's threads spread onto idle cores, so a cycle timed while another program held them would
    overstate what widening saves."""

    def __init__(self):
        self.first_s = self.last_s = None
        self.spare_seen = False  # spare devices were offered; the next cycle is timed with them idle

    def timed(self, seconds: float) -> None:
        self.last_s = seconds
        if self.first_s is None:
            self.first_s = seconds

    def worth_widening(self, per_device: int, per_device_wider: int, cycles_left: int) -> bool:
        """No when the spare devices are offered for the first time (the cycle just timed shared them);
        after that, `worth_widening` with the last cycle's seconds and the first's excess as the compile."""
        if not self.spare_seen:
            self.spare_seen = True
            return False
        compile_s = max(self.first_s - self.last_s, 0.0)
        return worth_widening(per_device, per_device_wider, cycles_left, self.last_s, compile_s)

    def recompiled(self) -> None:
        self.first_s, self.spare_seen = None, False


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
