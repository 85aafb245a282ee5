"""DVC stage ``design``: design guidance from a controlled experiment -> data/design/, metrics/design.json.

``python -m pipeline.design`` reads params.yaml (``design:``; null: the stage writes a metrics file saying it was
not asked for), runs the controlled design experiment of :mod:`bogie.fleet.design.experiment` (the method: the designs,
the operating conditions, the tilt grid, the sample rows) and analyses it with :mod:`bogie.fleet.design.analysis` (the
shares within 5 % with Wilson intervals, the tilt tolerances, the Pareto fronts, the guidance sentences); the
method is ``docs/design.md``'s. This module is the stage: params.yaml's ``design:`` as
:class:`bogie.fleet.DesignSettings`, the runs and the outputs.

The runs go through :func:`pipeline.simulate.simulate_samples` into ``data/design_runs`` (chunked, resumable, byte
for byte the same whatever the number of workers, loky or dask); a failed run is a ``failed`` row there and is left
out of its design's shares, counted in ``n_failed``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.design.analysis import DesignAnalysis, DesignError, analyse_designs, guidance_sentences
from bogie.fleet.design.experiment import (
    DesignExperiment,
    DesignSettings,
    design_experiment,
    experiment_runs,
    typical_design,
)
from bogie.fleet.sampling.sample import COLUMNS
from bogie.rounding import json_number
from pipeline.atomic import atomic_outputs, run_stage, stage_inputs
from pipeline.chunks import NotRunsDatasetError
from pipeline.config import Config, load_config
from pipeline.schema import read_runs_frame
from pipeline.simulate import simulate_samples

__all__ = [
    "DESIGN_KEYS", "analysed", "design_entry", "experiment", "main", "metrics", "run", "settings", "skipped_metrics",
    "tables", "write_outputs",
]  # fmt: skip

#: the keys of each entry of ``design.json``'s ``designs``, in order (issue 16)
DESIGN_KEYS: tuple[str, ...] = (
    "group", "bush_stiffness", "equaliser_arm", "contact_roll_radius", "friction_coefficient",
    "spring_friction_band", "tilt_tolerance_nose_up_deg", "tilt_tolerance_nose_down_deg",
    "share_within_5pct_at_tolerance",
)  # fmt: skip


# ---- params.yaml -> the library ---------------------------------------------------------------------------------
def settings(config: Config) -> DesignSettings:
    """params.yaml's ``design:``, the library's settings as the configuration holds them; the section must not be
    null."""
    if config.design is None:
        raise DesignError("design is null in params.yaml: there is no design study to set up")
    return config.design


def experiment(config: Config) -> DesignExperiment:
    """The experiment of params.yaml: :func:`bogie.fleet.design.experiment.design_experiment` of its fleet,
    ``design:`` and master seed."""
    return design_experiment(config.fleet_study, settings(config), config.seed)


# ---- outputs ---------------------------------------------------------------------------------------------------
def design_entry(row: Mapping[str, Any]) -> dict[str, Any]:
    """One entry of ``design.json``'s ``designs``: exactly the keys of :data:`DESIGN_KEYS` (SI, tilts in degrees)."""
    return {
        "group": row["group"],
        "bush_stiffness": json_number(row["bush_stiffness"], 4),
        "equaliser_arm": json_number(row["equaliser_arm"], 6),
        "contact_roll_radius": json_number(row["contact_roll_radius"], 6),
        "friction_coefficient": json_number(row["friction_coefficient"], 4),
        "spring_friction_band": json_number(row["spring_friction_band"], 2),
        "tilt_tolerance_nose_up_deg": json_number(row["tilt_tolerance_nose_up_deg"], 2),
        "tilt_tolerance_nose_down_deg": json_number(row["tilt_tolerance_nose_down_deg"], 2),
        "share_within_5pct_at_tolerance": json_number(row["share_within_5pct_at_tolerance"], 4),
    }


def metrics(
    analysis: DesignAnalysis, spec: DesignSettings, tilts: np.ndarray, typical: Mapping[str, float], text: Sequence[str]
) -> dict[str, Any]:
    """``metrics/design.json``: ``designs`` (steel, best of each group first), and the air references, the
    ``typical`` design [SI], the experiment's size, the interpolation check and the sentences ``text``."""
    table = analysis.designs
    steel = table[table["suspension"] == "steel"]
    air = table[table["suspension"] == "air"]
    check = analysis.check

    def summary(row: Mapping[str, Any]) -> dict[str, Any]:
        return {
            "design": row["design"], "kind": row["kind"], "pareto": bool(row["pareto"]),
            "distance": json_number(row["distance"], 4), "share_within_5pct": json_number(row["share_within_5pct"], 4),
            "share_within_5pct_interval": [json_number(row[f"share_within_5pct_{e}"], 4) for e in ("low", "high")],
            "share_within_10pct": json_number(row["share_within_10pct"], 4),
            "share_within_10pct_interval": [json_number(row[f"share_within_10pct_{e}"], 4) for e in ("low", "high")],
            "n_failed": int(row["n_failed"]),
        }  # fmt: skip

    return {
        "designs": [design_entry(r) for r in steel.to_dict("records")],
        "design_summaries": [summary(r) for r in steel.to_dict("records")],
        "air": {r["group"]: {**design_entry(r), **summary(r)} for r in air.to_dict("records")},
        "typical": dict(typical),
        "target_share": spec.target_share,
        "confidence_level": spec.confidence_level,
        "protocol": "static",
        "n_conditions": spec.n_conditions,
        "tilt_grid_deg": [float(t) for t in tilts],
        "tilt_range_deg": [float(tilts[0]), float(tilts[-1])],
        "runs": int(table["n_runs"].sum()),
        "failed": int(table["n_failed"].sum()),
        "interpolation_check": {
            "pairs": len(check),
            "largest_max_deviation_difference_pct": json_number(
                100.0 * (check["max_deviation_interpolated"] - check["max_deviation_direct"]).abs().max(), 3
            )
            if len(check)
            else None,
            "within_5pct_disagreements": int((check["within_interpolated"] != check["within_direct"]).sum())
            if len(check)
            else 0,
        },  # fmt: skip
        "guidance": list(text),
    }


def write_outputs(
    tables: Mapping[str, pd.DataFrame], summary: Mapping[str, Any], out_dir: Path, metrics_path: Path,
    own: Sequence[str | Path] = (),
) -> None:  # fmt: skip
    """data/design/ (one CSV per table) and metrics/design.json, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir], stage="design", own=own) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(summary, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():
            frame.to_csv(tmp_dir / f"{name}.csv", index=False, float_format="%.6g", lineterminator="\n")
        if not tables:
            (tmp_dir / "README.txt").write_text(f"design study skipped: {summary['skipped']}\n", encoding="utf-8")


def tables(analysis: DesignAnalysis, conds: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The stage's tables by file name (without ``.csv``)."""
    return {"designs": analysis.designs, "tilt_curves": analysis.curves, "conditions": conds, "check": analysis.check}


def skipped_metrics(reason: str) -> dict[str, Any]:
    """The metrics of a stage that was not asked to run: no designs, and why."""
    return {"designs": [], "skipped": reason}


def analysed(config: Config, exp: DesignExperiment, runs: pd.DataFrame) -> tuple[DesignAnalysis, dict[str, Any]]:
    """The analysis of the experiment's runs (as read from ``data/design_runs``) and the metrics."""
    spec = settings(config)
    runs = experiment_runs(exp, runs)
    analysis = analyse_designs(runs, exp.designs, exp.tilts, spec.target_share, spec.confidence_level)
    text = guidance_sentences(analysis.designs, exp.tilts, spec.target_share, dict(config.fleet_study.presets))
    return analysis, metrics(analysis, spec, exp.tilts, typical_design(config.fleet_study), text)


def run(
    config: Config, runs_dir: Path, log: Callable[[str], None] = print
) -> tuple[DesignAnalysis, pd.DataFrame, dict[str, Any]]:
    """Run the experiment (resuming from ``runs_dir``) and analyse it; returns the tables and the metrics."""
    exp = experiment(config)
    log(
        f"design: {len(exp.designs)} designs ({', '.join(config.design.groups)}, air references included) x "
        f"{len(exp.conditions)} conditions x ({len(exp.tilts)} grid tilts + each condition's own) = "
        f"{len(exp.samples)} static runs"
    )
    protocols = {"design": (("static", config.protocol.static),)}
    simulate_samples({"design": exp.samples[list(COLUMNS)]}, protocols, config.execution, runs_dir, log, "design")
    # every part verified (the file's SHA-256, its pages' CRC32s: pipeline.schema.read_runs_frame), as every stage
    # that reads runs does
    analysis, summary = analysed(config, exp, read_runs_frame(runs_dir, "design"))
    return analysis, exp.conditions, summary


def main(argv: list[str] | None = None) -> int:
    """Run the stage from the command line."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.design", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/design_runs", help="runs dataset directory (default: data/design_runs)")
    parser.add_argument("--out", default="data/design", help="tables directory (default: data/design)")
    parser.add_argument("--metrics", default="metrics/design.json", help="metrics file (default: metrics/design.json)")
    args = parser.parse_args(argv)
    return run_stage("design", parser, args, lambda own: _configured(args, own), files=["metrics"], dirs=["out"])


def _configured(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """Read params.yaml, then the stage's work (:func:`_stage`); the exit code."""
    with stage_inputs("design", prefix=f"{args.params}: "):
        config = load_config(args.params)
    log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - progress to the terminal and logs
    return _stage(config, Path(args.runs), Path(args.out), Path(args.metrics), log, own)


def _stage(
    config: Config, runs_dir: Path, out: Path, metrics_path: Path, log: Callable[[str], None], own: Sequence[Path] = ()
) -> int:
    """The stage's work while it owns its outputs: run, analyse, write; the exit code."""
    with stage_inputs("design", NotRunsDatasetError):
        if config.design is None:
            summary, frames = skipped_metrics("design is null in params.yaml (no design study asked for)"), {}
        else:
            analysis, conds, summary = run(config, runs_dir, log)
            frames = tables(analysis, conds)
    write_outputs(frames, summary, out, metrics_path, own)
    if not frames:
        runs_dir.mkdir(parents=True, exist_ok=True)  # the stage's other output exists, empty
        print(f"design: skipped, {summary['skipped']}")
        return 0
    for line in summary["guidance"]:
        print(f"design: {line}")
    print(f"design: wrote {out} and {metrics_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
