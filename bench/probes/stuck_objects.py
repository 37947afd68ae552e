"""Where the paper's selection rule looks: at every stuck state of the oracle bridge's episodes (each seed's
training task and test tasks), whether the closest interactable object (`core/observations.closest_object`)
is the one the fix acts on (the env's `oracle_object`) or another object of its type: a distractor env's aim.

    python -m bench.probes.stuck_objects --env doorknobs_distractor --seeds 0-7
"""
from __future__ import annotations

import jax
import numpy as np

from bench.command import CommandParser
from envs_jax import env_class
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.core.observations import closest_object
from jaxbridge.core.tasks import TaskBatch, evaluation_batch, make_batch
from jaxbridge.utils.cli import positive_int
from jaxbridge.utils.stats import seed_range


def stuck_picks(batch: TaskBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The oracle's episodes: solved per task, and at each stuck state the rule's pick, the fix's object
    (-1: none) and whether the two are of one type."""
    env = batch.env
    result, records = rollout(MetaPolicy(env, env.oracle_bridge), batch.arrays,
                              jax.random.split(jax.random.key(0), batch.size), batch.max_steps, record=True)

    def picks(state):
        objects, fix = env.objects(state), env.oracle_object(state)
        slot = closest_object(objects)[0]
        return slot, fix, objects.type_id[slot] == objects.type_id[fix]

    stuck = np.asarray(records.stuck & records.live)
    chosen, fix, same_type = (np.asarray(x)[stuck] for x in jax.vmap(jax.vmap(picks))(records.env_state))
    return np.asarray(result.success), chosen, fix, same_type & (fix >= 0)


def report(name: str, batch: TaskBatch) -> str:
    solved, chosen, fix, same_type = stuck_picks(batch)
    share = lambda picked: f"{picked.sum() / max(len(chosen), 1):.2f}"
    right = chosen == fix
    return (f"{name}: {len(chosen)} stuck states; the rule picks the fix's object at {share(right)} of them, "
            f"another object of its type at {share(same_type & ~right)}, of another type at "
            f"{share(~same_type & (fix >= 0))} (the oracle solved {int(solved.sum())} of {solved.size} tasks)")


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__, env="doorknobs_distractor", seeds="0-7")
    parser.add_argument("--num-tasks", type=positive_int, default=10, help="test tasks per seed (default: %(default)s)")
    args = parser.parse_args()
    cls, seeds = env_class(args.env), args.seed_list
    train = make_batch(cls, [cls.train_task(s) for s in seeds], seeds, [cls.train_steps] * len(seeds))
    print(f"{args.env}, seeds {seed_range(seeds)}, the oracle bridge's episodes")
    print(report("training tasks", train))
    print(report("test tasks", evaluation_batch(cls, seeds, args.num_tasks)))


if __name__ == "__main__":
    main()
