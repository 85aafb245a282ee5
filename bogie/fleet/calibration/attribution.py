"""What the WIM shows, by cause: on the calibrated fleet, how much of the inequality the readings show comes from
the file's resolution, the sensor, the chassis tilt and the dynamics, and how much is the suspension's own at rest
(``docs/calibration.md``, issue 30 Must 6).

Paired runs: the calibration bogies of the calibrated fleet (their fitted tilts, suspensions and inhibitor
distributions) weighed four ways with common random numbers: by WIM at their tilt and level, statically at their
tilt and level. From those, the **scenarios** (each the readings as observed with one cause switched off, and the
suspension at rest with all of them off):

| scenario | readings |
|---|---|
| ``as_observed`` | WIM at the fitted tilt, times the sensor's factors, read at the file's resolution |
| ``no_resolution`` | the same, not rounded |
| ``no_sensor`` | WIM at the fitted tilt, read at the resolution, no sensor error |
| ``no_tilt`` | WIM with the chassis level, with the sensor's error, at the resolution |
| ``no_dynamics`` | the static weighing at the fitted tilt, with the sensor's error, at the resolution |
| ``at_rest`` | the static weighing with the chassis level, exact: the suspension mechanics alone |

A cause's **share** of a statistic is ``as_observed - no_<cause>``: what switching that one cause off removes (the
causes interact, so the shares need not add up to ``as_observed - at_rest``; the difference is their interaction).
The groups compared are the same in every scenario: those ``as_observed`` keeps (laden, every wheel read) and that
every scenario weighed. Intervals: a paired bootstrap over the groups.
"""

from __future__ import annotations

from collections.abc import Mapping
from concurrent.futures import Executor
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.problem import SIZES, CalibrationError, Mapper, Table
from bogie.fleet.calibration.table import bogie_tilts, moved_samples, protocol_spec, weigh_readings
from bogie.fleet.weighing.settings import StaticProtocol
from bogie.intervals import percentile_interval
from bogie.rounding import json_number
from bogie.weighings.stats import at_resolution, group_inequality

__all__ = ["CAUSES", "SCENARIOS", "STATISTICS", "attribution", "scenario_loads"]

#: the causes switched off one at a time, and the scenario without each
CAUSES: dict[str, str] = {
    "resolution": "no_resolution", "sensor": "no_sensor", "tilt": "no_tilt", "dynamics": "no_dynamics",
}  # fmt: skip
#: every scenario, in the order of the table
SCENARIOS: tuple[str, ...] = ("as_observed", *CAUSES.values(), "at_rest")
#: the statistics attributed: share of groups outside 5 % (VSB 11) [-], share with an axle over 10 % of its equal
#: share [-], mean spread (max - min) / mean [%]
STATISTICS: tuple[str, ...] = ("share_outside_5pct", "share_over_10pct", "mean_spread_pct")


def scenario_loads(
    table: Table, values: Mapping[str, float], static: StaticProtocol, weight_step_kg: float | None,
    executor: Executor | Mapper | None = None,
) -> tuple[dict[str, np.ndarray], np.ndarray]:  # fmt: skip
    """Every scenario's loads [kg] of the calibrated fleet (:data:`SCENARIOS` -> (n, 3)), and each bogie's suspension
    (``steel``/``air``). Four direct weighings of the calibration bogies (WIM and static, tilted and level)."""
    if table.protocol != "wim":
        raise CalibrationError("attribution: the table must be a WIM calibration's (it splits the WIM's readings)")
    if not isinstance(static, StaticProtocol):
        raise CalibrationError(f"static = {static!r}: must be a StaticProtocol (the weighing without dynamics)")
    tilt = np.radians(bogie_tilts(table, values))
    kinds = np.where(table.air_u < values["air_share"], "air", "steel")
    rows = moved_samples(table, values).to_dict("records")
    wim = protocol_spec(table, values["site_iri_m_km"])
    weighed = {}
    for name, protocol, spec, level in (
        ("wim", "wim", wim, False), ("wim_level", "wim", wim, True), ("static", "static", static, False),
        ("static_level", "static", static, True),
    ):  # fmt: skip
        tasks = [
            ({**row, "suspension": kinds[i], "chassis_tilt": 0.0 if level else float(tilt[i])}, protocol, spec)
            for i, row in enumerate(rows)
        ]  # fmt: skip
        weighed[name] = weigh_readings(tasks, executor)
    factors = (1.0 + 0.01 * values["sensor_error_pct"] * table.z) * table.pass_factors()[:, None]
    step = weight_step_kg
    loads = {
        "as_observed": at_resolution(weighed["wim"] * factors, step),
        "no_resolution": weighed["wim"] * factors,
        "no_sensor": at_resolution(weighed["wim"], step),
        "no_tilt": at_resolution(weighed["wim_level"] * factors, step),
        "no_dynamics": at_resolution(weighed["static"] * factors, step),
        "at_rest": weighed["static_level"],
    }  # fmt: skip
    return loads, kinds


def _statistics(loads: np.ndarray, n: int) -> np.ndarray:
    """Per group: outside 5 %, over 10 %, spread [%] (columns of :data:`STATISTICS`)."""
    ineq = group_inequality(loads, np.full(len(loads), n))
    return np.column_stack([ineq["outside_5pct"], ineq["over_10pct"], ineq["spread_pct"]]).astype(float)


def attribution(
    table: Table, values: Mapping[str, float], min_group_load_kg: float, static: StaticProtocol,
    weight_step_kg: float | None = None, executor: Executor | Mapper | None = None, seed: int = 0,
    resamples: int = 200, confidence_level: float = 0.9,
) -> tuple[pd.DataFrame, dict[str, Any]]:  # fmt: skip
    """The attribution of the calibrated fleet's WIM inequality to its causes.

    Parameters
    ----------
    table, values
        The calibration's table (a WIM one) and the calibrated fleet's values (every quantity).
    min_group_load_kg
        The survey's smallest group load [kg], applied to the ``as_observed`` readings.
    static
        The static weighing's settings: the readings without dynamics.
    weight_step_kg
        The observed file's resolution [kg] (None: whole numbers as they are).
    executor
        Where the weighings run.
    seed, resamples, confidence_level
        The paired bootstrap's seed, resamples (>= 2) and the intervals' confidence level (0, 1).

    Returns
    -------
    table : DataFrame
        One row per scenario, size and suspension: ``n_groups`` and each of :data:`STATISTICS`.
    metrics : dict
        Per ``size/suspension``: ``n_groups``, ``n_dropped`` (weighed in one scenario but not another),
        ``as_observed`` and ``at_rest`` statistics, and per cause of :data:`CAUSES` each statistic's share
        ``value`` with its interval ``low``, ``high``.
    """
    loads, kinds = scenario_loads(table, values, static, weight_step_kg, executor)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(4,)))
    rows, metrics = [], {}
    for size, n in SIZES.items():
        for kind in ("steel", "air"):
            sel = (table.size == size) & (kinds == kind)
            obs = loads["as_observed"][sel, :n]
            laden = np.all(np.isfinite(obs) & (obs > 0.0), axis=1) & (np.nansum(obs, axis=1) >= min_group_load_kg)
            ok = laden.copy()
            for name in SCENARIOS:
                w = loads[name][sel, :n]
                ok &= np.all(np.isfinite(w) & (w > 0.0), axis=1)
            if not ok.any():
                continue
            per = {name: _statistics(loads[name][sel, :n][ok], n) for name in SCENARIOS}
            means = {name: per[name].mean(axis=0) for name in SCENARIOS}
            for name in SCENARIOS:
                rows.append({"scenario": name, "group": size, "suspension": kind, "n_groups": int(ok.sum()),
                             **dict(zip(STATISTICS, means[name]))})  # fmt: skip
            metrics[f"{size}/{kind}"] = _metrics_of(per, means, int(ok.sum()), int((laden & ~ok).sum()), rng,
                                                    resamples, confidence_level)  # fmt: skip
    return pd.DataFrame(rows, columns=["scenario", "group", "suspension", "n_groups", *STATISTICS]), metrics


def _share(diff: np.ndarray, boot: np.ndarray, confidence_level: float) -> dict[str, float | None]:
    """A cause's share of one statistic: the mean paired difference and its percentile interval, for JSON."""
    low, high = percentile_interval(boot, confidence_level)
    return {"value": json_number(diff.mean()), "low": json_number(low), "high": json_number(high)}


def _metrics_of(per, means, n_groups, dropped, rng, resamples, confidence_level) -> dict[str, Any]:
    k = len(per["as_observed"])
    idx = rng.integers(0, k, size=(max(resamples, 2), k))
    causes = {}
    for cause, scenario in CAUSES.items():
        diff = per["as_observed"] - per[scenario]  # paired: the same groups
        boot = diff[idx].mean(axis=1)  # (resamples, statistics)
        causes[cause] = {
            s: _share(diff[:, j], boot[:, j], confidence_level)
            for j, s in enumerate(STATISTICS)
        }  # fmt: skip
    return {
        "n_groups": n_groups, "n_dropped": dropped,
        "as_observed": {s: json_number(means["as_observed"][j]) for j, s in enumerate(STATISTICS)},
        "at_rest": {s: json_number(means["at_rest"][j]) for j, s in enumerate(STATISTICS)},
        "causes": causes,
    }  # fmt: skip
