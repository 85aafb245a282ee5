"""The calibration and what bounds it: the fit, its bootstrap intervals, a fit piled against a bound, the
trade-offs between fitted quantities, the valley of the most correlated pair and each quantity's profile.

:func:`calibrate` runs them on a :class:`~bogie.fleet.calibration.problem.Problem` (``docs/calibration.md``). A fit at a
bound of its range, or bootstrap refits piled against one, is flagged (:func:`bound_finding`): a finding about the
model (the data ask for a value the range excludes, or the quantity absorbs what the model misstates), not a value
of the fleet.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.posterior import Posterior, posterior
from bogie.fleet.calibration.priors import default_priors
from bogie.fleet.calibration.problem import CalibrationSettings, Problem, _values, fit
from bogie.fleet.calibration.table import _quiet
from bogie.fleet.constants import AT_BOUND, PILED
from bogie.intervals import percentile_interval
from bogie.rounding import json_number

__all__ = [
    "AT_BOUND", "PILED", "PROFILE_POINTS", "TRADE_OFF", "VALLEY_POINTS", "Calibration", "at_bound", "bound_finding",
    "calibrate", "priors_for",
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
        Per fitted quantity: ``value``, the interval ``low`` and ``high`` (None without a bootstrap of 2 or more) and
        its ``bounds``, in the unit of its name.
    distance, evaluations, seconds_per_evaluation
        The best distance [-], the evaluations of the fit [-] and the wall time of one [s].
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

    fitted: dict[str, dict[str, float]]
    distance: float
    evaluations: int
    seconds_per_evaluation: float
    bootstrap: pd.DataFrame
    correlation: pd.DataFrame
    trade_offs: list[dict[str, Any]]
    valley: pd.DataFrame
    profiles: pd.DataFrame
    values: dict[str, float]
    posterior: Posterior | None = None


def _bootstrap(problem: Problem, settings: CalibrationSettings, progress: Callable[[str], None]) -> pd.DataFrame:
    """The fit on each resample of the observed groups and of the calibration bogies together."""
    seed = settings.seed
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    rows = []
    for b in range(settings.bootstrap_resamples):
        obs_w = {
            k: rng.multinomial(len(v), np.full(len(v), 1.0 / len(v))).astype(float) for k, v in problem.obs.items()
        }
        n = len(problem.table.size)
        slots = rng.multinomial(n, np.full(n, 1.0 / n)).astype(float)
        theta, d, _ = fit(problem, seed + 1 + b, settings.maxiter, settings.popsize, obs_w, slots)
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
    problem: Problem, settings: CalibrationSettings, progress: Callable[[str], None] | None = None
) -> Calibration:
    """Fit, then the bootstrap intervals, the trade-offs, the valley and the profiles.

    Parameters
    ----------
    problem
        What is fitted to what (:func:`make_problem`).
    settings
        The optimiser's seed and settings, the bootstrap's resamples and confidence level (its ``fit`` made the
        problem).
    progress
        Told each generation of the fit and each resample (None: nothing).
    """
    progress = progress or _quiet
    start = time.perf_counter()
    best, dist_best, evaluations = fit(problem, settings.seed, settings.maxiter, settings.popsize, progress=progress)
    per_eval = (time.perf_counter() - start) / max(evaluations, 1)
    boot = _bootstrap(problem, settings, progress)
    fitted = _intervals(problem, best, boot, settings.confidence_level)
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
        post = posterior(problem, priors, best, settings.posterior_draws, settings.seed, settings.confidence_level)
        _posterior_findings(fitted, post)
    return Calibration(
        fitted, dist_best, evaluations, per_eval, boot, corr, trade, valley, profiles,
        _values(best, problem.fitted, problem.base), post,
    )  # fmt: skip


def priors_for(problem: Problem, settings: CalibrationSettings) -> dict[str, Any]:
    """The settings' priors, or the documented defaults (:func:`bogie.fleet.calibration.priors.default_priors`) for the
    problem's fleet."""
    if settings.priors is not None:
        return dict(settings.priors)
    return default_priors(problem.base, {q: t.mean_range() for q, t in problem.table.tilted.items()})


def _posterior_findings(fitted: dict[str, dict[str, Any]], post: Posterior) -> None:
    """Each fitted quantity's posterior summary; a posterior piled against a bound flagged as a fit at it is."""
    for q, entry in fitted.items():
        summary = post.summary[q]
        entry["posterior"] = summary
        side = summary["piled"]
        share = {"low": summary["share_at_low"], "high": summary["share_at_high"]}
        finding = entry.get("at_bound")
        if finding is None and side is not None:
            limit = entry["bounds"][0] if side == "low" else entry["bounds"][1]
            finding = {"bound": side, "value": summary["median"], "limit": float(limit), "share_of_refits": None}
        if finding is not None:
            finding["share_of_posterior"] = share[finding["bound"]]
        entry["at_bound"] = finding


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
