"""DVC stage ``calibrate``: the fleet quantities that make the simulated survey the observed one -> data/calibration/.

``python -m pipeline.calibrate`` fits the fleet quantities listed in ``calibrate.fit`` (the chassis tilt
distribution's centre and spread, the air share, the WIM site's roughness, the sensor's error) so that the
simulated readings' distributions of each axle position's load share and of the spread match the observed survey's
under the same filters (``observed:``). The method and its checks are the library's, with plain arguments:
:mod:`bogie.fleet.calibration` (the calibration fleet's table of readings, the distance, the fit, the bootstrap;
``docs/calibration.md``) and :mod:`bogie.fleet.calibration.checks` (the calibrated fleet simulated directly, the
held-out half, the ablation). This stage reads params.yaml, turns it into those arguments (the calibration fleet is
the first ``calibrate.n_bogies`` bogies of the fleet study), weighs on the pipeline's one executor
(:func:`pipeline.workers.map_ordered`: simulate's loky pool, or the dask cluster of ``execution.backend: dask``)
and writes data/calibration/ and metrics/calibration.json.

Without an observed survey (``observed.path: null``) or a ``calibrate`` section the stage writes one line, a
metrics file that says why, and nothing else. Nothing here has a date: the same inputs give the same bytes.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration import problem as calibration
from bogie.fleet.calibration.checks import calibrate_survey
from bogie.fleet.calibration.problem import CalibrationError, CalibrationSettings, Mapper, Observed, Table, base_values
from bogie.fleet.constants import TILTED_QUANTITIES
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.rounding import json_number
from bogie.weighings.survey import observed_survey
from pipeline.atomic import atomic_outputs, run_stage, stage_inputs
from pipeline.config import Config, ExecutionConfig, load_config, observed_file
from pipeline.config.rules import calibration_tilt_count
from pipeline.config.schema import CALIBRATION_METHOD_KEYS
from pipeline.resources import worker_count
from pipeline.sample import sample_fleet
from pipeline.workers import map_ordered

__all__ = [
    "build_table", "calibration_samples", "crn_table", "defaults", "main", "method_settings", "observed_groups", "run",
    "workers_map",
]  # fmt: skip


# ---- params.yaml -> the library's arguments ----------------------------------------------------------------------
def method_settings(config: Config) -> CalibrationSettings:
    """``calibrate:``'s fit, optimiser and bootstrap settings, and the master seed."""
    cal = config.calibrate
    shared = {key: getattr(cal, key) for key in CALIBRATION_METHOD_KEYS}  # declared by CalibrationSettings
    return CalibrationSettings(fit=dict(cal.fit), seed=config.seed, **shared)


def defaults(config: Config) -> dict[str, float]:
    """The value each quantity has in params.yaml (what an unfitted quantity keeps): the air share is the mean of
    ``fleet.suspension_mix``'s distinct air shares."""
    mix = config.fleet.suspension_mix
    shares = {mix[g]["air"] for g in mix}
    air = float(np.mean(sorted(shares)))
    return base_values(config.distributions["chassis_tilt"], air, config.protocol.wim, _inhibitors(config))


def _inhibitors(config: Config) -> dict[str, Any]:
    """The fleet's distributions of the inhibitors whose mean a calibration may fit (SI)."""
    return {c: config.distributions[c] for c, _ in TILTED_QUANTITIES.values() if c in config.distributions}


def calibration_samples(config: Config) -> pd.DataFrame:
    """The first ``calibrate.n_bogies`` fleet bogies (their own samples, whatever suspension the fleet gave them)."""
    return sample_fleet(config).iloc[: config.calibrate.n_bogies].reset_index(drop=True)


def _tilt_grid(config: Config) -> np.ndarray:
    dist = config.distributions["chassis_tilt"]
    low, high = (math.degrees(v) for v in dist.support)
    return np.linspace(low, high, calibration_tilt_count(low, high, config.calibrate.tilt_step_deg))


def _fleet(config: Config) -> dict[str, Any]:
    """:func:`bogie.fleet.calibration.table.crn_table`'s arguments from params.yaml."""
    cal = config.calibrate
    settings: StaticProtocol | WimProtocol = config.protocol.static if cal.protocol == "static" else config.protocol.wim
    return {
        "samples": calibration_samples(config), "tilt_distribution": config.distributions["chassis_tilt"],
        "seed": config.seed, "protocol": cal.protocol, "settings": settings, "tilts": _tilt_grid(config),
        "site_iri_levels": cal.site_iri_levels, "study": "fleet", "inhibitor_distributions": _inhibitors(config),
        "table_sites": cal.table_sites,
    }  # fmt: skip


def crn_table(config: Config) -> Table:
    """The calibration fleet of params.yaml and its common random numbers, no reading yet."""
    return calibration.crn_table(**_fleet(config))


def build_table(config: Config, progress: Callable[[str], None] = print) -> Table:
    """The calibration fleet of params.yaml weighed on its grid, on the workers of ``execution``."""
    return calibration.build_table(**_fleet(config), executor=workers_map(config.execution), progress=progress)


def workers_map(execution: ExecutionConfig) -> Mapper:
    """The library's map-like executor on the stage's workers: simulate's pool of loky workers on this machine
    (``n_jobs`` capped as simulate's, at each call), or the dask cluster of ``execution.backend: dask``
    (:func:`pipeline.workers.map_ordered`, the one executor), the tasks in chunks; the same numbers either way."""

    def mapper(func: Callable[[Any], Any], tasks: Sequence[Any]) -> list:
        chosen = execution
        if chosen.backend != "dask":
            log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - the cap's warning to the log
            chosen = dataclasses.replace(chosen, n_jobs=worker_count(chosen.n_jobs, log, "calibrate"))
        chunk = max(1, len(tasks) // (8 * max(chosen.n_jobs, 1)) or 1)
        parts = [tasks[i : i + chunk] for i in range(0, len(tasks), chunk)]
        results = map_ordered(functools.partial(_each, func), parts, chosen, "calibration")
        return [value for part in results for value in part]

    return mapper


def _each(func: Callable[[Any], Any], part: Sequence[Any]) -> list:
    """``func`` of each item of a part of the tasks, on a worker."""
    return [func(item) for item in part]


#: why a survey of several sites is not calibrated (a folder of files, or a file of stations)
ONE_SITE = (
    "the calibration fits one site's survey (its site roughness, bias and between-site covariance are one site's: "
    "docs/calibration.md, 'The site'), and a network's calibration (issue 46 Must 2) is not yet in: the calibration "
    "is skipped; the report's observed pages set the sites side by side. Give one site's records to calibrate"
)


class SeveralSites(CalibrationError):
    """A survey of several sites: the stage skips the calibration, saying why (:data:`ONE_SITE`)."""


def observed_groups(path: Path, config: Config) -> tuple[Observed, pd.DataFrame]:
    """The observed survey's laden tandem and tri-axle groups under ``observed:``'s filters, and its groups table.

    Raises
    ------
    CalibrationError
        If too few groups of either size pass the filters (:func:`bogie.fleet.calibration.problem.observed_groups`).
    """
    obs = config.observed
    survey = observed_survey(path, obs.format, min_group_load_kg=obs.min_group_load, group_spacing_m=obs.group_spacing,
                             position=obs.position, resolution_kg=obs.resolution_kg)  # fmt: skip
    if survey.stations:  # several sites pooled would read as one site: the site terms and covariance are one site's
        names = sorted(survey.stations)
        raise SeveralSites(
            f"observed.path = {obs.path!r} holds {len(names)} stations ({', '.join(names[:3])}"
            f"{', ...' if len(names) > 3 else ''}), each a WIM site; {ONE_SITE}"
        )
    try:
        return calibration.observed_groups(survey), survey.groups
    except CalibrationError as exc:
        raise CalibrationError(
            f"observed.path = {obs.path!r}: after the filters (min_group_load_t {obs.min_group_load / 1000:g} t, "
            f"group_spacing_m {obs.group_spacing:g} m, position {obs.position}): {exc}. To compare this survey with "
            "the fleet on the report's observed page without calibrating to it, set calibrate: null in params.yaml"
        ) from None


# ---- the stage ---------------------------------------------------------------------------------------------------
def skipped_metrics(reason: str) -> dict[str, Any]:
    """metrics/calibration.json when nothing is calibrated."""
    return {"skipped": True, "reason": reason, "fitted": None, "observed": None, "calibrated": None, "held_out": None}


def run(config: Config, path: Path, progress: Callable[[str], None] = print) -> tuple[dict, dict[str, pd.DataFrame]]:
    """The whole calibration of params.yaml: metrics and the tables of data/calibration/
    (:func:`bogie.fleet.calibration.checks.calibrate_survey`)."""
    observed, _ = observed_groups(path, config)
    table = build_table(config, progress)
    metrics, tables = calibrate_survey(
        table, observed, method_settings(config), defaults(config), config.observed.min_group_load,
        workers_map(config.execution), progress, config.protocol.static,
    )  # fmt: skip
    values = {q: e["value"] for q, e in metrics["fitted"].items()}
    return {"skipped": False, **metrics, "fleet_study": fleet_study_overrides(values, config)}, tables


#: each fitted quantity's params.yaml key(s) in the fleet study (None: no params.yaml form; see fleet_study_overrides)
PARAMS_KEYS: dict[str, tuple[str, ...] | None] = {
    "chassis_tilt_mean_deg": ("distributions.chassis_tilt_deg.mean",),
    "chassis_tilt_sd_deg": ("distributions.chassis_tilt_deg.sd",),
    "air_share": ("fleet.suspension_mix",),  # each group's steel and air
    "site_iri_m_km": ("protocol.wim.site_iri_m_km",),
    "sensor_error_pct": ("protocol.wim.sensor_axle_error_pct",),
    "contact_roll_radius_mean_mm": None,
    "bush_stiffness_geomean": None,
}


def fleet_study_overrides(values: Mapping[str, float], config: Config) -> dict[str, Any]:
    """The fitted values as params.yaml settings for the fleet study (issue 31: offer to feed them back): ``set``
    (key -> value), ``command`` (the ``dvc exp run -S ...`` line that runs the study with them) and ``not_settable``
    (the fitted means of the inhibitor distributions: an exponential tilt of the fleet's uniform or log-uniform, a
    kind params.yaml has no form for; the fleet study keeps its own; and the site's bias, a property of the surveyed
    site, not of the fleet: the fleet study's WIM site reads without one)."""
    settings, not_settable = {}, []
    for quantity, value in values.items():
        keys = PARAMS_KEYS.get(quantity)
        if keys is None:
            not_settable.append(quantity)
            continue
        v = json_number(value, 4)
        if quantity == "air_share":  # one air share for every group, as the calibration fits it
            for group in config.fleet.suspension_mix:
                settings[f"{keys[0]}.{group}.steel"] = json_number(1.0 - v, 4)
                settings[f"{keys[0]}.{group}.air"] = v
        else:
            settings[keys[0]] = v
    command = "dvc exp run " + " ".join(f"-S {k}={v:g}" for k, v in settings.items()) if settings else None
    return {"set": settings, "command": command, "not_settable": not_settable}


def write_outputs(
    metrics: Mapping[str, Any], tables: Mapping[str, pd.DataFrame], out_dir, metrics_path, own: Sequence[Path] = ()
) -> None:
    """data/calibration/ and metrics/calibration.json, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir], stage="calibrate", own=own) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():  # the library's tables by name; the stage's files by name + .csv
            frame.to_csv(tmp_dir / f"{name}.csv", index=False, float_format="%.6g")
        if not tables:
            (tmp_dir / "README.txt").write_text(f"calibration skipped: {metrics['reason']}\n", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    """Run the stage; exit 2 with one line naming the bad input, nothing written."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.calibrate", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--out", default="data/calibration", help="output directory (default: data/calibration)")
    parser.add_argument("--metrics", default="metrics/calibration.json", help="default: metrics/calibration.json")
    args = parser.parse_args(argv)
    log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - progress to the terminal and logs
    return run_stage("calibrate", parser, args, lambda own: _stage(args, log, own), files=["metrics"], dirs=["out"])


def _stage(args: argparse.Namespace, log: Callable[[str], None], own: Sequence[Path] = ()) -> int:
    """The stage's work while it owns its outputs: read, calibrate, write; the exit code."""
    with stage_inputs("calibrate"):
        config = load_config(args.params, note=lambda line: log(f"calibrate: {line}"))
        path = observed_file(config.observed, Path(args.params).resolve().parent)
        reason = None
        if path is None or config.calibrate is None or path.is_dir():
            reason = (
                "no observed survey given (observed.path is null in params.yaml; docs/observed.md)" if path is None
                else "no calibrate section in params.yaml (calibrate: null)" if config.calibrate is None
                else f"observed.path = {config.observed.path!r} is a folder of files, each a site; {ONE_SITE}"
            )  # fmt: skip
        else:
            try:
                metrics, tables = run(config, path, log)
            except SeveralSites as exc:
                reason = str(exc)
        if reason is not None:
            metrics, tables = skipped_metrics(reason), {}
    write_outputs(metrics, tables, args.out, args.metrics, own)
    if metrics["skipped"]:
        print(f"calibrate: skipped, {metrics['reason']}")
    else:
        fitted = ", ".join(f"{q} {e['value']:.3g}" for q, e in metrics["fitted"].items())
        print(f"calibrate: {fitted}; distance {metrics['distance']}; wrote {args.out} and {args.metrics}")
        post = metrics.get("posterior") or {}
        if post.get("converged") is False:  # issue 43 Must 5: an unconverged posterior is said, with what to change
            print(f"calibrate: posterior {post['advice']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
