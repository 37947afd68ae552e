"""How tests/data/v11_run was made, with the code of commit cd8db1a (config version 11): a light_switch_door run
of ours, 1 seed, 2 cycles, stopped before cycle 2 (its checkpoint of cycle 1 and metrics of cycle 1 kept; its curves.png removed to keep it small).

    python tests/data/make_v11_run.py tests/data/v11_run   # in a checkout of cd8db1a
"""
import jaxbridge
import sys
from pathlib import Path

from jaxbridge.learn.setup import make_setup
from jaxbridge.run import rundir
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import train


class Stop(Exception):
    pass


def stop(cycle, learners):
    if cycle == 2:
        raise Stop
    return learners


out = Path(sys.argv[1])
config = jaxbridge.make_config("light_switch_door", num_seeds=1, cycles=2, episodes_per_cycle=2, num_test_tasks=2,
                             updates_per_cycle=10, buffer_capacity=256, checkpoint_every=1)
rundir.prepare(out, overwrite=False)
try:
    train(make_setup(config), out, RunHooks(progress=False), fault_injection=stop)
except Stop:
    pass
