"""The calibration and what bounds it: the posterior (the answer), the prior-free minimum of the distance with its
bootstrap intervals (a diagnostic), a value piled against a bound, the trade-offs between fitted quantities, the
valley of the most correlated pair and each quantity's profile.

:func:`calibrate` runs them on a :class:`~bogie.fleet.calibration.problem.Problem` (``docs/calibration.md``). The
calibrated fleet is the posterior's (issue 43 Must 1): each fitted value is its posterior median, priors included,
with its credible interval; the differential evolution's minimum of the distance, without the priors, starts the
sampler and is kept as a diagnostic (``prior_free``), never offered as the fleet. A value at a bound of its range,
or bootstrap refits or posterior draws piled against one, is flagged (:func:`bound_finding`): a finding about the
model (the data ask for a value the range excludes, or the quantity absorbs what the model misstates), not a value
of the fleet.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.posterior import Posterior, posterior
from bogie.fleet.calibration.priors import default_priors
from bogie.fleet.calibration.problem import CalibrationSettings, Problem, _values, fit
from bogie.fleet.calibration.table import _quiet, map_tasks
from bogie.fleet.constants import AT_BOUND, PILED
from bogie.intervals import percentile_interval
from bogie.road.wim import STRIP_SENSOR_RMS_PCT
from bogie.rounding import json_number

__all__ = [
    "AT_BOUND", "PILED", "PRIOR_FREE", "PROFILE_POINTS", "TRADE_OFF", "VALLEY_POINTS", "Calibration", "at_bound",
    "bound_finding", "calibrate", "posterior_fitted", "priors_for", "sensor_finding",
]  # fmt: skip

#: the distance over the valley's pair of quantities is evaluated on this many points per side [-]
VALLEY_POINTS = 21
#: points of each quantity's profile [-]
PROFILE_POINTS = 25
#: bootstrap correlation from which two fitted quantities are reported as trading off [-]
TRADE_OFF = 0.5
# AT_BOUND (2 % of the width from a bound) and PILED (a quarter of the refits or draws) are conventions of
# bogie.fleet.constants


@dataclass
class Calibration:
    """The outcome of :func:`calibrate`.

    Attributes
    ----------
    fitted
        Per fitted quantity, the calibrated fleet's: ``value`` (the posterior median), the credible interval ``low``
        and ``high``, its ``bounds``, ``at_bound`` (:func:`bound_finding`, or None) and ``source`` (``posterior``; the
        prior-free minimum's, named so, only when no posterior was drawn: ``posterior_draws`` 0), in the unit of its
        name.
    prior_free
        The diagnostic: per fitted quantity the distance's minimum without the priors (``value``, the bootstrap
        interval ``low``, ``high``, None without a bootstrap of 2 or more, ``bounds``, ``at_bound``).
    distance, prior_free_distance, evaluations, seconds_per_evaluation
        The distance [-] at the fitted values and at the prior-free minimum, the evaluations of the minimisation [-]
        and the wall time of one [s].
    bootstrap
        One row per resample: ``resample``, each fitted quantity and the ``distance``.
    correlation, trade_offs
        The bootstrap correlation of the fitted quantities; the pairs correlated by :data:`TRADE_OFF` or more.
    valley, profiles
        The distance over the most correlated pair's bounds (``quantity_x``, ``x``, ``quantity_y``, ``y``,
        ``distance``) and along each quantity with the others at their best (``quantity``, ``value``, ``distance``).
    values
        Every quantity's value in the calibrated fleet (the base's for an unfitted one).
    posterior
        The posterior (:func:`bogie.fleet.calibration.posterior.posterior`); None with ``posterior_draws`` 0.
    """

    fitted: dict[str, dict[str, Any]]
    prior_free: dict[str, dict[str, Any]]
    distance: float
    prior_free_distance: float
    evaluations: int
    seconds_per_evaluation: float
    bootstrap: pd.DataFrame
    correlation: pd.DataFrame
    trade_offs: list[dict[str, Any]]
    valley: pd.DataFrame
    profiles: pd.DataFrame
    values: dict[str, float]
    posterior: Posterior | None = None


def _refit(task: tuple) -> tuple[np.ndarray, float]:
    """One bootstrap refit (a module-level function: it runs on the executor's workers)."""
    problem, seed, maxiter, popsize, obs_w, slots = task
    theta, d, _ = fit(problem, seed, maxiter, popsize, obs_w, slots)
    return theta, d


def _bootstrap(
    problem: Problem, settings: CalibrationSettings, progress: Callable[[str], None], executor: Any = None
) -> pd.DataFrame:
    """The fit on each resample of the observed groups and of the calibration bogies together: the resamples drawn
    here, in order, the refits on ``executor`` (:func:`~bogie.fleet.calibration.table.map_tasks`; each refit seeded
    by its number alone, so the same refits wherever they run)."""
    seed = settings.seed
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    tasks = []
    for b in range(settings.bootstrap_resamples):
        obs_w = {
            k: rng.multinomial(len(v), np.full(len(v), 1.0 / len(v))).astype(float) for k, v in problem.obs.items()
        }
        n = len(problem.table.size)
        slots = rng.multinomial(n, np.full(n, 1.0 / n)).astype(float)
        tasks.append((problem, seed + 1 + b, settings.maxiter, settings.popsize, obs_w, slots))
    if tasks:
        progress(f"calibrate: bootstrap, {len(tasks)} refits on the executor")
    rows = []
    for b, (theta, d) in enumerate(map_tasks(_refit, tasks, executor)):
        rows.append({"resample": b, **dict(zip(problem.fitted, theta)), "distance": d})
        progress(f"calibrate: bootstrap {b + 1}/{settings.bootstrap_resamples}: distance {d:.5f}")
    return pd.DataFrame(rows, columns=["resample", *problem.fitted, "distance"])


def at_bound(value: float, bounds: Sequence[float]) -> str | None:
    """``"low"`` or ``"high"`` if ``value`` lies within :data:`AT_BOUND` of the width of ``bounds`` from that bound,
    else None."""
    low, high = bounds
    margin = AT_BOUND * (high - low)
    return "low" if value <= low + margin else "high" if value >= high - margin else None


def bound_finding(value: float, bounds: Sequence[float], refits: Sequence[float]) -> dict[str, Any] | None:
    """Whether a fit is piled against a bound: the fit at it (:func:`at_bound`), or :data:`PILED` of the bootstrap
    refits ``refits`` at one bound. None if neither; else ``bound`` (``low``/``high``), ``value``, the bound's
    ``limit`` and the ``share_of_refits`` at that bound (None without refits)."""
    sides = [at_bound(float(r), bounds) for r in refits]
    shares = {side: sides.count(side) / len(sides) for side in ("low", "high")} if sides else {}
    side = at_bound(value, bounds) or next((s for s in ("low", "high") if shares.get(s, 0.0) >= PILED), None)
    if side is None:
        return None
    limit = bounds[0] if side == "low" else bounds[1]
    return {"bound": side, "value": float(value), "limit": float(limit), "share_of_refits": shares.get(side)}


def _intervals(
    problem: Problem, best: np.ndarray, boot: pd.DataFrame, confidence_level: float
) -> dict[str, dict[str, Any]]:
    fitted = {}
    for i, q in enumerate(problem.fitted):
        entry = {"value": float(best[i]), "low": None, "high": None, "bounds": list(problem.bounds[i])}
        if len(boot) >= 2:
            entry["low"], entry["high"] = (float(e) for e in percentile_interval(boot[q], confidence_level))
            # a basic interval must hold the estimate: the fit on all the data is one of the bootstrap's worlds
            entry["low"], entry["high"] = min(entry["low"], entry["value"]), max(entry["high"], entry["value"])
        refits = boot[q].to_numpy(dtype=float) if q in boot else np.zeros(0)
        entry["at_bound"] = bound_finding(entry["value"], problem.bounds[i], refits)
        fitted[q] = entry
    return fitted


def _trade_offs(fitted: Sequence[str], corr: pd.DataFrame) -> list[dict[str, Any]]:
    trade = []
    for i, a in enumerate(fitted):
        for b_ in fitted[i + 1 :]:
            r = corr.loc[a, b_] if not corr.empty else math.nan
            if np.isfinite(r) and abs(r) >= TRADE_OFF:
                trade.append({"quantities": [a, b_], "correlation": json_number(r, 3)})
    return trade


def calibrate(
    problem: Problem, settings: CalibrationSettings, progress: Callable[[str], None] | None = None,
    executor: Any = None,
) -> Calibration:  # fmt: skip
    """The prior-free minimum and its bootstrap intervals, the trade-offs, the valley and the profiles, then the
    posterior from that minimum: the fitted values (:class:`Calibration`).

    Parameters
    ----------
    problem
        What is fitted to what (:func:`make_problem`).
    settings
        The optimiser's seed and settings, the bootstrap's resamples and confidence level (its ``fit`` made the
        problem).
    progress
        Told each generation of the fit and each resample (None: nothing).
    executor
        Where the bootstrap's refits and the posterior's between-site weighings run (an Executor or a map-like
        callable, :func:`~bogie.fleet.calibration.table.map_tasks`; None: here).
    """
    progress = progress or _quiet
    start = time.perf_counter()
    best, dist_best, evaluations = fit(problem, settings.seed, settings.maxiter, settings.popsize, progress=progress)
    per_eval = (time.perf_counter() - start) / max(evaluations, 1)
    boot = _bootstrap(problem, settings, progress, executor)
    prior_free = _intervals(problem, best, boot, settings.confidence_level)
    corr = boot[list(problem.fitted)].corr() if len(boot) >= 3 else pd.DataFrame()
    trade = _trade_offs(problem.fitted, corr)
    pair = _valley_pair(problem.fitted, corr)
    f = problem.objective(problem.unit_weights(), None)
    valley = _valley(problem, f, best, pair) if pair else pd.DataFrame(columns=["x", "y", "distance"])
    profiles = _profiles(problem, f, best)
    post = None
    if settings.posterior_draws:
        progress(f"calibrate: posterior, {settings.posterior_draws} draws")
        priors = priors_for(problem, settings)
        post = posterior(problem, priors, best, settings.posterior_draws, settings.seed, settings.confidence_level,
                         chains=settings.chains, sites=settings.sites, executor=executor)  # fmt: skip
        fitted = posterior_fitted(prior_free, post)
    else:  # no posterior asked for: the minimum is all there is, and says so
        fitted = {q: {**e, "source": PRIOR_FREE} for q, e in prior_free.items()}
    theta = np.array([fitted[q]["value"] for q in problem.fitted])
    return Calibration(
        fitted, prior_free, float(f(theta)), dist_best, evaluations, per_eval, boot, corr, trade, valley, profiles,
        _values(theta, problem.fitted, problem.base), post,
    )  # fmt: skip


def priors_for(problem: Problem, settings: CalibrationSettings) -> dict[str, Any]:
    """The settings' priors, or the documented defaults (:func:`bogie.fleet.calibration.priors.default_priors`) for the
    problem's fleet."""
    if settings.priors is not None:
        return dict(settings.priors)
    return default_priors(problem.base, {q: t.mean_range() for q, t in problem.table.tilted.items()})


#: the ``source`` of a fitted value that is not the posterior's (``posterior_draws`` 0)
PRIOR_FREE = "prior-free minimum of the distance (posterior_draws = 0: no posterior, no priors)"


def posterior_fitted(prior_free: dict[str, dict[str, Any]], post: Posterior) -> dict[str, dict[str, Any]]:
    """The fitted values from the posterior: per quantity its median, credible interval and bounds, flagged when the
    median lies at a bound or the draws pile against one (:func:`at_bound`, :data:`PILED`)."""
    fitted = {}
    for q, entry in prior_free.items():
        summary = post.summary[q]
        bounds = entry["bounds"]
        side = at_bound(summary["median"], bounds) or summary["piled"]
        finding = None
        if side is not None:
            finding = {"bound": side, "value": summary["median"], "limit": float(bounds[0 if side == "low" else 1]),
                       "share_of_posterior": summary[f"share_at_{side}"]}  # fmt: skip
        fitted[q] = {
            "value": summary["median"], "low": summary["low"], "high": summary["high"], "bounds": bounds,
            "at_bound": finding, "source": "posterior",
        }  # fmt: skip
    return fitted


def sensor_finding(fitted: Mapping[str, Mapping[str, Any]]) -> dict[str, Any] | None:
    """Issue 43 Must 4: the fitted per-axle sensor error ``sensor_error_pct`` against the most a strip sensor's whole
    error reaches (:data:`bogie.road.wim.STRIP_SENSOR_RMS_PCT`, Cebon and Winkler 1991): its value, interval, the
    bound, whether it exceeds it and, if so, what that says in words. None when it is not fitted."""
    entry = fitted.get("sensor_error_pct")
    if entry is None:
        return None
    value, bound = float(entry["value"]), STRIP_SENSOR_RMS_PCT
    exceeds = value > bound
    words = None
    if exceeds:
        words = (
            f"the per-axle sensor error is fitted at {value:.3g} %, above the {bound:g} % RMS a strip sensor's whole "
            "error reaches against an instrumented vehicle (Cebon and Winkler 1991): it is per-axle scatter the model "
            "lacks (dynamics, tyres, loading the fleet does not have), taken up by the sensor, not the sensor's error"
        )
    return {"value": value, "low": entry.get("low"), "high": entry.get("high"), "bound_pct": bound,
            "exceeds": exceeds, "finding": words}  # fmt: skip


def _valley_pair(fitted: Sequence[str], corr: pd.DataFrame) -> tuple[str, str] | None:
    if len(fitted) < 2:
        return None
    if corr.empty or not np.isfinite(corr.to_numpy()).any():
        return (fitted[0], fitted[1])
    best, pair = -1.0, (fitted[0], fitted[1])
    for i, a in enumerate(fitted):
        for b in fitted[i + 1 :]:
            r = abs(corr.loc[a, b])
            if np.isfinite(r) and r > best:
                best, pair = r, (a, b)
    return pair


def _valley(problem: Problem, f: Callable, best: np.ndarray, pair: tuple[str, str]) -> pd.DataFrame:
    ia, ib = problem.fitted.index(pair[0]), problem.fitted.index(pair[1])
    xa = np.linspace(*problem.bounds[ia], VALLEY_POINTS)
    xb = np.linspace(*problem.bounds[ib], VALLEY_POINTS)
    rows = []
    for a in xa:
        for b in xb:
            theta = best.copy()
            theta[ia], theta[ib] = a, b
            rows.append({"quantity_x": pair[0], "x": a, "quantity_y": pair[1], "y": b, "distance": f(theta)})
    return pd.DataFrame(rows)


def _profiles(problem: Problem, f: Callable, best: np.ndarray) -> pd.DataFrame:
    rows = []
    for i, q in enumerate(problem.fitted):
        for x in np.linspace(*problem.bounds[i], PROFILE_POINTS):
            theta = best.copy()
            theta[i] = x
            rows.append({"quantity": q, "value": x, "distance": f(theta)})
    return pd.DataFrame(rows)
