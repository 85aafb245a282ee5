"""The project's intervals, one definition each (issue 42 Must 2): the Wilson score interval of a proportion,
without importing scipy.stats (a second of import time, issue 41 Must 4: ``bogie weighings`` paid it for one
interval), for the design table and the road figures; and the percentile interval of bootstrap or posterior draws,
for the road figures, the calibration's fitted values, posterior and attribution. The ablation's paired intervals
are scipy's ``stats.bootstrap`` (percentile method) on the same vocabulary: a ``confidence_level`` in (0, 1).
"""

from __future__ import annotations

from math import sqrt
from typing import Any

import numpy as np

__all__ = ["percentile_interval", "wilson_interval"]

#: the normal quantiles of the common levels, scipy.special.ndtri(0.5 + confidence_level / 2)'s bits (``tests/
#: test_intervals.py`` holds them equal), so that a command that needs one interval does not import scipy.special
#: (0.26 s of ``bogie weighings``' 3.7 s on a year of records, issue 41 Must 4); any other level asks scipy
_Z = {0.9: 1.6448536269514722, 0.95: 1.959963984540054, 0.99: 2.5758293035489004}


def _z(confidence_level: float) -> float:
    """scipy.special.ndtri(0.5 + 0.5 confidence_level): the two-sided normal quantile of ``confidence_level``."""
    if confidence_level in _Z:
        return _Z[confidence_level]
    from scipy.special import ndtri

    return float(ndtri(0.5 + 0.5 * confidence_level))


def wilson_interval(k: np.ndarray, n: np.ndarray, confidence_level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval of each proportion ``k / n``; NaN where ``n`` is 0.

    The interval of :meth:`scipy.stats.binomtest(k, n).proportion_ci(method="wilson")
    <scipy.stats._result_classes.BinomTestResult.proportion_ci>` (two-sided, no continuity correction), computed
    with scipy's own expressions in their order (``scipy/stats/_binomtest.py``, ``_binom_wilson_conf_int``), so
    with its bits: ``tests/test_intervals.py`` holds the two equal.

    References
    ----------
    E. B. Wilson, "Probable inference, the law of succession, and statistical inference", Journal of the American
    Statistical Association 22 (1927), 209-212; R. G. Newcombe, Statistics in Medicine 17 (1998), 857-872.
    """
    k, n = np.asarray(k), np.asarray(n)
    low, high = np.full(k.shape, np.nan), np.full(k.shape, np.nan)
    z = _z(confidence_level)
    for i in np.flatnonzero(n > 0):
        ki, ni = int(round(float(k.flat[i]))), int(n.flat[i])
        p = ki / ni
        denom = 2 * (ni + z**2)
        center = (2 * ni * p + z**2) / denom
        q = 1 - p
        delta = z / denom * sqrt(4 * ni * p * q + z**2)
        low.flat[i] = 0.0 if ki == 0 else center - delta
        high.flat[i] = 1.0 if ki == ni else center + delta
    return low, high


def percentile_interval(draws: np.ndarray, confidence_level: float, axis: int | None = None) -> tuple[Any, Any]:
    """The percentile interval of ``draws`` (bootstrap replicates, or posterior draws): their (1 - c) / 2 and
    1 - (1 - c) / 2 quantiles at ``confidence_level`` c, numpy's linear interpolation, over ``axis`` (None: all).
    B. Efron, R. J. Tibshirani, *An Introduction to the Bootstrap*, Chapman & Hall, 1993, ch. 13."""
    tail = (1.0 - confidence_level) / 2.0
    low, high = np.quantile(draws, [tail, 1 - tail], axis=axis)
    return low, high
