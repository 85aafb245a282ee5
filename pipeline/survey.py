"""DVC stage ``survey``: roadside-survey statistics of the fleet study -> data/survey/ and metrics/survey.json.

``python -m pipeline.survey`` reads the fleet study's runs (``data/runs/study=fleet``) and tabulates, per protocol
(static weighbridge, weigh-in-motion) and axle group (tandem, tri-axle), what a road authority's survey of that
fleet would find (:func:`bogie.fleet.weighing.survey.survey_tables`, every statistic a plain function of a runs
DataFrame), and the design guidance (the share within 5 % binned by the design parameters, with Wilson intervals:
:mod:`bogie.fleet.design.table`; the report draws it). This module reads, calls and writes. Definitions, units and
file layout: ``docs/outputs.md``.

Failed runs (``status == "failed"``, zeros in their numbers) are excluded from every statistic and counted in
``counts.csv`` and ``failures.csv``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa

from bogie.fleet.design.table import DESIGN_COLUMNS, design_table
from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.survey import (
    REQUIRED_COLUMNS,
    SUSPENSION_STATISTICS,
    inequality_columns,
    readings,
    survey_tables,
)
from bogie.params import GRAVITY
from bogie.rounding import json_number
from bogie.weighings.writers import write_weighings
from pipeline.atomic import StageError, atomic_outputs, run_stage, stage_inputs
from pipeline.config import load_config
from pipeline.schema import SchemaError, check_runs, checksummed_content, read_checksummed, read_runs_frame

#: the study a roadside survey samples
SURVEY_STUDY = "fleet"


class RunsError(ValueError):
    """The runs dataset is missing, incomplete or not in the expected form."""


# ---- reading -----------------------------------------------------------------------------------------------------
def read_runs(runs_dir: str | Path, study: str, columns: Sequence[str] = REQUIRED_COLUMNS) -> pd.DataFrame:
    """The runs of one study from the hive-partitioned dataset ``runs_dir/study=<study>/part-*.parquet``.

    Each part file is verified (:func:`pipeline.schema.read_runs_frame`: its SHA-256 and page checksums, the runs
    schema's fields) and the rows checked against the null rule: no null in a successful row, only nulls in the
    results of a failed one. Every stage that reads runs reads them here.

    Raises
    ------
    RunsError
        If the study has no part file, a file fails verification (named, with what failed), or the nulls break the
        rule.
    """
    runs_dir = Path(runs_dir)
    partition = runs_dir / f"study={study}"
    if not any(partition.glob("*.parquet")):
        raise RunsError(f"no runs of study {study!r}: {partition}/ holds no Parquet file; run the simulate stage first")
    try:
        frame = read_runs_frame(runs_dir, study)
        check_runs(frame, f"runs of study {study!r} in {runs_dir}")
    except SchemaError as exc:
        raise RunsError(str(exc)) from None
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise RunsError(f"runs of study {study!r} in {runs_dir} lack the columns {', '.join(missing)}")
    return frame


def check_complete(runs: pd.DataFrame, n_samples: int, protocols: Sequence[str], study: str = "fleet") -> None:
    """Check that the runs hold each of ``n_samples`` samples once under each protocol (simulate has finished).

    Raises
    ------
    RunsError
        Naming how many runs are missing or duplicated and a few of their sample ids.
    """
    have = runs.groupby([runs["protocol"].astype(str), "sample_id"], observed=True).size()
    expected = pd.MultiIndex.from_product([list(protocols), range(n_samples)], names=["protocol", "sample_id"])
    missing = expected.difference(have.index)
    extra = have.index.difference(expected).union(have[have > 1].index)
    if len(missing) or len(extra):
        shown = ", ".join(f"{p} {i}" for p, i in list(missing)[:5])
        raise RunsError(
            f"the {study} runs are incomplete: {len(missing)} of {len(expected)} (sample, protocol) runs missing"
            + (f" (e.g. {shown})" if shown else "")
            + (f", {len(extra)} unexpected or repeated" if len(extra) else "")
            + "; run the simulate stage to completion (make repro) first"
        )


#: headline column -> decimals in metrics/survey.json
_HEADLINE_DIGITS = {
    "share_outside_5pct": 4, "share_over_10pct": 4, "mean_max_deviation": 4, "mean_spread_pct": 2,
    "mean_spread_kg": 1, "mean_road_wear_factor": 4, "rear_overload_share_nose_up": 4,
    "frac_axle_over_group_legal": 4, "share_on_stop": 4,
}  # fmt: skip


def headline_metrics(tables: Mapping[str, pd.DataFrame]) -> dict[str, Any]:
    """The small dict of metrics/survey.json: totals, then protocol -> group -> headline numbers, rounded."""
    summary = tables["summary"]
    metrics: dict[str, Any] = {
        "n_runs": int(summary["n_runs"].sum()),
        "n_ok": int(summary["n_ok"].sum()),
        "n_failed": int(summary["n_failed"].sum()),
        "n_airborne": int(summary["n_airborne"].sum()),
    }
    for row in summary.itertuples(index=False):
        entry = {key: json_number(getattr(row, key), digits) for key, digits in _HEADLINE_DIGITS.items()}
        entry.update(n_ok=int(row.n_ok), n_failed=int(row.n_failed), n_airborne=int(row.n_airborne))
        metrics.setdefault(row.protocol, {})[row.group] = entry
    by_kind: dict[str, Any] = {}
    for row in tables["by_suspension"].to_dict("records"):
        entry = {"n_ok": int(row["n_ok"]), "n_failed": int(row["n_failed"]), "n_airborne": int(row["n_airborne"])}
        entry.update({key: json_number(row[key], 4 if key.startswith("share") else 1) for key in SUSPENSION_STATISTICS})
        by_kind.setdefault(row["protocol"], {}).setdefault(row["group"], {})[row["suspension"]] = entry
    metrics["by_suspension"] = by_kind
    pairs = tables["static_vs_wim"]
    if not pairs.empty:
        metrics["static_vs_wim"] = {
            row.group: {
                "mean_dynamic_excess": json_number(row.mean_dynamic_excess, 4),
                "corr_max_deviation": json_number(row.corr_max_deviation, 3),
                "n_pairs": int(row.n_pairs),
            }
            for row in pairs.itertuples(index=False)
        }
    wim_class = tables.get("wim_class")
    if wim_class is not None and not wim_class.empty:
        # the COST 323 class the whole simulated system reaches (bogie.road.cost323; pi0 an assumption)
        metrics["wim_class"] = {
            group: {
                "class_reached": sub["class_reached"].iloc[0],
                "required_share": float(sub["required_share"].iloc[0]),
                **{f"sd_{row.criterion}_error_pct": json_number(row.sd_error_pct, 2) for row in sub.itertuples()},
            }
            for group, sub in wim_class.groupby("group", sort=False)
        }
    return metrics


# ---- output --------------------------------------------------------------------------------------------------------
# ---- the fleet's WIM readings as records ------------------------------------------------------------------------
#: the export's synthetic clock: the first record's time, then one record every EXPORT_HEADWAY_S. The fleet study has
#: no traffic flow; the times only order the records and keep each distinct (a reader counts a repeat as bad)
EXPORT_START = "2026-01-01T00:00:00"
EXPORT_HEADWAY_S = 10


def wim_records(runs: pd.DataFrame, samples: pd.DataFrame, speed: float) -> tuple[pd.DataFrame, dict[str, int]]:
    """The fleet study's WIM readings as a vehicle table of :func:`bogie.weighings.writers.write_weighings`.

    One record per WIM reading kept by the survey (not failed, no wheel in the air), in ``sample_id`` order: the
    bogie's axles only (the tractor and the rest of the vehicle are not simulated), its axle loads [kg] as the WIM
    read them, its axle spacings [m] from the bogie's geometry, the WIM pass's ``speed`` [m/s], lane 1, direction 1,
    on the synthetic clock :data:`EXPORT_START` + :data:`EXPORT_HEADWAY_S` per record. Returns the table and the
    counts ``{"n_readings", "n_failed", "n_airborne", "n_written"}``.
    """
    wim = runs[runs["protocol"].astype(str) == "wim"]
    failed = wim["status"].astype(str) != "ok"
    airborne = ~failed & wim["wheel_airborne"].fillna(False).astype(bool)
    kept = wim[~failed & ~airborne].sort_values("sample_id", kind="stable")
    counts = {
        "n_readings": len(wim), "n_failed": int(failed.sum()), "n_airborne": int(airborne.sum()),
        "n_written": len(kept),
    }  # fmt: skip
    n = kept["n_axles"].to_numpy(dtype=np.int64)
    width = int(n.max()) if len(kept) else 2
    by_id = samples.set_index("sample_id")
    spacings = np.full((len(kept), width - 1), np.nan)
    for j, sample_id in enumerate(kept["sample_id"].to_numpy()):
        axle_x = bogie_from_sample(by_id.loc[sample_id].to_dict()).axle_x
        spacings[j, : len(axle_x) - 1] = np.diff(axle_x)
    vehicles = pd.DataFrame({
        "timestamp": pd.Timestamp(EXPORT_START) + pd.to_timedelta(EXPORT_HEADWAY_S * np.arange(len(kept)), unit="s"),
        "speed": np.full(len(kept), speed), "lane": 1, "direction": 1, "n_axles": n,
    })  # fmt: skip
    for i in range(width):
        load = kept[f"axle_load_{i + 1}"].to_numpy(dtype=float) / GRAVITY
        vehicles[f"axle_load_{i + 1}"] = np.where(n > i, load, np.nan)
    for i in range(width - 1):
        vehicles[f"spacing_{i + 1}"] = spacings[:, i]
    return vehicles, counts


def _write_table(frame: pd.DataFrame, path: Path) -> None:
    if path.suffix == ".parquet":
        path.write_bytes(checksummed_content(pa.Table.from_pandas(frame, preserve_index=False)))
    else:
        frame.to_csv(path, index=False, float_format="%.6g")


#: the survey's tables written as Parquet (the rest as CSV), by name
PARQUET_TABLES: frozenset[str] = frozenset({"static_vs_wim_pairs"})


def table_file(name: str) -> str:
    """The file of a survey table (:func:`bogie.fleet.survey_tables`' name): ``<name>.csv``, or ``.parquet``."""
    return f"{name}.parquet" if name in PARQUET_TABLES else f"{name}.csv"


def write_outputs(
    tables: Mapping[str, pd.DataFrame], out_dir: str | Path, metrics: Mapping[str, Any], metrics_path: str | Path,
    records: tuple[str, pd.DataFrame, str] | None = None, stage: str = "survey", own: Sequence[str | Path] = (),
) -> None:  # fmt: skip
    """Write the tables into ``out_dir`` and the metrics JSON, all or nothing; ``records`` (file name, vehicle table,
    format) is written with :func:`bogie.weighings.writers.write_weighings` into ``out_dir`` too.

    The tables go to a temporary sibling directory that replaces ``out_dir`` by renames, and the JSON to a
    temporary file renamed last: a reader sees the old outputs or the new ones, never a mix or half a file, and an
    error while writing leaves the old outputs in place. Parent directories are created.
    """
    with atomic_outputs(files=[metrics_path], dirs=[out_dir], stage=stage, own=own) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():
            _write_table(frame, tmp_dir / name)
        if records is not None:
            name, vehicles, fmt = records
            write_weighings(vehicles, tmp_dir / name, fmt)


def main(argv: list[str] | None = None) -> int:
    """Run the stage: read the fleet runs, compute the survey, write data/survey/ and metrics/survey.json."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.survey", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--samples", default="data/samples", help="sample tables (default: data/samples)")
    parser.add_argument("--out", default="data/survey", help="output directory (default: data/survey)")
    parser.add_argument("--metrics", default="metrics/survey.json", help="metrics file (default: metrics/survey.json)")
    args = parser.parse_args(argv)
    return run_stage("survey", parser, args, lambda own: _stage(args, own), files=["metrics"], dirs=["out"])


def _stage(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """The stage's work while it owns its outputs: read, compute, write; the exit code."""
    with stage_inputs("survey"):
        config = load_config(args.params)
        runs = read_runs(args.runs, SURVEY_STUDY, (*REQUIRED_COLUMNS, *DESIGN_COLUMNS))
        check_complete(runs, config.fleet.n_bogies, config.protocol.run, SURVEY_STUDY)
    tables = survey_tables(runs, config.fleet.legal_axle_load, config.fleet.legal_group_load)
    metrics = headline_metrics(tables)
    tables["design_guidance"] = design_table(inequality_columns(readings(runs)))
    records = None
    fmt = config.survey.export_format
    if fmt is not None:
        with stage_inputs("survey"):
            samples = read_checksummed(
                Path(args.samples) / f"{SURVEY_STUDY}.parquet", "delete it and rerun the sample stage"
            ).to_pandas()
        vehicles, counts = wim_records(runs, samples, config.protocol.wim.speed)
        records = (f"fleet_wim.{fmt}", vehicles, fmt)
        metrics["export"] = {"format": fmt, "file": f"fleet_wim.{fmt}", **counts}
    files = {table_file(name): frame for name, frame in tables.items()}  # the library names; the stage's files
    try:
        write_outputs(files, args.out, metrics, args.metrics, records, own=own)
    except ValueError as exc:  # a reading that does not fit the export format's fields (an OSError: run_stage's)
        raise StageError(f"survey: {exc}") from exc
    n_ok, n_runs, n_failed = metrics["n_ok"], metrics["n_runs"], metrics["n_failed"]
    print(f"survey: {n_ok} of {n_runs} runs succeeded ({n_failed} failed); wrote {args.out} and {args.metrics}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
