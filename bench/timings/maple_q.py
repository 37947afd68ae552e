"""Where Maple Q's cycle goes, beside ours': one seed on one device, each part of its cycle timed alone,
into docs/results/ENV/maple_q_profile.json (or --out).

    python -m bench.timings.maple_q [--env doorknobs] [--approaches ours,maple_q] [--warmup 5] [--repeats 5] [--out FILE]

Per approach, after --warmup cycles of the run's own Cycle (one seed, one device): what the bridge sees and
the replay buffer keeps (the observation's width, the stored entries, bytes per seed); per cycle (mean over
the warm-up cycles after the first): the training episodes' env steps and bridge decisions, and the test
episodes' env steps, bridge decisions (of the timed test rollout) and horizon; milliseconds of each part
of the next cycle, jitted alone on the learner after the warm-up (training rollout, its transitions into
the buffer, `learn`: relabelling and updates, test rollout), of the whole per-seed cycle jitted alone, and
of the Cycle call as train.py makes it (the seed map and the host's check for plan-table misses);
microseconds per minibatch update of `learn`, and bench.timings.update_parts's parts (its buffer fill). Each time
is the median over --repeats rounds, each round timing every approach's parts in turn, so that a machine
whose speed drifts, or which others share, slows them alike. Prints the figures as JSON, with each
approach's ratio to the first's. The parts run outside the cycle's program, so their sum need not be the
whole per-seed cycle.
"""
from __future__ import annotations

import jaxbridge
import json
import statistics
import sys
import time
from functools import partial
from pathlib import Path
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from bench.command import CommandParser
from bench.records import DIRTY_RECORDS, RECORDS, check_clean, git_commit, machine, record_path, shown
from bench.timings.update_parts import measure as update_parts
from jaxbridge.core.meta_policy import MetaPolicy, rollout
from jaxbridge.learn.devices import SeedMesh, select_devices
from jaxbridge.learn.hyper import Hyper
from jaxbridge.learn.learner import epsilon
from jaxbridge.learn.online import Cycle, bridge_params, make_seed_cycle
from jaxbridge.learn.setup import Setup, make_setup
from jaxbridge.learn.transitions import episode_transitions


def warm_up(setup: Setup, cycles: int) -> tuple[Callable, object, list]:
    """`cycles` cycles of the run's Cycle on its one seed: (a call of the next cycle, as train.py makes it,
    the seed's learner after them, each cycle's metrics)."""
    seeds = SeedMesh(1, tuple(select_devices(1)), setup.config.seed_block)
    cycle, learners = Cycle(setup, seeds), seeds.place(setup.init_learners())
    metrics = []
    for _ in range(cycles):
        learners, out = cycle(learners)
        metrics.append(jax.tree.map(lambda x: float(np.asarray(x)[0]), seeds.unpad(out)))
    return partial(cycle, learners), jax.tree.map(lambda x: x[0], seeds.unpad(learners)), metrics


def cycle_parts(setup: Setup, learner) -> dict[str, Callable]:
    """Each part of the seed's cycle as a call of a jitted function on `learner` (what `online.make_seed_cycle`
    calls, with its arguments), and the whole per-seed cycle jitted alone."""
    config, learning, controls = setup.config, setup.learner, setup.controls
    train, test, hyper = setup.train.arrays, setup.test.arrays, Hyper.of(config)  # one seed: its tasks alone
    episodes, shared = config.episodes_per_cycle, learning.shares_network
    keys = lambda n: jax.random.split(learner.key, n)

    @jax.jit
    def train_rollout(learner):
        explore = bridge_params(learning, learning.greedy(learner), epsilon(hyper, learner.decisions), episodes)
        policy = MetaPolicy(setup.train_env, setup.bridge(setup.train_env), explore, controls, shared_params=shared)
        return rollout(policy, train, keys(episodes), config.train_steps, record=True, host_planner=False)

    @jax.jit
    def observe(learner, result, records):
        transitions, valid = jax.vmap(episode_transitions, in_axes=(1, 0, None, None, None, None))(
            records, result.success, setup.train_env.num_skills, hyper.call_planner_bonus, config.counts_steps,
            controls.plan_progress)
        return learning.observe(learner, transitions, valid)

    @jax.jit
    def test_rollout(learner):
        greedy = bridge_params(learning, learning.greedy(learner), jnp.float32(0.0), config.num_test_tasks)
        policy = MetaPolicy(setup.test_env, setup.bridge(setup.test_env), greedy, controls, shared_params=shared)
        return rollout(policy, test, keys(config.num_test_tasks), setup.test.max_steps, host_planner=False)[0]

    learn = jax.jit(lambda learner: learning.learn(learner, jnp.int32(1), train.tasks))
    seed_cycle = jax.jit(make_seed_cycle(setup, host_planner=False))
    result, records = train_rollout(learner)
    return {"train_rollout": partial(train_rollout, learner), "observe": partial(observe, learner, result, records),
            "learn": partial(learn, learner), "test_rollout": partial(test_rollout, learner),
            "seed_cycle": partial(seed_cycle, learner, train, test, hyper)}


def timed_rounds(calls: dict[str, dict[str, Callable]], repeats: int) -> dict[str, dict[str, float]]:
    """{approach: {part: milliseconds}}: each call once to compile, then `repeats` rounds that time every
    approach's calls in turn, and each call's median over the rounds (a machine whose speed drifts, or
    which others share, slows every approach alike within a round)."""
    for parts in calls.values():
        for call in parts.values():
            jax.block_until_ready(call())
    times = {name: {part: [] for part in parts} for name, parts in calls.items()}
    for _ in range(repeats):
        for name, parts in calls.items():
            for part, call in parts.items():
                start = time.perf_counter()
                jax.block_until_ready(call())
                times[name][part].append(1e3 * (time.perf_counter() - start))
    return {name: {part: statistics.median(t) for part, t in parts.items()} for name, parts in times.items()}


def figures(setup: Setup, learner, metrics: list, ms: dict, tested, fill: int) -> dict:
    """One approach's figures on its env (seed 0): `ms` its timed parts, `tested` its test rollout's result."""
    config, learning = setup.config, setup.learner
    mean = lambda field: round(float(np.mean([getattr(m, field) for m in metrics[1:]])), 2)  # the first compiles
    buffer = getattr(learner, "buffer", None)
    parts = ("train_rollout", "observe", "learn", "test_rollout")
    ms = {**ms, "parts_sum": sum(ms[part] for part in parts)}
    return {
        "observation": {"width": learning.num_features, "stored": getattr(learning, "stored_features", None)},
        "buffer": None if buffer is None else {
            "capacity": buffer.capacity, "bytes_per_seed": sum(x.nbytes for x in jax.tree.leaves(buffer.data)),
            "filled_after_warmup": int(buffer.size)},
        "per_cycle": {"train_episodes": config.episodes_per_cycle, "train_steps_each": config.train_steps,
                      "train_env_steps": mean("train_env_steps"), "train_decisions": mean("train_decisions"),
                      "test_tasks": config.num_test_tasks, "test_horizon": setup.test.max_steps,
                      "test_env_steps": mean("test_env_steps"), "test_decisions": int(tested.bridge_decisions.sum()),
                      "test_solve_rate": mean("test_solve_rate"), "table_misses": mean("table_misses")},
        "ms": {k: round(v, 1) for k, v in ms.items()},
        "updates_per_cycle": config.learner.updates_per_cycle,
        "learn_us_per_update": round(1e3 * ms["learn"] / max(config.learner.updates_per_cycle, 1), 1),
        "update_parts_us": {k: round(v, 1) for k, v in
                            update_parts(config.env, config.approach, fill, config.learner.updates_per_cycle).items()},
    }


def profile(env: str, approaches: list[str], warmup: int, repeats: int, fill: int) -> dict:
    """Every approach's figures on `env` (seed 0), their parts timed in the same rounds."""
    setups = {a: make_setup(jaxbridge.make_config(env, approach=a, num_seeds=1)) for a in approaches}
    seeds = {a: warm_up(setup, warmup) for a, setup in setups.items()}
    calls = {a: {**cycle_parts(setups[a], learner), "cycle_call": cycle} for a, (cycle, learner, _) in seeds.items()}
    ms = timed_rounds(calls, repeats)
    return {a: figures(setups[a], learner, metrics, ms[a], calls[a]["test_rollout"](), fill)
            for a, (_, learner, metrics) in seeds.items()}


def with_ratios(measured: dict) -> dict:
    """Each approach's milliseconds and microseconds per update as a ratio to the first approach's."""
    first = next(iter(measured.values()))
    return {name: {key: round(value / first["ms"][key], 2) for key, value in f["ms"].items()}
            | {"learn_us_per_update": round(f["learn_us_per_update"] / first["learn_us_per_update"], 2)}
            for name, f in list(measured.items())[1:]}


def main(argv=None) -> int:
    parser = CommandParser(__spec__.name, __doc__, env="doorknobs", dirty_records=shown(DIRTY_RECORDS))
    parser.add_argument("--approaches", default="ours,maple_q", help="comma-separated, the first the reference "
                        "(default: %(default)s)")
    parser.add_argument("--warmup", type=int, default=5, help="cycles before the parts are timed (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=5, help="timed rounds (default: %(default)s)")
    parser.add_argument("--fill", type=int, default=16384, help="bench.timings.update_parts's buffer fill (default: %(default)s)")
    parser.add_argument("--out", type=Path, help="write the record here instead (default: docs/results/ENV/"
                        "maple_q_profile.json, which PERFORMANCE renders, for the default --approaches; with others "
                        "the record is only printed)")
    args = parser.parse_args(argv)
    path = record_path("bench.timings.maple_q", args.out or RECORDS / args.env / "maple_q_profile.json", args.allow_dirty)
    measured = profile(args.env, args.approaches.split(","), args.warmup, args.repeats, args.fill)
    record = {"env": args.env, "seed": 0, "figures": measured, "ratio_to_first": with_ratios(measured),
              "commit": git_commit(check_clean("bench.timings.maple_q", args.allow_dirty, during=True)),
              "command": "python -m bench.timings.maple_q " + " ".join(argv if argv is not None else sys.argv[1:]),
              "machine": machine()}
    print(json.dumps(record, indent=2))
    if args.out is None and args.approaches != parser.get_default("approaches"):
        print("bench.timings.maple_q: other approaches than PERFORMANCE's record: printed only (--out FILE keeps it)",
              file=sys.stderr)
        return 0
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2) + "\n")
    print(f"bench.timings.maple_q: -> {shown(path)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
