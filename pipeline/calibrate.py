"""DVC stage ``calibrate``: the fleet quantities that make the simulated survey the observed one -> data/calibration/.

``python -m pipeline.calibrate`` fits the fleet quantities listed in ``calibrate.fit`` (the chassis tilt
distribution's centre and spread, the air share, the WIM site's roughness, the sensor's error) so that the
simulated readings' distributions of each axle position's load share and of the spread match the observed survey's
under the same filters (``observed:``). The method and its checks are ``docs/calibration.md``; in short:

1. **The calibration fleet** is the first ``calibrate.n_bogies`` bogies of the fleet study (data/samples), each
   both as its steel group and as the air-sprung group on the same trailer. Everything but the fitted quantities is
   the bogie's own sample (payload, tyre wear, road, inhibitors). Common random numbers: each bogie keeps one
   uniform for its tilt (its tilt's rank under the fleet's distribution), one for its suspension (its
   :func:`bogie.fleet.sampling.suspension_draw`) and one standard normal per axle for the sensor (its ``sensor_seed``).
2. **A table of readings**: every calibration group weighed (error free) at every tilt of a grid over the tilt
   distribution's bounds and, for WIM, at every site roughness of ``site_iri_levels_m_km``. A fleet of given
   quantities then costs no simulation: each bogie's tilt is the quantile of its uniform, its readings are
   interpolated linearly in tilt and roughness, the sensor's error multiplies them, and the air share weighs its
   air group against its steel one (a mixture, smooth in the share).
3. **The distance**: over laden tandem and tri-axle groups, the sum over each axle position's load share and the
   spread [%] of the energy distance between the observed and the simulated distribution, each over the observed
   quantity's standard deviation (so that every term is in the same units).
4. **The fit**: scipy's ``differential_evolution`` (derivative free, global, seeded; the distance is deterministic
   under common random numbers, so Monte Carlo noise is a fixed bias, not a changing one). **Intervals**: the fit
   repeated on bootstrap resamples of the observed records and of the calibration bogies together, so that they
   carry the survey's sampling error and the simulation's Monte Carlo error. **Trade-offs**: the bootstrap
   correlation of each pair of fitted quantities, and the distance over the most correlated pair (the valley).
5. **Checks**: the calibrated fleet simulated directly (not through the table) at the fitted values, under the
   survey's filters (``calibrated``); a fit on alternate records held against the other half (``held_out``); the
   ablation re-run on the calibrated fleet's steel groups.

Without an observed survey (``observed.path: null``) or a ``calibrate`` section the stage writes one line, a
metrics file that says why, and nothing else. Nothing here has a date: the same inputs give the same bytes.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml
from scipy.optimize import differential_evolution
from scipy.stats import energy_distance, truncnorm

from bogie.fleet.distributions import TruncNormal
from bogie.fleet.observed import by_size
from bogie.fleet.sampling import bogie_from_sample, suspension_draw
from bogie.fleet.weighing import weigh
from bogie.metrics import max_deviation
from bogie.params import GRAVITY, INHIBITORS
from bogie.road import wim
from bogie.weighings.stats import at_resolution, group_inequality, survey_statistics
from bogie.weighings.survey import observed_survey
from bogie.weighings.writers import write_weighings
from pipeline.atomic import LockedError, atomic_outputs, io_error, stage_outputs
from pipeline.config import CalibrateConfig, Config, ConfigError, ExecutionConfig, load_config, observed_file
from pipeline.config.rules import calibration_tilt_count
from pipeline.config.schema import CALIBRATION_QUANTITIES
from pipeline.resources import worker_count
from pipeline.sample import sample_fleet
from pipeline.simulate import map_ordered

__all__ = [
    "Calibration", "CalibrationError", "Observed", "Table", "build_table", "calibrate", "distance", "main",
    "observed_quantities", "simulate_fleet",
]  # fmt: skip

#: the fitted quantities in the order of the optimiser's vector
ORDER: tuple[str, ...] = tuple(CALIBRATION_QUANTITIES)
#: the axle groups the distance covers
SIZES: dict[str, int] = {"tandem": 2, "triaxle": 3}
#: the fewest observed groups of one size that enter the distance (fewer: that size is left out, and said so)
MIN_GROUPS = 10
#: the distance over the valley's pair of quantities is evaluated on this many points per side [-]
VALLEY_POINTS = 21
#: points of each quantity's profile [-]
PROFILE_POINTS = 25
#: bootstrap correlation from which two fitted quantities are reported as trading off [-]
TRADE_OFF = 0.5


class CalibrationError(ValueError):
    """An input that calibration cannot use (named, with what was expected)."""


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


def observed_groups(path: Path, config: Config) -> tuple[Observed, pd.DataFrame]:
    """The observed survey's laden tandem and tri-axle groups under ``observed:``'s filters.

    Raises
    ------
    CalibrationError
        If no group of either size passes the filters.
    """
    obs = config.observed
    survey = observed_survey(path, obs.format, obs.min_group_load / 1000.0, obs.group_spacing, obs.position)
    groups = survey.groups
    # alternate records, not alternate groups: the rank of each group's record in the file
    rank = pd.factorize(groups["line"], sort=True)[0] if len(groups) else np.zeros(0, dtype=int)
    loads, record = {}, {}
    for size, n in SIZES.items():
        sel = (groups["group"] == size).to_numpy()
        loads[size] = groups.loc[sel, [f"axle_load_{i}" for i in range(n)]].to_numpy(dtype=float)
        record[size] = np.asarray(rank)[sel]
    if not any(len(v) >= MIN_GROUPS for v in loads.values()):
        counts = ", ".join(f"{len(v)} {k}" for k, v in loads.items())
        raise CalibrationError(
            f"observed.path = {obs.path!r}: after the filters (min_group_load_t {obs.min_group_load / 1000:g} t, "
            f"group_spacing_m {obs.group_spacing:g} m, position {obs.position}) it has {counts} groups; calibration "
            f"needs at least {MIN_GROUPS} laden tandem or tri-axle groups"
        )
    return Observed(loads, record, survey.read.weight_step_kg), groups


def observed_quantities(loads: np.ndarray) -> np.ndarray:
    """Per group (rows of ``loads`` [any unit], front first): each axle's load share W_i / mean(W), then the spread
    (max - min) / mean [%], from :func:`bogie.weighings.stats.group_inequality`, shape (groups, n + 1)."""
    n = loads.shape[1]
    ineq = group_inequality(loads, np.full(len(loads), n))
    return np.column_stack([ineq["load_share"][:, :n], ineq["spread_pct"]])


# ---- the calibration fleet and its table of readings -------------------------------------------------------------
@dataclass(frozen=True)
class Table:
    """The calibration fleet's error-free readings on the grid, and its common random numbers.

    ``loads`` has shape (2, n, K, J, 3): suspension (steel, air), bogie, tilt, site roughness, axle [kg]; NaN for
    a weighing that failed or read a wheel in the air, and past a tandem's second axle.
    """

    samples: pd.DataFrame
    size: np.ndarray  # (n,) "tandem" | "triaxle"
    tilt_u: np.ndarray  # (n,) the tilt's uniform
    air_u: np.ndarray  # (n,) the suspension's uniform
    z: np.ndarray  # (n, 3) the sensor's standard normals
    tilts: np.ndarray  # (K,) [degree]
    iris: np.ndarray  # (J,) [m/km]; one NaN entry for the static protocol
    loads: np.ndarray
    n_failed: int


def defaults(config: Config) -> dict[str, float]:
    """The value each quantity has in params.yaml (what an unfitted quantity keeps)."""
    dist = config.distributions["chassis_tilt"]
    wim_spec = config.protocol.wim
    mix = config.fleet.suspension_mix
    shares = {mix[g]["air"] for g in mix}
    return {
        "chassis_tilt_mean_deg": math.degrees(getattr(dist, "mean", 0.0)),
        "chassis_tilt_sd_deg": math.degrees(getattr(dist, "sd", 1.0)),
        "air_share": float(np.mean(sorted(shares))),
        "site_iri_m_km": wim_spec.site_iri,
        "sensor_error_pct": 100.0 * wim.axle_error_sd(wim_spec.accuracy_class, wim_spec.confidence_level),
    }


def _spec(config: Config, iri: float) -> Any:
    cal = config.calibrate
    if cal.protocol == "static":
        return config.protocol.static
    spec = dataclasses.replace(config.protocol.wim, accuracy_class="none")
    return spec if math.isnan(iri) else dataclasses.replace(spec, site_iri=float(iri))


def _weigh_kg(sample: Mapping[str, Any], protocol: str, spec: Any) -> np.ndarray:
    """A sample's error-free axle loads [kg] (3 entries, NaN past the group's axles), all NaN if the weighing
    failed or read a wheel in the air."""
    out = np.full(3, np.nan)
    try:
        bogie = bogie_from_sample(sample)
    except (ValueError, TypeError):
        return out
    row = weigh(bogie, sample, protocol, spec)
    if row["status"] != "ok" or row["wheel_airborne"]:
        return out
    n = int(sample["n_axles"])
    out[:n] = [row[f"axle_load_{i}"] / GRAVITY for i in range(n)]
    return out


def _weigh_many(tasks: Sequence[tuple[dict, str, Any]], execution: ExecutionConfig) -> np.ndarray:
    """Each task's readings [kg], shape (tasks, 3), weighed on the stage's workers: simulate's pool of loky workers
    on this machine (``n_jobs`` capped as simulate's), or the dask cluster of ``execution.backend: dask``
    (:func:`pipeline.simulate.map_ordered`, the one executor); the same numbers either way."""
    if execution.backend != "dask":
        log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - the cap's warning to the log
        execution = dataclasses.replace(execution, n_jobs=worker_count(execution.n_jobs, log, "calibrate"))
    chunk = max(1, len(tasks) // (8 * max(execution.n_jobs, 1)) or 1)
    parts = [tasks[i : i + chunk] for i in range(0, len(tasks), chunk)]
    results = map_ordered(_weigh_part, parts, execution, "calibration")
    return np.concatenate(results) if results else np.zeros((0, 3))


def _weigh_part(part: Sequence[tuple[dict, str, Any]]) -> np.ndarray:
    """The readings [kg] of a part of the calibration's weighings, shape (len(part), 3)."""
    return np.array([_weigh_kg(*t) for t in part]).reshape(len(part), 3)


def calibration_samples(config: Config) -> pd.DataFrame:
    """The first ``calibrate.n_bogies`` fleet bogies (their own samples, whatever suspension the fleet gave them)."""
    return sample_fleet(config).iloc[: config.calibrate.n_bogies].reset_index(drop=True)


def _tilt_grid(config: Config) -> np.ndarray:
    dist = config.distributions["chassis_tilt"]
    low, high = (math.degrees(v) for v in dist.support)
    return np.linspace(low, high, calibration_tilt_count(low, high, config.calibrate.tilt_step))


def crn_table(config: Config) -> Table:
    """The calibration fleet and its common random numbers, with no reading yet (``loads`` empty)."""
    samples = calibration_samples(config)
    dist = config.distributions["chassis_tilt"]
    # each bogie's rank under its own distribution: the uniform a refitted distribution maps to its tilt
    tilt = samples["chassis_tilt"].to_numpy(dtype=float)
    truncated = isinstance(dist, TruncNormal)
    tilt_u = np.clip(_cdf(dist, tilt), 1e-12, 1 - 1e-12) if truncated else np.full(len(tilt), np.nan)
    air_u = np.array([suspension_draw(config.seed, "fleet", int(i)) for i in samples["sample_id"]])
    # the sensor's normals: those of bogie.road.wim.axle_errors for the bogie's sensor_seed
    z = np.array([np.random.default_rng(int(s)).standard_normal(3) for s in samples["sensor_seed"]])
    iris = np.asarray(config.calibrate.site_iri_levels, dtype=float) if config.calibrate.protocol == "wim" else [np.nan]
    size = samples["group"].astype(str).to_numpy()
    tilts = _tilt_grid(config)
    loads = np.zeros((2, len(samples), len(tilts), len(iris), 3))
    return Table(samples, size, tilt_u, air_u, z, tilts, np.asarray(iris, dtype=float), loads, 0)


def build_table(config: Config, progress: Callable[[str], None] = print) -> Table:
    """Weigh the calibration fleet on the grid of tilts (and site roughnesses): the one simulation the fit needs."""
    cal = config.calibrate
    base = crn_table(config)
    n, tilts, iris = len(base.size), base.tilts, base.iris
    tasks, records = [], base.samples.to_dict("records")
    for kind in ("steel", "air"):
        for row in records:
            for tilt in tilts:
                for iri in iris:
                    sample = {**row, "suspension": kind, "chassis_tilt": math.radians(float(tilt))}
                    tasks.append((sample, cal.protocol, _spec(config, iri)))
    progress(
        f"calibrate: weighing {len(tasks)} calibration groups ({n} bogies x steel, air x {len(tilts)} tilts x "
        f"{len(iris)} site roughnesses)"
    )
    start = time.perf_counter()
    loads = _weigh_many(tasks, config.execution).reshape(2, n, len(tilts), len(iris), 3)
    progress(f"calibrate: table done in {time.perf_counter() - start:.0f} s")
    failed = int(np.isnan(loads[..., 0]).sum())
    return dataclasses.replace(base, loads=loads, n_failed=failed)


#: the tractor a synthetic survey puts in front of each simulated group (:func:`write_csv_survey`): a 4x2 tractor,
#: steer and drive axle [kg] and the spacings steer-drive and drive-group [m]. Placeholders that make the group the
#: vehicle's third, a trailer group (bogie.weighings.groups); single axles, so no statistic of tandems or tri-axles
#: reads them
SYNTHETIC_TRACTOR = {"loads_kg": (6500.0, 10500.0), "spacings_m": (3.6, 6.0)}


def write_csv_survey(frame: pd.DataFrame, path: str | Path, speed_kmh: float = 80.0, spacing_m: float = 1.31) -> None:
    """Write simulated groups (:func:`simulate_fleet`'s wide loads [kg]) as a survey in the ``csv`` weighings format
    (``docs/weighings.md``), one semi-trailer a record, a second apart: a synthetic survey the stage reads as a real
    one. Each group is the trailer group of a vehicle behind :data:`SYNTHETIC_TRACTOR`; loads in whole kilograms."""
    steer, drive = SYNTHETIC_TRACTOR["loads_kg"]
    n_group = frame["n_axles"].to_numpy(dtype=np.int64)
    width = 2 + int(n_group.max()) if len(frame) else 5
    vehicles = pd.DataFrame({
        "timestamp": pd.Timestamp("2026-01-05T06:00:00") + pd.to_timedelta(np.arange(len(frame)), unit="s"),
        "speed": speed_kmh / 3.6, "lane": 1, "n_axles": 2 + n_group,
    })  # fmt: skip
    for i in range(width):
        if i < 2:
            load = np.full(len(frame), (steer, drive)[i])
        else:
            column = frame[f"axle_load_{i - 2}"].to_numpy(dtype=float) if i - 2 < 3 else np.zeros(len(frame))
            load = np.where(n_group > i - 2, np.round(column), np.nan)
        vehicles[f"axle_load_{i}"] = load
    for i in range(width - 1):
        gap = SYNTHETIC_TRACTOR["spacings_m"][i] if i < 2 else spacing_m
        vehicles[f"spacing_{i}"] = np.where(2 + n_group - 1 > i, gap, np.nan)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_weighings(vehicles, path, "csv")


def _cdf(dist: TruncNormal, x: np.ndarray) -> np.ndarray:
    a, b = (dist.low - dist.mean) / dist.sd, (dist.high - dist.mean) / dist.sd
    return truncnorm.cdf(x, a, b, loc=dist.mean, scale=dist.sd)


def bogie_tilts(table: Table, values: Mapping[str, float], dist: Any) -> np.ndarray:
    """Each calibration bogie's tilt [degree] in a fleet of ``values``: the quantile of its uniform under the
    fleet's truncated normal with the centre and spread of ``values``; its own sampled tilt when the fleet's tilt
    distribution is of another kind (then its centre and spread cannot be fitted: the schema refuses to fit them)."""
    if not isinstance(dist, TruncNormal):
        return np.degrees(table.samples["chassis_tilt"].to_numpy(dtype=float))
    mean, sd = math.radians(values["chassis_tilt_mean_deg"]), math.radians(values["chassis_tilt_sd_deg"])
    return np.degrees(dataclasses.replace(dist, mean=mean, sd=sd).ppf(table.tilt_u))


# ---- a fleet of given quantities, from the table -----------------------------------------------------------------
def _values(theta: Sequence[float], fitted: Sequence[str], base: Mapping[str, float]) -> dict[str, float]:
    values = dict(base)
    values.update(zip(fitted, (float(t) for t in theta)))
    return values


def fleet_readings(table: Table, values: Mapping[str, float], dist: Any) -> np.ndarray:
    """The calibration fleet's readings [kg] with the quantities ``values``: shape (2, n, 3), steel and air.

    Each bogie's tilt is :func:`bogie_tilts` under the fleet's tilt distribution ``dist``, its readings
    interpolated linearly in tilt and in site roughness, then multiplied by 1 + s z (s the sensor error, z the
    bogie's normals).
    """
    tilt = bogie_tilts(table, values, dist)
    grid = table.tilts
    k = np.clip(np.searchsorted(grid, tilt, side="right") - 1, 0, len(grid) - 2)
    f = ((tilt - grid[k]) / (grid[k + 1] - grid[k]))[None, :, None, None]
    idx = np.arange(len(tilt))
    at = table.loads[:, idx, k] * (1.0 - f) + table.loads[:, idx, k + 1] * f  # (2, n, J, 3)
    if len(table.iris) > 1:
        iri = float(np.clip(values["site_iri_m_km"], table.iris[0], table.iris[-1]))
        j = int(np.clip(np.searchsorted(table.iris, iri, side="right") - 1, 0, len(table.iris) - 2))
        g = (iri - table.iris[j]) / (table.iris[j + 1] - table.iris[j])
        at = at[:, :, j] * (1.0 - g) + at[:, :, j + 1] * g
    else:
        at = at[:, :, 0]
    if not math.isnan(table.iris[0]):
        at = at * (1.0 + 0.01 * values["sensor_error_pct"] * table.z[None, :, :])
    return at


@dataclass(frozen=True)
class Simulated:
    """Per size: each calibration group's quantities (rows), its mixture weight, for steel then air stacked."""

    quantities: Mapping[str, np.ndarray]
    weights: Mapping[str, np.ndarray]


def simulated(
    table: Table, values: Mapping[str, float], dist: Any, min_load_kg: float,
    slot_counts: np.ndarray | None = None, weight_step_kg: float | None = None,
) -> Simulated:  # fmt: skip
    """The simulated survey: the calibration groups that pass the filters, weighted (1 - a) steel and a air; every
    reading first read at the observed file's resolution ``weight_step_kg`` [kg] (None: as it is)."""
    readings = at_resolution(fleet_readings(table, values, dist), weight_step_kg)
    share = values["air_share"]
    counts = np.ones(len(table.size)) if slot_counts is None else slot_counts
    quantities, weights = {}, {}
    for size, n in SIZES.items():
        sel = table.size == size
        loads = readings[:, sel, :n].reshape(-1, n)
        w = np.concatenate([(1.0 - share) * counts[sel], share * counts[sel]])
        keep = np.all(np.isfinite(loads), axis=1) & np.all(loads > 0.0, axis=1) & (loads.sum(axis=1) >= min_load_kg)
        keep &= w > 0.0
        quantities[size] = observed_quantities(loads[keep]) if keep.any() else np.zeros((0, n + 1))
        weights[size] = w[keep]
    return Simulated(quantities, weights)


def distance(
    obs: Mapping[str, np.ndarray], obs_weights: Mapping[str, np.ndarray], sim: Simulated,
    scales: Mapping[str, np.ndarray],
) -> float:  # fmt: skip
    """Sum over sizes and quantities of the energy distance observed-simulated over the observed sd."""
    total = 0.0
    for size, q in obs.items():
        s = sim.quantities[size]
        if len(s) == 0 or sim.weights[size].sum() <= 0.0:
            return math.inf
        for c in range(q.shape[1]):
            total += energy_distance(q[:, c], s[:, c], obs_weights[size], sim.weights[size]) / scales[size][c]
    return float(total)


# ---- the fit -----------------------------------------------------------------------------------------------------
@dataclass
class Problem:
    """Everything one evaluation of the distance needs."""

    table: Table
    obs: dict[str, np.ndarray]  # per size used: quantities (groups, n + 1)
    scales: dict[str, np.ndarray]
    fitted: tuple[str, ...]
    bounds: tuple[tuple[float, float], ...]
    base: dict[str, float]
    tilt_distribution: Any  # the fleet's (bogie.fleet.distributions), SI
    min_load_kg: float
    weight_step_kg: float | None = None  # the observed file's resolution [kg]

    def objective(self, obs_weights: Mapping[str, np.ndarray], slot_counts: np.ndarray | None) -> Callable:
        def f(theta: np.ndarray) -> float:
            values = _values(theta, self.fitted, self.base)
            sim = simulated(
                self.table, values, self.tilt_distribution, self.min_load_kg, slot_counts, self.weight_step_kg
            )
            return distance(self.obs, obs_weights, sim, self.scales)

        return f

    def unit_weights(self) -> dict[str, np.ndarray]:
        return {k: np.ones(len(v)) for k, v in self.obs.items()}


def make_problem(table: Table, observed: Observed, config: Config) -> Problem:
    """The fit of ``config.calibrate.fit`` to ``observed`` on ``table`` (sizes with too few groups left out)."""
    obs = {k: observed_quantities(v) for k, v in observed.loads.items() if len(v) >= MIN_GROUPS}
    scales = {k: np.maximum(np.std(v, axis=0), 1e-9) for k, v in obs.items()}
    fitted = tuple(q for q in ORDER if q in config.calibrate.fit)
    bounds = tuple(tuple(config.calibrate.fit[q]) for q in fitted)
    dist = config.distributions["chassis_tilt"]
    return Problem(
        table, obs, scales, fitted, bounds, defaults(config), dist, config.observed.min_group_load,
        observed.weight_step_kg,
    )  # fmt: skip


def fit(
    problem: Problem, seed: int, maxiter: int, popsize: int, obs_weights=None, slot_counts=None,
    progress: Callable[[str], None] | None = None, label: str = "fit",
) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """Minimise the distance by differential evolution: (best values, distance, evaluations)."""
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


@dataclass
class Calibration:
    """The outcome: fitted values with intervals, the distance, the bootstrap, trade-offs, valley and profiles."""

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


def calibrate(
    problem: Problem, seed: int, cal: CalibrateConfig, progress: Callable[[str], None] = print
) -> Calibration:
    """Fit, then the bootstrap intervals, the trade-offs, the valley and the profiles."""
    start = time.perf_counter()
    best, dist_best, evaluations = fit(problem, seed, cal.maxiter, cal.popsize, progress=progress)
    per_eval = (time.perf_counter() - start) / max(evaluations, 1)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(1,)))
    rows = []
    for b in range(cal.bootstrap_resamples):
        obs_w = {
            k: rng.multinomial(len(v), np.full(len(v), 1.0 / len(v))).astype(float) for k, v in problem.obs.items()
        }
        n = len(problem.table.size)
        slots = rng.multinomial(n, np.full(n, 1.0 / n)).astype(float)
        theta, d, _ = fit(problem, seed + 1 + b, cal.maxiter, cal.popsize, obs_w, slots)
        rows.append({"resample": b, **dict(zip(problem.fitted, theta)), "distance": d})
        progress(f"calibrate: bootstrap {b + 1}/{cal.bootstrap_resamples}: distance {d:.5f}")
    boot = pd.DataFrame(rows, columns=["resample", *problem.fitted, "distance"])
    alpha = 1.0 - cal.confidence_level
    fitted = {}
    for i, q in enumerate(problem.fitted):
        entry = {"value": float(best[i]), "low": None, "high": None, "bounds": list(problem.bounds[i])}
        if len(boot) >= 2:
            entry["low"], entry["high"] = (float(np.quantile(boot[q], p)) for p in (alpha / 2, 1 - alpha / 2))
            # a basic interval must hold the estimate: the fit on all the data is one of the bootstrap's worlds
            entry["low"], entry["high"] = min(entry["low"], entry["value"]), max(entry["high"], entry["value"])
        fitted[q] = entry
    corr = boot[list(problem.fitted)].corr() if len(boot) >= 3 else pd.DataFrame()
    trade = []
    for i, a in enumerate(problem.fitted):
        for b_ in problem.fitted[i + 1 :]:
            r = corr.loc[a, b_] if not corr.empty else math.nan
            if np.isfinite(r) and abs(r) >= TRADE_OFF:
                trade.append({"quantities": [a, b_], "correlation": round(float(r), 3)})
    pair = _valley_pair(problem.fitted, corr)
    f = problem.objective(problem.unit_weights(), None)
    valley = _valley(problem, f, best, pair) if pair else pd.DataFrame(columns=["x", "y", "distance"])
    profiles = _profiles(problem, f, best)
    return Calibration(
        fitted, dist_best, evaluations, per_eval, boot, corr, trade, valley, profiles,
        _values(best, problem.fitted, problem.base),
    )  # fmt: skip


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


# ---- the calibrated fleet, simulated directly -------------------------------------------------------------------
def simulate_fleet(
    table: Table, values: Mapping[str, float], config: Config, variant: str = "baseline", steel_only: bool = False,
    weight_step_kg: float | None = None,
) -> pd.DataFrame:  # fmt: skip
    """The calibration fleet with the quantities ``values``, weighed directly (no table): one row per group kept
    (wide loads [kg], ``n_axles``, ``group``, ``suspension``), with the sensor's error, before the filters.

    ``variant`` removes an inhibitor of the steel groups (:data:`bogie.params.INHIBITORS`, or ``all``);
    ``weight_step_kg`` reads the loads at the observed file's resolution [kg] (None: as they are; the ablation's
    physics is read so).
    """
    tilt = bogie_tilts(table, values, config.distributions["chassis_tilt"])
    kinds = np.where(table.air_u < values["air_share"], "air", "steel")
    iri = values["site_iri_m_km"] if config.calibrate.protocol == "wim" else math.nan
    spec = _spec(config, iri)
    tasks, keep = [], []
    for i, row in enumerate(table.samples.to_dict("records")):
        if steel_only and kinds[i] != "steel":
            continue
        sample = {**row, "suspension": kinds[i], "chassis_tilt": math.radians(float(tilt[i]))}
        if variant != "baseline":
            for name, ideal in INHIBITORS.items():
                if variant in (name, "all"):
                    sample[name] = ideal
        tasks.append((sample, config.calibrate.protocol, spec))
        keep.append(i)
    loads = _weigh_many(tasks, config.execution)
    if config.calibrate.protocol == "wim":
        loads = loads * (1.0 + 0.01 * values["sensor_error_pct"] * table.z[keep])
    loads = at_resolution(loads, weight_step_kg)
    frame = pd.DataFrame({
        "slot": keep, "group": table.size[keep], "n_axles": [SIZES[s] for s in table.size[keep]],
        "suspension": kinds[keep], "tilt_deg": tilt[keep],
        **{f"axle_load_{i}": loads[:, i] for i in range(3)},
    })  # fmt: skip
    return frame


def filtered(frame: pd.DataFrame, min_load_kg: float) -> pd.DataFrame:
    """The groups a survey keeps: weighed, every wheel on the road, laden."""
    n = frame["n_axles"].to_numpy()
    loads = frame[[f"axle_load_{i}" for i in range(3)]].to_numpy()
    present = np.arange(3)[None, :] < n[:, None]
    ok = np.all(np.where(present, np.isfinite(loads) & (loads > 0.0), True), axis=1)
    total = np.nansum(np.where(present, loads, 0.0), axis=1)
    return frame[ok & (total >= min_load_kg)].reset_index(drop=True)


def groups_stats(loads_by_size: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """``bogie weighings --json``'s ``groups`` object of per-size load tables [kg]."""
    rows = []
    for size, loads in loads_by_size.items():
        for w in loads:
            rows.append({"group": size, "n_axles": SIZES[size], **{f"axle_load_{i}": w[i] for i in range(len(w))}})
    frame = pd.DataFrame(rows)
    if frame.empty:
        return by_size(pd.DataFrame())
    return by_size(survey_statistics(frame, by="group"))


def frame_stats(frame: pd.DataFrame) -> dict[str, Any]:
    """:func:`groups_stats` of a simulated frame."""
    return groups_stats({
        size: frame.loc[frame["group"] == size, [f"axle_load_{i}" for i in range(n)]].to_numpy()
        for size, n in SIZES.items()
    })  # fmt: skip


def frame_distance(frame: pd.DataFrame, obs: Mapping[str, np.ndarray], scales: Mapping[str, np.ndarray]) -> float:
    """The distance of a directly simulated (unweighted) survey to observed quantities."""
    q, w = {}, {}
    for size, n in SIZES.items():
        loads = frame.loc[frame["group"] == size, [f"axle_load_{i}" for i in range(n)]].to_numpy()
        q[size] = observed_quantities(loads) if len(loads) else np.zeros((0, n + 1))
        w[size] = np.ones(len(loads))
    return distance(obs, {k: np.ones(len(v)) for k, v in obs.items()}, Simulated(q, w), scales)


def ablation(table: Table, values: Mapping[str, float], config: Config) -> pd.DataFrame:
    """The calibrated fleet's steel groups with each inhibitor removed: mean max deviation, share outside 5 %."""
    rows = []
    for variant in ("baseline", *INHIBITORS, "all"):
        frame = filtered(
            simulate_fleet(table, values, config, variant, steel_only=True), config.observed.min_group_load
        )
        for size, n in SIZES.items():
            loads = frame.loc[frame["group"] == size, [f"axle_load_{i}" for i in range(n)]].to_numpy()
            if len(loads) == 0:
                continue
            max_dev = max_deviation(loads)
            outside = group_inequality(loads, np.full(len(loads), n))["outside_5pct"]
            rows.append({
                "variant": variant, "group": size, "n_groups": len(loads),
                "mean_max_deviation_pct": 100.0 * float(max_dev.mean()), "share_outside_5pct": float(outside.mean()),
            })  # fmt: skip
    table_ = pd.DataFrame(rows)
    base = table_[table_["variant"] == "baseline"].set_index("group")
    table_["buys_points"] = [
        base.loc[g, "mean_max_deviation_pct"] - m for g, m in zip(table_["group"], table_["mean_max_deviation_pct"])
    ]
    return table_


# ---- the stage ---------------------------------------------------------------------------------------------------
def _round(x: Any, digits: int = 4) -> Any:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return None
    return round(float(x), digits) + 0.0


def skipped_metrics(reason: str) -> dict[str, Any]:
    """metrics/calibration.json when nothing is calibrated."""
    return {"skipped": True, "reason": reason, "fitted": None, "observed": None, "calibrated": None, "held_out": None}


def run(config: Config, path: Path, progress: Callable[[str], None] = print) -> tuple[dict, dict[str, pd.DataFrame]]:
    """The whole calibration: metrics and the tables of data/calibration/."""
    observed, _ = observed_groups(path, config)
    table = build_table(config, progress)
    problem = make_problem(table, observed, config)
    cal = config.calibrate
    result = calibrate(problem, config.seed, cal, progress)
    step = observed.weight_step_kg
    direct = filtered(simulate_fleet(table, result.values, config, weight_step_kg=step), config.observed.min_group_load)
    # held out: a fit on the even records, the odd ones against the fleet it calibrates
    even, odd = observed.half(0), observed.half(1)
    held: dict[str, Any] = {"fit_on": "even records", "held_out": "odd records"}
    try:
        half = make_problem(table, even, config)
        theta, d_half, _ = fit(half, config.seed, cal.maxiter, cal.popsize, progress=progress, label="half fit")
        values_half = _values(theta, half.fitted, half.base)
        direct_half = filtered(
            simulate_fleet(table, values_half, config, weight_step_kg=step), config.observed.min_group_load
        )
        odd_q = {k: observed_quantities(v) for k, v in odd.loads.items() if k in half.obs and len(v)}
        held.update(
            fitted={q: _round(values_half[q]) for q in half.fitted},
            distance_fit_half=_round(d_half, 5),
            distance_held_out=_round(frame_distance(direct_half, odd_q, half.scales), 5),
            distance_halves=_round(_obs_distance(half.obs, odd_q, half.scales), 5),
            groups=groups_stats(odd.loads),
            calibrated_groups=frame_stats(direct_half),
        )
    except CalibrationError as exc:
        held.update(reason=str(exc), groups=None)
    abl = ablation(table, result.values, config)
    metrics = {
        "skipped": False,
        "protocol": cal.protocol,
        "method": "differential evolution on the energy distance, common random numbers, tabulated readings",
        "fitted": {
            q: {k: (_round(v) if not isinstance(v, list) else v) for k, v in e.items()}
            for q, e in result.fitted.items()
        },  # fmt: skip
        "fixed": {q: _round(v) for q, v in result.values.items() if q not in result.fitted},
        "confidence_level": cal.confidence_level,
        "bootstrap_resamples": cal.bootstrap_resamples,
        "distance": _round(result.distance, 5),
        "distance_direct": _round(frame_distance(direct, problem.obs, problem.scales), 5),
        "sizes_fitted": sorted(problem.obs),
        "evaluations": result.evaluations,
        "trade_offs": result.trade_offs,
        "table": {
            "n_bogies": len(table.size),
            "tilts_deg": [_round(t, 3) for t in table.tilts],
            "site_iri_levels_m_km": [None if math.isnan(x) else x for x in table.iris],
            "n_weighings": int(np.prod(table.loads.shape[:4])),
            "n_failed": table.n_failed,
        },  # fmt: skip
        "observed": {"groups": groups_stats(observed.loads), "weight_step_kg": step},
        "calibrated": {"groups": frame_stats(direct)},
        "held_out": held,
        "ablation": {
            f"{r.variant}/{r.group}": {
                "mean_max_deviation_pct": _round(r.mean_max_deviation_pct),
                "share_outside_5pct": _round(r.share_outside_5pct),
                "buys_points": _round(r.buys_points),
                "n_groups": int(r.n_groups),
            }
            for r in abl.itertuples()
        },  # fmt: skip
    }
    progress(f"calibrate: {result.evaluations} evaluations of {result.seconds_per_evaluation * 1e3:.1f} ms")
    tables = {
        "bootstrap.csv": result.bootstrap, "valley.csv": result.valley, "profiles.csv": result.profiles,
        "calibrated.csv": direct, "ablation.csv": abl,
    }  # fmt: skip
    return metrics, tables


def _obs_distance(a: Mapping[str, np.ndarray], b: Mapping[str, np.ndarray], scales: Mapping[str, np.ndarray]) -> float:
    """The distance between two observed halves: the floor a held-out distance can reach."""
    sim = Simulated({k: b.get(k, np.zeros((0, v.shape[1]))) for k, v in a.items()},
                    {k: np.ones(len(b.get(k, []))) for k in a})  # fmt: skip
    return distance(a, {k: np.ones(len(v)) for k, v in a.items()}, sim, scales)


def write_outputs(metrics: Mapping[str, Any], tables: Mapping[str, pd.DataFrame], out_dir, metrics_path) -> None:
    """data/calibration/ and metrics/calibration.json, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir]) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():
            frame.to_csv(tmp_dir / name, index=False, float_format="%.6g")
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
    try:
        # a second calibrate is refused here, and what a killed one left beside the outputs is removed
        with stage_outputs("calibrate", files=[args.metrics], dirs=[args.out], log=log):
            return _stage(args, log)
    except LockedError as exc:
        print(f"calibrate: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(io_error("calibrate", exc), file=sys.stderr)
        return 2


def _stage(args: argparse.Namespace, log: Callable[[str], None]) -> int:
    """The stage's work while it owns its outputs: read, calibrate, write; the exit code."""
    try:
        config = load_config(args.params)
        path = observed_file(config.observed, Path(args.params).resolve().parent)
        if path is None or config.calibrate is None:
            reason = (
                "no observed survey given (observed.path is null in params.yaml; docs/observed.md)"
                if path is None else "no calibrate section in params.yaml (calibrate: null)"
            )  # fmt: skip
            metrics, tables = skipped_metrics(reason), {}
        else:
            metrics, tables = run(config, path, log)
    except (ConfigError, CalibrationError, OSError, ValueError, yaml.YAMLError) as exc:
        print(f"calibrate: {exc}", file=sys.stderr)
        return 2
    try:
        write_outputs(metrics, tables, args.out, args.metrics)
    except OSError as exc:
        print(io_error("calibrate", exc), file=sys.stderr)
        return 2
    if metrics["skipped"]:
        print(f"calibrate: skipped, {metrics['reason']}")
    else:
        fitted = ", ".join(f"{q} {e['value']:.3g}" for q, e in metrics["fitted"].items())
        print(f"calibrate: {fitted}; distance {metrics['distance']}; wrote {args.out} and {args.metrics}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
