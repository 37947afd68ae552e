"""The statistics of every published figure: IQM, bootstrap intervals, against values known exactly."""
import itertools

import numpy as np
import pytest
import scipy.stats

from jaxbridge.utils import stats


@pytest.mark.parametrize("runs", [1, 4, 7, 8, 10, 32, 33])
def test_iqm_is_scipys_quarter_trimmed_mean(runs):
    scores = np.random.default_rng(runs).random((runs, 5))
    np.testing.assert_allclose(stats.iqm(scores), scipy.stats.trim_mean(scores, 0.25, axis=0), rtol=1e-12)


def test_iqm_ignores_the_outer_quarters():
    assert stats.iqm(np.array([0.0, 0.5, 0.7, 1.0])) == pytest.approx(0.6)
    assert stats.iqm(np.array([0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])) == 1.0  # 2 failed seeds of 8 are cut


def test_bootstrap_interval_matches_the_exact_bootstrap_distribution():
    """Three runs 0, 1, 2: the 27 equally likely resamples give the mean 0 with probability 1/27 (> 2.5%)
    and at most 5/3 with probability 26/27 (< 97.5%), so the exact 95% interval is [0, 2]."""
    scores = np.array([0.0, 1.0, 2.0])
    means = sorted(np.mean(scores[list(i)]) for i in itertools.product(range(3), repeat=3))
    assert means[0] == 0.0 and means.count(2.0) == 1 and means[-2] == pytest.approx(5 / 3)
    low, high = stats.bootstrap_ci(scores, reps=20_000)
    assert (low, high) == (0.0, 2.0)


def test_bootstrap_interval_of_the_mean_approaches_the_normal_one():
    """32 seeds: the percentile interval of the mean is close to mean +- 1.96 sd / sqrt(n) (sd of the
    empirical distribution, which the bootstrap resamples)."""
    scores = np.random.default_rng(3).random(32)
    half = 1.959964 * scores.std() / np.sqrt(32)
    low, high = stats.bootstrap_ci(scores)
    assert low == pytest.approx(scores.mean() - half, abs=0.012)
    assert high == pytest.approx(scores.mean() + half, abs=0.012)


def test_intervals_per_cycle_are_each_columns_own_and_repeat_exactly():
    scores = np.random.default_rng(5).random((16, 3))
    together = stats.describe(scores)
    for c in range(3):
        alone = stats.describe(scores[:, c:c + 1])
        for key, value in together.items():
            assert value[c] == pytest.approx(alone[key][0], rel=1e-12), key
    again = stats.describe(scores)
    assert all(np.array_equal(together[k], again[k]) for k in together)
    for name in stats.STATISTICS:
        assert np.all(together[f"{name}_low"] <= together[name]) and np.all(together[name] <= together[f"{name}_high"])


def test_identical_seeds_have_no_spread():
    out = stats.describe(np.full((8, 2), 0.7))
    for key in ("mean", "mean_low", "mean_high", "iqm", "iqm_low", "iqm_high", "min", "max"):
        np.testing.assert_allclose(out[key], 0.7)


def test_seed_ranges_in_words():
    assert stats.seed_range(list(range(100, 132))) == "100-131"
    assert stats.seed_range([7, 0, 1, 2, 3]) == "0-3, 7"
    assert stats.seed_range([5]) == "5"



def test_the_drop_is_each_cycle_minus_the_best_before_for_the_statistic_and_for_each_seed():
    """Two seeds: one learns at cycle 2 and loses half of it at 3, the other learns at 3. The mean curve
    0, 0.5, 0.75 never falls; seed 0 falls by 0.5 at cycle 3, which min reports."""
    scores = np.array([[0.0, 1.0, 0.5], [0.0, 0.0, 1.0]])
    drop = stats.describe_drop(scores, reps=500)
    np.testing.assert_allclose(drop["mean"], [0.0, 0.5, 0.25])
    np.testing.assert_allclose(drop["min"], [0.0, 0.0, -0.5])
    np.testing.assert_allclose(drop["max"], [0.0, 1.0, 1.0])
    # resampling both seeds from seed 0 alone gives its own fall, -0.5: the interval reaches it
    assert drop["mean_low"][2] == pytest.approx(-0.5) and drop["mean_high"][2] >= 0.25
    np.testing.assert_allclose(stats.drop_from_best(np.array([0.2, 0.9, 0.4, 1.0, 0.8])), [0.0, 0.7, -0.5, 0.1, -0.2])


def test_ci_text_shows_signs_for_differences_and_one_value_where_the_interval_rounds_to_it():
    assert stats.ci_text(-0.0123, (-0.04, 0.001), signed=True) == "-0.01 [-0.04, +0.00]"
    assert stats.ci_text(0.5, (0.4991, 0.5004)) == "0.50"
    assert stats.ci_text(0.85, (0.7, 0.95)) == "0.85 [0.70, 0.95]"
