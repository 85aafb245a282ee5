"""Axle-load inequality metrics: the reference's p, P1 and RMS (Equations 2, 4, 5) and the field's LSC, DLC and
road-wear factor.

Every function takes wheel loads with the axles on the **last** axis, so it works on one load set ``(n,)``, a
time history ``(n_t, n)`` or a whole fleet ``(n_bogies, n)``. Loads may be in newtons or non-dimensional; p and
P1 come out in the same unit, the others are dimensionless. Definitions and the n-axle generalisations are in
``docs/metrics.md``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics


def _loads(loads: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(loads, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] < 2:
        raise ValueError(f"loads has shape {arr.shape}: the last axis must hold the wheel loads of >= 2 axles")
    return arr


def reference_axle(n_axles: int) -> int:
    """Index of the axle that Equation 2 measures the others against: the middle one, the front one for n = 2.

    For even n > 2 it is the front one of the two middle axles: (n - 1) // 2.
    """
    return (n_axles - 1) // 2


def p(loads: ArrayLike) -> NDArray[np.float64]:
    """Wheel load deviation parameter p of Equation 2, generalised to n axles.

    p = sqrt(sum_{i != r} (W_i - W_r)^2) with r = :func:`reference_axle`: for three axles
    sqrt((W_1 - W_2)^2 + (W_3 - W_2)^2) exactly, for two |W_1 - W_2|. Zero when the loads are equal.
    """
    arr = _loads(loads)
    r = reference_axle(arr.shape[-1])
    dev = arr - arr[..., r : r + 1]
    return np.sqrt(np.sum(dev * dev, axis=-1))


def p1(loads: ArrayLike) -> NDArray[np.float64]:
    """Wheel load parameter P1 of Equation 4: the root mean square deviation of the loads from their mean.

    P1 = sqrt(sum_i (W_i - W_m)^2 / n). For two axles P1 = p / 2.
    """
    arr = _loads(loads)
    return np.std(arr, axis=-1)


def rms(loads: ArrayLike) -> NDArray[np.float64]:
    """RMS equalisation parameter of Equation 5 over a time history (time on axis -2, axles on axis -1).

    RMS = sqrt(mean_t (P1_t / mean_t W)^2). For two axles P1 / mean = |W_1 - W_2| / (W_1 + W_2), so this is the
    reference's (1/n_t sum ((W_1 - W_2) / (W_1 + W_2))^2)^(1/2) exactly; for n axles it is the time-RMS of the
    coefficient of variation of the axle loads.
    """
    arr = _loads(loads)
    if arr.ndim < 2:
        raise ValueError(f"loads has shape {arr.shape}: rms needs a time history of shape (n_t, n_axles)")
    cov = p1(arr) / np.mean(arr, axis=-1)
    return np.sqrt(np.mean(cov * cov, axis=-1))


def lsc(loads: ArrayLike) -> NDArray[np.float64]:
    """Load sharing coefficient of each axle, LSC_i = n W_i / sum_j W_j [-]; 1 is perfect sharing."""
    arr = _loads(loads)
    return arr.shape[-1] * arr / np.sum(arr, axis=-1, keepdims=True)


def max_deviation(loads: ArrayLike) -> NDArray[np.float64]:
    """Largest relative deviation of an axle load from the group mean, max_i |W_i - W_m| / W_m [-]."""
    arr = _loads(loads)
    mean = np.mean(arr, axis=-1, keepdims=True)
    return np.max(np.abs(arr - mean), axis=-1) / mean[..., 0]


def spread(loads: ArrayLike) -> NDArray[np.float64]:
    """Heaviest minus lightest axle load, in the unit of ``loads``."""
    arr = _loads(loads)
    return np.max(arr, axis=-1) - np.min(arr, axis=-1)


def dlc(history: ArrayLike) -> NDArray[np.float64]:
    """Dynamic load coefficient of each wheel over a time history (time on axis 0): SD over mean [-]."""
    arr = np.asarray(history, dtype=float)
    if arr.ndim < 1 or arr.shape[0] < 2:
        raise ValueError(f"history has shape {arr.shape}: dlc needs at least 2 time samples on axis 0")
    return np.std(arr, axis=0) / np.mean(arr, axis=0)


def road_wear_factor(loads: ArrayLike) -> NDArray[np.float64]:
    """Fourth-power road-wear factor sum_i (W_i / W_m)^4 / n [-]: 1 for equal loads, more for unequal ones."""
    arr = _loads(loads)
    ratio = arr / np.mean(arr, axis=-1, keepdims=True)
    return np.mean(numerics.power(ratio, 4.0), axis=-1)  # not ratio**4: numpy's power is the CPU's SIMD loop
