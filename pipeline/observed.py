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
import math
import shutil
import sys
import tempfile
import weakref
from collections.abc import Mapping, Sequence
from pathlib import Path, PurePosixPath
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from bogie.fleet.weighing.observed import (
    INEQUALITY_COLUMNS,
    READING_RUN_COLUMNS,
    SIMULATED_COLUMNS,
    SIMULATED_POSITIONS,
    simulated_readings,
    simulated_statistics,
    with_inequality,
)
from bogie.rounding import json_number
from bogie.weighings.groups import GROUP_TABLE_COLUMNS
from bogie.weighings.sites import compare_sites
from bogie.weighings.survey import observed_survey
from pipeline.atomic import atomic_outputs, run_stage, stage_inputs
from pipeline.config import ObservedConfig, WimProtocol, load_config, observed_file
from pipeline.schema import ChecksummedWriter, checksummed_content
from pipeline.survey import SURVEY_STUDY, check_complete, read_runs

__all__ = [
    "COLUMN_TYPES", "GROUPS_SCHEMA", "SIMULATED_POSITIONS", "SIMULATED_SCHEMA", "GroupsFile", "arrow_schema",
    "observed_metrics", "observed_table", "main", "simulated_readings", "simulated_statistics", "wim_model",
]  # fmt: skip

#: the Arrow type and unit of each column the two tables hold, by name; a numbered column (``axle_load_1..3``) by
#: its name without the number. The columns themselves, and their order, are the library's.
COLUMN_TYPES: dict[str, tuple[pa.DataType, str]] = {
    "line": (pa.int64(), "-"), "timestamp": (pa.timestamp("us"), "-"), "speed": (pa.float64(), "m/s"),
    "lane": (pa.int64(), "-"), "vehicle_groups": (pa.int64(), "-"), "group_index": (pa.int64(), "-"),
    "first_axle": (pa.int64(), "-"), "sample_id": (pa.int64(), "-"), "protocol": (pa.string(), "-"),
    "n_axles": (pa.int64(), "-"), "group": (pa.string(), "-"), "position": (pa.string(), "-"),
    "group_load": (pa.float64(), "kg"), "axle_load_": (pa.float64(), "kg"), "spacing_": (pa.float64(), "m"),
    "load_share_": (pa.float64(), "-"), "spread_kg": (pa.float64(), "kg"), "spread_pct": (pa.float64(), "%"),
    "outside_5pct": (pa.bool_(), "-"), "over_10pct": (pa.bool_(), "-"), "site": (pa.string(), "-"),
}  # fmt: skip


#: decimals of the sites' shares [-], intervals [-] and mean spreads [kg], significant digits of their p-values [-],
#: in metrics/observed.json
SITE_DIGITS = 6


def arrow_schema(columns: Sequence[str]) -> pa.Schema:
    """The Arrow schema of the named columns, in their order, each field with its unit in its metadata
    (:data:`COLUMN_TYPES`)."""
    fields = []
    for name in columns:
        kind, unit = COLUMN_TYPES[name] if name in COLUMN_TYPES else COLUMN_TYPES[name.rstrip("0123456789")]
        fields.append(pa.field(name, kind, metadata={"unit": unit}))
    return pa.schema(fields)


#: data/observed/groups.parquet: the columns of bogie.weighings.groups.axle_groups, then the inequality quantities,
#: then each group's site (its file in a folder, its station, or ``file:station``; null for one file without a
#: station column)
GROUPS_SCHEMA = arrow_schema((*GROUP_TABLE_COLUMNS, *INEQUALITY_COLUMNS, "site"))
#: data/observed/simulated.parquet: one row per simulated reading kept
#: (bogie.fleet.weighing.observed.SIMULATED_COLUMNS), loads in kg as the observed ones
SIMULATED_SCHEMA = arrow_schema(SIMULATED_COLUMNS)


def _table(frame: pd.DataFrame, schema: pa.Schema) -> pa.Table:
    return pa.Table.from_pandas(frame[schema.names], schema=schema, preserve_index=False)


# ---- the observed side -------------------------------------------------------------------------------------------
class GroupsFile:
    """``groups.parquet`` filled chunk by chunk as the survey streams (:func:`bogie.weighings.survey.observed_survey`'s
    ``sink``): each chunk's kept groups with their inequality, one row group, written to a temporary directory, so
    that the stage never holds the whole group table (issue 41 Must 4); :func:`write_outputs` moves the sealed file
    into place. The directory is removed when the object is collected.

    A survey of several files (a folder, issue 46): each file's groups go to a part of their own, begun afresh when
    the file is read again, and are copied into ``groups.parquet`` a row group at a time once the file is done
    (:meth:`next_file`, :meth:`close`), in file order."""

    def __init__(self) -> None:
        self.dir = Path(tempfile.mkdtemp(prefix="bogie-observed-"))
        self._cleanup = weakref.finalize(self, shutil.rmtree, self.dir, True)
        self.path = self.dir / "groups.parquet"
        self.part: Path | None = None  # the part of the file being read, of several
        self.file: ChecksummedWriter | None = None
        self._part_writer: pq.ParquetWriter | None = None

    def next_file(self, site: str) -> None:
        self._copy_part()
        if self.file is None:
            self.file = ChecksummedWriter(GROUPS_SCHEMA, self.path)
        self.part = self.dir / "part.parquet"

    def start(self) -> None:
        if self.part is None:  # one file: written in place
            self.file = ChecksummedWriter(GROUPS_SCHEMA, self.path)
        else:
            self._close_part()
            self._part_writer = pq.ParquetWriter(str(self.part), GROUPS_SCHEMA)

    def write(self, groups: pd.DataFrame) -> None:
        if len(groups):
            if "site" not in groups:  # one site: the column is null
                groups = groups.assign(site=None)
            target = self.file if self.part is None else self._part_writer
            target.write(_table(with_inequality(groups), GROUPS_SCHEMA))

    def close(self) -> None:
        """Seal ``groups.parquet`` (a survey of several files: after copying the last file's part into it)."""
        self._copy_part()
        self.file.close()

    def _close_part(self) -> None:
        if self._part_writer is not None:
            self._part_writer.close()
            self._part_writer = None

    def _copy_part(self) -> None:
        """The part of the file just read into ``groups.parquet``, its row groups as they were."""
        if self.part is None:
            return
        self._close_part()
        if self.part.exists():
            parts = pq.ParquetFile(self.part)
            for k in range(parts.num_row_groups):
                self.file.write(parts.read_row_group(k))
            parts.close()
            self.part.unlink()


def _sha256(path: Path) -> str:
    """The file's SHA-256, read a megabyte at a time."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def observed_table(
    path: Path | None, observed: ObservedConfig
) -> tuple[pd.DataFrame | GroupsFile, dict[str, Any] | None]:
    """The observed groups that pass the filters and their statistics (``bogie weighings --json``'s shape).

    Parameters
    ----------
    path
        The file of records, a folder of files (each a site, pooled: issue 46), or None when no survey is given.
    observed
        The ``observed`` section (format, filters).

    Returns
    -------
    groups : pandas.DataFrame or GroupsFile
        No survey: an empty table of the columns of :data:`GROUPS_SCHEMA`. A survey: the checksummed Parquet file
        of its groups (those columns), written to a temporary directory chunk by chunk as the file streams.
    statistics : dict or None
        ``{"path", "format" (the one read), "format_asked" (``auto`` or that one), "sha256", "records": {"read",
        "skipped", "weight_step_kg", "resolution", "skipped_by_reason"}, "groups": {"tandem", "triaxle"}}``, or
        None for no survey; for several sites (a folder, a file of stations) also ``"stations"`` and ``"sites"``
        (:func:`site_rows`), for a folder ``"files"`` (each file's path, site, format, records and sha256; the
        folder's ``sha256`` is :func:`_folder_sha256`).

    Raises
    ------
    ValueError
        The reader refused the file (named, with the format expected and what was found).
    """
    if path is None:
        empty = pd.DataFrame({f.name: pd.Series(dtype=f.type.to_pandas_dtype()) for f in GROUPS_SCHEMA})
        return empty, None
    groups = GroupsFile()
    survey = observed_survey(
        path,
        observed.format,
        min_group_load_kg=observed.min_group_load,
        group_spacing_m=observed.group_spacing,
        position=observed.position,
        resolution_kg=observed.resolution_kg,
        keep_groups=False,
        sink=groups,
    )
    stats = survey.to_dict()
    # the file as params.yaml names it, relative to the project: the outputs must not depend on where the project is
    stats["settings"]["file"] = observed.path
    stats["records"]["skipped_by_reason"] = dict(sorted(survey.read.skipped.items()))
    groups.close()
    if survey.files:  # a folder: each file a site (issue 46), named in the project's terms, with its own digest
        for entry in stats["files"]:
            name = Path(entry["path"]).name
            entry.update(path=f"{observed.path}/{name}", sha256=_sha256(path / name))
        digest = _folder_sha256(stats["files"])
    else:
        digest = _sha256(path)
    header = {"path": observed.path, "format": survey.read.format, "format_asked": observed.format, "sha256": digest}
    if survey.stations:  # several stations (a state-wide TMG file) or files: each a site, side by side (issue 46)
        table = compare_sites(survey.site_counts(PurePosixPath(observed.path).name))
        stats["sites"] = site_rows(table)
    return groups, {**header, **stats, "n_kept": survey.n_kept}


def _folder_sha256(files: Sequence[Mapping[str, Any]]) -> str:
    """A folder's digest: the SHA-256 of its files' names and digests, a line each in file order (``sha256sum``'s
    lines), so that a renamed, changed, added or removed file changes it."""
    lines = "".join(f"{entry['sha256']}  {PurePosixPath(entry['path']).name}\n" for entry in files)
    return hashlib.sha256(lines.encode()).hexdigest()


def site_rows(table: pd.DataFrame) -> list[dict[str, Any]]:
    """:func:`bogie.weighings.sites.compare_sites`' table as JSON rows: the shares, their intervals and mean spreads
    rounded to :data:`SITE_DIGITS` decimals, the p-values to as many significant digits (their last bits are the C
    library's ``erfc`` and ``sqrt``, scalar, and rounded they are the same bytes on every machine; a p-value of
    3.4e-6 stays one), an undefined value None."""
    rows = []
    for row in table.to_dict("records"):
        rows.append({key: _site_value(key, v) for key, v in row.items()})
    return rows


def _site_value(key: str, v: Any) -> Any:
    """One value of :func:`site_rows`: a p-value to :data:`SITE_DIGITS` significant digits, any other float to as
    many decimals, None for NaN; numpy's booleans and integers as Python's."""
    if isinstance(v, float):
        if key.startswith("p_"):
            return None if math.isnan(v) else float(f"{v:.{SITE_DIGITS}g}")
        return json_number(v, SITE_DIGITS)
    return bool(v) if isinstance(v, np.bool_) else int(v) if isinstance(v, np.integer) else v


def wim_model(wim: WimProtocol) -> dict[str, Any]:
    """What the simulated WIM reading includes, for the caveats (``docs/wim-site.md``): the speed; the smooth site
    (its lengths and IRI) if it has one; the weighing length (sensor plus tyre contact) if not a point; the sensor
    error's type and its two parts' sds [%] if it has one."""
    site = wim.site_length_before + wim.site_length_after > 0.0
    length = wim.sensor_length + wim.contact_length > 0.0
    error = not wim.error_free
    return {
        "speed_m_s": wim.speed,
        "site_pavement": site,
        "site_before_m": wim.site_length_before if site else None,
        "site_after_m": wim.site_length_after if site else None,
        "site_iri_m_km": wim.site_iri if site else None,
        "weighing_length": length,
        "sensor_length_m": wim.sensor_length if length else None,
        "contact_length_m": wim.contact_length if length else None,
        "sensor_error": error,
        "sensor": wim.sensor if error else None,
        "sensor_vehicle_error_pct": json_number(100.0 * wim.vehicle_error_sd, 6) if error else None,
        "sensor_axle_error_pct": json_number(100.0 * wim.axle_error_sd, 6) if error else None,
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
    groups: pd.DataFrame | GroupsFile,
    readings: pd.DataFrame,
    metrics: Mapping[str, Any],
    out_dir: str | Path,
    metrics_path: str | Path,
    own: Sequence[str | Path] = (),
) -> None:
    """Write data/observed/ (groups.parquet, simulated.parquet) and the metrics JSON, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir], stage="observed", own=own) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        if isinstance(groups, GroupsFile):
            shutil.move(groups.path, tmp_dir / "groups.parquet")
        else:
            (tmp_dir / "groups.parquet").write_bytes(checksummed_content(_table(groups, GROUPS_SCHEMA)))
        (tmp_dir / "simulated.parquet").write_bytes(checksummed_content(_table(readings, SIMULATED_SCHEMA)))


def main(argv: list[str] | None = None) -> int:
    """Run the stage: the observed survey (if given) and the fleet under the same filters; exit 2 with the reason."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.observed", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--out", default="data/observed", help="output directory (default: data/observed)")
    parser.add_argument("--metrics", default="metrics/observed.json", help="default: metrics/observed.json")
    args = parser.parse_args(argv)
    return run_stage("observed", parser, args, lambda own: _stage(args, own), files=["metrics"], dirs=["out"])


def _stage(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """The stage's work while it owns its outputs: read, compute, write; the exit code."""
    with stage_inputs("observed"):
        config = load_config(args.params)
        observed = config.observed
        # the project root is where params.yaml is: observed.path is relative to it
        path = observed_file(observed, Path(args.params).resolve().parent, held=False)
        runs = read_runs(args.runs, SURVEY_STUDY, READING_RUN_COLUMNS)
        check_complete(runs, config.fleet.n_bogies, config.protocol.run, SURVEY_STUDY)
        groups, observed_stats = observed_table(path, observed)
    n_kept = observed_stats.pop("n_kept") if observed_stats is not None else 0
    step = observed_stats["records"]["weight_step_kg"] if observed_stats is not None else None
    readings, counts = simulated_readings(runs, observed.min_group_load, observed.position, step)
    metrics = observed_metrics(observed, observed_stats, simulated_statistics(readings, counts), config.protocol.wim)
    write_outputs(groups, readings, metrics, args.out, args.metrics, own=own)
    given = f"{n_kept} observed groups from {observed.path}" if path else "no observed survey given"
    print(f"observed: {given}, {len(readings)} simulated readings kept; wrote {args.out} and {args.metrics}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
