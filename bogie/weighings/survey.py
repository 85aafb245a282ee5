"""An observed survey from Python: read a file of weighings, split it into axle groups, filter, tabulate.

:func:`observed_survey` is what ``bogie weighings`` prints; its statistics are those of
:func:`bogie.weighings.stats.survey_statistics`, the function the pipeline's survey stage applies to the simulated
fleet.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bogie.weighings.groups import GROUP_SPACING_M, POSITIONS, SIZES, axle_groups, filter_groups
from bogie.weighings.readers import ReadResult, read_weighings
from bogie.weighings.stats import STATISTICS_COLUMNS, statistics_dict, survey_statistics
from bogie.weighings.wear import EU_LEGAL_AXLE_KG, EU_LEGAL_GROUP_KG, wear_dict, wear_statistics

__all__ = ["SURVEYED", "ObservedSurvey", "observed_survey"]

#: the group sizes the statistics are tabulated for
SURVEYED: tuple[str, ...] = ("tandem", "triaxle")


#: the size labels of the position counts, by axles in the group (4 and more: other)
SIZE_LABELS = {1: "single", **SIZES}


@dataclass
class ObservedSurvey:
    """An observed survey: the groups that passed the filters, their statistics and what the reader skipped.

    Attributes
    ----------
    groups
        One row per group (:func:`bogie.weighings.groups.axle_groups`), every size, after the filters.
    statistics
        :func:`bogie.weighings.stats.survey_statistics` of the tandems and tri-axles, one row each.
    read
        The reader's result: the vehicles and the skipped records.
    positions
        How many groups of each position (steer, drive, trailer) and size (single, tandem, triaxle, other: 4 or
        more axles) the file has,
        before any filter: in a WIM file most laden tandems are tractors' drive tandems, not trailer groups.
    road
        :func:`bogie.weighings.wear.wear_statistics` of the tandems and tri-axles, one row each: the extra pavement
        wear their unequal sharing causes and the overloaded axles hidden in legal groups.
    """

    groups: pd.DataFrame
    statistics: pd.DataFrame
    read: ReadResult
    positions: dict[str, dict[str, int]]
    road: pd.DataFrame

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``bogie weighings --json``: records read and skipped, then the statistics per group size.

        ``{"records": {"read", "skipped", "weight_step_kg"}, "positions": {"steer": {"tandem": n, ...}, ...},
        "groups": {"tandem": {...}, "triaxle": {...}}}``; shares are fractions 0..1; a size with no group has
        ``n_groups`` 0 and None for its numbers; ``weight_step_kg`` is the file's weight resolution in use [kg]
        (None: not whole kilograms), ``resolution`` where it came from and the evidence
        (:meth:`bogie.weighings.resolution.Resolution.to_dict`). ``road`` per size:
        :func:`bogie.weighings.wear.wear_statistics`'s figures (extra wear as a fraction, extra standard axles per
        1,000 groups, hidden overloads, with their intervals).
        """
        stats = statistics_dict(self.statistics)
        road = wear_dict(self.road, ["group"]) if len(self.road) else {}
        empty = {"n_groups": 0, **dict.fromkeys(STATISTICS_COLUMNS[1:]), "load_share_quantiles": {}}
        return {
            "records": {
                "read": self.read.n_read,
                "skipped": self.read.n_skipped,
                "weight_step_kg": self.read.weight_step_kg,
                "resolution": None if self.read.resolution is None else self.read.resolution.to_dict(),
            },
            "positions": self.positions,
            "groups": {size: stats.get(size, empty) for size in SURVEYED},
            "road": {size: road.get(size, {"n_groups": 0}) for size in SURVEYED},
        }


def observed_survey(
    path: str | Path,
    fmt: str,
    min_group_load_t: float = 0.0,
    group_spacing_m: float = GROUP_SPACING_M,
    position: str = "all",
    speed_kmh: Sequence[float] | None = None,
    legal_group_kg: dict[str, float] | None = None,
    legal_axle_kg: float = EU_LEGAL_AXLE_KG,
    resolution_kg: float | None = None,
) -> ObservedSurvey:
    """Read ``path`` in format ``fmt``, group the axles, filter the groups and compute the survey statistics.

    Parameters
    ----------
    path, fmt
        The file and its format (:func:`bogie.weighings.readers.read_weighings`).
    min_group_load_t
        Smallest group load kept [t].
    group_spacing_m
        Largest spacing of two axles of one group [m].
    position
        ``all``, ``steer``, ``drive`` or ``trailer``.
    speed_kmh
        (lowest, highest) speed kept [km/h]; None keeps every speed.
    legal_group_kg, legal_axle_kg
        Legal load of each group size and of one axle, for the hidden overloads [kg]; None: Directive 96/53/EC's
        (:data:`bogie.weighings.wear.EU_LEGAL_GROUP_KG`, 10 t an axle).
    resolution_kg
        The file's weight resolution [kg]; None: detected from its loads
        (:func:`bogie.weighings.readers.read_weighings`).

    Raises
    ------
    ValueError
        A file refused by the reader, or a parameter out of its range (named, with its unit).
    """
    read = read_weighings(path, fmt, resolution_kg)
    every = axle_groups(read.vehicles, group_spacing_m)
    axles = every["n_axles"].to_numpy()
    size = np.select([axles == k for k in SIZE_LABELS], list(SIZE_LABELS.values()), "other")
    positions = {
        where: {label: int(((every["position"] == where) & (size == label)).sum()) for label in (*SIZE_LABELS.values(),
                "other")}
        for where in POSITIONS[1:]
    }  # fmt: skip
    groups = filter_groups(every, min_group_load_t, position, speed_kmh)
    surveyed = groups[groups["group"].isin(SURVEYED)]
    statistics = survey_statistics(surveyed, by="group") if len(surveyed) else pd.DataFrame(columns=["group"])
    legal = dict(EU_LEGAL_GROUP_KG if legal_group_kg is None else legal_group_kg)
    road = wear_statistics(surveyed, legal, legal_axle_kg) if len(surveyed) else pd.DataFrame(columns=["group"])
    return ObservedSurvey(groups, statistics, read, positions, road)
