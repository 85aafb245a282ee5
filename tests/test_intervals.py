"""bogie.intervals.wilson_interval is scipy's Wilson interval, bit for bit, without scipy.stats."""

import numpy as np
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
