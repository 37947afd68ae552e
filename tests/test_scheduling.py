"""The experiment's devices: programs take shares of them, a running program takes the spare ones once
no program waits and they pay for their compile (run/scheduling.py). That a widened program's numbers
are those of one device: tests/test_devices.py."""
from jaxbridge.run.scheduling import CycleTimes, DevicePool, worth_widening


class Device:
    def __init__(self, i):
        self.platform, self.id = "cpu", i


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_spare_shares_go_to_a_running_program_only_once_none_waits():
    a, b, clock = Device(0), Device(1), Clock()
    pool = DevicePool([[a], [b]], programs=3, clock=clock)
    first, second = pool.take(), pool.take()
    assert (first, second) == ([[a]], [[b]])
    clock.now = 10.0
    pool.give_back(first)  # the third program has not started: the share is kept for it
    assert pool.spare(lambda count: True) == []
    third = pool.take()
    clock.now = 15.0
    pool.give_back(second)
    asked = []
    assert pool.spare(lambda count: asked.append(count) or False) == [] and asked == [1]  # not worth it: kept
    assert pool.spare(lambda count: True) == [[b]]
    assert pool.spare(lambda count: True) == []  # taken
    clock.now = 20.0
    pool.give_back(third + [[b]])
    assert pool.record() == {"wall_s": 20.0, "busy_s": {"cpu:0": 20.0, "cpu:1": 20.0}}


def test_no_spare_for_the_default_device():
    pool = DevicePool([None, None], programs=1)
    pool.give_back(pool.take())
    assert pool.spare(lambda count: True) == []


def test_more_devices_are_taken_when_the_cycles_left_pay_for_the_compile():
    assert worth_widening(8, 4, cycles_left=50, cycle_s=3.0, compile_s=20.0)  # saves 75 s, costs 40
    assert not worth_widening(8, 4, cycles_left=5, cycle_s=3.0, compile_s=20.0)  # saves 7.5 s
    assert not worth_widening(1, 1, cycles_left=99, cycle_s=9.0, compile_s=0.0)  # one seed: nothing to share
    assert worth_widening(3, 2, cycles_left=10, cycle_s=3.0, compile_s=1.0)  # 3 seeds on 2 devices: 2 each


def test_widening_is_judged_by_a_cycle_run_with_the_spare_devices_idle():
    times = CycleTimes()
    times.timed(15.0)  # compiles
    times.timed(0.5)  # shared the cores with another program: would save 25 s over 100 cycles
    assert not times.worth_widening(8, 4, cycles_left=100)  # offered for the first time: time one more
    times.timed(0.06)  # alone: saves 3 s, while compiling again costs about 15
    assert not times.worth_widening(8, 4, cycles_left=99)
    times.timed(0.6)
    assert times.worth_widening(8, 4, cycles_left=98)  # saves 29 s
    times.recompiled()  # widened: its next cycle compiles, and new spares are timed again before judging
    times.timed(14.0)
    times.timed(0.3)
    assert not times.worth_widening(4, 2, cycles_left=96)
