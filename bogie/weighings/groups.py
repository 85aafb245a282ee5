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

from bogie.group_names import GROUP_OF_AXLES
from bogie.settings import check_value
from bogie.weighings._groups_core import split_groups
from bogie.weighings._records import REL_TOL
from bogie.weighings.settings import GROUP_FILTER, POSITIONS

__all__ = [
    "GROUPING_RULES", "GROUP_SPACING_M", "GROUP_TABLE_COLUMNS", "POSITIONS", "SIZES", "US_TANDEM_M", "axle_groups",
    "filter_groups", "grouping_rule",
]  # fmt: skip

#: largest spacing of two axles of one group [m] (issue 13's default; see the module text)
GROUP_SPACING_M: float = 2.0
#: the US tandem axle (23 CFR 658.5): consecutive axles more than 40 in and not more than 96 in apart [m] (an inch
#: is 0.0254 m exactly)
US_TANDEM_M: tuple[float, float] = (40 * 0.0254, 96 * 0.0254)
#: the grouping rules :func:`axle_groups` applies: ``spacing`` (axles at most ``group_spacing_m`` apart) and
#: ``us-tandem`` (23 CFR 658.5's spacing band, :data:`US_TANDEM_M`)
GROUPING_RULES: tuple[str, ...] = ("spacing", "us-tandem")
#: group labels by number of axles (:mod:`bogie.group_names`)
SIZES: dict[int, str] = GROUP_OF_AXLES
#: most axles in a group's columns of the group table [-] (a group with more is labelled ``other``)
_GROUP_COLUMNS = 3
#: the columns of the group table (:func:`axle_groups`), in order; units in its docstring
GROUP_TABLE_COLUMNS: tuple[str, ...] = (
    "line", "timestamp", "speed", "lane", "vehicle_groups", "group_index", "first_axle", "n_axles", "group",
    "position", "group_load", *(f"axle_load_{i + 1}" for i in range(_GROUP_COLUMNS)),
    *(f"spacing_{i + 1}" for i in range(_GROUP_COLUMNS - 1)),
)  # fmt: skip


def grouping_rule(rule: str, group_spacing_m: float = GROUP_SPACING_M) -> str:
    """The grouping rule in words, as the outputs name it."""
    if rule == "us-tandem":
        low, high = US_TANDEM_M
        return (f"us-tandem: consecutive axles more than 40 in ({low:g} m) and at most 96 in ({high:g} m) apart "
                "(23 CFR 658.5)")  # fmt: skip
    return f"spacing: consecutive axles at most {group_spacing_m:g} m apart"


def axle_groups(
    vehicles: pd.DataFrame, group_spacing_m: float = GROUP_SPACING_M, rule: str = "spacing"
) -> pd.DataFrame:
    """Split each vehicle into axle groups.

    Parameters
    ----------
    vehicles
        The vehicle table of :func:`bogie.weighings.readers.read_weighings`: ``n_axles``, ``axle_load_1..`` [kg],
        ``spacing_1..`` [m], ``line``, ``timestamp``, ``speed`` [m/s], ``lane``.
    group_spacing_m
        Largest spacing between two consecutive axles of one group, in (0, 5] [m] (rule ``spacing``).
    rule
        ``spacing`` (default) or ``us-tandem``: two consecutive axles are in one group when their spacing is more
        than 40 in and at most 96 in (23 CFR 658.5's tandem axle), ``group_spacing_m`` not used. A spacing read
        at 0.1 m (TMG 2001) is compared as read: 2.4 m is in, 2.5 m out; the file cannot place 2.4384 m closer.

    Returns
    -------
    pandas.DataFrame
        One row per group, front group first within a vehicle: ``line``, ``timestamp``, ``speed`` [m/s],
        ``lane`` (of its vehicle), ``vehicle_groups`` (groups of the vehicle), ``group_index`` (1 = front),
        ``first_axle`` (1 = the vehicle's front axle: axles and groups count from 1, as in the
        CSV layout, the CLI and the JSON), ``n_axles``, ``group`` (size label) and ``position`` (both
        categorical),
        ``group_load`` [kg], ``axle_load_1..3`` [kg] (front first; NaN past the group's axles or for a group of
        more than three) and ``spacing_1..2`` [m].
    """
    GROUP_FILTER["group_spacing"].check("group_spacing_m", group_spacing_m)
    if rule not in GROUPING_RULES:
        raise ValueError(f"rule = {rule!r} unknown; allowed: {', '.join(GROUPING_RULES)}")
    columns = list(GROUP_TABLE_COLUMNS)
    if not len(vehicles):
        return pd.DataFrame(columns=columns)
    # every vehicle at once (a year of a WIM site is millions of vehicles), in one compiled pass over the axles
    n = vehicles["n_axles"].to_numpy(dtype=np.int64)
    width = int(n.max())
    loads = vehicles[[f"axle_load_{i + 1}" for i in range(width)]].to_numpy(dtype=float)
    gaps = vehicles[[f"spacing_{i + 1}" for i in range(width - 1)]].to_numpy(dtype=float).reshape(len(n), width - 1)
    # a spacing equal to a limit (read from the file as an integer times its unit) is within the group
    if rule == "us-tandem":
        low, high = US_TANDEM_M[0] * (1.0 + REL_TOL), US_TANDEM_M[1] * (1.0 + REL_TOL)
    else:
        low, high = -np.inf, group_spacing_m * (1.0 + REL_TOL)
    vehicle_of, index, first_axle, size, group_load, axle_loads, spacings, n_groups = split_groups(
        n, np.ascontiguousarray(loads), np.ascontiguousarray(gaps), low, high
    )
    out = pd.DataFrame({
        "line": vehicles["line"].to_numpy()[vehicle_of], "timestamp": vehicles["timestamp"].to_numpy()[vehicle_of],
        "speed": vehicles["speed"].to_numpy()[vehicle_of], "lane": vehicles["lane"].to_numpy()[vehicle_of],
        "vehicle_groups": n_groups[vehicle_of], "group_index": index + 1, "first_axle": first_axle + 1, "n_axles": size,
        "group": _labels(np.minimum(size, 4), [SIZES.get(k, "other") for k in range(5)]),
        "position": _labels(np.minimum(index, 2), ("steer", "drive", "trailer")),
        "group_load": group_load,
        **{f"axle_load_{i + 1}": axle_loads[:, i] for i in range(_GROUP_COLUMNS)},
        **{f"spacing_{i + 1}": spacings[:, i] for i in range(_GROUP_COLUMNS - 1)},
    }, copy=False)  # fmt: skip
    return out[columns]


def _labels(codes: np.ndarray, labels: Sequence[str]) -> pd.Series:
    """``labels[codes]`` as a categorical column of the distinct labels (a million Python strings take pandas half
    a second to make; the codes, a few milliseconds). It compares, filters, groups and writes as the strings do."""
    distinct = list(dict.fromkeys(labels))
    where = np.array([distinct.index(label) for label in labels])
    return pd.Series(pd.Categorical.from_codes(where[codes], categories=distinct))


def filter_groups(
    groups: pd.DataFrame,
    *,
    min_group_load_kg: float = 0.0,
    position: str = "all",
    speed_kmh: Sequence[float] | None = None,
) -> pd.DataFrame:
    """The groups that pass the filters (a fresh index).

    Parameters
    ----------
    groups
        The table of :func:`axle_groups`.
    min_group_load_kg
        Smallest group load kept, in [0, 100 000] [kg]: laden groups only (e.g. 15 000 kg for tri-axles). The
        filters are keywords only (issue 42 made the load kilograms, as the records hold it; it was tonnes).
    position
        ``all``, ``steer``, ``drive`` or ``trailer``.
    speed_kmh
        (lowest, highest) speed kept, inclusive, 0 <= lowest <= highest <= 160 [km/h]; None keeps every speed,
        a range drops groups of unknown speed.
    """
    GROUP_FILTER["min_group_load"].check("min_group_load_kg", min_group_load_kg)
    GROUP_FILTER["position"].check("position", position)
    keep = groups["group_load"].to_numpy() >= min_group_load_kg
    if position != "all":
        keep &= (groups["position"] == position).to_numpy(dtype=bool)
    if speed_kmh is not None:
        low, high = speed_kmh
        check_value("speed_kmh lowest", low, "km/h", low=0.0, high=160.0)
        check_value("speed_kmh highest", high, "km/h", low=low, high=160.0)
        speed = 3.6 * groups["speed"].to_numpy(dtype=float)
        # 1e-9 km/h: a speed read in km/h comes back from m/s a rounding error off, and the bounds are inclusive
        keep &= (speed >= low - 1e-9) & (speed <= high + 1e-9)
    return groups[keep].reset_index(drop=True)
