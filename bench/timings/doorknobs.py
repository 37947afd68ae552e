"""Cost of Doorknobs on CPU: the oracle meta-policy rollout of the 80 test tasks of seeds 0-7 (the shape
of one greedy evaluation), and the env's two motion calls alone at batch 80.

    python -m bench.timings.doorknobs [--repeats 5]
    python -m bench.timings.doorknobs --baseline DIR    # against another checkout, e.g. `git worktree add DIR HEAD`

Every figure is a 200-step `lax.scan` whose carry feeds the next step's input (the robot positions), so
XLA cannot hoist loop-invariant work out of the loop; each is the best of `repeats` runs, in ms per scan
step of the whole batch. With --baseline, the two code trees run in turns in fresh processes and the
best of each is kept, so a neighbour's load on a shared machine spoils both alike.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from bench.command import CommandParser

STEPS = 200
FIGURES = ("oracle rollout, 80 test tasks", "skill_action (MoveToDoor)", "skill_initiable (8 ground ops)")


def best_ms_per_step(fn, repeats: int) -> float:
    import jax

    jax.block_until_ready(fn())  # compile
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - start)
    return 1e3 * min(times) / STEPS


def measure(repeats: int) -> dict:
    """The figures of the code tree on sys.path, and the oracle's results (the behaviour to keep)."""
    import jax
    import jax.numpy as jnp

    from envs_jax.base import SkillCall
    from envs_jax.doorknobs.env import Doorknobs
    from jaxbridge.core.bridges import make_bridge
    from jaxbridge.core.meta_policy import MetaPolicy, rollout
    from jaxbridge.core.tasks import evaluation_batch

    batch = evaluation_batch(Doorknobs, list(range(8)))
    env, tasks, size = batch.env, batch.tasks, batch.size
    states = jax.vmap(env.reset)(tasks)
    move_to, through = env.skill_index("MoveToDoor"), env.skill_index("MoveThroughDoor")
    doors = jnp.argmax(tasks.door_mask, axis=-1).astype(jnp.int32)  # some door of each map
    skills = jnp.full((size, 8), move_to, jnp.int32).at[:, 4:].set(through)
    slots = jnp.tile(jnp.arange(8, dtype=jnp.int32) % (2 * env.map_size ** 2), (size, 1))

    def scanned(per_step):
        """200 steps of `per_step(states) -> float32[B, 2]`, fed back as the robots' next positions."""
        @jax.jit
        def run(states):
            def body(robot, _):
                return robot + 1e-6 * per_step(states.replace(robot=robot)), None
            return jax.lax.scan(body, states.robot, None, STEPS)[0]
        return lambda: run(states)

    def action(states):
        calls = SkillCall(jnp.full(size, move_to, jnp.int32), doors, jnp.zeros(size), jnp.ones(size, bool),
                          jnp.zeros(size, jnp.int32))
        return jax.vmap(env.skill_action)(states, calls)[:, :2]

    def initiable(states):
        ok = jax.vmap(env.skill_initiable)(states, skills, slots)
        return jnp.sum(ok, -1, dtype=jnp.float32)[:, None] * jnp.ones(2)

    oracle = make_bridge("oracle", env)
    keys = jax.random.split(jax.random.key(0), size)
    run_oracle = lambda: rollout(MetaPolicy(env, oracle), batch.arrays, keys, STEPS)[0]
    result = run_oracle()
    times = [best_ms_per_step(fn, repeats) for fn in (run_oracle, scanned(action), scanned(initiable))]
    return {"ms": dict(zip(FIGURES, times)), "solved": int(result.success.sum()), "episodes": size,
            "steps": [int(s) for s in result.steps]}


def in_tree(tree: Path, repeats: int) -> dict:
    """`measure` in a fresh process that imports the code of `tree`."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, __file__, "--json", "--repeats", str(repeats)], cwd=tree, env=env,
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.splitlines()[-1])


def main() -> None:
    parser = CommandParser(__spec__.name, __doc__)
    parser.add_argument("--repeats", type=int, default=5, help="timings per figure, best kept (default: %(default)s)")
    parser.add_argument("--baseline", type=Path, default=None, help="another code tree to compare with (default: none)")
    parser.add_argument("--rounds", type=int, default=2, help="turns per tree with --baseline (default: %(default)s)")
    parser.add_argument("--json", action="store_true", help="print this tree's figures as one JSON line")
    args = parser.parse_args()
    if args.json:
        print(json.dumps(measure(args.repeats)))
        return
    here = Path(__file__).resolve().parents[2]  # the repository holding this file
    trees = {"this": here} if args.baseline is None else {"baseline": args.baseline.resolve(), "this": here}
    runs: dict = {name: [] for name in trees}
    for _ in range(1 if args.baseline is None else args.rounds):
        for name, tree in trees.items():
            runs[name].append(in_tree(tree, args.repeats))
    best = {name: {f: min(r["ms"][f] for r in rs) for f in FIGURES} for name, rs in runs.items()}
    print(f"ms per step at batch {runs['this'][0]['episodes']} ({STEPS}-step scans, best of "
          f"{args.repeats} x {len(runs['this'])} runs)")
    print(f"  {'':>32}" + "".join(f"{name:>10}" for name in trees) + ("   speed-up" if len(trees) > 1 else ""))
    for f in FIGURES:
        row = "".join(f"{best[name][f]:10.3f}" for name in trees)
        ratio = f"{best['baseline'][f] / best['this'][f]:10.1f}x" if len(trees) > 1 else ""
        print(f"  {f:>32}{row}{ratio}")
    for name, rs in runs.items():
        print(f"  {name}: oracle solves {rs[0]['solved']}/{rs[0]['episodes']}, max {max(rs[0]['steps'])} steps")
    if len(trees) > 1:
        same = runs["this"][0]["steps"] == runs["baseline"][0]["steps"]
        print(f"  episode lengths {'identical' if same else 'DIFFER'} between the trees")


if __name__ == "__main__":
    main()
