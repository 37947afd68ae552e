"""The generalisation sweep: every env's sweep tasks have the stated number of novelties and are solvable
within their scaled horizon (by the oracle bridge, while pure planning fails them), and the sweep
groups episodes by count, marks what an approach cannot see, and writes its table, CSV and plot."""
import jaxbridge
import csv
import io
from dataclasses import dataclass

import numpy as np
import pytest
from oracle_vs_planning import oracle_and_pure_planning

from envs_jax import BUILTIN, LightSwitchDoor, env_class
from jaxbridge.core.config import TrainConfig
from jaxbridge.core.meta_policy import EpisodeResult
from jaxbridge.run.sweep import SweepResult, evaluate_sweep, sweep_batch, sweep_csv, sweep_markdown, sweep_tasks
from jaxbridge.viz.figures import plot_sweep

NOVELTIES = {  # how each env's task shows its number of novelty instances
    "light_switch_door": lambda spec: len(spec.door_cells),
    "doorknobs": lambda spec: spec.doors_to_goal,
    "coffee": lambda spec: len(spec.cups),
}


@pytest.mark.parametrize("name", BUILTIN)
def test_sweep_tasks_have_their_count_and_the_oracle_solves_them_within_the_scaled_horizon(name):
    env_cls = env_class(name)
    sweep = env_cls.novelty_sweep
    specs, counts = sweep_tasks(env_cls, 2, sweep_seed=3)
    assert [NOVELTIES[name](s) for s in specs] == counts.tolist() == [k for k in sweep.counts for _ in range(2)]
    test_horizon = max(spec.horizon for spec in env_cls.test_tasks(0, 10))
    assert all(sweep.horizon(s) >= min(test_horizon, s.horizon) for s in specs)
    batch = sweep_batch(env_cls, specs, seeds=[0])
    assert batch.horizons.tolist() == [sweep.horizon(s) for s in specs]
    result = oracle_and_pure_planning(batch)
    assert result["oracle"].success.all(), counts[~result["oracle"].success]
    assert (result["oracle"].steps <= batch.horizons).all()
    assert not result["none"].success.any()  # every task holds a novelty the planner cannot pass


def test_sweep_draws_do_not_depend_on_other_counts_and_follow_the_sweep_seed():
    env_cls = env_class("light_switch_door")
    specs, counts = sweep_tasks(env_cls, 3, sweep_seed=0)
    again, _ = sweep_tasks(env_cls, 3, sweep_seed=0)
    other, _ = sweep_tasks(env_cls, 3, sweep_seed=1)
    assert specs == again and specs != other
    rng = np.random.default_rng([0, 5])  # count 5's own stream
    assert [s for s, k in zip(specs, counts) if k == 5] == [env_cls.novelty_sweep.task(rng, 5) for _ in range(3)]


@dataclass
class FakePolicy:
    """Stands in for a TrainedPolicy: solves a task iff its door count is in `solves`, per seed."""

    config: TrainConfig
    solves: dict  # seed -> set of door counts
    full_state: bool = False
    batches: list = None
    env_cls = LightSwitchDoor
    models = None  # no learned models: every seed in one batch

    def can_see(self, env) -> bool:
        return env.full_state_fits or not self.full_state

    def planned(self, batch):  # a run without a learned model plans its tasks as they are
        return batch

    def run(self, batch, seed=0):
        self.batches.append(batch)
        success = np.array([len(spec.door_cells) in self.solves[s] for spec, s in zip(batch.specs, batch.seeds)])
        return EpisodeResult(success=success, steps=None, planner_calls=None, table_misses=None,
                             bridge_decisions=None, stuck_events=None)


def test_sweep_groups_episodes_by_seed_and_count_and_marks_what_an_approach_cannot_see():
    config = jaxbridge.make_config("light_switch_door", num_seeds=2, first_seed=4)
    batches = []
    good = FakePolicy(config, {4: {1, 2, 3}, 5: {1, 3}}, batches=batches)
    blind = FakePolicy(config, {4: set(), 5: set()}, full_state=True, batches=batches)
    result = evaluate_sweep({"good": good, "full state": blind}, tasks_per_count=2)
    counts = np.array(result.counts)
    assert result.counted == "doors" and counts.tolist() == list(range(1, 17))
    np.testing.assert_array_equal(result.solve_rate["good"], [np.isin(counts, [1, 2, 3]), np.isin(counts, [1, 3])])
    assert np.isnan(result.solve_rate["full state"]).all()  # 60 cells do not fit its 20-cell input
    assert len(batches) == 1 and batches[0].size == 2 * 16 * 2  # seeds x counts x tasks, seed-major
    assert batches[0].seeds.tolist() == [4] * 32 + [5] * 32
    table = sweep_markdown(result)
    assert "| 2 | 0.50 [0.00, 1.00] | n/a |" in table and "| 3 | 1.00 | n/a |" in table
    rows = list(csv.DictReader(io.StringIO(sweep_csv(result))))
    assert len(rows) == 2 * 2 * 16
    assert {(r["seed"], r["doors"], r["solve_rate"]) for r in rows if r["line"] == "good" and r["doors"] == "2"} \
        == {("4", "2", "1.0000"), ("5", "2", "0.0000")}
    assert all(r["solve_rate"] == "" for r in rows if r["line"] == "full state")


def test_sweep_plot_is_a_png():
    rate = np.array([[1.0, 0.5, 0.0], [1.0, 1.0, 0.5]])
    result = SweepResult("coffee", "cups", "on the table", (1, 2, 3), 4, {"ours": rate, "full": np.full_like(rate, np.nan)},
                         {"ours": [0, 1], "full": [0, 1]})
    png = plot_sweep(result, "title")
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_each_approach_keeps_one_colour_in_every_figure():
    from jaxbridge.learn.approaches import APPROACHES, KNOWN
    from jaxbridge.viz.figures import colour

    assert all(colour(name) == colour(approach.label) for name, approach in KNOWN.items())
    assert len({colour(name) for name in APPROACHES}) == len(APPROACHES)  # the paper's figure: all apart


def test_a_line_that_coincides_with_an_earlier_one_is_named():
    from jaxbridge.viz.figures import same_as

    zeros, rising = np.zeros(5), np.linspace(0, 1, 5)
    nan_start = np.array([np.nan, 0.5, 1.0, 1.0, 1.0])
    lines = {"pure planning": zeros, "ours": rising, "random": zeros.copy(), "late": nan_start, "late too": nan_start.copy(),
             "almost": rising + 1e-3}
    assert same_as(lines) == {"random": "pure planning", "late too": "late"}  # the first drawn is named
