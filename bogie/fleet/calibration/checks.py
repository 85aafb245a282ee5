"""The checks of a calibration, and a whole calibration of an observed survey in one call (``docs/calibration.md``).

:func:`calibrate_survey` fits (:func:`bogie.fleet.calibration.fitting.calibrate`) and checks: the calibrated fleet
simulated directly, not through the table, under the survey's filters (``calibrated``); a fit on alternate records held
against the other half (``held_out``); the ablation re-run on the calibrated fleet's steel groups. Its metrics are
those of ``metrics/calibration.json`` (the DVC stage ``pipeline/calibrate.py`` writes them). :func:`write_csv_survey`
writes simulated groups as a survey file, a synthetic survey to calibrate to. Loads in kg.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.attribution import attribution
from bogie.fleet.calibration.fitting import PRIOR_FREE, calibrate, priors_for, sensor_finding
from bogie.fleet.calibration.posterior import posterior
from bogie.fleet.calibration.prior_sensitivity import prior_sensitivity
from bogie.fleet.calibration.problem import (
    SIZES,
    CalibrationError,
    CalibrationSettings,
    Mapper,
    Observed,
    Simulated,
    Table,
    _values,
    distance,
    fit,
    make_problem,
    observed_quantities,
)

# the synthetic survey's writer, in its own module; its names are still found here
from bogie.fleet.calibration.synthetic import SYNTHETIC_TRACTOR, write_csv_survey
from bogie.fleet.calibration.table import (
    _quiet,
    _summary,
    bogie_tilts,
    moved_samples,
    protocol_spec,
    weigh_readings,
)
from bogie.fleet.weighing.observed import by_size
from bogie.fleet.weighing.settings import StaticProtocol
from bogie.intervals import percentile_interval
from bogie.metrics import max_deviation
from bogie.params import INHIBITORS
from bogie.rounding import json_number
from bogie.weighings.stats import at_resolution, group_inequality, survey_statistics

__all__ = [
    "SYNTHETIC_TRACTOR", "ablation", "calibrate_survey", "filtered", "frame_distance", "frame_stats", "groups_stats",
    "held_out", "observed_distance", "simulate_fleet", "write_csv_survey",
]  # fmt: skip


# ---- the calibrated fleet, simulated directly -------------------------------------------------------------------
def simulate_fleet(
    table: Table, values: Mapping[str, float], variant: str = "baseline", steel_only: bool = False,
    weight_step_kg: float | None = None, executor: Executor | Mapper | None = None,
) -> pd.DataFrame:  # fmt: skip
    """The calibration fleet with the quantities ``values``, weighed directly (no table): one row per group kept
    (``slot``, ``group``, ``n_axles``, ``suspension``, ``tilt_deg`` [degree], wide loads ``axle_load_1..3`` [kg]),
    with the site's bias and the sensor's error, before the filters; WIM on the table's site, each bogie at its
    speed (:meth:`~bogie.fleet.calibration.table.Table.task`).

    ``variant`` removes an inhibitor of the steel groups (:data:`bogie.params.INHIBITORS`, or ``all``);
    ``weight_step_kg`` reads the loads at the observed file's resolution [kg] (None: as they are; the ablation's
    physics is read so); ``executor`` is where the weighings run
    (:func:`bogie.fleet.calibration.table.weigh_readings`).
    """
    if variant not in ("baseline", *INHIBITORS, "all"):
        raise CalibrationError(f"variant = {variant!r}: must be baseline, all or one of {', '.join(INHIBITORS)}")
    tilt = bogie_tilts(table, values)
    kinds = np.where(table.air_u < values["air_share"], "air", "steel")
    iri = values["site_iri_m_km"] if table.protocol == "wim" else math.nan
    spec = protocol_spec(table, iri)
    tasks, keep = [], []
    for i, row in enumerate(moved_samples(table, values).to_dict("records")):
        if steel_only and kinds[i] != "steel":
            continue
        sample = {**row, "suspension": kinds[i], "chassis_tilt": math.radians(float(tilt[i]))}
        if variant != "baseline":
            for name, ideal in INHIBITORS.items():
                if variant in (name, "all"):
                    sample[name] = ideal
        tasks.append(table.task(i, sample, spec))
        keep.append(i)
    loads = weigh_readings(tasks, executor) * table.reading_factors(values, np.asarray(keep, dtype=int))
    loads = at_resolution(loads, weight_step_kg)
    frame = pd.DataFrame({
        "slot": keep, "group": table.size[keep], "n_axles": [SIZES[s] for s in table.size[keep]],
        "suspension": kinds[keep], "tilt_deg": tilt[keep],
        **{f"axle_load_{i + 1}": loads[:, i] for i in range(3)},
    })  # fmt: skip
    return frame


def filtered(frame: pd.DataFrame, min_group_load_kg: float) -> pd.DataFrame:
    """The groups a survey keeps: weighed, every wheel on the road, laden (at least ``min_group_load_kg`` [kg])."""
    n = frame["n_axles"].to_numpy()
    loads = frame[[f"axle_load_{i + 1}" for i in range(3)]].to_numpy()
    present = np.arange(3)[None, :] < n[:, None]
    ok = np.all(np.where(present, np.isfinite(loads) & (loads > 0.0), True), axis=1)
    total = np.nansum(np.where(present, loads, 0.0), axis=1)
    return frame[ok & (total >= min_group_load_kg)].reset_index(drop=True)


def groups_stats(loads_by_size: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """``bogie weighings --json``'s ``groups`` object of per-size load tables [kg]."""
    rows = []
    for size, loads in loads_by_size.items():
        for w in loads:
            rows.append({"group": size, "n_axles": SIZES[size], **{f"axle_load_{i + 1}": w[i] for i in range(len(w))}})
    frame = pd.DataFrame(rows)
    if frame.empty:
        return by_size(pd.DataFrame())
    return by_size(survey_statistics(frame, by="group"))


def frame_stats(frame: pd.DataFrame) -> dict[str, Any]:
    """:func:`groups_stats` of a simulated frame (:func:`simulate_fleet`)."""
    return groups_stats({
        size: frame.loc[frame["group"] == size, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy()
        for size, n in SIZES.items()
    })  # fmt: skip


def frame_distance(frame: pd.DataFrame, obs: Mapping[str, np.ndarray], scales: Mapping[str, np.ndarray]) -> float:
    """The distance [-] of a directly simulated (unweighted) survey to observed quantities
    (:func:`bogie.fleet.calibration.problem.observed_quantities` per size) over their ``scales``."""
    q, w = {}, {}
    for size, n in SIZES.items():
        loads = frame.loc[frame["group"] == size, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy()
        q[size] = observed_quantities(loads) if len(loads) else np.zeros((0, n + 1))
        w[size] = np.ones(len(loads))
    return distance(obs, {k: np.ones(len(v)) for k, v in obs.items()}, Simulated(q, w), scales)


def observed_distance(
    a: Mapping[str, np.ndarray], b: Mapping[str, np.ndarray], scales: Mapping[str, np.ndarray]
) -> float:
    """The distance [-] between two observed halves' quantities: the floor a held-out distance can reach."""
    sim = Simulated({k: b.get(k, np.zeros((0, v.shape[1]))) for k, v in a.items()},
                    {k: np.ones(len(b.get(k, []))) for k in a})  # fmt: skip
    return distance(a, {k: np.ones(len(v)) for k, v in a.items()}, sim, scales)


def ablation(
    table: Table, values: Mapping[str, float], min_group_load_kg: float, executor: Executor | Mapper | None = None
) -> pd.DataFrame:
    """The calibrated fleet's steel groups with each inhibitor removed, groups of at least ``min_group_load_kg``
    [kg]: per variant and size, ``n_groups``, the mean max deviation [%], the share outside 5 % [-] and the points
    [%] the variant buys against the baseline."""
    rows = []
    for variant in ("baseline", *INHIBITORS, "all"):
        frame = filtered(simulate_fleet(table, values, variant, steel_only=True, executor=executor), min_group_load_kg)
        for size, n in SIZES.items():
            loads = frame.loc[frame["group"] == size, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy()
            if len(loads) == 0:
                continue
            max_dev = max_deviation(loads)
            outside = group_inequality(loads, np.full(len(loads), n))["outside_5pct"]
            rows.append({
                "variant": variant, "group": size, "n_groups": len(loads),
                "mean_max_deviation_pct": 100.0 * float(max_dev.mean()), "share_outside_5pct": float(outside.mean()),
            })  # fmt: skip
    columns = ["variant", "group", "n_groups", "mean_max_deviation_pct", "share_outside_5pct"]
    table_ = pd.DataFrame(rows, columns=columns)
    base = table_[table_["variant"] == "baseline"].set_index("group")
    # a size the baseline has no laden group of (a small calibration fleet) has nothing to buy against: NaN, stated
    # by the baseline's missing row, not a KeyError
    table_["buys_points"] = [
        base.loc[g, "mean_max_deviation_pct"] - m if g in base.index else math.nan
        for g, m in zip(table_["group"], table_["mean_max_deviation_pct"])
    ]
    return table_


# ---- held out, and the whole calibration of a survey ---------------------------------------------------------------
def held_out(
    table: Table, observed: Observed, settings: CalibrationSettings, base: Mapping[str, float],
    min_group_load_kg: float, executor: Executor | Mapper | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:  # fmt: skip
    """A calibration on the even records, the odd ones held against the fleet it calibrates (values rounded for a
    metrics file): the half's fitted values (its posterior's medians, as the whole survey's; the prior-free minimum
    without a posterior), their distance, the held-out distance of the odd half to that fleet simulated directly and
    the distance between the halves (its floor), the odd half's and the calibrated fleet's statistics. With a
    ``reason`` instead when the half cannot be fitted."""
    even, odd = observed.half(0), observed.half(1)
    held: dict[str, Any] = {"fit_on": "even records", "held_out": "odd records"}
    try:
        half = make_problem(table, even, settings.fit, base, min_group_load_kg)
        theta, _, _ = fit(half, settings.seed, settings.maxiter, settings.popsize, progress=progress,
                          label="half fit")  # fmt: skip
        post = None
        if settings.posterior_draws:  # the half's posterior: its medians are the fleet it calibrates
            post = posterior(half, priors_for(half, settings), theta, settings.posterior_draws, settings.seed,
                             settings.confidence_level, chains=settings.chains, sites=settings.sites,
                             executor=executor)  # fmt: skip
            theta = np.array([post.summary[q]["median"] for q in half.fitted])
        d_half = half.objective(half.unit_weights(), None)(theta)
        values_half = _values(theta, half.fitted, half.base)
        step = observed.weight_step_kg
        direct_half = filtered(
            simulate_fleet(table, values_half, weight_step_kg=step, executor=executor), min_group_load_kg
        )
        odd_q = {k: observed_quantities(v) for k, v in odd.loads.items() if k in half.obs and len(v)}
        held.update(
            fitted={q: json_number(values_half[q]) for q in half.fitted},
            distance_fit_half=json_number(d_half, 5),
            distance_held_out=json_number(frame_distance(direct_half, odd_q, half.scales), 5),
            distance_halves=json_number(observed_distance(half.obs, odd_q, half.scales), 5),
            groups=groups_stats(odd.loads),
            calibrated_groups=frame_stats(direct_half),
        )
        held["source"] = "posterior" if post is not None else PRIOR_FREE
        if post is not None:  # the held-out check's posterior predictive; one piled at a bound is no check
            held["posterior_predictive"] = posterior_predictive(
                table, post, values_half, min_group_load_kg, step, settings.confidence_level, executor
            )
            held["posterior"] = _summary(post.summary)
            held["posterior_piled"] = {q: e["piled"] for q, e in post.summary.items() if e["piled"]}
    except CalibrationError as exc:
        held.update(reason=str(exc), groups=None)
    return held


def calibrate_survey(
    table: Table, observed: Observed, settings: CalibrationSettings, base: Mapping[str, float],
    min_group_load_kg: float = 0.0, executor: Executor | Mapper | None = None,
    progress: Callable[[str], None] | None = None, static: StaticProtocol | None = None,
) -> tuple[dict[str, Any], dict[str, pd.DataFrame]]:  # fmt: skip
    """The whole calibration of an observed survey: the posterior (the calibrated fleet), the prior-free minimum and
    its bootstrap (a diagnostic), the trade-offs, and the checks.

    Parameters
    ----------
    table
        The calibration fleet's table (:func:`bogie.fleet.calibration.problem.build_table`).
    observed
        The observed groups (:func:`bogie.fleet.calibration.problem.observed_groups`).
    settings
        The quantities fitted, their bounds, the optimiser's and the bootstrap's settings.
    base
        Every quantity's value in the fleet (:func:`bogie.fleet.calibration.problem.base_values`), kept if not fitted.
    min_group_load_kg
        Smallest group load kept [kg], the survey's own filter.
    executor
        Where the direct simulations (the checks) are weighed (:func:`~bogie.fleet.calibration.table.weigh_readings`).
    progress
        Told the fit's generations, the resamples and the cost of an evaluation (None: nothing).
    static
        The static weighing's settings: with a WIM table, the calibrated fleet's inequality is attributed to its
        causes (:func:`bogie.fleet.calibration.attribution.attribution`, the weighing without dynamics); None: not.

    Returns
    -------
    metrics : dict
        JSON-ready, values rounded: ``fitted`` (the posterior's), ``prior_free_minimum``, the distances, the table,
        the observed, calibrated and held-out statistics, the ablation (``docs/calibration.md``, ``docs/outputs.md``).
    tables : dict
        DataFrames by name: ``bootstrap``, ``valley``, ``profiles``, ``calibrated`` (the calibrated fleet simulated
        directly and filtered), ``ablation``, and ``posterior`` (with posterior draws) and ``attribution`` (a WIM
        calibration with a static protocol); the calibrate stage writes each as ``<name>.csv``.

    Raises :class:`CalibrationError` if the arguments are not what :func:`make_problem` wants.
    """
    progress = progress or _quiet
    problem = make_problem(table, observed, settings.fit, base, min_group_load_kg)
    result = calibrate(problem, settings, progress, executor)
    step = observed.weight_step_kg
    direct = filtered(simulate_fleet(table, result.values, weight_step_kg=step, executor=executor), min_group_load_kg)
    held = held_out(table, observed, settings, base, min_group_load_kg, executor, progress)
    abl = ablation(table, result.values, min_group_load_kg, executor)
    metrics = _metrics(table, observed, settings, result, problem.obs, problem.scales, direct, held, abl)
    metrics["table_faithful"] = _faithful(metrics["distance"], metrics["distance_direct"], held.get("distance_halves"))
    if result.posterior is not None:  # does the answer depend on the tilt prior? (issue 43 Must 6)
        metrics["prior_sensitivity"] = _prior_sensitivity(problem, settings, result, progress, executor)
    if result.posterior is not None:  # the statistics the posterior predicts, beside those at its medians
        metrics["calibrated"]["posterior_predictive"] = posterior_predictive(table, result.posterior, result.values,
            min_group_load_kg, step, settings.confidence_level, executor)  # fmt: skip
    by_cause = None
    if static is not None and table.protocol == "wim":
        by_cause = _attribute(table, result.values, min_group_load_kg, static, step, executor, settings, progress,
                              metrics)  # fmt: skip
    progress(f"calibrate: {result.evaluations} evaluations of {result.seconds_per_evaluation * 1e3:.1f} ms")
    return metrics, _tables(result, direct, abl, by_cause)


def _prior_sensitivity(
    problem: Any, settings: CalibrationSettings, result: Any, progress: Callable[[str], None], executor: Any = None
) -> dict[str, Any] | None:
    """:func:`bogie.fleet.calibration.prior_sensitivity.prior_sensitivity` of the calibration, rounded."""
    progress("calibrate: prior sensitivity, the posterior with the tilt prior's sd halved and doubled")
    best = np.array([result.prior_free[q]["value"] for q in problem.fitted])
    return _rounded(prior_sensitivity(problem, priors_for(problem, settings), result.posterior, best,
                                      settings.posterior_draws, settings.seed, settings.confidence_level,
                                      settings.chains, executor))  # fmt: skip


def _attribute(
    table: Table, values: Mapping[str, float], min_group_load_kg: float, static: StaticProtocol, step: float | None,
    executor: Executor | Mapper | None, settings: CalibrationSettings, progress: Callable[[str], None],
    metrics: dict[str, Any],
) -> pd.DataFrame:  # fmt: skip
    """The calibrated fleet's inequality by cause (:func:`attribution`); its metrics go to metrics["attribution"]."""
    progress("calibrate: attribution, the calibrated fleet weighed four ways")
    by_cause, metrics["attribution"] = attribution(
        table, values, min_group_load_kg, static, step, executor, settings.seed,
        max(settings.bootstrap_resamples, 200), settings.confidence_level,
    )  # fmt: skip
    return by_cause


def _tables(result: Any, direct: pd.DataFrame, abl: pd.DataFrame, by_cause: pd.DataFrame | None) -> dict:
    """The tables of :func:`calibrate_survey` by name, ``posterior`` and ``attribution`` only when there are some."""
    tables = {
        "bootstrap": result.bootstrap, "valley": result.valley, "profiles": result.profiles, "calibrated": direct,
        "ablation": abl,
    }  # fmt: skip
    if result.posterior is not None:
        tables["posterior"] = result.posterior.draws
    if by_cause is not None:
        tables["attribution"] = by_cause
    return tables


def _metrics(
    table: Table, observed: Observed, settings: CalibrationSettings, result: Any, obs: Mapping[str, np.ndarray],
    scales: Mapping[str, np.ndarray], direct: pd.DataFrame, held: dict[str, Any], abl: pd.DataFrame,
) -> dict[str, Any]:  # fmt: skip
    """The metrics of :func:`calibrate_survey`."""
    return {
        "protocol": table.protocol,
        "method": "the posterior (the priors times a synthetic likelihood of the survey's summaries), sampled from "
        "the minimum of the energy distance found by differential evolution; common random numbers, tabulated "
        "readings",
        # the calibrated fleet: each value the posterior's median, priors included, with its credible interval
        "fitted": _entries(result.fitted),
        # a value (or the posterior's draws) piled against a bound: a finding about the model, not a value of the fleet
        "at_bounds": _findings(result.fitted),
        "posterior": _posterior_metrics(result.posterior, settings.confidence_level),
        # the per-axle sensor error against a strip sensor's whole error (issue 43 Must 4), in words when above it
        "sensor_per_axle": sensor_finding(result.fitted),
        # the diagnostic: the distance's minimum without the priors, with its bootstrap; not the calibrated fleet
        "prior_free_minimum": {
            "note": "a diagnostic, not the calibrated fleet: the energy distance's minimum without the priors (the "
            "posterior's starting point), its bootstrap intervals and the values piled at bounds",
            "fitted": _entries(result.prior_free),
            "at_bounds": _findings(result.prior_free),
            "distance": json_number(result.prior_free_distance, 5),
        },
        "fixed": {q: json_number(v) for q, v in result.values.items() if q not in result.fitted},
        "confidence_level": settings.confidence_level,
        "bootstrap_resamples": settings.bootstrap_resamples,
        "distance": json_number(result.distance, 5),
        "distance_direct": json_number(frame_distance(direct, obs, scales), 5),
        "sizes_fitted": sorted(obs),
        "evaluations": result.evaluations,
        "trade_offs": result.trade_offs,
        "table": {
            "n_bogies": len(table.size),
            "tilts_deg": [json_number(t, 3) for t in table.tilts],
            "site_iri_levels_m_km": [None if math.isnan(x) else x for x in table.iris],
            "n_weighings": int(np.prod(table.loads.shape[:4])),
            "n_failed": table.n_failed,
        },  # fmt: skip
        "observed": {"groups": groups_stats(observed.loads), "weight_step_kg": observed.weight_step_kg},
        "calibrated": {"groups": frame_stats(direct)},
        "held_out": held,
        "ablation": {
            f"{r.variant}/{r.group}": {
                "mean_max_deviation_pct": json_number(r.mean_max_deviation_pct),
                "share_outside_5pct": json_number(r.share_outside_5pct),
                "buys_points": json_number(r.buys_points),
                "n_groups": int(r.n_groups),
            }
            for r in abl.itertuples()
        },  # fmt: skip
    }


#: posterior draws the posterior predictive statistics simulate the calibration fleet at, evenly spaced through the
#: kept draws [-]: a convention (each is a direct simulation of the whole calibration fleet)
PREDICTIVE_DRAWS = 8
#: the survey statistics the posterior predictive summarises, per size
PREDICTIVE_STATISTICS: tuple[str, ...] = (
    "mean_spread_kg", "median_spread_pct", "share_outside_5pct", "share_over_10pct", "mean_group_load_kg",
)  # fmt: skip


def posterior_predictive(
    table: Table, post: Any, base: Mapping[str, float], min_group_load_kg: float, weight_step_kg: float | None,
    confidence_level: float, executor: Executor | Mapper | None = None, draws: int = PREDICTIVE_DRAWS,
) -> dict[str, Any]:  # fmt: skip
    """The survey statistics the posterior predicts (issue 43 Must 1): the calibration fleet simulated directly
    (:func:`simulate_fleet`, filtered as the survey) at ``draws`` posterior draws evenly spaced through the kept
    ones, each statistic of :data:`PREDICTIVE_STATISTICS` per size as its median over the draws and the
    equal-tailed interval at ``confidence_level`` (with so few draws, the range they span). The kilogram figures carry
    the site's bias drawn with the rest (issue 43 Must 2)."""
    kept = post.draws
    picks = np.unique(np.linspace(0, len(kept) - 1, max(min(draws, len(kept)), 1)).round().astype(int))
    fitted = [c for c in kept.columns if c in base]
    per_size: dict[str, dict[str, list[float]]] = {}
    for i in picks:
        values = {**base, **{q: float(kept[q].iloc[i]) for q in fitted}}
        kept_groups = filtered(simulate_fleet(table, values, weight_step_kg=weight_step_kg, executor=executor),
                               min_group_load_kg)  # fmt: skip
        stats = frame_stats(kept_groups)
        for size, entry in stats.items():
            entry["mean_group_load_kg"] = _mean_group_load(kept_groups, size)  # moved by the site's bias one for one
            for s in PREDICTIVE_STATISTICS:
                if entry.get(s) is not None:
                    per_size.setdefault(size, {}).setdefault(s, []).append(float(entry[s]))
    out: dict[str, Any] = {"draws": len(picks), "credible_level": confidence_level}
    for size, stats_ in per_size.items():
        out[size] = {}
        for s, xs in stats_.items():
            low, high = percentile_interval(np.asarray(xs), confidence_level)
            out[size][s] = {"median": json_number(float(np.median(xs))), "low": json_number(low),
                            "high": json_number(high)}  # fmt: skip
    return out


def _rounded(x: Any) -> Any:
    """``x`` with every float rounded for a metrics file (:func:`bogie.rounding.json_number`), containers walked."""
    if isinstance(x, dict):
        return {k: _rounded(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_rounded(v) for v in x]
    return json_number(x) if isinstance(x, float) else x


def _mean_group_load(frame: pd.DataFrame, size: str) -> float | None:
    """The mean load [kg] of the ``size`` groups of a filtered simulated frame (None: none)."""
    rows = frame.loc[frame["group"] == size, [f"axle_load_{i + 1}" for i in range(SIZES[size])]].to_numpy()
    return float(rows.sum(axis=1).mean()) if len(rows) else None


def _entries(fitted: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per quantity its value, interval, bounds and source, for a metrics file."""
    return {
        q: {k: (json_number(v) if isinstance(v, float | int) else v) for k, v in e.items() if k != "at_bound"}
        for q, e in fitted.items()
    }  # fmt: skip


def _findings(fitted: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """The quantities at a bound, each finding for a metrics file."""
    return {
        q: {k: (v if isinstance(v, str) or v is None else json_number(v)) for k, v in e["at_bound"].items()}
        for q, e in fitted.items()
        if e.get("at_bound")
    }  # fmt: skip


def _faithful(table: float | None, direct: float | None, halves: float | None) -> dict[str, Any]:
    """Issue 30 Must 4: the table is faithful when the calibrated fleet simulated directly is as far from the survey
    as the table said, within the sampling floor (the distance between the survey's two halves)."""
    gap = None if table is None or direct is None else json_number(direct - table, 5)
    faithful = None if gap is None or halves is None else bool(abs(gap) <= halves)
    return {"gap": gap, "floor": halves, "faithful": faithful}


def _posterior_metrics(post: Any, level: float) -> dict[str, Any] | None:
    """The posterior's summary per quantity (with its R-hat and bulk and tail ESS), its priors, draws, chains and
    acceptance, whether it converged, what to change if not and the thresholds (None: no posterior)."""
    if post is None:
        return None
    return {
        "method": "random-walk Metropolis (adapted in burn-in), several chains, on the priors times a synthetic "
        "likelihood of the survey's summaries over the table (bogie.fleet.calibration.posterior)",
        "credible_level": level,
        "draws": len(post.draws),
        "chains": post.chains,
        "acceptance": json_number(post.acceptance),
        "converged": post.converged,
        # the likelihood's covariance by source, each summary in its own units (issue 43 Must 2: between sites)
        "covariance_sites": post.sites,
        "covariance_shares": _rounded(post.covariance_shares),
        # how far the between-site correlations were shrunk towards none (Schaefer-Strimmer; 0: not at all)
        "covariance_site_shrinkage": json_number(post.likelihood.shrinkage) if post.likelihood is not None else None,
        "advice": post.advice,
        "thresholds": post.thresholds,
        "quantities": {
            q: {**e, **{k: json_number(e[k], 1) for k in ("ess_bulk", "ess_tail")}}
            for q, e in _summary(post.summary).items()
        },  # fmt: skip
        "priors": post.priors,
    }
