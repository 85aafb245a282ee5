"""bogie.intervals.wilson_interval is scipy's Wilson interval, bit for bit, without scipy.stats."""

import numpy as np
import pytest
from scipy.stats import binomtest

from bogie.intervals import wilson_interval


def test_the_wilson_interval_is_scipys_to_the_bit():
    ks, ns = np.meshgrid(np.arange(0, 41), np.array([1, 2, 3, 7, 40, 1000, 123_457]))
    ks = np.minimum(ks, ns)
    for confidence in (0.9, 0.95, 0.99):
        low, high = wilson_interval(ks.ravel(), ns.ravel(), confidence)
        for k, n, lo, hi in zip(ks.ravel(), ns.ravel(), low, high):
            ci = binomtest(int(k), int(n)).proportion_ci(confidence, method="wilson")
            assert (lo, hi) == (ci.low, ci.high), (k, n, confidence)
    low, high = wilson_interval(np.array([0]), np.array([0]))
    assert np.isnan(low[0]) and np.isnan(high[0])


def test_the_tabled_normal_quantiles_are_scipys_and_any_other_level_asks_scipy():
    from scipy.special import ndtri

    from bogie import intervals

    for confidence, z in intervals._Z.items():
        assert z == ndtri(0.5 + 0.5 * confidence), confidence
    assert intervals._z(0.8) == ndtri(0.9)
    low, high = wilson_interval(np.array([3]), np.array([40]), 0.8)
    ci = binomtest(3, 40).proportion_ci(0.8, method="wilson")
    assert (low[0], high[0]) == (ci.low, ci.high)


def test_the_percentile_interval_is_the_tails_quantiles_by_hand_and_to_the_bit():
    from bogie.intervals import percentile_interval

    # five draws 0..4 at 50 %: the 25 % and 75 % quantiles, at virtual indexes 1 and 3 exactly
    assert percentile_interval(np.arange(5.0), 0.5) == (1.0, 3.0)
    # at 90 % of 0..10: (1 - 0.9) / 2 = 0.04999999999999999 (binary), index 0.4999999999999999 -> 0.5 to 1e-15
    low, high = percentile_interval(np.arange(11.0), 0.9)
    assert low == pytest.approx(0.5, abs=1e-14) and high == pytest.approx(9.5, abs=1e-14)
    # the arithmetic every site used before it was one function: each tail's quantile on its own, to the bit
    draws = np.random.default_rng(7).normal(size=(997, 3))
    for level in (0.9, 0.95, 0.99):
        tail = (1.0 - level) / 2.0
        low, high = percentile_interval(draws[:, 1], level)
        assert (low, high) == (np.quantile(draws[:, 1], tail), np.quantile(draws[:, 1], 1 - tail))
        lows, highs = percentile_interval(draws, level, axis=0)
        assert np.array_equal(lows, np.quantile(draws, tail, axis=0))
        assert np.array_equal(highs, np.quantile(draws, 1 - tail, axis=0))
