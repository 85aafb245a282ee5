"""Axle groups of weighed vehicles: consecutive axles close together, labelled by size and position, filtered.

A group is a run of consecutive axles each at most ``group_spacing_m`` from the next (default 2.0 m, issue 13: above
the 1.31 m spacing of this project's presets and the 1.0-1.8 m of common tandem and tri-axle bogies, below the
several metres from a tractor's drive axles to its semi-trailer's group). Size: ``tandem`` (2 axles), ``triaxle``
(3), ``other``. Position (issue 27): ``steer``, the group of the first axle; ``drive``, the second group (a tractor's
drive group, or a rigid truck's rear group); ``trailer``, every group after the second, so that a B-double's lead
trailer counts as a trailer as its rear trailer does (before, only a vehicle's last group did, and a lead trailer was
called a drive group). The group table is wide, as
:func:`bogie.weighings.stats.survey_statistics` takes it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

__all__ = ["GROUP_SPACING_M", "POSITIONS", "SIZES", "axle_groups", "filter_groups"]

#: largest spacing of two axles of one group [m] (issue 13's default; see the module text)
GROUP_SPACING_M: float = 2.0
#: group labels by number of axles
SIZES: dict[int, str] = {2: "tandem", 3: "triaxle"}
#: group positions a filter can ask for
POSITIONS: tuple[str, ...] = ("all", "steer", "drive", "trailer")
#: most axles in a group's columns of the group table [-] (a group with more is labelled ``other``)
_GROUP_COLUMNS = 3


def _check(name: str, value: float, low: float, high: float, unit: str, low_open: bool = False) -> None:
    bad = not (low < value <= high if low_open else low <= value <= high) or not np.isfinite(value)
    if bad:
        bracket = "(" if low_open else "["
        raise ValueError(f"{name} = {value!r} {unit} outside the allowed range {bracket}{low:g}, {high:g}] {unit}")


def axle_groups(vehicles: pd.DataFrame, group_spacing_m: float = GROUP_SPACING_M) -> pd.DataFrame:
    """Split each vehicle into axle groups.

    Parameters
    ----------
    vehicles
        The vehicle table of :func:`bogie.weighings.readers.read_weighings`: ``n_axles``, ``axle_load_0..`` [kg],
        ``spacing_0..`` [m], ``line``, ``timestamp``, ``speed`` [m/s], ``lane``.
    group_spacing_m
        Largest spacing between two consecutive axles of one group, in (0, 5] [m].

    Returns
    -------
    pandas.DataFrame
        One row per group, front group first within a vehicle: ``line``, ``timestamp``, ``speed`` [m/s],
        ``lane`` (of its vehicle), ``vehicle_groups`` (groups of the vehicle), ``group_index`` (0 = front),
        ``first_axle`` (0 = the vehicle's front axle), ``n_axles``, ``group`` (size label), ``position``,
        ``group_load`` [kg], ``axle_load_0..2`` [kg] (front first; NaN past the group's axles or for a group of
        more than three) and ``spacing_0..1`` [m].
    """
    _check("group_spacing_m", group_spacing_m, 0.0, 5.0, "m", low_open=True)
    rows = []
    load_cols = [c for c in vehicles.columns if c.startswith("axle_load_")]
    for v in vehicles.itertuples(index=False):
        n = int(v.n_axles)
        loads = np.array([getattr(v, c) for c in load_cols[:n]], dtype=float)
        spacings = np.array([getattr(v, f"spacing_{i}") for i in range(n - 1)], dtype=float)
        # a new group starts after every spacing wider than group_spacing_m
        starts = [0, *(i + 1 for i in np.flatnonzero(spacings > group_spacing_m))]
        ends = [*starts[1:], n]
        for k, (a, b) in enumerate(zip(starts, ends)):
            size = b - a
            position = "steer" if k == 0 else "drive" if k == 1 else "trailer"
            row = {
                "line": v.line, "timestamp": v.timestamp, "speed": v.speed, "lane": v.lane,
                "vehicle_groups": len(starts), "group_index": k, "first_axle": a, "n_axles": size,
                "group": SIZES.get(size, "other"), "position": position, "group_load": float(loads[a:b].sum()),
            }  # fmt: skip
            for i in range(_GROUP_COLUMNS):
                row[f"axle_load_{i}"] = loads[a + i] if i < size and size <= _GROUP_COLUMNS else np.nan
            for i in range(_GROUP_COLUMNS - 1):
                row[f"spacing_{i}"] = spacings[a + i] if i < size - 1 and size <= _GROUP_COLUMNS else np.nan
            rows.append(row)
    columns = [
        "line", "timestamp", "speed", "lane", "vehicle_groups", "group_index", "first_axle", "n_axles", "group",
        "position", "group_load", *(f"axle_load_{i}" for i in range(_GROUP_COLUMNS)),
        *(f"spacing_{i}" for i in range(_GROUP_COLUMNS - 1)),
    ]  # fmt: skip
    return pd.DataFrame(rows, columns=columns)


def filter_groups(
    groups: pd.DataFrame,
    min_group_load_t: float = 0.0,
    position: str = "all",
    speed_kmh: Sequence[float] | None = None,
) -> pd.DataFrame:
    """The groups that pass the filters (a fresh index).

    Parameters
    ----------
    groups
        The table of :func:`axle_groups`.
    min_group_load_t
        Smallest group load kept, in [0, 100] [t]: laden groups only (e.g. 15 t for tri-axles).
    position
        ``all``, ``steer``, ``drive`` or ``trailer``.
    speed_kmh
        (lowest, highest) speed kept, inclusive, 0 <= lowest <= highest <= 160 [km/h]; None keeps every speed,
        a range drops groups of unknown speed.
    """
    _check("min_group_load_t", min_group_load_t, 0.0, 100.0, "t")
    if position not in POSITIONS:
        raise ValueError(f"position = {position!r} unknown; allowed: {', '.join(POSITIONS)}")
    keep = groups["group_load"].to_numpy() >= 1000.0 * min_group_load_t
    if position != "all":
        keep &= groups["position"].to_numpy() == position
    if speed_kmh is not None:
        low, high = speed_kmh
        _check("speed_kmh lowest", low, 0.0, 160.0, "km/h")
        _check("speed_kmh highest", high, low, 160.0, "km/h")
        speed = 3.6 * groups["speed"].to_numpy(dtype=float)
        # 1e-9 km/h: a speed read in km/h comes back from m/s a rounding error off, and the bounds are inclusive
        keep &= (speed >= low - 1e-9) & (speed <= high + 1e-9)
    return groups[keep].reset_index(drop=True)
