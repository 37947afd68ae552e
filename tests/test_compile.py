"""Compilation: the training cycle compiles once, whatever the number of cycles.

Measured with jax.monitoring (jaxbridge.compile_cache.record: programs traced and compiled) and the
jitted cycle's own dispatch cache. The
persistent cache cannot hide a recompilation here: the cycle holds a host callback (the planner
fallback), which JAX never writes to it.
"""
import jax

from jaxbridge import compile_cache
from jaxbridge.config import TrainConfig
from jaxbridge.devices import SeedMesh
from jaxbridge.online import build_experiment, init_learners, make_cycle

TINY = TrainConfig(num_seeds=2, episodes_per_cycle=2, num_test_tasks=2, updates_per_cycle=2, buffer_capacity=512,
                   n_sample=4, n_target_sample=2)


def test_the_cycle_compiles_once_across_cycles():
    experiment = build_experiment(TINY)
    seeds = SeedMesh(TINY.num_seeds)  # one device: where XLA used to hand back replicated leaves
    learners = seeds.place(init_learners(experiment))
    cycle = make_cycle(experiment, seeds)
    with compile_cache.record() as first:
        learners, _ = cycle(learners)
        jax.block_until_ready(learners)
    with compile_cache.record() as later:
        for _ in range(2):
            learners, metrics = cycle(learners)
        jax.block_until_ready((learners, metrics))
    assert first.compiles >= 1 and first.compile_s > 0
    assert later.compiles == 0, f"cycles 2-3 compiled {later.compiles} program(s) ({later.compile_s:.1f} s)"
    assert later.traces == 0
    assert cycle._run._cache_size() == 1  # one dispatch entry (on 2 devices it can gain a second, untraced)
    leaves = jax.tree.leaves(learners)
    assert all(x.sharding.is_equivalent_to(seeds.sharding, x.ndim) for x in leaves)
