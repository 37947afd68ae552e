"""bench.sweep's reliability line: the figures the tuning records in docs/RESULTS.md quote."""
import numpy as np

from bench.sweep import reliability


def test_the_sweeps_reliability_figures_count_late_dips_and_low_means():
    rates = np.ones((4, 60))
    rates[0, 44] = 0.6  # cycle 45: before 50, only the means count it
    rates[1, 54:56] = 0.7  # cycles 55-56: two seed-cycles below 0.8
    rates[2, 59] = 0.8  # cycle 60: 0.8 is not below 0.8
    line = reliability(rates, 0.93)
    assert "lowest mean from cycle 40 0.900" in line and "cycles from 40 with mean < 0.95: 3;" in line  # cycles 45, 55, 56
    assert "seed-cycles below 0.8 from cycle 50: 2/44" in line and "lowest mean from cycle 50 0.925" in line
    assert "cycles from 50 with mean >= 0.93: 9/11" in line
    assert "mean stays >= 0.93 from cycle 57" in line  # cycles 55-56 are the last below 0.93
    assert "mean stays >= 0.95 from cycle 1" in reliability(np.ones((2, 50)), 0.95)
    assert reliability(rates[:, :49], 0.95) == "reliability: needs 50 cycles or more"
