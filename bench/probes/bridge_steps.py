"""Where the greedy bridge spends the test horizon: train seeds with config overrides (as bench.probes.sweep)
and, at each cycle of --at, print per seed its test solve rate, the env steps its bridge's skills take
per test task (not the planner's), and its greedy decisions on the seed's first test task. The
evidence of Coffee's diagnosis (docs/TUNING.md): the twist's parameter sets how many steps it takes,
and the 4-cup test tasks have few to spare.

    python -m bench.probes.bridge_steps --env coffee --seeds 0-31 --cycles 100 --at 25,50
"""
from __future__ import annotations

import numpy as np

from bench.probes.decisions import greedy_test_rollout
from bench.probes.sweep import swept_config
from bench.timings.training import overrides_parser
from envs_jax.base import ACTOR_BRIDGE
from jaxbridge.learn.devices import SeedMesh, select_devices
from jaxbridge.learn.online import Cycle
from jaxbridge.learn.setup import make_setup


def describe(env, skills: np.ndarray, params: np.ndarray) -> str:
    """A decision sequence as `Skill(p)`, the parameter only for skills that take one."""
    specs = env.skills
    names = [s.name for s in specs] + ["CallPlanner"]
    shown = [names[k] + (f"({p:+.2f})" if k < len(specs) and specs[k].param_low < specs[k].param_high else "")
             for k, p in zip(skills, params)]
    return " ".join(shown)


def report(setup, learners, config, cycle: int) -> None:
    result, records = greedy_test_rollout(setup, learners, config.num_seeds, config.num_test_tasks)
    tests = config.num_test_tasks
    success = np.asarray(result.success).reshape(config.num_seeds, tests)
    bridge = np.asarray(records.live & (records.actor == ACTOR_BRIDGE)).sum(0).reshape(config.num_seeds, tests)
    decided = np.asarray(records.decided & records.live)
    skill, param = np.asarray(records.skill), np.asarray(records.param)
    print(f"cycle {cycle}: mean test solve rate {success.mean():.3f}, bridge steps per task {bridge.mean():.2f}")
    for s, seed in enumerate(config.seeds):
        first = s * tests
        at = np.flatnonzero(decided[:, first])
        print(f"  seed {seed:>3}: solved {success[s].mean():.1f}, bridge steps {bridge[s].mean():5.2f}; "
              f"task 0: {describe(setup.test_env, skill[at, first], param[at, first])}")


def main() -> None:
    parser = overrides_parser(__spec__.name, __doc__, "coffee", "0-31", 100)
    parser.add_argument("--at", default="25,50", help="cycles to report at before the last (--cycles), "
                        "comma-separated (default: %(default)s)")
    args = parser.parse_args()
    try:
        at = sorted({int(c) for c in args.at.split(",") if c} | {args.cycles})
    except ValueError:
        parser.error(f"--at takes cycle numbers, e.g. 25,50; got {args.at!r}")
    if at[0] < 1 or at[-1] > args.cycles:
        parser.error(f"--at cycles must lie in 1..{args.cycles} (--cycles)")
    config, changes = swept_config(args)
    print(f"{config.env}, seeds {config.seeds[0]}-{config.seeds[-1]}, overrides {changes or 'none'}")
    setup = make_setup(config)
    seeds = SeedMesh(config.num_seeds, tuple(select_devices()), config.seed_block)
    learners, cycle = seeds.place(setup.init_learners()), Cycle(setup, seeds)
    for c in range(1, at[-1] + 1):
        learners, _ = cycle(learners)
        if c in at:
            report(setup, seeds.unpad(learners), config, c)


if __name__ == "__main__":
    main()
