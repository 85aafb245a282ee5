"""The report's inputs: everything the earlier stages wrote, read and checked once into :class:`ReportInputs`."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

import bogie
import pipeline
from bogie.fleet.weighing.survey import REQUIRED_COLUMNS, inequality_columns, readings
from pipeline.config import Config, load_config, load_params
from pipeline.schema import SchemaError, read_checksummed, read_runs_frame
from pipeline.survey import RunsError, read_runs

__all__ = [
    "ReportInputs", "build_date", "calibration_inputs", "code_digest", "design_inputs", "read_inputs", "read_tables",
    "skipped_calibration",
]  # fmt: skip

#: the columns of every study's runs the report reads (status, not results)
STATUS_COLUMNS = ["study", "sample_id", "group", "variant", "protocol", "status", "message"]
#: tables the report needs from each stage's output directory
SURVEY_TABLES = ("tilt.csv", "static_vs_wim_pairs.parquet", "design_guidance.csv")
SENSITIVITY_TABLES = ("sobol_indices.csv", "ablation.csv")
OBSERVED_TABLES = ("groups.parquet", "simulated.parquet")
#: tables of data/calibration the calibration pages draw when a fit was made (none when it was skipped)
CALIBRATION_TABLES = ("bootstrap.csv", "valley.csv", "profiles.csv", "calibrated.csv", "ablation.csv")
#: tables of data/design the design-guidance pages draw when the study ran (none when it was skipped)
DESIGN_TABLES = ("designs.csv", "tilt_curves.csv", "check.csv")


@dataclass(frozen=True)
class ReportInputs:
    """Everything the report is made from.

    Attributes
    ----------
    raw_params, config
        params.yaml as read and as validated (SI).
    facts
        Provenance: ``date`` (None unless ``SOURCE_DATE_EPOCH`` is set), ``code_sha256`` (:func:`code_digest`),
        ``params_sha256``.
    fleet
        The fleet study's samples (data/samples/fleet.parquet), SI.
    runs
        Every study's runs, status columns only (``study``, ``sample_id``, ``group``, ``variant``, ``protocol``,
        ``status``, ``message``).
    ok
        The fleet's succeeded runs with the survey's inequality columns.
    survey, sensitivity
        The tables of data/survey and data/sensitivity, by file name.
    survey_metrics, sensitivity_metrics
        metrics/survey.json and metrics/sensitivity.json.
    observed
        The tables of data/observed (``groups.parquet``: the observed groups, none when no survey is given;
        ``simulated.parquet``: the fleet's readings under the same filters).
    observed_metrics
        metrics/observed.json.
    calibration
        The tables of data/calibration (:data:`CALIBRATION_TABLES`; none when the calibration was skipped).
    calibration_metrics
        metrics/calibration.json; when the file is missing, a skipped calibration with that as its reason
        (:func:`skipped_calibration`).
    design, design_metrics
        The tables of data/design (:data:`DESIGN_TABLES`) and metrics/design.json; none and a skipped study (with
        its reason) when the design stage did not run or was not asked for.
    road_metrics
        metrics/road.json (what unequal sharing costs the road, docs/pavement.md); empty when the road stage has not
        run.
    """

    raw_params: dict[str, Any]
    config: Config
    facts: dict[str, str]
    fleet: pd.DataFrame
    runs: pd.DataFrame
    ok: pd.DataFrame
    survey: dict[str, pd.DataFrame]
    sensitivity: dict[str, pd.DataFrame]
    survey_metrics: dict[str, Any]
    sensitivity_metrics: dict[str, Any]
    observed: dict[str, pd.DataFrame]
    observed_metrics: dict[str, Any]
    calibration: dict[str, pd.DataFrame] = field(default_factory=dict)
    calibration_metrics: dict[str, Any] = field(default_factory=lambda: skipped_calibration(NO_CALIBRATION))
    design: dict[str, pd.DataFrame] = field(default_factory=dict)
    design_metrics: dict[str, Any] = field(default_factory=lambda: {"designs": [], "skipped": NO_DESIGN})
    road_metrics: dict[str, Any] = field(default_factory=dict)


#: the reason of a calibration whose metrics file is missing
NO_CALIBRATION = "no metrics/calibration.json: the calibrate stage has not run (dvc repro calibrate)"


#: the reason of a design study whose metrics file is missing
NO_DESIGN = "no metrics/design.json: the design stage has not run (dvc repro design)"


def design_inputs(design_dir: str | Path, metrics_file: str | Path) -> tuple[dict[str, pd.DataFrame], dict[str, Any]]:
    """data/design's tables and metrics/design.json; a missing metrics file reads as a skipped study."""
    metrics_file = Path(metrics_file)
    if not metrics_file.is_file():
        return {}, {"designs": [], "skipped": NO_DESIGN}
    metrics = json.loads(metrics_file.read_text())
    if metrics.get("skipped"):
        return {}, metrics
    return read_tables(design_dir, DESIGN_TABLES), metrics


def skipped_calibration(reason: str) -> dict[str, Any]:
    """metrics/calibration.json of a calibration that was skipped for ``reason`` (as pipeline.calibrate writes it)."""
    return {"skipped": True, "reason": reason, "fitted": None, "observed": None, "calibrated": None, "held_out": None}


def calibration_inputs(
    calibration_dir: str | Path, metrics_file: str | Path
) -> tuple[dict[str, pd.DataFrame], dict[str, Any]]:
    """data/calibration's tables and metrics/calibration.json.

    A missing metrics file reads as a skipped calibration (:data:`NO_CALIBRATION`), so a project without the
    calibrate stage still gets its report; a skipped one needs no tables, a fitted one every table of
    :data:`CALIBRATION_TABLES`.
    """
    metrics_file = Path(metrics_file)
    if not metrics_file.is_file():
        return {}, skipped_calibration(NO_CALIBRATION)
    metrics = json.loads(metrics_file.read_text())
    if metrics.get("skipped", False):
        return {}, metrics
    return read_tables(calibration_dir, CALIBRATION_TABLES), metrics


def code_digest() -> str:
    """The sha256 of the code that made the report: every source and template of ``bogie`` and ``pipeline``.

    The report names its code by content, not by git revision or date: committing the ``dvc.lock`` of a build
    changes the revision, so a report that printed it could never match the lock it is recorded in, and a date
    changes every day. The same code and parameters give the same report, byte for byte.
    """
    digest = hashlib.sha256()
    for package in (bogie, pipeline):
        root = Path(package.__file__).parent
        for path in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".j2") and p.is_file()):
            digest.update(path.relative_to(root.parent).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def build_date() -> str | None:
    """The date of ``SOURCE_DATE_EPOCH`` as YYYY-MM-DD when it is set (for a dated, still reproducible build)."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    return dt.datetime.fromtimestamp(int(epoch), dt.UTC).date().isoformat() if epoch else None


def read_tables(directory: str | Path, required: Sequence[str]) -> dict[str, pd.DataFrame]:
    """The tables of a stage's output directory by file name; a clear error if one the report needs is missing."""
    directory = Path(directory)
    missing = [name for name in required if not (directory / name).is_file()]
    if missing:
        raise RunsError(f"{directory}/ lacks {', '.join(missing)}: run the stage that writes it first")
    rerun = f"delete it and rerun the stage that writes {directory}/"
    read = {".csv": pd.read_csv, ".parquet": lambda f: read_checksummed(f, rerun).to_pandas()}
    return {f.name: read[f.suffix](f) for f in sorted(directory.iterdir()) if f.suffix in read}


def _read_runs(runs: str | Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Every run's status (each part file verified) and the fleet's good readings with their inequality.

    Raises
    ------
    RunsError
        If ``runs`` holds no runs or a part file is not what the simulate stage writes.
    """
    if not any(Path(runs).glob("study=*/*.parquet")):
        raise RunsError(f"{runs}/ holds no runs; run the simulate stage first")
    try:  # every part file verified, as every stage reads them
        every = read_runs_frame(runs, columns=[c for c in STATUS_COLUMNS if c != "study"])[STATUS_COLUMNS]
    except SchemaError as exc:
        raise RunsError(str(exc)) from None
    return every, inequality_columns(readings(read_runs(runs, "fleet", REQUIRED_COLUMNS)))


def read_inputs(
    params: str | Path,
    samples: str | Path,
    runs: str | Path,
    survey_dir: str | Path,
    sensitivity_dir: str | Path,
    metrics_dir: str | Path,
    observed_dir: str | Path | None = None,
    calibration_dir: str | Path | None = None,
    design_dir: str | Path | None = None,
) -> ReportInputs:
    """Read and check every input of the report (see :class:`ReportInputs`).

    ``observed_dir`` defaults to ``observed`` beside ``survey_dir`` (data/observed), ``calibration_dir`` to
    ``calibration`` beside it (data/calibration) and ``design_dir`` to ``design`` (data/design); their metrics are
    ``metrics_dir``/calibration.json and design.json.

    Raises
    ------
    ConfigError, RunsError, OSError
        For bad parameters, a missing or incomplete runs dataset, or a missing table or metrics file.
    """
    params = Path(params)
    config = load_config(params)
    facts = {
        "date": build_date(),
        "code_sha256": code_digest(),
        "params_sha256": hashlib.sha256(params.read_bytes()).hexdigest(),
    }
    every, ok = _read_runs(runs)
    metrics_dir = Path(metrics_dir)
    observed_dir = Path(survey_dir).with_name("observed") if observed_dir is None else observed_dir
    calibration_dir = Path(survey_dir).with_name("calibration") if calibration_dir is None else calibration_dir
    calibration, calibration_metrics = calibration_inputs(calibration_dir, metrics_dir / "calibration.json")
    design_dir = Path(survey_dir).with_name("design") if design_dir is None else design_dir
    design, design_metrics = design_inputs(design_dir, metrics_dir / "design.json")
    road_file = metrics_dir / "road.json"
    road_metrics = json.loads(road_file.read_text()) if road_file.is_file() else {}
    return ReportInputs(
        raw_params=load_params(params),
        config=config,
        facts=facts,
        fleet=read_checksummed(Path(samples) / "fleet.parquet", "delete it and rerun the sample stage").to_pandas(),
        runs=every,
        ok=ok,
        survey=read_tables(survey_dir, SURVEY_TABLES),
        sensitivity=read_tables(sensitivity_dir, SENSITIVITY_TABLES),
        survey_metrics=json.loads((metrics_dir / "survey.json").read_text()),
        sensitivity_metrics=json.loads((metrics_dir / "sensitivity.json").read_text()),
        observed=read_tables(observed_dir, OBSERVED_TABLES),
        observed_metrics=json.loads((metrics_dir / "observed.json").read_text()),
        calibration=calibration,
        calibration_metrics=calibration_metrics,
        design=design,
        design_metrics=design_metrics,
        road_metrics=road_metrics,
    )
