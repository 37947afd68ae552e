"""Whether a change kept every approach's program: one cycle's (with the host planner) and make_train's, as
jaxprs, at two commits, compared as text. Equal programs on equal inputs give equal numbers, so a change
that keeps them kept every metric, with no training run (bench.timings.identical trains and compares).

    python -m bench.timings.same_program --base ec894a8 [--env light_switch_door]

Each commit is checked out into its own worktree, where a child process traces every approach the commit
knows (but the low-level baselines, which brax trains, and those make_train refuses) on a tiny config of
each env; prints, per env and approach, "same program" or "differs" (with the first differing line), and
exits 1 if any differs. Approaches only one commit knows are listed apart.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import jaxbridge
from bench.command import CommandParser
from bench.timings.ab import checked_out
from bench.timings.identical import first_difference

# Run in each worktree (its own code first on the path): {"env approach": [cycle jaxpr, make_train jaxpr]}.
TRACE = """
import json, sys
sys.path.insert(0, ".")
import jax, jaxbridge
from jaxbridge.learn.approaches import KNOWN
from jaxbridge.learn.online import Cycle, make_train
from jaxbridge.learn.setup import make_setup

out = {}
for env in sys.argv[2].split(","):
    for name, approach in KNOWN.items():
        if approach.low_level or getattr(approach, "repairs_model", False):
            continue
        config = jaxbridge.make_config(env, approach=name, num_seeds=1, episodes_per_cycle=2, num_test_tasks=2,
                                       updates_per_cycle=2, cycles=2)
        setup = make_setup(config)
        cycle = Cycle(setup)
        out[f"{env} {name}"] = [str(jax.make_jaxpr(lambda learners: cycle.run(learners, True))(setup.init_learners())),
                                str(jax.make_jaxpr(make_train(setup))())]
open(sys.argv[1], "w").write(json.dumps(out))
"""


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--base", required=True, help="commit A (the reference)")
    parser.add_argument("--head", default="HEAD", help="commit B (default: %(default)s)")
    parser.add_argument("--env", default=",".join(jaxbridge.env_names()),
                        help="the envs to trace, comma-separated (default: every registered env)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="jaxbridge-same-program-") as tmp, \
            checked_out({"A": args.base, "B": args.head}, Path(tmp)) as trees:
        programs = {}
        for side, tree in trees.items():
            dump = Path(tmp) / f"{side}.json"
            subprocess.run([sys.executable, "-c", TRACE, str(dump), args.env], cwd=tree, check=True)
            programs[side] = json.loads(dump.read_text())
    a, b = programs["A"], programs["B"]
    differ = 0
    for key in sorted(a.keys() & b.keys()):
        changed = [(x, y) for x, y in zip(a[key], b[key]) if x != y]
        differ += bool(changed)
        print(f"{key}: " + (f"differs ({first_difference(*changed[0])})" if changed else "same program"))
    for side, only in (("base", a.keys() - b.keys()), ("head", b.keys() - a.keys())):
        if only:
            print(f"only at {side}: {', '.join(sorted(only))}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
