"""The oracle bridge and pure planning on the same batch of tasks, in one rollout (one compilation):
the batch twice, each episode's bridge picked by its params. Shared by the env test files."""
import jax
import jax.numpy as jnp
import numpy as np

from jaxbridge.core.bridges import make_bridge
from jaxbridge.core.meta_policy import MetaPolicy, rollout


def oracle_and_pure_planning(batch) -> dict:
    """{"oracle": EpisodeResult[B], "none": EpisodeResult[B]} as numpy."""
    oracle, none = make_bridge("oracle", batch.env), make_bridge("none", batch.env)

    def either(use_oracle, obs, key):
        return jax.tree.map(lambda a, b: jnp.where(use_oracle, a, b), oracle(None, obs, key), none(None, obs, key))

    twice = lambda tree: jax.tree.map(lambda x: jnp.concatenate([x, x]), tree)
    use_oracle = jnp.arange(2 * batch.size) < batch.size
    result, _ = rollout(MetaPolicy(batch.env, either, use_oracle), twice(batch.arrays),
                        jax.random.split(jax.random.key(0), 2 * batch.size), batch.max_steps)
    result = jax.tree.map(np.asarray, result)
    return {"oracle": jax.tree.map(lambda x: x[: batch.size], result),
            "none": jax.tree.map(lambda x: x[batch.size:], result)}
