"""How a Doorknobs bridge generalises over doorways: train seeds with config overrides (as bench.probes.sweep),
then ask each final greedy Q, at every knob offset a test doorway can show, which knob turn it would
pick. A seed's training map shows it one or two doorways; the test maps' doorways lie over a range of
offsets (docs/TUNING.md), and a bridge that turns the knob wrongly at some of them is the
failure left on the evaluation seeds (issue #19).

    python -m bench.probes.knob_offsets --seeds 0-7 --cycles 100 updates_per_cycle=150

Per seed: the fraction of a grid of offsets (larger offset 0.08-0.18, smaller 0.03-0.12, the robot not
yet moved, the knob at 0 and its door closed) where the best knob turn among 201 evenly spaced ones
misses the opening window (0.65, 0.85), and where OpenDoor at its best turn is not the best action.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from bench.probes.sweep import print_digits, reliability, swept_config, train_seeds
from bench.timings.training import overrides_parser
from envs_jax.doorknobs.env import MOVE_THROUGH_DOOR, MOVE_TO_DOOR, OPEN_DOOR
from envs_jax.doorknobs.maps import KNOB_TARGET, OPEN_TOLERANCE
from jaxbridge.learn.q_bridge import encode

LARGER, SMALLER = np.linspace(0.08, 0.18, 21), np.linspace(0.03, 0.12, 19)
TURNS = np.linspace(-1.0, 1.0, 201)


def offset_grid() -> np.ndarray:
    """float32[G, 7]: closed-door doorway features over the offset grid (larger offset first)."""
    big, small = np.meshgrid(LARGER, SMALLER, indexing="ij")
    keep = big >= small
    rows = [np.array([b, s, 0.0, KNOB_TARGET, 0.0, 0.0, 0.0]) for b, s in zip(big[keep], small[keep])]
    return np.asarray(rows, np.float32)


def probe(env, net, q_params, features: jax.Array) -> tuple[jax.Array, jax.Array]:
    """For each feature row: the best knob turn, and whether OpenDoor at it beats every other skill."""
    turns = jnp.asarray(TURNS, jnp.float32)
    q_turn = net.apply(q_params, encode(env, features[:, None, :], jnp.int32(OPEN_DOOR), turns[None, :]))
    others = jnp.asarray([MOVE_TO_DOOR, MOVE_THROUGH_DOOR, env.num_skills], jnp.int32)
    q_other = net.apply(q_params, encode(env, features[:, None, :], others[None, :], jnp.float32(0)))
    return turns[jnp.argmax(q_turn, axis=1)], q_turn.max(axis=1) > q_other.max(axis=1)


def main() -> None:
    parser = overrides_parser(__spec__.name, __doc__, "doorknobs", "0-7", 100)
    args = parser.parse_args()
    if args.env != "doorknobs":
        parser.error("the probe's grid is Doorknobs' doorways: --env doorknobs")
    config, changes = swept_config(args)
    setup, learners, rates = train_seeds(config)
    print_digits(config.seeds, rates)
    print(reliability(rates, 0.95))

    features = jnp.asarray(offset_grid())
    env, net = setup.test_env, setup.learner.net
    wrong, not_open = [], []
    for s, seed in enumerate(config.seeds):
        q_params = jax.tree.map(lambda x, s=s: x[s], learners.online)
        turn, open_best = map(np.asarray, probe(env, net, q_params, features))
        wrong.append(np.mean(np.abs(turn - KNOB_TARGET) >= OPEN_TOLERANCE))
        not_open.append(1 - open_best.mean())
        print(f"seed {seed:>3}: wrong turn at {wrong[-1]:.2f} of {len(turn)} offsets "
              f"(turns {np.quantile(turn, [0, 0.5, 1]).round(2).tolist()} min/median/max), "
              f"OpenDoor not best at {not_open[-1]:.2f}")
    print(f"overrides {changes or 'none'}: wrong turn at {np.mean(wrong):.3f} of offsets on average, "
          f"seeds with any wrong turn {int(np.sum(np.asarray(wrong) > 0))}/{len(wrong)}; "
          f"OpenDoor not best at {np.mean(not_open):.3f}")


if __name__ == "__main__":
    main()
