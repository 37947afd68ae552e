"""What the bridge sees: one kind of observation per approach (`Controls.observation`), each a small
value with its width on an env and the function that makes it from the current and the stuck state.

The built-in kinds: the env's hand-made `features` (the paper's selection, per env), the `full_state`
(every object's raw features, padded), the paper's rule read off the object view (`closest_object`) and
every candidate object as a token (`object_tokens`, for the learned selector). A new kind is one
`Observation` and one `register` call (its name must be new)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np

from envs_jax.base import POSITION_DIM, NoveltyEnv, Objects


@dataclass(frozen=True, eq=False)  # compared by identity: one value per kind, a static part of the controls
class Observation:
    name: str
    size: Callable[[NoveltyEnv], int]
    """Its length on `env` (the network's input width)."""
    observe: Callable[[NoveltyEnv, Any, Any], jax.Array]
    """float32[size(env)] from (env, state, stuck_state): the state at which control last passed to the bridge."""
    whole_state: bool = False
    """The env's whole padded state: its task-constant entries can be stored once per task (learn/q_bridge)."""
    tokens: bool = False
    """Object tokens: the network attends over them (learn/object_q.py)."""


def token_width(env: NoveltyEnv) -> int:
    """An object token's length: one-hot type, features, offset from the robot where it got stuck, offset
    from the robot now, interactable."""
    return len(env.object_types) + env.object_width + 2 * POSITION_DIM + 1


def token_position(env: NoveltyEnv, at_stall: bool) -> tuple[int, int]:
    """(start, end): where a token's offset from the robot lies, where it got stuck (`at_stall`) or now."""
    start = len(env.object_types) + env.object_width + (0 if at_stall else POSITION_DIM)
    return start, start + POSITION_DIM


def token_measured_entries(env: NoveltyEnv) -> np.ndarray:
    """The entries of `object_tokens` that measure an object (its features and offsets), not those that say
    what it is (its type's one-hot, interactable): the ones feature noise perturbs."""
    width, kinds = token_width(env), len(env.object_types)
    return (np.arange(len(token_slots(env)))[:, None] * width + np.arange(kinds, width - 1)).reshape(-1)


def robot_features(env: NoveltyEnv) -> tuple[int, int] | None:
    """(start, end): where the robot's token holds the robot's own features (after its type's one-hot); None
    where the robot's type has none (every env but Coffee's)."""
    start, count = len(env.object_types), len(env.object_types["robot"])
    return (start, start + count) if count else None


def relative_to_robot(position: jax.Array, robot: jax.Array) -> jax.Array:
    """Offsets from the robot squashed to (-1, 1) per axis, d / (1 + |d|): exact near the robot, bounded
    far away, so a larger test task's distances are not beyond the training task's."""
    offset = position - robot
    return offset / (1.0 + jnp.abs(offset))


def closest_object(objects: Objects) -> tuple[jax.Array, jax.Array]:
    """The paper's feature selection: the slot of the interactable object closest to the robot (ties: the
    lowest slot), and whether there is one."""
    distance = jnp.linalg.norm(objects.position - objects.position[0], axis=-1)
    return jnp.argmin(jnp.where(objects.interactable, distance, jnp.inf)), jnp.any(objects.interactable)


def closest_object_width(env: NoveltyEnv) -> int:
    return 1 + env.object_width + 2 * POSITION_DIM


def closest_object_features(env: NoveltyEnv, state: Any, stuck_state: Any) -> jax.Array:
    """float32[1 + W + 6]: the paper's selection as one function of the object view. The object is chosen
    in the stuck state and read in this one: a flag that there is one, its features and its position
    relative to the robot (zeros without one), then how far the robot has moved since it got stuck."""
    then, now = env.objects(stuck_state), env.objects(state)
    slot, found = closest_object(then)
    chosen = jnp.concatenate([now.features[slot], relative_to_robot(now.position[slot], now.position[0])])
    moved = relative_to_robot(now.position[0], then.position[0])
    return jnp.concatenate([found[None].astype(jnp.float32), jnp.where(found, chosen, 0.0), moved])


def token_slots(env: NoveltyEnv) -> np.ndarray:
    """The slots that become tokens: the robot's and every one a skill may act on (the paper's candidates
    for its selection); cells, rooms and the like only cost attention."""
    return np.r_[0, env.candidate_slots]


def object_tokens(env: NoveltyEnv, state: Any, stuck_state: Any) -> jax.Array:
    """float32[T * token_width]: the object view's `token_slots` as tokens, the robot first; a masked-out
    slot is zeros. Offsets are `relative_to_robot`: each object's from the robot in the stuck state (the
    robot's own: how far it has moved since), as the paper's rule chooses there, and from the robot now."""
    now, then = (jax.tree.map(lambda x: x[token_slots(env)], env.objects(s)) for s in (state, stuck_state))
    kind = jax.nn.one_hot(now.type_id, len(env.object_types)) * now.mask[:, None]
    at_stall = relative_to_robot(then.position, then.position[0]).at[0].set(
        relative_to_robot(now.position[0], then.position[0])) * now.mask[:, None]
    relative = relative_to_robot(now.position, now.position[0]) * now.mask[:, None]
    tokens = jnp.concatenate([kind, now.features, at_stall, relative, now.interactable[:, None].astype(jnp.float32)], -1)
    return tokens.reshape(-1)


FEATURES = Observation("features", lambda env: env.num_features,
                       lambda env, state, stuck_state: env.features(state, stuck_state))
FULL_STATE = Observation("full_state", lambda env: env.full_state_size,
                         lambda env, state, stuck_state: env.full_state(state), whole_state=True)
CLOSEST_OBJECT = Observation("closest_object", closest_object_width, closest_object_features)
OBJECT_TOKENS = Observation("object_tokens", lambda env: len(token_slots(env)) * token_width(env),
                            object_tokens, tokens=True)

OBSERVATIONS: dict[str, Observation] = {}


def register(kind: Observation) -> Observation:
    """Make `kind` known by its name (for approaches declared elsewhere to name it); ValueError if taken."""
    if OBSERVATIONS.get(kind.name, kind) is not kind:
        raise ValueError(f"an observation named {kind.name!r} is registered already")
    OBSERVATIONS[kind.name] = kind
    return kind


for _kind in (FEATURES, FULL_STATE, CLOSEST_OBJECT, OBJECT_TOKENS):
    register(_kind)
