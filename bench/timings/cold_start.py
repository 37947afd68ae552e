"""What a second process saves through JAX's persistent compilation cache: the same short run twice,
each in a fresh process, into one cache directory that starts empty.

    python -m bench.timings.cold_start [--env light_switch_door] [--approach ours] [--seeds 0-7]

Prints, per process: the first cycle's seconds (mostly compilation), the programs XLA built and how
many of them came from the cache, and their compile seconds.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile

from bench.command import CommandParser

CHILD = """
import json, sys
from jaxbridge.utils import compile_cache
compile_cache.enable(sys.argv[1])
from bench.records import seed_list
from bench.timings.training import measure_cycles
import jaxbridge
config = jaxbridge.make_config(sys.argv[2], approach=sys.argv[3], seeds=seed_list(sys.argv[4]), cycles=2)
run = measure_cycles(config, jaxbridge.local_devices(), 2)
print(json.dumps({"first_cycle_s": run["times"][0], **run["first"].as_dict()}))
"""


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="light_switch_door", seeds="0-7")
    parser.add_argument("--approach", default="ours", help="approach (default: %(default)s)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        for process in ("first", "second"):
            out = subprocess.run([sys.executable, "-c", CHILD, cache, args.env, args.approach, args.seeds],
                                 capture_output=True, text=True, check=True).stdout
            r = json.loads(out.strip().splitlines()[-1])
            print(f"{process} process: first cycle {r['first_cycle_s']:.1f} s; {r['compiles']} programs "
                  f"({r['cache_hits']} from the cache), {r['compile_s']:.1f} s compiling", flush=True)


if __name__ == "__main__":
    main()
