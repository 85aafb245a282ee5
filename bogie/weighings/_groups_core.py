"""The compiled kernel of :func:`bogie.weighings.groups.axle_groups`: every vehicle's axles split into groups in one
pass over the axles (issue 41 Must 4: the array version took a second a million vehicles, the kernel a few tens of
milliseconds). Sums are in axle order, front first, one add at a time: the bits of the array version's
``np.bincount``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: most axles of a group whose loads and spacings are given column by column (a larger group: NaN there)
GROUP_COLUMNS = 3


@njit(cache=True, nogil=True)
def split_groups(n, loads, gaps, low, high):  # pragma: no cover - compiled
    """Groups of each vehicle: a new group starts after a spacing above ``high`` or at most ``low`` [m] (NaN: no
    new group). Returns (vehicle, index in vehicle, first axle (0-based), axles, group load, loads (groups, 3),
    spacings (groups, 2), groups of each vehicle)."""
    m = n.shape[0]
    per_vehicle = np.ones(m, np.int64)
    for v in range(m):
        for i in range(n[v] - 1):
            g = gaps[v, i]
            if g > high or g <= low:
                per_vehicle[v] += 1
    total = 0
    for v in range(m):
        total += per_vehicle[v]
    vehicle = np.empty(total, np.int64)
    index = np.empty(total, np.int64)
    first = np.empty(total, np.int64)
    size = np.zeros(total, np.int64)
    load = np.zeros(total)
    axle_loads = np.full((total, GROUP_COLUMNS), np.nan)
    spacings = np.full((total, GROUP_COLUMNS - 1), np.nan)
    k = -1
    for v in range(m):
        j = 0
        for i in range(n[v]):
            if i == 0 or gaps[v, i - 1] > high or gaps[v, i - 1] <= low:
                k += 1
                vehicle[k] = v
                index[k] = j
                first[k] = i
                j += 1
            size[k] += 1
            load[k] += loads[v, i]
    # the group's own loads and spacings, front first, for groups of at most three axles
    for g in range(total):
        if size[g] <= GROUP_COLUMNS:
            v = vehicle[g]
            for a in range(size[g]):
                axle_loads[g, a] = loads[v, first[g] + a]
                if a < size[g] - 1:
                    spacings[g, a] = gaps[v, first[g] + a]
    return vehicle, index, first, size, load, axle_loads, spacings, per_vehicle
