"""A weigh-in-motion (WIM) site and sensor: the site's pavement, the sensor's weighing length, its accuracy class.

Three parts, each a pure function or a small frozen dataclass (derivations and sources in ``docs/wim-site.md``):

- **site pavement**: :class:`SiteRoad` smooths a sampled road over the site, ``before`` metres ahead of the sensor
  and ``after`` metres past it (COST 323: 50 m and 25 m), to the roughness of a given International Roughness
  Index (IRI); :func:`iri_of_iso8608` and :func:`gd_n0_for_iri` convert between IRI and the ISO 8608 displacement
  PSD G_d(n0) (the golden quarter car's response to the PSD, in closed form);
- **weighing length**: :func:`sensor_reading` is the tyre force averaged over the tyre's passage across the sensor,
  weighted by the length of the contact patch that stands on the sensor, integrated exactly on the stored samples;
- **the sensor's error**: a reading is the averaged force times :func:`sensor_factors`, ``(1 + s_v z_v) (1 + s_a
  z_i)``, a part common to a pass's axles and each axle's own, their sizes by sensor type (:data:`SENSOR_ERRORS`,
  assumptions within the sources of ``docs/wim-site.md``); the COST 323 class the whole system reaches is a test of
  its readings against static weights (:mod:`bogie.road.cost323`, :data:`COST323_TOLERANCES`).

References
----------
COST 323, European Specification on Weigh-in-Motion of Road Vehicles, version 3.0, EUCO-COST/323/8/99, LCPC,
Paris, 1999; Jacob B., O'Brien E.J., Jehaes S. (eds.), Weigh-in-Motion of Road Vehicles: Final Report of the COST
323 Action, LCPC, Paris, 2002 (accuracy classes, site classes).
Sayers M.W., Gillespie T.D., Paterson W.D.O., Guidelines for Conducting and Calibrating Road Roughness
Measurements, World Bank Technical Paper 46, 1986 (the IRI's golden quarter car and 250 mm base).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.settings import check_value, refusal

__all__ = [
    "COST323_TOLERANCES", "SENSORS", "SENSOR_ERRORS", "SITE_BLEND_LENGTH", "STRIP_SENSOR_RMS_PCT", "SiteRoad",
    "gd_n0_for_iri", "iri_of_iso8608", "sensor_factors", "sensor_normals", "sensor_reading",
]  # fmt: skip

# ---- accuracy ------------------------------------------------------------------------------------------------------
#: COST 323 (1999) accuracy classes: the tolerance delta [%] of the confidence interval [W (1 - delta), W (1 + delta)]
#: around the static load W, for the gross weight, a group of axles, a single axle and an axle of a group
COST323_TOLERANCES: dict[str, dict[str, float]] = {
    "A(5)": {"gross": 5.0, "group": 7.0, "single_axle": 8.0, "axle_of_group": 10.0},
    "B+(7)": {"gross": 7.0, "group": 10.0, "single_axle": 11.0, "axle_of_group": 14.0},
    "B(10)": {"gross": 10.0, "group": 13.0, "single_axle": 15.0, "axle_of_group": 20.0},
    "C(15)": {"gross": 15.0, "group": 18.0, "single_axle": 20.0, "axle_of_group": 25.0},
    "D+(20)": {"gross": 20.0, "group": 23.0, "single_axle": 25.0, "axle_of_group": 30.0},
    "D(25)": {"gross": 25.0, "group": 28.0, "single_axle": 30.0, "axle_of_group": 35.0},
}

#: the sensor types and the standard deviations of their errors' two parts [-]: (common to a vehicle pass's axles,
#: each axle's own). ASSUMPTIONS, named as such (issue 43 Must 4; docs/wim-site.md, "The observation model"): no
#: source splits a sensor's error in two, and none can (whole-system figures cannot separate the sensor's per-axle
#: error from the vehicle's dynamics). Per pass: what every axle of a pass meets alike, the site's calibration drift
#: with temperature (-0.02 %/degC, a Lineas-type data sheet; Rys, Sensors 19:3272, 2019) and the strip's
#: non-uniformity along its length (every axle of a group crosses it at one lateral position); per axle: what differs
#: between the axles of one pass (noise, each tyre's own contact and impact). Bounds: a strip sensor's whole error
#: under 4 % RMS (Cebon and Winkler, TRR 1311, 1991; STRIP_SENSOR_RMS_PCT); COST 323's classes A(5) and B+(7), read
#: as a common part plus an independent per-axle part, imply a common part of 1.6-2.3 % and TRL RR307's
#: multiple-sensor results leave 2.1 % that does not average out (both whole systems, the dynamics in them). Quartz
#: 1.5 % and 2.0 % (2.5 % in all). The bending plate: drift the smallest (LTPP consistency study, Masud 2022). The
#: polymer strip: its weakness, temperature, is per pass (3 %), its per-axle part what keeps the whole under 4 %
#: (2.5 %: 3.9 % in all).
SENSOR_ERRORS: dict[str, tuple[float, float]] = {
    "none": (0.0, 0.0),
    "quartz": (0.015, 0.02),
    "bending_plate": (0.01, 0.02),
    "piezo_polymer": (0.03, 0.025),
}
#: the whole error of a strip sensor against an instrumented vehicle's dynamic wheel loads: under 4 % RMS (Cebon and
#: Winkler, TRR 1311, 1991), its two parts together [%]; a per-axle part fitted above it is per-axle scatter the model
#: lacks, not a sensor (issue 43 Must 4; bogie.fleet.calibration.fitting.sensor_finding)
STRIP_SENSOR_RMS_PCT = 4.0
#: the sensor types; ``none`` is an error-free sensor
SENSORS: tuple[str, ...] = tuple(SENSOR_ERRORS)


def _fraction(name: str, value: float) -> float:
    return check_value(name, value, "-", low=0.0, high=0.5, high_open=True, note="a fraction: 0.02 is 2 %")


def sensor_normals(seed: int, n_axles: int) -> tuple[float, NDArray[np.float64]]:
    """The standard normals of one pass's sensor errors: the pass's ``z_v`` and each axle's ``z_i``, front first.

    ``z_i`` is the i-th draw of ``numpy.random.default_rng(seed)`` (axle i has the same draw whatever the number of
    axles); ``z_v`` the first draw of a stream of its own, ``SeedSequence(seed, spawn_key=(1,))``, so that the pass's
    part changes no axle's draw (common random numbers)."""
    check_value("seed", seed, low=0, whole=True)
    z_axles = np.random.default_rng(int(seed)).standard_normal(int(n_axles))
    z_pass = float(np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(1,))).standard_normal())
    return z_pass, z_axles


def sensor_factors(vehicle_sd: float, axle_sd: float, seed: int, n_axles: int) -> NDArray[np.float64]:
    """The factors a sensor reads each axle's averaged force with, front first: ``(1 + s_v z_v) (1 + s_a z_i)``.

    Parameters
    ----------
    vehicle_sd, axle_sd
        ``s_v``, the sd of the error common to the pass's axles, and ``s_a``, of each axle's own [-] (fractions).
    seed
        The pass's sensor seed (:func:`sensor_normals`).
    n_axles
        Axles of the group [-].
    """
    s_v, s_a = _fraction("vehicle_sd", vehicle_sd), _fraction("axle_sd", axle_sd)
    z_pass, z_axles = sensor_normals(seed, n_axles)
    return (1.0 + s_v * z_pass) * (1.0 + s_a * z_axles)


# ---- weighing length -----------------------------------------------------------------------------------------------
def _weight(xc: NDArray[np.float64], contact_length: float, sensor_length: float) -> NDArray[np.float64]:
    """The share [-] of a tyre's force on the sensor, its contact patch centred ``xc`` [m] from the sensor's centre,
    over its largest value: the overlap of patch and strip over the shorter of the two, or, if one has no length,
    1 while the patch is over the strip (the limit)."""
    short = min(contact_length, sensor_length)
    if short == 0.0:
        reach = 0.5 * max(contact_length, sensor_length)
        return (np.abs(xc) <= reach * (1.0 + 1e-9)).astype(float)
    lo = np.maximum(xc - 0.5 * contact_length, -0.5 * sensor_length)
    hi = np.minimum(xc + 0.5 * contact_length, 0.5 * sensor_length)
    return np.maximum(hi - lo, 0.0) / short


def sensor_reading(
    t: ArrayLike, force: ArrayLike, t_centre: float, speed: float, sensor_length: float, contact_length: float
) -> float:
    """The force a sensor reads from one tyre's passage [N]: its force averaged over the passage.

    A tyre whose contact patch (length L, uniform pressure) is centred at x_c from the sensor's centre puts the
    share o(x_c) / L of its force on a sensor strip of length S along the road, o the length of patch and strip
    that overlap (a strip of no length: the patch's uniform pressure, 1 / L while the patch is over it). The
    system integrates the sensor's force over time and divides by the integral a constant force would give (the
    usual area method), so the reading is F = int F(t) o(t) dt / int o(t) dt: the mean force over
    the (S + L) / v the patch takes to cross, weighted by a trapezoid (flat over |S - L| / v). With S = L = 0 it is
    the force at ``t_centre``, the point sensor. F(t) is taken linear between the stored samples, so the product
    is quadratic between the merged breakpoints and Simpson's rule on them is exact.

    Parameters
    ----------
    t, force
        Sample times [s] (increasing) and the tyre's force at them [N].
    t_centre
        Time the patch's centre is over the sensor's centre [s].
    speed
        Road speed [m/s], > 0.
    sensor_length
        The sensor's weighing length along the road, S [m], >= 0 (strip ~0.05, bending plate ~0.5).
    contact_length
        The tyre's contact patch length, L [m], >= 0.

    Returns
    -------
    float
        The reading [N]; NaN if the passage is not inside ``t``.
    """
    t = np.asarray(t, dtype=float)
    f = np.asarray(force, dtype=float)
    half = 0.5 * (sensor_length + contact_length) / speed
    if half <= 0.0:
        return float(np.interp(t_centre, t, f))
    if t_centre - half < t[0] or t_centre + half > t[-1]:
        return math.nan
    flat = 0.5 * abs(sensor_length - contact_length) / speed
    # the samples strictly inside the passage, and one more each side: all that interpolation on the passage
    # reads (issue 15: the whole record was scanned and its force column copied for each interpolation)
    lo = int(np.searchsorted(t, t_centre - half, side="right"))
    hi = int(np.searchsorted(t, t_centre + half, side="left"))
    inside = t[lo:hi]
    t, f = t[max(lo - 1, 0) : hi + 1], np.ascontiguousarray(f[max(lo - 1, 0) : hi + 1])
    knots = np.unique(np.concatenate([inside, t_centre + np.array([-half, -flat, flat, half])]))
    return _weighted_mean(t, f, knots, t_centre, speed, sensor_length, contact_length)


def _weighted_mean(
    t: NDArray[np.float64],
    f: NDArray[np.float64],
    knots: NDArray[np.float64],
    t_centre: float,
    speed: float,
    sensor_length: float,
    contact_length: float,
) -> float:
    """int F(t) o(t) dt / int o(t) dt of :func:`sensor_reading` by Simpson's rule between the ``knots`` [s] (exact:
    F linear between the samples ``t``, ``f``, the overlap o linear between the knots)."""
    mid = 0.5 * (knots[:-1] + knots[1:])
    width = np.diff(knots)

    def weighted(tt: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        o = _weight(speed * (tt - t_centre), contact_length, sensor_length)
        return o * np.interp(tt, t, f), o

    # the three point sets at once (element for element the same as one by one)
    m = len(mid)
    fo, oo = weighted(np.concatenate([knots[:-1], mid, knots[1:]]))
    (fa, fm, fb), (oa, om, ob) = (fo[:m], fo[m : 2 * m], fo[2 * m :]), (oo[:m], oo[m : 2 * m], oo[2 * m :])
    numerator = np.sum(width * (fa + 4.0 * fm + fb)) / 6.0
    denominator = np.sum(width * (oa + 4.0 * om + ob)) / 6.0
    return float(numerator / denominator)


# ---- site pavement ------------------------------------------------------------------------------------------------
#: the golden quarter car of the IRI, per unit sprung mass: tyre k1, suspension k2 [1/s^2], damper c [1/s], mass
#: ratio mu [-], at 80 km/h (Sayers et al. 1986)
_GOLDEN_CAR = {"k1": 653.0, "k2": 63.3, "c": 6.0, "mu": 0.15, "speed": 80.0 / 3.6}
#: the IRI's moving-average base length [m]
_IRI_BASE = 0.25


def iri_of_iso8608(gd_n0: float, waviness: float = 2.0, n_min: float = 0.011, n_max: float = 2.83) -> float:
    """IRI [m/km] of a Gaussian road with the ISO 8608 PSD G_d(n) = G_d(n0) (n / n0)^-w, n0 = 0.1 cycle/m.

    The IRI is the mean rectified relative velocity of the golden quarter car at 80 km/h over its speed,
    E|z_s' - z_u'| / v; for a Gaussian profile E|X| = sqrt(2 / pi) sd(X), and the variance is the integral of
    |H(n)|^2 G_d(n) over the band, H the relative velocity's response to the profile (with the IRI's 250 mm moving
    average, sinc(n 0.25)). IRI is proportional to sqrt(G_d(n0)): 0.543 m/km at 1e-6 m^3 for w = 2, so ISO 8608
    class A (G_d(n0) 16e-6 m^3 geometric mean, up to 32e-6) is 2.17 m/km (up to 3.07).

    Parameters
    ----------
    gd_n0
        G_d(n0) [m^3], > 0.
    waviness
        w [-].
    n_min, n_max
        The band of spatial frequencies [cycle/m] (those of :class:`bogie.road.ISO8608Profile`).
    """
    check_value("gd_n0", gd_n0, "m^3", low=0.0, low_open=True)
    car = _GOLDEN_CAR
    n = numerics.geomspace(n_min, n_max, 20_001)
    s = 2j * np.pi * car["speed"] * n
    coupling = car["c"] * s + car["k2"]
    a11, a22 = s**2 + coupling, car["mu"] * s**2 + coupling + car["k1"]
    det = a11 * a22 - coupling**2
    z_sprung, z_unsprung = coupling * car["k1"] / det, a11 * car["k1"] / det
    h = s * (z_sprung - z_unsprung) * numerics.sinc(n * _IRI_BASE)
    gain = h.real**2 + h.imag**2  # |h|^2, not numpy's complex abs (a SIMD loop the CPU picks)
    psd = gd_n0 * numerics.power(n / 0.1, -waviness)
    variance = float(np.trapezoid(gain * psd, n))
    return math.sqrt(2.0 / math.pi) * math.sqrt(variance) / car["speed"] * 1000.0


def gd_n0_for_iri(iri: float, waviness: float = 2.0) -> float:
    """The ISO 8608 G_d(n0) [m^3] of a road whose IRI is ``iri`` [m/km] (inverse of :func:`iri_of_iso8608`)."""
    check_value("iri", iri, "m/km", low=0.0, low_open=True)
    return 1e-6 * (iri / _unit_iri(float(waviness))) ** 2


@functools.lru_cache(maxsize=8)
def _unit_iri(waviness: float) -> float:
    """IRI [m/km] of G_d(n0) = 1e-6 m^3, computed once per waviness: every WIM pass asks for its site's G_d(n0),
    and the quarter car's response over 20 001 frequencies took about a tenth of a pass's time."""
    return iri_of_iso8608(1e-6, waviness)


#: length over which the sampled road's roughness tapers to the site's, outside the site [m]
SITE_BLEND_LENGTH = 5.0


@dataclass(frozen=True)
class SiteRoad:
    """A sampled road with a WIM site's roughness over the site: h(x) = road(x) (1 - (1 - r) b(x)).

    b is 1 from ``before`` ahead of the sensor to ``after`` past it and tapers to 0 over
    :data:`SITE_BLEND_LENGTH` outside (a cosine); r = sqrt(site_gd_n0 / road_gd_n0) scales the road's heights to the
    site's roughness (the ISO 8608 heights scale with sqrt(G_d)), so the site keeps the shape of the road it was built
    on: smoothed (r < 1), or rougher than its road (r > 1, a worn site on a smooth road). Not capped at 1 (issue 43):
    the site's roughness is then the one asked for on every road, as a measured site's is, whatever its road's class.

    Parameters
    ----------
    road
        The sampled road, height [m] of distance [m].
    sensor
        The sensor's position [m].
    before, after
        Site length ahead of and past the sensor [m], >= 0; both 0: no site.
    scale
        r [-], finite and >= 0.
    """

    road: Callable[[ArrayLike], NDArray[np.float64]]
    sensor: float
    before: float
    after: float
    scale: float

    def __post_init__(self) -> None:
        for name in ("before", "after"):
            if not getattr(self, name) >= 0.0:  # inf allowed: a site the whole road long
                raise ValueError(refusal(name, getattr(self, name), "m", low=0.0))
        check_value("scale", self.scale, "-", low=0.0)

    def site_weight(self, x: ArrayLike) -> NDArray[np.float64]:
        """b(x) [-]: 1 on the site, 0 on the sampled road, a cosine taper between."""
        xx = np.asarray(x, dtype=float)
        if self.before == 0.0 and self.after == 0.0:
            return np.zeros_like(xx)
        outside = np.maximum(self.sensor - self.before - xx, xx - self.sensor - self.after)
        ramp = np.clip(1.0 - outside / SITE_BLEND_LENGTH, 0.0, 1.0)
        if ramp.ndim == 0:
            return 0.5 * (1.0 - numerics.cos(np.pi * ramp))
        # 0.5 (1 - cos 0) is exactly 0 and 0.5 (1 - cos pi) exactly 1: the cosine only over the tapers (issue 15),
        # the same weights value for value
        weight = np.zeros_like(ramp)
        weight[ramp >= 1.0] = 1.0
        blend = ~((ramp <= 0.0) | (ramp >= 1.0))
        weight[blend] = 0.5 * (1.0 - numerics.cos(np.pi * ramp[blend]))
        return weight

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        """Road height [m] at distance ``x`` [m]."""
        return self.road(x) * (1.0 - (1.0 - self.scale) * self.site_weight(x))
