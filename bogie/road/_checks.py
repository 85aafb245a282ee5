"""The road inputs' shared checks and array helpers (private)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def _finite_array(name: str, value: ArrayLike, unit: str) -> np.ndarray:
    """``value`` as a float ndarray, or a ValueError naming the first non-finite entry."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not an array of numbers in {unit}") from None
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f"{name}[{', '.join(map(str, idx))}]" if idx else name
        raise ValueError(f"{where} = {float(arr[idx])!r} is not finite: every {name} must be a finite number in {unit}")
    return arr


def _read_only(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=float)
    arr.flags.writeable = False
    return arr


def _frozen(arr: np.ndarray) -> np.ndarray:
    """``arr`` itself (a float array made here, referenced nowhere else), made read-only without a copy."""
    arr.flags.writeable = False
    return arr


def _uniform_interp(
    x: np.ndarray, grid_x: np.ndarray, grid_h: np.ndarray, slope: np.ndarray, points_per_m: float
) -> np.ndarray | None:
    """``np.interp(x, grid_x, grid_h)`` value for value on a uniform grid (``grid_x[k]`` = k / points_per_m up to
    rounding), the interval found by arithmetic instead of a binary search; None (use np.interp) if some x is not
    strictly inside the grid's span after one correction each way.

    np.interp returns ``grid_h[j]`` where x is ``grid_x[j]`` and ``slope[j] (x - grid_x[j]) + grid_h[j]`` between,
    ``slope[j]`` = (grid_h[j + 1] - grid_h[j]) / (grid_x[j + 1] - grid_x[j]): the same operations here.
    """
    last = len(grid_x) - 2
    j = np.minimum((x * points_per_m).astype(np.intp), last)
    np.maximum(j, 0, out=j)
    j -= grid_x[j] > x
    np.maximum(j, 0, out=j)
    j += grid_x[j + 1] <= x
    np.minimum(j, last, out=j)
    lo = grid_x[j]
    if not ((lo <= x) & (x < grid_x[j + 1])).all():
        return None
    h = grid_h[j]
    return np.where(x == lo, h, slope[j] * (x - lo) + h)
