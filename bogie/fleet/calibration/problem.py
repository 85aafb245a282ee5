"""Calibration to an observed survey: the fleet quantities that make the simulated readings the observed ones.

The method of ``docs/calibration.md``, with plain arguments (the DVC stage ``pipeline/calibrate.py`` reads them from
params.yaml). The fitted quantities are those of :data:`bogie.fleet.constants.CALIBRATION_QUANTITIES`: the chassis
tilt distribution's centre and spread [degree], the air share [-], the WIM site's roughness [m/km] and the sensor's
error [%]. In short:

1. **The calibration fleet** (:func:`crn_table`): sampled bogies, each both as its steel group and as the air-sprung
   group on the same trailer, with common random numbers: one uniform for its tilt (its tilt's rank under the
   fleet's distribution), one for its suspension (:func:`bogie.fleet.sampling.sample.suspension_draw`) and one standard
   normal per axle for the sensor (its ``sensor_seed``).
2. **A table of readings** (:func:`build_table`): every group weighed, error free, at every tilt of a grid and, for
   WIM, at every site roughness; a fleet of given quantities is then interpolated (:func:`fleet_readings`).
3. **The distance** (:func:`distance`): over laden tandem and tri-axle groups, the sum over each axle position's
   load share and the spread [%] of the energy distance between the observed and the simulated distribution, each
   over the observed quantity's standard deviation.
4. **The fit** (:func:`fit`; :func:`bogie.fleet.calibration.fitting.calibrate`): scipy's seeded
   ``differential_evolution``; intervals from a bootstrap of the observed records and of the calibration bogies
   together; a fit piled against a bound flagged; trade-offs, the valley and the profiles.

The checks of a calibration (the fleet simulated directly, a held-out half, the ablation) and the whole calibration
of a survey in one call are :mod:`bogie.fleet.calibration.checks`. Same arguments, same numbers: whatever the
executor or the number of workers.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import differential_evolution

from bogie.fleet.calibration.settings import ORDER, CalibrationSettings, check_fit
from bogie.fleet.calibration.table import (
    SIZES,
    CalibrationError,
    Mapper,
    Table,
    base_values,
    build_table,
    crn_table,
    fleet_readings,
    steel_weights,
)
from bogie.fleet.constants import CALIBRATION_QUANTITIES, TILTED_QUANTITIES, WIM_QUANTITIES
from bogie.fleet.sampling.distributions import TruncNormal
from bogie.weighings.settings import GROUP_FILTER
from bogie.weighings.stats import at_resolution
from bogie.weighings.survey import ObservedSurvey

__all__ = [
    "MIN_GROUPS", "ORDER", "SIZES", "CalibrationError", "CalibrationSettings", "Mapper", "Observed", "Problem",
    "Simulated", "Table", "base_values", "build_table", "check_fit", "crn_table", "distance", "fit", "fleet_readings",
    "make_problem", "observed_groups", "observed_quantities", "simulated",
]  # fmt: skip

#: the fewest observed groups of one size that enter the distance (fewer: that size is left out, and said so)
MIN_GROUPS = 10


# ---- the observed side -------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Observed:
    """Per size: the observed groups' loads [kg] (rows, front first), and each group's record rank (for halves);
    the file's weight resolution [kg] (None: not whole kilograms), at which the simulated readings are read."""

    loads: Mapping[str, np.ndarray]
    record: Mapping[str, np.ndarray]
    weight_step_kg: float | None = None

    def half(self, parity: int) -> Observed:
        """The groups of alternate records: even (0) or odd (1) ranks."""
        keep = {k: self.record[k] % 2 == parity for k in self.loads}
        return Observed(
            {k: v[keep[k]] for k, v in self.loads.items()}, {k: v[keep[k]] for k, v in self.record.items()},
            self.weight_step_kg,
        )  # fmt: skip


def observed_groups(survey: ObservedSurvey) -> Observed:
    """The laden tandem and tri-axle groups of an observed survey (:func:`bogie.weighings.survey.observed_survey`,
    filtered as wanted), and the file's weight resolution.

    Raises
    ------
    CalibrationError
        If fewer than :data:`MIN_GROUPS` groups of either size passed the survey's filters.
    """
    groups = survey.groups
    # alternate records, not alternate groups: the rank of each group's record in the file
    rank = pd.factorize(groups["line"], sort=True)[0] if len(groups) else np.zeros(0, dtype=int)
    loads, record = {}, {}
    for size, n in SIZES.items():
        sel = (groups["group"] == size).to_numpy()
        loads[size] = groups.loc[sel, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy(dtype=float)
        record[size] = np.asarray(rank)[sel]
    if not any(len(v) >= MIN_GROUPS for v in loads.values()):
        counts = ", ".join(f"{len(v)} {k}" for k, v in loads.items())
        raise CalibrationError(
            f"the survey has {counts} groups after its filters; calibration needs at least {MIN_GROUPS} laden tandem "
            "or tri-axle groups"
        )
    return Observed(loads, record, survey.read.weight_step_kg)


def observed_quantities(loads: np.ndarray) -> np.ndarray:
    """Per group (rows of ``loads`` [any unit], front first, every axle present): each axle's load share
    W_i / mean(W), then the spread (max - min) / mean [%], shape (groups, n + 1): the arithmetic of
    :func:`bogie.weighings.stats.group_inequality`, without its other quantities (the fit's inner loop)."""
    n = loads.shape[1]
    total = loads.sum(axis=1)
    spread = 100.0 * (loads.max(axis=1) - loads.min(axis=1)) / (total / n)
    return np.column_stack([n * loads / total[:, None], spread])


# ---- a fleet of given quantities, from the table -----------------------------------------------------------------
def _values(theta: Sequence[float], fitted: Sequence[str], base: Mapping[str, float]) -> dict[str, float]:
    values = dict(base)
    values.update(zip(fitted, (float(t) for t in theta)))
    return values


@dataclass(frozen=True)
class Simulated:
    """Per size: each calibration group's quantities (rows), its mixture weight, for steel then air stacked."""

    quantities: Mapping[str, np.ndarray]
    weights: Mapping[str, np.ndarray]
    sites: Mapping[str, np.ndarray] | None = None  # per size, each row's WIM site (a table over several; else None)


def simulated(
    table: Table, values: Mapping[str, float], min_group_load_kg: float, slot_counts: np.ndarray | None = None,
    weight_step_kg: float | None = None, readings: np.ndarray | None = None, bogies: np.ndarray | None = None,
) -> Simulated:  # fmt: skip
    """The simulated survey: the calibration groups that pass the filters (every axle read and loaded, the group at
    least ``min_group_load_kg`` [kg]), weighted (1 - a) steel and a air (a: ``values["air_share"]``; times each bogie's
    bootstrap count ``slot_counts``, None: 1; a steel group also by its density ratio under the fitted inhibitor
    distributions, :func:`~bogie.fleet.calibration.table.steel_weights`); every reading first read at the observed
    file's resolution ``weight_step_kg`` [kg] (None: as it is).

    ``readings`` (2, m, 3) [kg], the readings of the calibration bogies ``bogies`` (m indices) weighed otherwise
    (on another site: :func:`bogie.fleet.calibration.posterior.site_covariance`), with the site's and the sensor's
    factors; None: every bogie's from the table (:func:`fleet_readings`), each row labelled with its bogie's site
    when the table spreads them over several (:meth:`~bogie.fleet.calibration.table.Table.site_labels`)."""
    rows = np.arange(len(table.size)) if bogies is None else np.asarray(bogies, dtype=int)
    readings_given = readings is not None  # another site's readings: one site for all, no labels
    readings = at_resolution(fleet_readings(table, values) if readings is None else readings, weight_step_kg)
    share = values["air_share"]
    counts = np.ones(len(rows)) if slot_counts is None else slot_counts[rows]
    moved = steel_weights(table, values)[rows]
    sizes = table.size[rows]
    quantities, weights, sites = {}, {}, {}
    labels = None if readings_given else table.site_labels(rows)
    for size, n in SIZES.items():
        sel = sizes == size
        loads = readings[:, sel, :n].reshape(-1, n)
        # the steel groups reweighted to the fitted inhibitor distributions, normalised so that steel keeps its share
        steel = counts[sel] * moved[sel]
        steel = steel * (counts[sel].sum() / steel.sum()) if steel.sum() > 0.0 else steel
        w = np.concatenate([(1.0 - share) * steel, share * counts[sel]])
        keep = (
            np.all(np.isfinite(loads), axis=1) & np.all(loads > 0.0, axis=1) & (loads.sum(axis=1) >= min_group_load_kg)
        )
        keep &= w > 0.0
        quantities[size] = observed_quantities(loads[keep]) if keep.any() else np.zeros((0, n + 1))
        weights[size] = w[keep]
        if labels is not None:
            sites[size] = np.concatenate([labels[sel], labels[sel]])[keep]  # steel then air, as the loads
    return Simulated(quantities, weights, sites if labels is not None else None)


def distance(
    obs: Mapping[str, np.ndarray], obs_weights: Mapping[str, np.ndarray], sim: Simulated,
    scales: Mapping[str, np.ndarray],
) -> float:  # fmt: skip
    """Sum over sizes and quantities (:func:`observed_quantities`' columns) of the energy distance between the
    observed and the simulated distribution, each over its scale (the observed sd): a dimensionless number, inf when
    a size has no simulated group. (:meth:`Problem.objective` sorts the observed side once per fit instead.)"""
    return _sorted_distance(_sorted_sides(obs, obs_weights), sim, scales)


class _SortedSample:
    """A weighted sample sorted once, with its CDF's steps: one side of :func:`_energy`."""

    def __init__(self, x: np.ndarray, w: np.ndarray) -> None:
        order = np.argsort(x, kind="stable")
        self.x = np.ascontiguousarray(x[order], dtype=float)
        cum = np.concatenate(([0.0], np.cumsum(w[order], dtype=float)))
        self.cdf = cum / cum[-1] if cum[-1] > 0.0 else cum


def _energy(u: _SortedSample, v: _SortedSample) -> float:
    """The energy distance of two weighted 1-D samples: ``sqrt(2)`` times the L2 distance of their CDFs, the
    formula of :func:`scipy.stats.energy_distance` (Szekely's E-statistic's square root in 1-D), from presorted
    sides."""
    both = np.concatenate((u.x, v.x))
    both.sort(kind="mergesort")
    deltas = np.diff(both)
    fu = u.cdf[u.x.searchsorted(both[:-1], "right")]
    fv = v.cdf[v.x.searchsorted(both[:-1], "right")]
    return math.sqrt(2.0) * math.sqrt(float(np.sum(np.square(fu - fv) * deltas)))


def _sorted_sides(obs: Mapping[str, np.ndarray], weights: Mapping[str, np.ndarray]) -> dict[str, list[_SortedSample]]:
    """Per size, each quantity's observed sample sorted (:class:`_SortedSample`)."""
    return {k: [_SortedSample(q[:, c], weights[k]) for c in range(q.shape[1])] for k, q in obs.items()}


def _sorted_distance(
    observed: Mapping[str, list[_SortedSample]], sim: Simulated, scales: Mapping[str, np.ndarray]
) -> float:
    """:func:`distance` from the observed side presorted (:func:`_sorted_sides`)."""
    total = 0.0
    for size, sides in observed.items():
        s, w = sim.quantities[size], sim.weights[size]
        if len(s) == 0 or w.sum() <= 0.0:
            return math.inf
        for c, u in enumerate(sides):
            total += _energy(u, _SortedSample(s[:, c], w)) / scales[size][c]
    return float(total)


# ---- the fit -----------------------------------------------------------------------------------------------------
@dataclass
class Problem:
    """Everything one evaluation of the distance needs (:func:`make_problem`)."""

    table: Table
    obs: dict[str, np.ndarray]  # per size used: quantities (groups, n + 1)
    scales: dict[str, np.ndarray]
    fitted: tuple[str, ...]
    bounds: tuple[tuple[float, float], ...]
    base: dict[str, float]
    min_group_load_kg: float
    weight_step_kg: float | None = None  # the observed file's resolution [kg]

    def objective(self, obs_weights: Mapping[str, np.ndarray], slot_counts: np.ndarray | None) -> Callable:
        # the observed side's sorted values and CDF steps, once per objective: only the simulated side changes
        observed = _sorted_sides(self.obs, obs_weights)

        def f(theta: np.ndarray) -> float:
            values = _values(theta, self.fitted, self.base)
            sim = simulated(self.table, values, self.min_group_load_kg, slot_counts, self.weight_step_kg)
            return _sorted_distance(observed, sim, self.scales)

        return f

    def unit_weights(self) -> dict[str, np.ndarray]:
        return {k: np.ones(len(v)) for k, v in self.obs.items()}


def _check_problem(
    table: Table, fit: Mapping[str, Sequence[float]], base: Mapping[str, float], min_group_load_kg: float
):
    check_fit(fit)
    if table.protocol != "wim" and any(q in WIM_QUANTITIES for q in fit):
        wim_only = [q for q in fit if q in WIM_QUANTITIES]
        raise CalibrationError(f"fit: {', '.join(wim_only)} belong to the WIM protocol; the table is {table.protocol}")
    if not isinstance(table.tilt_distribution, TruncNormal) and any(q.startswith("chassis_tilt") for q in fit):
        dist = table.tilt_distribution
        raise CalibrationError(f"fit: the chassis tilt's centre and spread are fitted; tilt_distribution = {dist!r}"
                               " must then be a TruncNormal")  # fmt: skip
    iri = fit.get("site_iri_m_km")
    if iri is not None and not table.iris[0] <= iri[0] < iri[1] <= table.iris[-1]:
        raise CalibrationError(f"fit['site_iri_m_km'] = {tuple(iri)!r}: must lie within the table's site_iri_levels, "
                               f"[{table.iris[0]:g}, {table.iris[-1]:g}] [m/km]")  # fmt: skip
    for q in (q for q in fit if q in TILTED_QUANTITIES):
        family = table.tilted.get(q)
        column = TILTED_QUANTITIES[q][0]
        if family is None:
            raise CalibrationError(f"fit: {q} moves the fleet's distribution of {column}, which the table was not "
                                   "given as a uniform or log-uniform (inhibitor_distributions)")  # fmt: skip
        lo, hi = family.mean_range()
        if not lo < fit[q][0] < fit[q][1] < hi:
            unit = CALIBRATION_QUANTITIES[q][2]
            raise CalibrationError(f"fit[{q!r}] = {tuple(fit[q])!r}: must lie strictly within the fleet distribution's "
                                   f"support ({lo:g}, {hi:g}) {unit}")  # fmt: skip
    missing = [q for q in ORDER if q not in base]
    if missing:
        raise CalibrationError(f"base: no value for {', '.join(missing)} (base_values gives every quantity)")
    GROUP_FILTER["min_group_load"].check("min_group_load_kg", min_group_load_kg, CalibrationError)


def make_problem(
    table: Table, observed: Observed, fit: Mapping[str, Sequence[float]], base: Mapping[str, float],
    min_group_load_kg: float = 0.0,
) -> Problem:  # fmt: skip
    """The fit of the quantities ``fit`` to ``observed`` on ``table`` (sizes with fewer than :data:`MIN_GROUPS`
    groups left out).

    Parameters
    ----------
    table
        The calibration fleet's table (:func:`build_table`).
    observed
        The observed groups (:func:`observed_groups`).
    fit
        Quantity -> (low, high), in the unit of its name (:class:`CalibrationSettings`' ``fit``).
    base
        Every quantity's value in the fleet (:func:`base_values`): what an unfitted quantity keeps.
    min_group_load_kg
        Smallest simulated group load kept [kg]: the survey's own filter.

    Raises
    ------
    CalibrationError
        If ``fit`` is not as :func:`check_fit` wants, fits a WIM quantity on a static table, the tilt's centre or
        spread of a tilt distribution that is not a TruncNormal, the site roughness outside the table's levels; if
        ``base`` lacks a quantity or ``min_group_load_kg`` is not a finite number >= 0; if no size has
        :data:`MIN_GROUPS` observed groups (a held-out half of a small survey).
    """
    _check_problem(table, fit, base, min_group_load_kg)
    obs = {k: observed_quantities(v) for k, v in observed.loads.items() if len(v) >= MIN_GROUPS}
    if not obs:  # nothing to fit to: the distance would be 0 whatever the values
        counts = ", ".join(f"{len(v)} {k}" for k, v in observed.loads.items())
        raise CalibrationError(f"observed: {counts} groups; a fit needs at least {MIN_GROUPS} of one size")
    scales = {k: np.maximum(np.std(v, axis=0), 1e-9) for k, v in obs.items()}
    fitted = tuple(q for q in ORDER if q in fit)
    bounds = tuple(tuple(fit[q]) for q in fitted)
    return Problem(table, obs, scales, fitted, bounds, dict(base), min_group_load_kg, observed.weight_step_kg)


def fit(
    problem: Problem, seed: int, maxiter: int, popsize: int, obs_weights=None, slot_counts=None,
    progress: Callable[[str], None] | None = None, label: str = "fit",
) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """Minimise the distance by differential evolution (seeded, Sobol' initial population, no polish): the best
    values (in the order of ``problem.fitted``, their units), the distance [-] and the evaluations [-].

    ``obs_weights`` (per size, each observed group's count) and ``slot_counts`` (each calibration bogie's) weigh a
    bootstrap resample; None: every one once. ``progress`` is told each generation (None: nothing)."""
    f = problem.objective(obs_weights or problem.unit_weights(), slot_counts)
    evaluations = [0]

    def counted(theta):
        evaluations[0] += 1
        return f(theta)

    generation = [0]

    def callback(intermediate_result):
        generation[0] += 1
        if progress is not None:
            progress(f"calibrate: {label}: generation {generation[0]}/{maxiter}, {evaluations[0]} evaluations, "
                     f"best distance {intermediate_result.fun:.5f}")  # fmt: skip

    result = differential_evolution(
        counted, problem.bounds, seed=seed, maxiter=maxiter, popsize=popsize, tol=1e-6, polish=False,
        init="sobol", callback=callback,
    )  # fmt: skip
    return np.asarray(result.x, dtype=float), float(result.fun), evaluations[0]
