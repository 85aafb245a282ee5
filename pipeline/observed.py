"""DVC stage ``observed``: an observed survey against the simulated fleet -> data/observed/, metrics/observed.json.

``python -m pipeline.observed`` reads the file of ``observed.path`` (a road authority's WIM or weighbridge records,
in ``observed/``; ``docs/observed.md``), splits it into axle groups and filters them
(:func:`bogie.weighings.survey.observed_survey`), and puts the fleet study's static and WIM readings through the
same filters. Both sides go through the one definition of the survey statistics,
:func:`bogie.weighings.stats.survey_statistics`. It writes:

- ``data/observed/groups.parquet``: one row per observed group that passed the filters (every size), with its
  load shares and spread; no row when no survey is given, the same columns and units;
- ``data/observed/simulated.parquet``: one row per simulated reading that passed the filters (protocol, group);
- ``metrics/observed.json``: the filters, the observed statistics (``null`` with a ``reason`` when no survey is
  given), the simulated statistics per protocol, and what the simulated WIM models.

The simulated groups are the fleet's trailer groups (tandem and tri-axle bogies): failed runs and WIM readings with a
wheel in the air are left out as the survey stage leaves them out, and counted; ``min_group_load_t`` applies to
their group loads too; ``position: drive`` or ``steer`` leaves no simulated group, and says so; ``group_spacing_m``
splits observed vehicles only (a simulated bogie is one group by construction). Nothing here has a date: the same
inputs give the same bytes.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import yaml

from bogie.params import GRAVITY
from bogie.weighings.stats import (
    STATISTICS_COLUMNS,
    at_resolution,
    group_inequality,
    statistics_dict,
    survey_statistics,
)
from bogie.weighings.survey import SURVEYED, observed_survey
from pipeline.atomic import atomic_outputs, io_error
from pipeline.config import ConfigError, ObservedConfig, WimProtocol, load_config, observed_file
from pipeline.survey import SURVEY_STUDY, RunsError, check_complete, read_runs

__all__ = [
    "GROUPS_SCHEMA", "SIMULATED_POSITIONS", "SIMULATED_SCHEMA", "observed_metrics", "observed_table", "main",
    "simulated_readings", "simulated_statistics", "wim_model",
]  # fmt: skip

#: the positions a simulated group has: every simulated bogie is a semi-trailer's group
SIMULATED_POSITIONS: tuple[str, ...] = ("all", "trailer")
#: the axle columns of the group tables (the widest group surveyed is a tri-axle)
_AXLES = 3
_RUN_COLUMNS = (
    "sample_id", "group", "n_axles", "protocol", "status", "wheel_airborne", "group_load",
    *(f"axle_load_{i}" for i in range(_AXLES)),
)  # fmt: skip


def _field(name: str, kind: pa.DataType, unit: str) -> pa.Field:
    return pa.field(name, kind, metadata={"unit": unit})


#: per-group quantities both tables carry (bogie.weighings.stats.group_inequality's definitions)
_INEQUALITY = [
    *(_field(f"load_share_{i}", pa.float64(), "-") for i in range(_AXLES)),
    _field("spread_kg", pa.float64(), "kg"),
    _field("spread_pct", pa.float64(), "%"),
    _field("outside_5pct", pa.bool_(), "-"),
    _field("over_10pct", pa.bool_(), "-"),
]
#: data/observed/groups.parquet: the columns of bogie.weighings.groups.axle_groups, then the inequality quantities
GROUPS_SCHEMA = pa.schema([
    _field("line", pa.int64(), "-"), _field("timestamp", pa.timestamp("us"), "-"), _field("speed", pa.float64(), "m/s"),
    _field("lane", pa.int64(), "-"), _field("vehicle_groups", pa.int64(), "-"), _field("group_index", pa.int64(), "-"),
    _field("first_axle", pa.int64(), "-"), _field("n_axles", pa.int64(), "-"), _field("group", pa.string(), "-"),
    _field("position", pa.string(), "-"), _field("group_load", pa.float64(), "kg"),
    *(_field(f"axle_load_{i}", pa.float64(), "kg") for i in range(_AXLES)),
    *(_field(f"spacing_{i}", pa.float64(), "m") for i in range(_AXLES - 1)),
    *_INEQUALITY,
])  # fmt: skip
#: data/observed/simulated.parquet: one row per simulated reading kept, loads in kg as the observed ones
SIMULATED_SCHEMA = pa.schema([
    _field("sample_id", pa.int64(), "-"), _field("protocol", pa.string(), "-"), _field("group", pa.string(), "-"),
    _field("n_axles", pa.int64(), "-"), _field("group_load", pa.float64(), "kg"),
    *(_field(f"axle_load_{i}", pa.float64(), "kg") for i in range(_AXLES)),
    *_INEQUALITY,
])  # fmt: skip


def with_inequality(groups: pd.DataFrame) -> pd.DataFrame:
    """``groups`` (wide: ``n_axles``, ``axle_load_0..2``) with each group's load shares, spread [kg, %] and flags.

    Groups of more than three axles or single axles (``other``) get NaN shares and spread and False flags: the survey
    statistics cover tandems and tri-axles.
    """
    out = groups.reset_index(drop=True).copy()
    n = out["n_axles"].to_numpy(dtype=np.int64)
    surveyed = (n >= 2) & (n <= _AXLES)
    loads = out[[f"axle_load_{i}" for i in range(_AXLES)]].to_numpy(dtype=float)[surveyed]
    ineq = group_inequality(loads, n[surveyed])
    for i in range(_AXLES):
        out[f"load_share_{i}"] = np.nan
        out.loc[surveyed, f"load_share_{i}"] = ineq["load_share"][:, i]
    for name, column in (("spread", "spread_kg"), ("spread_pct", "spread_pct")):
        out[column] = np.nan
        out.loc[surveyed, column] = ineq[name]
    for name, column in (("outside_5pct", "outside_5pct"), ("over_10pct", "over_10pct")):
        out[column] = False
        out.loc[surveyed, column] = ineq[name]
    return out


def _table(frame: pd.DataFrame, schema: pa.Schema) -> pa.Table:
    return pa.Table.from_pandas(frame[schema.names], schema=schema, preserve_index=False)


# ---- the observed side -------------------------------------------------------------------------------------------
def observed_table(path: Path | None, observed: ObservedConfig) -> tuple[pd.DataFrame, dict[str, Any] | None]:
    """The observed groups that pass the filters and their statistics (``bogie weighings --json``'s shape).

    Parameters
    ----------
    path
        The file of records, or None when no survey is given.
    observed
        The ``observed`` section (format, filters).

    Returns
    -------
    groups : pandas.DataFrame
        The columns of :data:`GROUPS_SCHEMA`; no row for no survey.
    statistics : dict or None
        ``{"path", "format" (the one read), "format_asked" (``auto`` or that one), "sha256", "records": {"read",
        "skipped", "weight_step_kg", "skipped_by_reason"}, "groups": {"tandem", "triaxle"}}``, or None for no
        survey.

    Raises
    ------
    ValueError
        The reader refused the file (named, with the format expected and what was found).
    """
    if path is None:
        empty = pd.DataFrame({f.name: pd.Series(dtype=f.type.to_pandas_dtype()) for f in GROUPS_SCHEMA})
        return empty, None
    survey = observed_survey(
        path, observed.format, observed.min_group_load / 1000.0, observed.group_spacing, observed.position
    )
    stats = survey.to_dict()
    stats["records"]["skipped_by_reason"] = dict(sorted(survey.read.skipped.items()))
    header = {
        "path": observed.path, "format": survey.read.format, "format_asked": observed.format,
        "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
    }  # fmt: skip
    return with_inequality(survey.groups), {**header, **stats}


# ---- the simulated side ------------------------------------------------------------------------------------------
def simulated_readings(
    runs: pd.DataFrame, min_group_load: float, position: str, weight_step_kg: float | None = None
) -> tuple[pd.DataFrame, dict[str, dict[str, int]]]:
    """The fleet's readings under the observed survey's filters, and what was left out, per protocol.

    Every reading (each protocol's) is first read at the observed file's weight resolution ``weight_step_kg``
    (:func:`bogie.weighings.stats.at_resolution`): each axle load rounded to the step, the group load their sum, as
    the observed groups' are; then the filters apply.

    Parameters
    ----------
    runs
        The fleet study's runs (every protocol, failed rows included).
    min_group_load
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
        The columns of :data:`SIMULATED_SCHEMA`, loads in kg, sorted by protocol and sample.
    counts : dict
        Per protocol: ``n_runs``, ``n_failed``, ``n_airborne`` (a WIM reading with a wheel in the air), ``n_light``
        (below ``min_group_load``), ``n_position`` (left out by the position filter) and ``n_kept``.
    """
    failed = runs["status"].astype(str) != "ok"
    airborne = ~failed & runs["wheel_airborne"].fillna(False).astype(bool)
    usable = ~failed & ~airborne
    n_axles = runs["n_axles"].to_numpy(dtype=np.int64)
    # each axle's reading [kg] at the file's resolution; a tandem's third load is no axle: NaN, as in the observed table
    loads = np.column_stack([
        np.where(n_axles > i, runs[f"axle_load_{i}"].to_numpy(dtype=float) / GRAVITY, np.nan) for i in range(_AXLES)
    ])  # fmt: skip
    if weight_step_kg is not None:
        loads = at_resolution(loads, weight_step_kg)
        group_load = np.nansum(loads, axis=1)
    else:
        group_load = runs["group_load"].to_numpy(dtype=float) / GRAVITY
    light = usable & (group_load < min_group_load)
    by_position = usable & ~light & (position not in SIMULATED_POSITIONS)
    kept = usable & ~light & ~by_position
    protocol = runs["protocol"].astype(str)
    counts = {}
    for name in sorted(set(protocol)):
        sel = protocol == name
        counts[name] = {
            "n_runs": int(sel.sum()), "n_failed": int((sel & failed).sum()), "n_airborne": int((sel & airborne).sum()),
            "n_light": int((sel & light).sum()), "n_position": int((sel & by_position).sum()),
            "n_kept": int((sel & kept).sum()),
        }  # fmt: skip
    frame = runs.loc[kept, list(_RUN_COLUMNS[:4])].astype({"group": str, "protocol": str})
    kept_rows = np.asarray(kept, dtype=bool)
    frame["group_load"] = group_load[kept_rows]
    for i in range(_AXLES):
        frame[f"axle_load_{i}"] = loads[kept_rows, i]
    frame = frame.sort_values(["protocol", "sample_id"], kind="stable")
    return with_inequality(frame)[SIMULATED_SCHEMA.names], counts


def _by_size(stats: pd.DataFrame) -> dict[str, dict]:
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
        out[protocol] = {"runs": dict(count), "groups": _by_size(stats)}
    return out


def wim_model(wim: WimProtocol) -> dict[str, Any]:
    """What the simulated WIM reading includes, for the caveats (``docs/wim-site.md``): the speed; the smooth site
    (its lengths and IRI) if it has one; the weighing length (sensor plus tyre contact) if not a point; the sensor
    error's COST 323 class and confidence level if not ``none``."""
    site = wim.site_before + wim.site_after > 0.0
    length = wim.sensor_length + wim.contact_length > 0.0
    error = wim.accuracy_class != "none"
    return {
        "speed_m_s": wim.speed,
        "site_pavement": site,
        "site_before_m": wim.site_before if site else None,
        "site_after_m": wim.site_after if site else None,
        "site_iri_m_km": wim.site_iri if site else None,
        "weighing_length": length,
        "sensor_length_m": wim.sensor_length if length else None,
        "contact_length_m": wim.contact_length if length else None,
        "sensor_error": error,
        "accuracy_class": wim.accuracy_class if error else None,
        "confidence_level": wim.confidence_level if error else None,
    }


def observed_metrics(
    observed: ObservedConfig,
    observed_stats: dict[str, Any] | None,
    simulated: dict[str, Any],
    wim: WimProtocol,
) -> dict[str, Any]:
    """metrics/observed.json: the filters, the observed statistics (or None and why), the simulated side."""
    position_note = (
        None
        if observed.position in SIMULATED_POSITIONS
        else f"position {observed.position}: the simulated fleet holds semi-trailer groups only, so no simulated "
        "group passes the filter"
    )
    reason = (
        None
        if observed_stats is not None
        else "no observed survey given: observed.path is null in params.yaml (docs/observed.md says how to give one)"
    )
    return {
        "filters": {
            "min_group_load_t": observed.min_group_load / 1000.0,
            "group_spacing_m": observed.group_spacing,
            "position": observed.position,
        },
        "observed": observed_stats,
        "reason": reason,
        "simulated": {
            "study": SURVEY_STUDY,
            "position_note": position_note,
            "wim_model": wim_model(wim),
            **simulated,
        },
    }


# ---- the stage ---------------------------------------------------------------------------------------------------
def write_outputs(
    groups: pd.DataFrame,
    readings: pd.DataFrame,
    metrics: Mapping[str, Any],
    out_dir: str | Path,
    metrics_path: str | Path,
) -> None:
    """Write data/observed/ (groups.parquet, simulated.parquet) and the metrics JSON, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir]) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        pq.write_table(_table(groups, GROUPS_SCHEMA), tmp_dir / "groups.parquet")
        pq.write_table(_table(readings, SIMULATED_SCHEMA), tmp_dir / "simulated.parquet")


def main(argv: list[str] | None = None) -> int:
    """Run the stage: the observed survey (if given) and the fleet under the same filters; exit 2 with the reason."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.observed", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--out", default="data/observed", help="output directory (default: data/observed)")
    parser.add_argument("--metrics", default="metrics/observed.json", help="default: metrics/observed.json")
    args = parser.parse_args(argv)
    try:
        config = load_config(args.params)
        observed = config.observed
        # the project root is where params.yaml is: observed.path is relative to it
        path = observed_file(observed, Path(args.params).resolve().parent)
        runs = read_runs(args.runs, SURVEY_STUDY, _RUN_COLUMNS)
        check_complete(runs, config.fleet.n_bogies, config.protocol.run, SURVEY_STUDY)
        groups, observed_stats = observed_table(path, observed)
    except (ConfigError, RunsError, OSError, ValueError, yaml.YAMLError) as exc:
        print(f"observed: {exc}", file=sys.stderr)
        return 2
    step = observed_stats["records"]["weight_step_kg"] if observed_stats is not None else None
    readings, counts = simulated_readings(runs, observed.min_group_load, observed.position, step)
    metrics = observed_metrics(observed, observed_stats, simulated_statistics(readings, counts), config.protocol.wim)
    try:
        write_outputs(groups, readings, metrics, args.out, args.metrics)
    except OSError as exc:
        print(io_error("observed", exc), file=sys.stderr)
        return 2
    given = f"{len(groups)} observed groups from {observed.path}" if path else "no observed survey given"
    print(f"observed: {given}, {len(readings)} simulated readings kept; wrote {args.out} and {args.metrics}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
