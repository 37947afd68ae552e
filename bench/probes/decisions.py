"""Why a trained bridge fails: train seeds with config overrides (as bench.probes.sweep), then print the greedy
bridge's decisions on the test tasks it does not solve (step, skill, parameter, features, applicable
actions, Q of the pick and of CallPlanner) and the cycle's test solve rates.

    python -m bench.probes.decisions --env coffee --seeds 0-7 --cycles 40 updates_per_cycle=250
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from bench.probes.sweep import print_digits, swept_config, train_seeds
from bench.timings.training import overrides_parser
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.learn.q_bridge import encode


def greedy_test_rollout(setup, learners, num_seeds: int, num_tests: int):
    """Every seed's greedy bridge on its test tasks, recorded: (EpisodeResult, StepRecord [T, episodes]);
    episode i is seed i // num_tests's task i % num_tests."""
    owner = np.repeat(np.arange(num_seeds), num_tests)
    greedy = setup.episode_params(learners, owner, jnp.zeros(len(owner), jnp.float32))
    keys = jax.random.split(jax.random.key(123), len(owner))
    env = setup.test_env
    return rollout(MetaPolicy(env, setup.bridge(env), greedy, setup.controls), setup.test.arrays, keys,
                   setup.test.max_steps, record=True)


def main() -> None:
    parser = overrides_parser(__spec__.name, __doc__, "coffee", "0-7", 40)
    parser.add_argument("--max-failed", type=int, default=3, help="failed tasks printed per seed")
    parser.add_argument("--max-decisions", type=int, default=12, help="decisions printed per failed task")
    args = parser.parse_args()
    config, _ = swept_config(args)
    setup, learners, rates = train_seeds(config)
    print_digits(config.seeds, rates)

    test, env, net = setup.test, setup.test_env, setup.learner.net
    result, records = greedy_test_rollout(setup, learners, config.num_seeds, config.num_test_tasks)
    names = env.skill_names + ("CallPlanner",)
    success = np.asarray(result.success)
    decided = np.asarray(records.decided & records.live)
    print(f"final greedy test solve rate per seed: {success.reshape(config.num_seeds, -1).mean(1).tolist()}")
    for s in range(config.num_seeds):
        failed = [i for i in range(s * config.num_test_tasks, (s + 1) * config.num_test_tasks) if not success[i]]
        params = jax.tree.map(lambda x, s=s: x[s], learners.online)
        for i in failed[: args.max_failed]:
            steps = np.flatnonzero(decided[:, i])
            cups = f" ({len(test.specs[i].cups)} cups)" if hasattr(test.specs[i], "cups") else ""
            print(f"seed {config.seeds[s]} task {i % config.num_test_tasks}{cups}: {len(steps)} decisions, "
                  f"{int(result.steps[i])} steps")
            for t in steps[: args.max_decisions]:
                f = records.features[t, i]
                g = np.asarray(records.num_ground[t, i])
                k, p = int(records.skill[t, i]), float(records.param[t, i])
                q = float(net.apply(params, encode(env, f, jnp.int32(k), jnp.float32(p))))
                q_cp = float(net.apply(params, encode(env, f, jnp.int32(env.num_skills), jnp.float32(0))))
                print(f"  t={t:3d} {names[k]:>17} p={p:+.2f} Q={q:.3f} Q(CP)={q_cp:.3f} "
                      f"f={np.round(np.asarray(f), 3).tolist()} ground={g.tolist()}")


if __name__ == "__main__":
    main()
