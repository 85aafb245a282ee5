"""The simulated fleet seen as an observed survey sees it: its readings through the survey's filters, side by side.

An observed survey (:func:`bogie.weighings.survey.observed_survey`: a road authority's WIM or weighbridge file read,
split into axle groups and filtered) and the fleet's runs (:func:`bogie.fleet.weigh_fleet`) go through the one
definition of the survey statistics, :func:`bogie.weighings.stats.survey_statistics`: :func:`simulated_readings`
puts the runs through the survey's filters at the file's weight resolution, and :func:`compare` tabulates both sides.
The simulated groups are the fleet's trailer groups: failed runs and WIM readings with a wheel in the air are left
out, as the survey leaves them out, and counted.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from bogie.params import GRAVITY
from bogie.weighings.stats import (
    STATISTICS_COLUMNS,
    at_resolution,
    group_inequality,
    statistics_dict,
    survey_statistics,
)
from bogie.weighings.survey import SURVEYED, ObservedSurvey

__all__ = [
    "INEQUALITY_COLUMNS", "READING_RUN_COLUMNS", "SIMULATED_COLUMNS", "SIMULATED_POSITIONS", "by_size", "compare",
    "simulated_readings", "simulated_statistics", "with_inequality",
]  # fmt: skip

#: the positions a simulated group has: every simulated bogie is a semi-trailer's group
SIMULATED_POSITIONS: tuple[str, ...] = ("all", "trailer")
#: the axle columns of the group tables (the widest group surveyed is a tri-axle)
_AXLES = 3
#: the run columns :func:`simulated_readings` reads
READING_RUN_COLUMNS: tuple[str, ...] = (
    "sample_id", "group", "n_axles", "protocol", "status", "wheel_airborne", "group_load",
    *(f"axle_load_{i + 1}" for i in range(_AXLES)),
)  # fmt: skip
#: per-group inequality quantities of both sides (bogie.weighings.stats.group_inequality's definitions)
INEQUALITY_COLUMNS: tuple[str, ...] = (
    *(f"load_share_{i + 1}" for i in range(_AXLES)), "spread_kg", "spread_pct", "outside_5pct", "over_10pct",
)  # fmt: skip
#: one simulated reading kept: sample, protocol, group, axles, group load [kg], axle loads [kg], inequality
SIMULATED_COLUMNS: tuple[str, ...] = (
    "sample_id", "protocol", "group", "n_axles", "group_load", *(f"axle_load_{i + 1}" for i in range(_AXLES)),
    *INEQUALITY_COLUMNS,
)  # fmt: skip


def with_inequality(groups: pd.DataFrame) -> pd.DataFrame:
    """``groups`` (wide: ``n_axles``, ``axle_load_1..3``) with each group's load shares, spread [kg, %] and flags.

    Groups of more than three axles or single axles (``other``) get NaN shares and spread and False flags: the survey
    statistics cover tandems and tri-axles.
    """
    out = groups.reset_index(drop=True).copy()
    n = out["n_axles"].to_numpy(dtype=np.int64)
    surveyed = (n >= 2) & (n <= _AXLES)
    loads = out[[f"axle_load_{i + 1}" for i in range(_AXLES)]].to_numpy(dtype=float)[surveyed]
    ineq = group_inequality(loads, n[surveyed])
    for i in range(_AXLES):
        out[f"load_share_{i + 1}"] = np.nan
        out.loc[surveyed, f"load_share_{i + 1}"] = ineq["load_share"][:, i]
    for name, column in (("spread", "spread_kg"), ("spread_pct", "spread_pct")):
        out[column] = np.nan
        out.loc[surveyed, column] = ineq[name]
    for name, column in (("outside_5pct", "outside_5pct"), ("over_10pct", "over_10pct")):
        out[column] = False
        out.loc[surveyed, column] = ineq[name]
    return out


def simulated_readings(
    runs: pd.DataFrame, min_group_load_kg: float = 0.0, position: str = "all", weight_step_kg: float | None = None
) -> tuple[pd.DataFrame, dict[str, dict[str, int]]]:
    """The fleet's readings under the observed survey's filters, and what was left out, per protocol.

    Every reading (each protocol's) is first read at the observed file's weight resolution ``weight_step_kg``
    (:func:`bogie.weighings.stats.at_resolution`): each axle load rounded to the step, the group load their sum, as
    the observed groups' are; then the filters apply.

    Parameters
    ----------
    runs
        The fleet study's runs (every protocol, failed rows included).
    min_group_load_kg
        Smallest group load kept [kg] (the runs' loads are in N: kg x GRAVITY).
    position
        The survey's position filter: ``all`` and ``trailer`` keep every simulated group, ``steer`` and ``drive``
        none (:data:`SIMULATED_POSITIONS`).
    weight_step_kg
        The observed file's weight resolution [kg]; None reads the simulated loads as they are (no survey, or a file
        of loads that are not whole kilograms).

    Returns
    -------
    readings : pandas.DataFrame
        The columns of :data:`SIMULATED_COLUMNS`, loads in kg, sorted by protocol and sample.
    counts : dict
        Per protocol: ``n_runs``, ``n_failed``, ``n_airborne`` (a WIM reading with a wheel in the air), ``n_light``
        (below ``min_group_load_kg``), ``n_position`` (left out by the position filter) and ``n_kept``.
    """
    failed = runs["status"].astype(str) != "ok"
    airborne = ~failed & runs["wheel_airborne"].fillna(False).astype(bool)
    usable = ~failed & ~airborne
    n_axles = runs["n_axles"].to_numpy(dtype=np.int64)
    # each axle's reading [kg] at the file's resolution; a tandem's third load is no axle: NaN, as in the observed table
    loads = np.column_stack([
        np.where(n_axles > i, runs[f"axle_load_{i + 1}"].to_numpy(dtype=float) / GRAVITY, np.nan) for i in range(_AXLES)
    ])  # fmt: skip
    if weight_step_kg is not None:
        loads = at_resolution(loads, weight_step_kg)
        group_load = np.nansum(loads, axis=1)
    else:
        group_load = runs["group_load"].to_numpy(dtype=float) / GRAVITY
    light = usable & (group_load < min_group_load_kg)
    by_position = usable & ~light & (position not in SIMULATED_POSITIONS)
    kept = usable & ~light & ~by_position
    counts = _protocol_counts(runs["protocol"].astype(str), failed, airborne, light, by_position, kept)
    frame = runs.loc[kept, list(READING_RUN_COLUMNS[:4])].astype({"group": str, "protocol": str})
    kept_rows = np.asarray(kept, dtype=bool)
    frame["group_load"] = group_load[kept_rows]
    for i in range(_AXLES):
        frame[f"axle_load_{i + 1}"] = loads[kept_rows, i]
    frame = frame.sort_values(["protocol", "sample_id"], kind="stable")
    return with_inequality(frame)[list(SIMULATED_COLUMNS)], counts


def _protocol_counts(
    protocol: pd.Series, failed: pd.Series, airborne: pd.Series, light: pd.Series, by_position: pd.Series,
    kept: pd.Series,
) -> dict[str, dict[str, int]]:  # fmt: skip
    """The counts of :func:`simulated_readings` per protocol, from each run's protocol and boolean masks."""
    counts = {}
    for name in sorted(set(protocol)):
        sel = protocol == name
        counts[name] = {
            "n_runs": int(sel.sum()), "n_failed": int((sel & failed).sum()), "n_airborne": int((sel & airborne).sum()),
            "n_light": int((sel & light).sum()), "n_position": int((sel & by_position).sum()),
            "n_kept": int((sel & kept).sum()),
        }  # fmt: skip
    return counts


def by_size(stats: pd.DataFrame) -> dict[str, dict]:
    """:func:`statistics_dict` of one side, with an entry (``n_groups`` 0, nulls) for a size with no group."""
    found = statistics_dict(stats) if len(stats) else {}
    empty = {"n_groups": 0, **dict.fromkeys(STATISTICS_COLUMNS[1:]), "load_share_quantiles": {}}
    return {size: found.get(size, empty) for size in SURVEYED}


def simulated_statistics(readings: pd.DataFrame, counts: Mapping[str, Mapping[str, int]]) -> dict[str, Any]:
    """Per protocol: the runs left out (``runs``) and the survey statistics of the readings kept (``groups``)."""
    out = {}
    for protocol, count in counts.items():
        sub = readings[readings["protocol"] == protocol]
        # survey_statistics takes loads in kg here (unit_per_kg 1): the table is converted already
        stats = survey_statistics(sub, by="group") if len(sub) else pd.DataFrame()
        out[protocol] = {"runs": dict(count), "groups": by_size(stats)}
    return out


def compare(
    runs: pd.DataFrame, observed: ObservedSurvey, *, min_group_load_kg: float = 0.0, position: str = "all"
) -> pd.DataFrame:
    """The survey statistics of an observed survey and of the simulated fleet's readings, one row per side and group.

    Parameters
    ----------
    runs
        The fleet's runs (:func:`bogie.fleet.weigh_fleet`), every protocol, failed rows included (counted, not used).
    observed
        The observed survey (:func:`bogie.weighings.survey.observed_survey`), filtered as wanted.
    min_group_load_kg
        Smallest simulated group load kept [kg]: the observed survey's own filter, for a like-for-like comparison.
    position
        The observed survey's position filter (``all``, ``trailer``: every simulated group; ``steer``, ``drive``:
        none).

    Returns
    -------
    pandas.DataFrame
        ``source`` (``observed``, then each protocol), then the columns of
        :func:`bogie.weighings.stats.survey_statistics` (``group``, ``n_groups``, shares as fractions 0..1, spreads
        in kg and %, the load-share quantiles); the simulated loads are read at the observed file's weight resolution
        first (:func:`bogie.weighings.stats.at_resolution`).
    """
    readings, _ = simulated_readings(runs, min_group_load_kg, position, observed.read.weight_step_kg)
    sides = [observed.statistics.assign(source="observed")]
    for protocol, sub in readings.groupby("protocol", sort=True):
        sides.append(survey_statistics(sub, by="group").assign(source=protocol))
    table = pd.concat([side for side in sides if len(side)], ignore_index=True)
    return table[["source", *(c for c in table.columns if c != "source")]]
