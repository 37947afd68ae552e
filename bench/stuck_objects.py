"""Where the paper's selection rule looks: at every stuck state of the oracle bridge's episodes (each seed's
training task and test tasks), whether the closest interactable object (`core/observations.closest_object`)
is the one the fix acts on (the env's `oracle_object`) or another object of its type: a distractor env's aim.

    python -m bench.stuck_objects --env doorknobs_distractor --first-seed 0 --num-seeds 8
"""
from __future__ import annotations

import argparse

import jax
import numpy as np

from envs_jax import env_class
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.observations import closest_object
from jaxbridge.core.tasks import TaskBatch, evaluation_batch, make_batch
from jaxbridge.utils.cli import non_negative_int, positive_int
from jaxbridge.utils.stats import seed_range


def stuck_picks(batch: TaskBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The oracle's episodes: (solved per task, and at each stuck state the rule's pick, its type and the
    fix's object)."""
    env = batch.env
    result, records = rollout(MetaPolicy(env, env.oracle_bridge), batch.arrays,
                              jax.random.split(jax.random.key(0), batch.size), batch.max_steps, record=True)

    def picks(state):
        objects = env.objects(state)
        slot = closest_object(objects)[0]
        return slot, objects.type_id[slot] == objects.type_id[env.oracle_object(state)], env.oracle_object(state)

    stuck = np.asarray(records.stuck & records.live)
    chosen, same_type, fix = (np.asarray(x)[stuck] for x in jax.vmap(jax.vmap(picks))(records.env_state))
    return np.asarray(result.success), chosen, same_type & (fix >= 0) & (chosen != fix), fix


def report(name: str, batch: TaskBatch) -> str:
    solved, chosen, other_of_type, fix = stuck_picks(batch)
    n = max(len(chosen), 1)
    return (f"{name}: {len(chosen)} stuck states; the rule picks the fix's object at {np.sum(chosen == fix) / n:.2f} "
            f"of them, another object of its type at {other_of_type.sum() / n:.2f} "
            f"(the oracle solved {int(solved.sum())} of {solved.size} tasks)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="doorknobs_distractor", help="a registered env (default: %(default)s)")
    parser.add_argument("--first-seed", type=non_negative_int, default=0)
    parser.add_argument("--num-seeds", type=positive_int, default=8)
    parser.add_argument("--num-tasks", type=positive_int, default=10, help="test tasks per seed (default: %(default)s)")
    args = parser.parse_args()
    cls, seeds = env_class(args.env), list(range(args.first_seed, args.first_seed + args.num_seeds))
    train = make_batch(cls, [cls.train_task(s) for s in seeds], seeds, [cls.train_steps] * len(seeds))
    print(f"{args.env}, seeds {seed_range(seeds)}, the oracle bridge's episodes")
    print(report("training tasks", train))
    print(report("test tasks", evaluation_batch(cls, seeds, args.num_tasks)))


if __name__ == "__main__":
    main()
