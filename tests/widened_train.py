"""tests/test_devices.py's short run (train.py SHORT), started on one device and widened onto a second
after its first cycle, into OUT/ours. Its own process: 2 virtual CPU devices must be set before JAX starts.

    python tests/widened_train.py OUT
"""
import jaxbridge
import sys
from pathlib import Path

import jax

from jaxbridge.learn.setup import make_setup
from jaxbridge.run.hooks import RunHooks
from jaxbridge.run.runner import train_settings

if __name__ == "__main__":
    jax.config.update("jax_num_cpu_devices", 2)
    out, (first, second) = Path(sys.argv[1]), jax.local_devices()
    config = jaxbridge.make_config("light_switch_door", num_seeds=3, cycles=3, updates_per_cycle=20, checkpoint_every=1)
    offered = []

    def widen(wanted):  # the second device, once, whatever the timing says
        offered.append(wanted(1))
        return [second] if len(offered) == 1 else []

    (out / "ours").mkdir(parents=True)
    train_settings(make_setup(config), [(config, out / "ours")], RunHooks(progress=False, devices=[first], widen=widen))
    print(len(offered), isinstance(offered[0], bool))
