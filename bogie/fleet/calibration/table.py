"""The calibration fleet and its table of readings (:mod:`bogie.fleet.calibration`, ``docs/calibration.md``).

The one simulation a calibration needs: every calibration bogie weighed, error free, as its steel group and as the
air-sprung group on the same trailer, at every tilt of a grid and (WIM) every site roughness (:func:`build_table`);
a fleet of given quantities is then read off the table (:func:`fleet_readings`) through each bogie's common random
numbers (:func:`crn_table`). Loads in kg, tilts in degrees, roughness in m/km.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.settings import CalibrationError
from bogie.fleet.calibration.site import SPEED_SD_M_S, Site, bogie_speeds, on_site, site_of
from bogie.fleet.constants import TILTED_QUANTITIES
from bogie.fleet.sampling.distributions import Distribution, TruncNormal, truncated_standard_normal_cdf
from bogie.fleet.sampling.sample import bogie_from_sample, suspension_draw
from bogie.fleet.sampling.tilted import Tilted
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.fleet.weighing.weigher import weigh
from bogie.group_names import GROUP_AXLES
from bogie.params import GRAVITY
from bogie.road import wim
from bogie.rounding import json_number
from bogie.settings import check_value

__all__ = [
    "SIZES", "CalibrationError", "Mapper", "Table", "base_values", "bogie_tilts", "build_table", "crn_table",
    "fleet_readings", "map_tasks", "moved_samples", "protocol_spec", "steel_weights", "tilted_families",
    "weigh_reading", "weigh_readings", "wim_task",
]  # fmt: skip

#: the axle groups a calibration covers, and their axles
SIZES: dict[str, int] = GROUP_AXLES

#: a map-like callable: ``mapper(func, items)`` gives ``func(item)`` of every item, in the items' order
Mapper = Callable[[Callable[[Any], Any], Sequence[Any]], Iterable[Any]]


def _quiet(text: str) -> None:
    """A progress callback that says nothing."""


def _summary(entries: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per quantity, a summary's numbers rounded (:func:`bogie.rounding.json_number`), its words and Nones kept."""
    return {
        q: {k: (v if v is None or isinstance(v, str) else json_number(v)) for k, v in e.items()}
        for q, e in entries.items()
    }


def _whole(name: str, value: Any, low: int) -> int:
    """``value`` if it is a whole number >= ``low``, else a :class:`CalibrationError` naming ``name``."""
    return check_value(name, value, low=low, whole=True, error=CalibrationError)


# ---- the calibration fleet and its table of readings -------------------------------------------------------------
@dataclass(frozen=True)
class Table:
    """The calibration fleet's error-free readings on the grid, its common random numbers, and how it is weighed.

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
    protocol: str = "wim"  # whose readings: "static" or "wim"
    settings: StaticProtocol | WimProtocol | None = None  # the protocol's (weighed with an error-free sensor)
    tilt_distribution: Distribution | None = None  # the fleet's chassis tilt distribution [rad]
    z_pass: np.ndarray | None = None  # (n,) the sensor's standard normal common to a pass's axles
    #: quantity of TILTED_QUANTITIES -> the family its fleet distribution moves in (those that can be fitted)
    tilted: Mapping[str, Tilted] = dataclasses.field(default_factory=dict)
    site: Site | None = None  # the WIM site every calibration bogie crosses (None: each its own road; static)
    speeds: np.ndarray | None = None  # (n,) each bogie's speed over the site [m/s] (None: the protocol's)
    seed: int = 0  # the fleet's master seed and study: the other sites' roads (bogie.fleet.calibration.site)
    study: str = "fleet"
    sites: int = 1  # the WIM sites the bogies are spread over: bogie i on site i mod sites (``site`` is site 0)

    def column(self, name: str) -> np.ndarray:
        """A sample column as floats, read once (the fit reads the inhibitors' columns at every evaluation)."""
        cache = self.__dict__.setdefault("_columns", {})
        if name not in cache:
            cache[name] = self.samples[name].to_numpy(dtype=float)
        return cache[name]

    def pass_factors(self) -> np.ndarray:
        """(n,) each bogie's factor of the sensor's error common to its pass's axles, ``1 + s_v z_v`` (the sensor's
        ``s_v`` as the WIM settings give it, not fitted: the load shares do not see it); ones for static."""
        if self.protocol != "wim" or self.z_pass is None or not isinstance(self.settings, WimProtocol):
            return np.ones(len(self.size))
        return 1.0 + self.settings.vehicle_error_sd * self.z_pass

    def reading_factors(self, values: Mapping[str, float], bogies: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) the factors a WIM reading of each bogie's axles is its force times (rows ``bogies``, None: all):
        the site's bias ``1 + b`` (``site_bias_pct`` / 100, 0 if absent), each axle's own sensor error
        ``1 + s_a z_i`` (``sensor_error_pct`` / 100) and the pass's, :meth:`pass_factors`; ones for static."""
        rows = np.arange(len(self.size)) if bogies is None else np.asarray(bogies)
        if self.protocol != "wim":
            return np.ones((len(rows), 3))
        bias = 1.0 + 0.01 * values.get("site_bias_pct", 0.0)
        return bias * (1.0 + 0.01 * values["sensor_error_pct"] * self.z[rows]) * self.pass_factors()[rows, None]

    def task(self, i: int, sample: Mapping[str, Any], spec: Any, protocol: str | None = None) -> tuple[dict, str, Any]:
        """The weighing task of bogie ``i`` (:func:`weigh_reading`) by ``protocol`` (None: the table's): for WIM,
        ``sample`` on the table's site at the bogie's speed (:func:`bogie.fleet.calibration.site.on_site`); static as
        given."""
        speed = None if self.speeds is None else self.speeds[i]
        return wim_task(sample, spec, self.site_for(i), speed, protocol or self.protocol)

    def site_for(self, i: int) -> Site | None:
        """Bogie ``i``'s WIM site: site ``i mod sites`` of :func:`~bogie.fleet.calibration.site.site_of` (None: no
        shared site)."""
        if self.site is None or self.sites == 1:
            return self.site
        made = self.__dict__.setdefault("_sites", {})
        if not made:
            classes = list(self.samples["road_class"].astype(str))
            made.update({k: site_of(self.seed, self.study, classes, k) for k in range(self.sites)})
        return made[i % self.sites]

    def site_labels(self, bogies: np.ndarray) -> np.ndarray | None:
        """The site number of each of ``bogies`` (None: one site, or none, for all)."""
        return None if self.site is None or self.sites == 1 else np.asarray(bogies, dtype=int) % self.sites


def wim_task(
    sample: Mapping[str, Any], spec: Any, site: Site | None, speed: float | None, protocol: str = "wim"
) -> tuple[dict, str, Any]:
    """A weighing task ``(sample, protocol, settings)``: a WIM one on ``site`` at ``speed`` [m/s]
    (:func:`bogie.fleet.calibration.site.on_site`), a static one as given."""
    if protocol != "wim":
        return dict(sample), protocol, spec
    moved, moved_spec = on_site(sample, spec, site, speed)
    return moved, protocol, moved_spec


def tilted_families(inhibitor_distributions: Mapping[str, Distribution] | None) -> dict[str, Tilted]:
    """Per quantity of :data:`~bogie.fleet.constants.TILTED_QUANTITIES` whose sample column has a uniform or a
    log-uniform distribution in ``inhibitor_distributions`` (sample column -> the fleet's distribution, SI): the
    family a fit moves it in (:class:`bogie.fleet.sampling.tilted.Tilted`). Other kinds are left out: their mean is not
    fitted."""
    families = {}
    for quantity, (column, scale) in TILTED_QUANTITIES.items():
        dist = (inhibitor_distributions or {}).get(column)
        try:
            families[quantity] = Tilted.of(dist, scale) if dist is not None else None
        except ValueError:
            families[quantity] = None
    return {q: f for q, f in families.items() if f is not None}


def base_values(
    tilt_distribution: Distribution, air_share: float, wim_settings: WimProtocol | None,
    inhibitor_distributions: Mapping[str, Distribution] | None = None,
) -> dict[str, float]:  # fmt: skip
    """The value of each quantity of :data:`ORDER` in a fleet (what an unfitted quantity keeps).

    Parameters
    ----------
    tilt_distribution
        The fleet's chassis tilt distribution [rad]: its ``mean`` and ``sd`` give the tilt's centre and spread in
        degrees (0 and 1 degree for a distribution without them).
    air_share
        Fraction of air-sprung groups [-].
    wim_settings
        The WIM protocol's settings: the site's roughness [m/km] and the sd of each axle reading's own sensor error
        [%] (:attr:`~bogie.fleet.WimProtocol.axle_error_sd`); None: both NaN (a static calibration uses neither).
    inhibitor_distributions
        Sample column -> the fleet's distribution (SI) of ``contact_roll_radius`` and ``bush_stiffness``: the mean
        radius [mm] and the geometric mean stiffness [N m/rad] of a uniform or log-uniform one
        (:func:`tilted_families`); NaN for another kind or none given (then not fittable).
    """
    families = tilted_families(inhibitor_distributions)
    moved = {q: families[q].fleet_mean if q in families else math.nan for q in TILTED_QUANTITIES}
    return {
        "chassis_tilt_mean_deg": math.degrees(getattr(tilt_distribution, "mean", 0.0)),
        "chassis_tilt_sd_deg": math.degrees(getattr(tilt_distribution, "sd", 1.0)),
        "air_share": float(air_share),
        "site_iri_m_km": math.nan if wim_settings is None else wim_settings.site_iri,
        "site_bias_pct": math.nan if wim_settings is None else 0.0,
        "sensor_error_pct": math.nan if wim_settings is None else 100.0 * wim_settings.axle_error_sd,
        **moved,
    }  # fmt: skip


def protocol_spec(table: Table, iri: float) -> StaticProtocol | WimProtocol:
    """The settings a calibration weighing uses: the static protocol's, or the WIM protocol's with no sensor error
    and, unless ``iri`` is NaN, the site roughness ``iri`` [m/km]."""
    if table.protocol == "static":
        return table.settings
    spec = dataclasses.replace(table.settings, sensor="none", sensor_vehicle_error=None, sensor_axle_error=None)
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
    out[:n] = [row[f"axle_load_{i + 1}"] / GRAVITY for i in range(n)]
    return out


def weigh_reading(task: tuple[Mapping[str, Any], str, Any]) -> np.ndarray:
    """The readings [kg] of one weighing task ``(sample, protocol, settings)``, 3 entries (NaN: none)."""
    return _weigh_kg(*task)


def map_tasks(func: Callable[[Any], Any], tasks: Sequence[Any], executor: Executor | Mapper | None = None) -> list:
    """``func(task)`` of every task, in the tasks' order: in this process (``executor`` None), over a
    :class:`concurrent.futures.Executor`'s workers in chunks, or through a map-like callable (:data:`Mapper`, e.g. the
    pipeline's). ``func`` must be importable (a module-level function) for the last two. The same results whichever."""
    if executor is None:
        return list(map(func, tasks))
    if isinstance(executor, Executor):
        workers = getattr(executor, "_max_workers", None) or os.cpu_count() or 1
        return list(executor.map(func, tasks, chunksize=max(1, len(tasks) // (8 * workers))))
    return list(executor(func, tasks))


def weigh_readings(tasks: Sequence[tuple[dict, str, Any]], executor: Executor | Mapper | None = None) -> np.ndarray:
    """Each task's readings [kg], shape (tasks, 3), in the tasks' order.

    ``executor``: None weighs in this process; a :class:`concurrent.futures.Executor` maps the tasks over its
    workers in chunks; a map-like callable (:data:`Mapper`, e.g. the pipeline's, which chunks and checks its
    workers itself) is called as ``executor(weigh_reading, tasks)``. The same numbers whichever.
    """
    out = [np.asarray(r, dtype=float) for r in map_tasks(weigh_reading, tasks, executor)]
    return np.array(out).reshape(len(tasks), 3) if out else np.zeros((0, 3))


def _increasing(name: str, values: Any, unit: str, positive: bool = False) -> np.ndarray:
    out = np.asarray(values, dtype=float)
    bad = out.ndim != 1 or len(out) < 2 or not np.all(np.isfinite(out)) or np.any(np.diff(out) <= 0.0)
    if bad or (positive and out[0] <= 0.0):
        sign = " positive" if positive else ""
        raise CalibrationError(f"{name} = {values!r}: must be two or more finite{sign} increasing values, in {unit}")
    return out


#: the sample columns a calibration fleet needs besides those of bogie_from_sample
_CRN_COLUMNS: tuple[str, ...] = ("sample_id", "group", "chassis_tilt", "sensor_seed")


def _check_fleet(
    samples: pd.DataFrame, tilt_distribution: Any, protocol: str, settings: Any,
    inhibitor_distributions: Mapping[str, Distribution] | None = None,
) -> None:  # fmt: skip
    kinds = {"static": StaticProtocol, "wim": WimProtocol}
    if protocol not in kinds:
        raise CalibrationError(f"protocol = {protocol!r}: must be one of {', '.join(kinds)}")
    if not isinstance(settings, kinds[protocol]):
        raise CalibrationError(f"settings = {settings!r}: must be a {kinds[protocol].__name__} for protocol {protocol}")
    if not isinstance(tilt_distribution, Distribution):
        raise CalibrationError(f"tilt_distribution = {tilt_distribution!r}: must be a bogie.fleet distribution [rad]")
    missing = [c for c in _CRN_COLUMNS if c not in samples.columns]
    if missing or not len(samples):
        raise CalibrationError(f"samples: {len(samples)} rows, missing {missing}: give one or more sample rows "
                               f"(bogie.fleet.sample_fleet) with the columns {', '.join(_CRN_COLUMNS)}")  # fmt: skip
    sizes = set(samples["group"].astype(str))
    if not sizes <= set(SIZES):
        raise CalibrationError(f"samples['group'] has {sorted(sizes - set(SIZES))}: must be {' or '.join(SIZES)}")
    for quantity in tilted_families(inhibitor_distributions):
        column = TILTED_QUANTITIES[quantity][0]
        if column not in samples.columns:
            raise CalibrationError(f"samples: no column {column!r} for inhibitor_distributions[{column!r}]")


def crn_table(
    samples: pd.DataFrame, tilt_distribution: Distribution, seed: int, protocol: str,
    settings: StaticProtocol | WimProtocol, tilts: Sequence[float], site_iri_levels: Sequence[float] = (),
    study: str = "fleet", inhibitor_distributions: Mapping[str, Distribution] | None = None,
    shared_site: bool = True, speed_sd_m_s: float = SPEED_SD_M_S, table_sites: int = 1,
) -> Table:  # fmt: skip
    """The calibration fleet and its common random numbers, with no reading yet (``loads`` zeros).

    Parameters
    ----------
    samples
        The calibration bogies: sample rows of :func:`bogie.fleet.sample_fleet` (their own samples, whatever
        suspension the fleet gave them; each becomes a steel and an air group).
    tilt_distribution
        The fleet's chassis tilt distribution [rad]; a truncated normal's centre and spread can be fitted (each
        bogie keeps its tilt's rank under it), another kind keeps each bogie's sampled tilt.
    seed, study
        The fleet's master seed [-] and study name, of each bogie's suspension draw
        (:func:`bogie.fleet.sampling.sample.suspension_draw`).
    protocol, settings
        ``static`` with a :class:`StaticProtocol` or ``wim`` with a :class:`WimProtocol`: the readings the survey is
        held against (error free in the table; the sensor's error is a fitted quantity).
    tilts
        The grid of chassis tilts the readings are tabulated on [degree], increasing, covering the tilts a fitted
        distribution gives (its support).
    site_iri_levels
        The WIM site roughnesses the readings are tabulated at [m/km], increasing (``wim`` only).
    inhibitor_distributions
        The fleet's distributions (SI) of ``contact_roll_radius`` and ``bush_stiffness``, the sample columns whose
        mean a fit may move (:func:`tilted_families`); None: neither can be fitted.
    shared_site, speed_sd_m_s, table_sites
        ``wim``: every bogie on one site's road (True; :mod:`bogie.fleet.calibration.site`), each at its own speed
        (sd ``speed_sd_m_s`` [m/s]); False: each on its own road at the protocol's speed. ``table_sites`` (>= 1):
        bogie i on site i mod ``table_sites``, the table for the population of sites (docs/calibration.md).

    Raises :class:`CalibrationError` if an argument is not of the kind or in the range said above (named, with its
    value and unit).
    """
    _check_fleet(samples, tilt_distribution, protocol, settings, inhibitor_distributions)
    _whole("seed", seed, 0), _whole("table_sites", table_sites, 1)
    grid = _increasing("tilts", tilts, "degree")
    iris = _increasing("site_iri_levels", site_iri_levels, "m/km", True) if protocol == "wim" else [np.nan]
    shared = protocol == "wim" and shared_site
    site, speeds = _site(samples, seed, study, settings, speed_sd_m_s) if shared else (None, None)
    tilt = samples["chassis_tilt"].to_numpy(dtype=float)  # its rank: the uniform a refitted distribution maps
    truncated = isinstance(tilt_distribution, TruncNormal)
    tilt_u = np.clip(_cdf(tilt_distribution, tilt), 1e-12, 1 - 1e-12) if truncated else np.full(len(tilt), np.nan)
    air_u = np.array([suspension_draw(seed, study, int(i)) for i in samples["sample_id"]])
    # the sensor's normals of bogie.road.wim.sensor_factors for the bogie's sensor_seed: each axle's, the pass's
    normals = [wim.sensor_normals(int(s), 3) for s in samples["sensor_seed"]]
    z = np.array([axles for _, axles in normals]).reshape(len(samples), 3)
    z_pass = np.array([p for p, _ in normals], dtype=float)
    size = samples["group"].astype(str).to_numpy()
    loads = np.zeros((2, len(samples), len(grid), len(iris), 3))
    families = tilted_families(inhibitor_distributions)
    return Table(
        samples, size, tilt_u, air_u, z, grid, np.asarray(iris, dtype=float), loads, 0, protocol, settings,
        tilt_distribution, z_pass, families, site, speeds, int(seed), study, int(table_sites),
    )  # fmt: skip


def _site(
    samples: pd.DataFrame, seed: int, study: str, settings: WimProtocol, speed_sd_m_s: float
) -> tuple[Site, np.ndarray]:
    """The table's shared WIM site and each bogie's speed over it [m/s] (:mod:`bogie.fleet.calibration.site`)."""
    if "road_class" not in samples.columns:
        raise CalibrationError("samples: no column 'road_class' (the site's road class) for shared_site = True")
    site = site_of(seed, study, list(samples["road_class"].astype(str)))
    try:
        speeds = bogie_speeds(seed, study, samples["sample_id"].to_numpy(), settings.speed, speed_sd_m_s)
    except ValueError as err:
        raise CalibrationError(str(err)) from None
    return site, speeds


def build_table(
    samples: pd.DataFrame, tilt_distribution: Distribution, seed: int, protocol: str,
    settings: StaticProtocol | WimProtocol, tilts: Sequence[float], site_iri_levels: Sequence[float] = (),
    executor: Executor | Mapper | None = None, progress: Callable[[str], None] | None = None, study: str = "fleet",
    inhibitor_distributions: Mapping[str, Distribution] | None = None, shared_site: bool = True,
    speed_sd_m_s: float = SPEED_SD_M_S, table_sites: int = 1,
) -> Table:  # fmt: skip
    """Weigh the calibration fleet on the grid of tilts (and site roughnesses): the one simulation the fit needs.

    The arguments are :func:`crn_table`'s; ``executor`` is where the weighings run (:func:`weigh_readings`) and
    ``progress`` is called with a line before and after (None: silent).

    Returns
    -------
    Table
        ``loads`` [kg] of shape (2, n, tilts, roughnesses, 3) and ``n_failed``, the weighings that gave no reading.
    """
    progress = progress or _quiet
    base = crn_table(
        samples, tilt_distribution, seed, protocol, settings, tilts, site_iri_levels, study, inhibitor_distributions,
        shared_site, speed_sd_m_s, table_sites,
    )  # fmt: skip
    n, tilts, iris = len(base.size), base.tilts, base.iris
    tasks, records = [], base.samples.to_dict("records")
    for kind in ("steel", "air"):
        for i, row in enumerate(records):
            for tilt in tilts:
                for iri in iris:
                    sample = {**row, "suspension": kind, "chassis_tilt": math.radians(float(tilt))}
                    tasks.append(base.task(i, sample, protocol_spec(base, iri)))
    progress(
        f"calibrate: weighing {len(tasks)} calibration groups ({n} bogies x steel, air x {len(tilts)} tilts x "
        f"{len(iris)} site roughnesses)"
    )
    start = time.perf_counter()
    loads = weigh_readings(tasks, executor).reshape(2, n, len(tilts), len(iris), 3)
    progress(f"calibrate: table done in {time.perf_counter() - start:.0f} s")
    failed = int(np.isnan(loads[..., 0]).sum())
    return dataclasses.replace(base, loads=loads, n_failed=failed)


def _cdf(dist: TruncNormal, x: np.ndarray) -> np.ndarray:
    a, b = (dist.low - dist.mean) / dist.sd, (dist.high - dist.mean) / dist.sd
    return truncated_standard_normal_cdf((np.asarray(x, dtype=float) - dist.mean) / dist.sd, a, b)


def bogie_tilts(table: Table, values: Mapping[str, float]) -> np.ndarray:
    """Each calibration bogie's tilt [degree] in a fleet of ``values``: the quantile of its uniform under the
    fleet's truncated normal with the centre and spread of ``values`` [degree]; its own sampled tilt when the
    fleet's tilt distribution is of another kind (then its centre and spread cannot be fitted)."""
    dist = table.tilt_distribution
    if not isinstance(dist, TruncNormal):
        return np.degrees(table.samples["chassis_tilt"].to_numpy(dtype=float))
    mean, sd = math.radians(values["chassis_tilt_mean_deg"]), math.radians(values["chassis_tilt_sd_deg"])
    return np.degrees(dataclasses.replace(dist, mean=mean, sd=sd).ppf(table.tilt_u))


@functools.lru_cache(maxsize=4096)
def _tilt(family: Tilted, value: float) -> float:
    return family.tilt(value)


def _tilts_of(table: Table, values: Mapping[str, float]) -> dict[str, float]:
    """Per moved quantity of the table, the tilt ``t`` of its value (0 for the fleet's own)."""
    out = {}
    for quantity, family in table.tilted.items():
        value = values.get(quantity, math.nan)
        if not math.isnan(value) and value != family.fleet_mean:
            out[quantity] = _tilt(family, float(value))
    return out


def steel_weights(table: Table, values: Mapping[str, float]) -> np.ndarray:
    """(n,) each calibration bogie's steel group's weight in a fleet whose inhibitor distributions have the means of
    ``values`` (:data:`~bogie.fleet.constants.TILTED_QUANTITIES`): the product of the density ratios of its sampled
    values (:meth:`bogie.fleet.sampling.tilted.Tilted.weights`), up to a common factor; ones for the fleet's own."""
    w = np.ones(len(table.size))
    for quantity, t in _tilts_of(table, values).items():
        w = w * table.tilted[quantity].weights(table.column(TILTED_QUANTITIES[quantity][0]), t)
    return w


def moved_samples(table: Table, values: Mapping[str, float]) -> pd.DataFrame:
    """The calibration bogies' samples in a fleet whose inhibitor distributions have the means of ``values``: each
    sampled value moved to its rank under the moved distribution (:meth:`bogie.fleet.sampling.tilted.Tilted.moved`),
    for a direct simulation. The table's own samples when no mean moves."""
    tilts = _tilts_of(table, values)
    if not tilts:
        return table.samples
    samples = table.samples.copy()
    for quantity, t in tilts.items():
        column = TILTED_QUANTITIES[quantity][0]
        samples[column] = table.tilted[quantity].moved(samples[column].to_numpy(dtype=float), t)
    return samples


def fleet_readings(table: Table, values: Mapping[str, float]) -> np.ndarray:
    """The calibration fleet's readings [kg] with the quantities ``values``: shape (2, n, 3), steel and air.

    Each bogie's tilt is :func:`bogie_tilts`, its readings interpolated linearly in tilt and in site roughness
    (``site_iri_m_km`` [m/km], clipped to the table's levels), then, for WIM, multiplied by the sensor's factors
    ``(1 + b) (1 + s_v z_v) (1 + s_a z_i)`` (:meth:`Table.reading_factors`: ``b`` the site's bias,
    ``site_bias_pct`` / 100; ``s_a`` each axle's own error, ``sensor_error_pct`` / 100, fitted; ``s_v`` the part
    common to the pass, :meth:`Table.pass_factors`; z the bogie's normals).
    """
    tilt = bogie_tilts(table, values)
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
        at = at * table.reading_factors(values)[None, :, :]
    return at
