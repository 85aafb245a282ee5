"""DVC stage ``road``: what unequal sharing costs the road -> data/road/, metrics/road.json (issue 32).

``python -m pipeline.road`` reads the fleet's runs, the observed survey's groups (``data/observed``; none without a
survey) and the design experiment (``data/design_runs``, ``data/design``; none with ``design: null``), and writes

- ``data/road/wear.csv``: per source (``simulated`` with its protocol, ``observed``), group size, position and
  suspension: the extra pavement wear that unequal sharing causes over the same groups shared equally, at each
  damage exponent (:data:`bogie.weighings.wear.DAMAGE_EXPONENTS`), as a share and as extra standard axles per 1,000
  laden groups, and the axles above the single-axle limit within legal groups (an indicator, not an offence), all
  with intervals
  (:func:`bogie.weighings.wear.wear_statistics`, one definition for both sources; ``observed_wear.csv`` the
  observed side's, by size and position);
- ``data/road/sharing_factors.csv``: the sharing factors for pavement design tools, per source, protocol, size,
  position and suspension, at each exponent, with their intervals and a header that says what each column is
  (:func:`bogie.weighings.pavement.sharing_factors`, ``docs/pavement.md``, "Sharing factors");
- ``data/road/savings.csv``: what acting would save against today's typical design, paired over the design
  experiment's conditions (:func:`bogie.fleet.road.design_savings`): the best steel design, air suspension, the
  chassis tilt held within the typical design's tolerance;
- ``metrics/road.json``: the same figures, nested, with the legal loads and exponents used.

The legal loads are Directive 96/53/EC's by each group's position and spacing (:mod:`bogie.weighings.legal`): an
observed group's from its own; the simulated fleet's are semi-trailer bogies, judged as trailer groups at their base
bogie's axle spacing (``fleet.presets``). ``fleet.legal_group_load_t`` is the load the fleet is laden to (its design
payload), not the limit it is judged against (the two agree for the default presets, 1.31 m apart: 18 and 24 t).

Laden groups are those of at least ``observed.min_group_load_t``, the filter the observed page applies to both
sides. The method, sources and assumptions are in ``docs/pavement.md``.
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

from bogie.bogie_file import base_bogie
from bogie.fleet.road import design_savings, fleet_wear, sensor_free
from bogie.group_names import GROUP_AXLES
from bogie.params import GRAVITY
from bogie.rounding import json_number
from bogie.weighings.legal import EU_SOURCE, group_limits, spacing_step_m
from bogie.weighings.pavement import aashto_view, sharing_factors, write_sharing_factors
from bogie.weighings.survey import SURVEYED
from bogie.weighings.wear import DAMAGE_EXPONENTS, STANDARD_AXLE_KG, wear_dict, wear_statistics
from pipeline.atomic import atomic_outputs, run_stage, stage_inputs
from pipeline.config import load_config
from pipeline.schema import read_checksummed, read_runs_frame
from pipeline.survey import SURVEY_STUDY, read_runs

__all__ = [
    "AASHTO_PAVEMENT", "CONFIDENCE", "RESAMPLES", "aashto_means", "calibrated_wear", "dynamics_and_sensor",
    "factors_table",
    "fleet_limits", "main", "observed_wear", "road_metrics",
]  # fmt: skip

#: bootstrap resamples of every interval of the stage [-]
RESAMPLES = 1000
#: the level of every interval of the stage [-]
CONFIDENCE = 0.95


def fleet_limits(presets: Mapping[str, str]) -> tuple[dict[str, float], float]:
    """The legal group load of each size of a simulated fleet of semi-trailer bogies and its single-axle limit [kg]:
    96/53/EC's for a trailer group at its base bogie's axle spacing (``presets``: size -> preset or bogie file)."""
    rows = []
    for group, name in presets.items():
        gaps = np.diff(base_bogie(name).axle_x)
        rows.append({"group": group, "position": "trailer", "spacing_1": float(gaps[0]),
                     "spacing_2": float(gaps[1]) if len(gaps) > 1 else float("nan")})  # fmt: skip
    group_kg, axle_kg = group_limits(pd.DataFrame(rows))
    return dict(zip(presets, (float(v) for v in group_kg))), float(axle_kg[0])


def observed_wear(groups: pd.DataFrame, seed: int, spacing_step: float = 0.0) -> pd.DataFrame:
    """:func:`bogie.weighings.wear.wear_statistics` of the observed tandems and tri-axles (loads in kg), by size and
    position, judged by 96/53/EC's limits by position and spacing (read at ``spacing_step`` [m]:
    :func:`bogie.weighings.formats.spacing_step_m`); an empty table without a survey."""
    surveyed = groups[groups["group"].astype(str).isin(SURVEYED)] if len(groups) else groups
    if not len(surveyed):
        return pd.DataFrame()
    surveyed = surveyed.assign(group=surveyed["group"].astype(str), position=surveyed["position"].astype(str))
    return wear_statistics(surveyed, None, None, by=["group", "position"], resamples=RESAMPLES,
                           confidence_level=CONFIDENCE, seed=seed, spacing_step_m=spacing_step)  # fmt: skip


def factors_table(
    simulated: pd.DataFrame, observed: pd.DataFrame, observed_kind: str,
    calibrated: tuple[pd.DataFrame, str] | None = None,
) -> pd.DataFrame:  # fmt: skip
    """``data/road/sharing_factors.csv``'s rows (:func:`bogie.weighings.pavement.sharing_factors`): the simulated
    fleet's trailer groups by protocol, size and suspension, then the observed survey's by size and position (its
    protocol ``observed_kind``, its suspension as observed), then the calibrated fleet's by size and suspension
    (``calibrated``: its wear table and protocol, :func:`calibrated_wear`)."""
    parts = [sharing_factors(simulated, DAMAGE_EXPONENTS, source="simulated", position="trailer")]
    if len(observed):
        parts.append(sharing_factors(observed, DAMAGE_EXPONENTS, source="observed", protocol=observed_kind,
                                     suspension="as observed"))  # fmt: skip
    if calibrated is not None and len(calibrated[0]):
        parts.append(sharing_factors(calibrated[0], DAMAGE_EXPONENTS, source="calibrated", protocol=calibrated[1],
                                     position="trailer"))  # fmt: skip
    return pd.concat(parts, ignore_index=True)


def calibrated_wear(
    table: Path, metrics: Path, legal_group: Mapping[str, float], legal_axle: float, seed: int
) -> tuple[pd.DataFrame, str] | None:
    """The calibrated fleet's figures by size and suspension (:func:`bogie.weighings.wear.wear_statistics`) and its
    protocol: ``table`` is the calibrate stage's direct simulation of the fleet at the posterior's medians
    (``data/calibration/calibrated.csv``: the calibration bogies' laden groups as the survey's protocol weighs them,
    loads in kg), ``metrics`` its metrics file (the protocol); the intervals are over the groups, not over the
    posterior. None without a calibration (the stage skipped, no table)."""
    if not table.is_file():
        return None
    frame = pd.read_csv(table)
    with open(metrics, encoding="utf-8") as fh:
        protocol = str(json.load(fh)["protocol"])
    frame = frame.assign(position="trailer", group=frame["group"].astype(str),
                         suspension=frame["suspension"].astype(str))  # fmt: skip
    wear = wear_statistics(frame, legal_group, legal_axle, by=["group", "suspension"], resamples=RESAMPLES,
                           confidence_level=CONFIDENCE, seed=seed)  # fmt: skip
    return wear, protocol


#: the figures of a split of the WIM reading's (:func:`dynamics_and_sensor`)
SPLIT_FIGURES: tuple[str, ...] = (
    "n_groups", "n_hidden", "share_hidden_overload", "share_group_over", "extra_wear_overall",
    "extra_wear_group_overall",
)  # fmt: skip


def dynamics_and_sensor(
    runs: pd.DataFrame, legal_group: Mapping[str, float], legal_axle: float, min_group_load: float, wim: Any
) -> dict[str, Any]:
    """The WIM side's laden groups as a sensor without error would read them (:func:`bogie.fleet.road.sensor_free`
    with the ``wim`` protocol's error sizes), by size and suspension: the same groups as the WIM figures (laden by
    their reading), so that static, this and WIM split what unequal sharing, the dynamics at the sensor and the
    sensor's error each add (issue 44 Must 3); no interval (the figures are the split's, beside the WIM's)."""
    is_wim = runs["protocol"].astype(str).eq("wim")
    laden = runs["group_load"].astype(float) / GRAVITY >= min_group_load
    kept = runs[is_wim & (laden | ~runs["status"].astype(str).eq("ok"))]
    free = fleet_wear(sensor_free(kept, wim.vehicle_error_sd, wim.axle_error_sd), legal_group, legal_axle, 0.0,
                      resamples=0)  # fmt: skip
    out = wear_dict(free, ["protocol", "group", "suspension"], digits=4).get("wim", {}) if len(free) else {}
    return {g: {k: {f: e[f] for f in SPLIT_FIGURES} for k, e in sus.items()} for g, sus in out.items()}


#: the flexible pavement AASHTO's factors are read on (:func:`aashto_means`): the guide's worked example's structural
#: number 5 and terminal serviceability 2.5 (Appendix D, Table D.5) [-]
AASHTO_PAVEMENT = {"structural_number": 5.0, "terminal_serviceability": 2.5}


def aashto_means(runs: pd.DataFrame, min_group_load: float) -> dict[str, Any]:
    """What AASHTO 1993 says about the fleet's laden steel groups (:func:`bogie.weighings.pavement.aashto_view` on
    :data:`AASHTO_PAVEMENT`), per protocol and size: the mean group factor (a tandem's or tridem's total: its sharing
    not in it), and the mean of its axles' factors as single axles as shared and as shared equally [-], with the
    groups counted (issue 44 Must 2)."""
    out: dict[str, Any] = {"pavement": dict(AASHTO_PAVEMENT)}
    ok = runs["status"].astype(str).eq("ok") & runs["suspension"].astype(str).eq("steel")
    laden = ok & (runs["group_load"].astype(float) / GRAVITY >= min_group_load)
    for (protocol, group), rows in runs[laden].groupby(["protocol", "group"], observed=True, sort=True):
        n = GROUP_AXLES[str(group)]
        loads = rows[[f"axle_load_{i + 1}" for i in range(n)]].to_numpy(dtype=float) / GRAVITY
        view = aashto_view(loads, **AASHTO_PAVEMENT)
        out.setdefault(str(protocol), {})[str(group)] = {
            "n_groups": len(rows), **{k: json_number(float(np.mean(v)), 4) for k, v in view.items()}
        }  # fmt: skip
    return out


def road_metrics(
    simulated: pd.DataFrame,
    observed: pd.DataFrame,
    savings: pd.DataFrame,
    legal_group: Mapping[str, float],
    legal_axle: float,
    min_group_load: float,
    design_note: str | None,
) -> dict[str, Any]:
    """metrics/road.json: the settings, the simulated and observed figures and the savings, NaN as null;
    ``legal_group``, ``legal_axle``: the simulated fleet's limits [kg] (:func:`fleet_limits`)."""
    return {
        "legal_group_load_kg": {k: json_number(v, 1) for k, v in legal_group.items()},
        "legal_axle_load_kg": json_number(legal_axle, 1),
        "legal_loads": {
            "source": EU_SOURCE,
            "simulated": "trailer groups at the base bogie's axle spacing",
            "observed": "each group by its own position and spacing",
        },  # fmt: skip
        "min_group_load_kg": json_number(min_group_load, 1),
        "standard_axle_kg": json_number(STANDARD_AXLE_KG, 1),
        "exponents": dict(DAMAGE_EXPONENTS),
        "confidence_level": CONFIDENCE,
        "simulated": wear_dict(simulated, ["protocol", "group", "suspension"]) if len(simulated) else {},
        "observed": wear_dict(observed, ["group", "position"]) if len(observed) else None,
        "savings": wear_dict(savings, ["group", "scenario"]) if len(savings) else None,
        "savings_note": design_note,
    }


def _spacing_step(path: Path) -> float:
    """The step the observed file's spacings were read at [m]: its format's, as the observed stage's metrics name it
    (a KeyError naming the key, or OSError, if they do not)."""
    with open(path, encoding="utf-8") as fh:
        read = json.load(fh).get("observed") or {}
    if "format" not in read:
        raise KeyError(f"{path}: observed.format (the format the survey was read in): rerun the observed stage")
    return spacing_step_m(read["format"])


def _design_inputs(config, design_runs: Path, design_dir: Path) -> tuple[pd.DataFrame, pd.DataFrame, Any] | None:
    """The design experiment's runs (with design, condition, slot), its design table and tilt grid; None without a
    design study."""
    if config.design is None:
        return None
    from bogie.fleet.design.experiment import experiment_runs
    from pipeline.design import experiment

    exp = experiment(config)
    runs = experiment_runs(exp, read_runs_frame(design_runs))
    return runs, pd.read_csv(design_dir / "designs.csv"), exp.tilts


def main(argv: list[str] | None = None) -> int:
    """Run the stage; exit 2 with the reason on bad input, leaving the old outputs."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.road", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--observed", default="data/observed", help="observed groups (default: data/observed)")
    parser.add_argument("--design-runs", default="data/design_runs", help="default: data/design_runs")
    parser.add_argument("--design", default="data/design", help="design tables (default: data/design)")
    parser.add_argument("--calibration", default="data/calibration", help="default: data/calibration")
    parser.add_argument("--calibration-metrics", default="metrics/calibration.json",
                        help="default: metrics/calibration.json")  # fmt: skip
    parser.add_argument("--observed-metrics", default="metrics/observed.json",
                        help="the observed stage's metrics, for the format its file was read in (default: "
                        "metrics/observed.json)")  # fmt: skip
    parser.add_argument("--out", default="data/road", help="output directory (default: data/road)")
    parser.add_argument("--metrics", default="metrics/road.json", help="default: metrics/road.json")
    args = parser.parse_args(argv)
    return run_stage("road", parser, args, lambda own: _stage(args, own), files=["metrics"], dirs=["out"])


def _stage(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """The stage's work while it owns its outputs: read, compute, write; the exit code."""
    with stage_inputs("road", KeyError):
        config = load_config(args.params)
        legal_group, legal_axle = fleet_limits(config.fleet.presets)
        min_load = float(config.observed.min_group_load)
        groups_file = Path(args.observed) / "groups.parquet"
        if config.observed.path is not None and not groups_file.is_file():
            raise ValueError(
                f"observed.path names a survey ({config.observed.path}) but {groups_file} is missing: run the observed "
                "stage first (dvc repro observed), or set observed.path: null"
            )
        runs = read_runs(args.runs, SURVEY_STUDY)
        rerun = "delete it and rerun the observed stage"
        groups = read_checksummed(groups_file, rerun).to_pandas() if groups_file.exists() else pd.DataFrame()
        step = _spacing_step(Path(args.observed_metrics)) if len(groups) else 0.0
        design = _design_inputs(config, Path(args.design_runs), Path(args.design))
        calibrated = calibrated_wear(Path(args.calibration) / "calibrated.csv", Path(args.calibration_metrics),
                                     legal_group, legal_axle, config.seed)  # fmt: skip
    simulated = fleet_wear(runs, legal_group, legal_axle, min_load, resamples=RESAMPLES, confidence_level=CONFIDENCE,
                           seed=config.seed)  # fmt: skip
    split = dynamics_and_sensor(runs, legal_group, legal_axle, min_load, config.protocol.wim)
    aashto = aashto_means(runs, min_load)
    observed = observed_wear(groups, config.seed, step)
    if design is None:
        savings, note = pd.DataFrame(), "design is null in params.yaml: no design experiment to compare designs over"
    else:
        savings = design_savings(*design, legal_group, legal_axle, resamples=RESAMPLES, confidence_level=CONFIDENCE,
                                 seed=config.seed)  # fmt: skip
        note = None
    metrics = road_metrics(simulated, observed, savings, legal_group, legal_axle, min_load, note)
    metrics["wim_without_sensor_error"] = split
    metrics["aashto"] = aashto
    metrics["calibrated"] = None if calibrated is None else wear_dict(calibrated[0], ["group", "suspension"])
    with atomic_outputs(files=[args.metrics], dirs=[args.out], stage="road", own=own) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        simulated.assign(source="simulated").to_csv(tmp_dir / "wear.csv", index=False, float_format="%.6g")
        if len(observed):
            observed.assign(source="observed").to_csv(tmp_dir / "observed_wear.csv", index=False, float_format="%.6g")
        savings.to_csv(tmp_dir / "savings.csv", index=False, float_format="%.6g")
        factors = factors_table(simulated, observed, config.observed.kind, calibrated)
        write_sharing_factors(factors, tmp_dir / "sharing_factors.csv")
    told = "no observed survey" if not len(observed) else f"{int(observed['n_groups'].sum())} observed groups"
    print(
        f"road: {int(simulated['n_groups'].sum())} simulated laden readings, {told}; wrote {args.out}, {args.metrics}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
