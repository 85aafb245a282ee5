"""The priors of the calibration's fittable quantities, each with its source (``docs/calibration.md``, issue 30 Must 2).

A prior is what is known of a quantity before the survey: a range or a distribution, and where it comes from. Where
no source gives more than a range, the prior is flat over it and says so. The calibration's posterior
(:mod:`bogie.fleet.calibration.posterior`) is the prior times the survey's synthetic likelihood, within the fit's
bounds (the prior truncated to them). Never tune a prior to a survey (issue 30, "Not allowed").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bogie.fleet.constants import CALIBRATION_QUANTITIES

__all__ = [
    "KINGPIN_TO_BOGIE_M",
    "KINDS",
    "SITE_BIAS_SD_PCT",
    "TILT_MIX",
    "TILT_PRIOR_SD_DEG",
    "Prior",
    "default_priors",
    "log_prior",
    "tilt_mixture",
]

#: the kinds of prior, and their two parameters ``a``, ``b``
KINDS: dict[str, str] = {
    "uniform": "low, high",
    "loguniform": "low, high (> 0)",
    "normal": "mean, sd (> 0)",
    "lognormal": "median (> 0), sigma of ln x (> 0)",
}


@dataclass(frozen=True)
class Prior:
    """A prior density (unnormalised) and its source: ``kind`` of :data:`KINDS` with parameters ``a`` and ``b`` in
    the unit of the quantity's name."""

    kind: str
    a: float
    b: float
    source: str

    def __post_init__(self) -> None:
        ok = self.kind in KINDS and all(isinstance(v, (int, float)) and math.isfinite(v) for v in (self.a, self.b))
        if ok and self.kind in ("uniform", "loguniform"):
            ok = self.a < self.b and (self.kind == "uniform" or self.a > 0.0)
        elif ok:
            ok = self.b > 0.0 and (self.kind == "normal" or self.a > 0.0)
        if not ok:
            raise ValueError(f"prior {self.kind!r} ({self.a!r}, {self.b!r}): must be one of {KINDS}")

    def log_density(self, x: float) -> float:
        """ln of the density at ``x`` up to a constant; -inf outside the support."""
        if self.kind == "uniform":
            return 0.0 if self.a <= x <= self.b else -math.inf
        if self.kind == "loguniform":
            return -math.log(x) if self.a <= x <= self.b else -math.inf
        if self.kind == "normal":
            return -0.5 * ((x - self.a) / self.b) ** 2
        if x <= 0.0:
            return -math.inf
        return -math.log(x) - 0.5 * (math.log(x / self.a) / self.b) ** 2

    def describe(self) -> str:
        """One line: the kind, its parameters and the source."""
        names = KINDS[self.kind].replace(" (> 0)", "").split(", ")
        return f"{self.kind}({names[0]} {self.a:g}, {names[1]} {self.b:g}): {self.source}"


#: kingpin to the centre of a 13.6 m semi-trailer's tri-axle bogie [m]: "the centre axle situated at around 8.1
#: metres from the kingpin" (Transport Engineer, "Long is beautiful"); 97/27/EC's turning rule caps it near 8.135 m
#: for a 2.55 m-wide trailer (Don-Bur, "Trailer turning circle requirements")
KINGPIN_TO_BOGIE_M = 8.1
#: the pairings of tractor and trailer, each with its assumed share of a fleet [-] and the range of its kingpin height
#: off the trailer's design height, dh [mm], read as uniform (docs/calibration.md, "The chassis tilt"). Heights: UK
#: fifth wheels 1,250 mm (Don-Bur, Commercial Motor 26 Apr 2017), trailers built for 1,150 mm (Krone Profi-liner), a
#: make at 1,285 mm rising to 1,335 mm with its lift axle up (transport.law.blog, 13 May 2024), low-deck tractors
#: 910-990 mm (eurotransport.de; Commercial Motor 13 Feb 1992), bought 100-150 a year in the UK, "a niche" (Transport
#: Engineer 2021), mega trailers 10-15 % of Krone's curtainsiders (eurotransport.de 2022). The shares are
#: ASSUMPTIONS (no survey of pairings found); the ranges follow from the heights
TILT_MIX: dict[str, tuple[float, float, float]] = {
    "matched": (0.90, -85.0, 85.0),  # 1,250 against 1,335 mm either way; the UK/continental gap (1,250/1,150) 100 mm
    "standard trailer, low-deck tractor": (0.07, -340.0, -160.0),  # 910-990 mm under a 1,150-1,250 mm trailer
    "mega trailer, standard tractor": (0.03, 200.0, 300.0),  # a low trailer on a 1,250 mm fifth wheel (UK only)
}


def tilt_mixture(
    mix: Mapping[str, tuple[float, float, float]] = TILT_MIX, length_m: float = KINGPIN_TO_BOGIE_M
) -> tuple[float, float]:
    """The mean and sd [degree] of the chassis tilt ``atan(dh / length_m)`` over the pairings ``mix`` (share, dh
    range [mm] read as uniform), nose up positive; small angles (``dh / length_m`` below 0.05: an error under 0.1 %)."""
    per_mm = math.degrees(1e-3 / length_m)
    mean = sum(w * (lo + hi) / 2.0 for w, lo, hi in mix.values()) * per_mm
    square = sum(w * ((lo + hi) ** 2 / 4.0 + (hi - lo) ** 2 / 12.0) for w, lo, hi in mix.values()) * per_mm**2
    return mean, math.sqrt(square - mean**2)


#: sd of the chassis tilt priors, the fleet's tilt mean's normal and its spread's half-normal [degree]; the source in
#: :func:`default_priors`, the derivation in docs/calibration.md ("The chassis tilt"); params.yaml's default fleet
#: (distributions.chassis_tilt_deg) is truncnormal(0, this, -2, 2): the priors' centre (issue 43 Must 7). The sd of
#: :func:`tilt_mixture` to 0.05 degree (tests/test_fleet_calibration.py holds it); the matched pairings alone: 0.35
TILT_PRIOR_SD_DEG = 0.65

#: sd of a WIM site's calibration bias, the prior of ``site_bias_pct`` [%]: its source in :func:`default_priors`
SITE_BIAS_SD_PCT = 4.0

#: the priors of the inhibitor distributions' fitted means: flat (in the quantity or its log) over the support of the
#: fleet's distribution, the kind and the source
_INHIBITOR_MEANS: dict[str, tuple[str, str]] = {
    "contact_roll_radius_mean_mm": (
        "uniform",
        "no source measures the contact-roll radius on a fleet (issue 30: why it is fitted): flat over the support "
        "of the fleet's distribution (distributions.contact_roll_radius_mm)",
    ),
    "bush_stiffness_geomean": (
        "loguniform",
        "no source measures the bush stiffness on a fleet (the reference's one bush, q = 4.3): flat in its log over "
        "the support of the fleet's log-uniform distribution (distributions.bush_stiffness)",
    ),
}


def default_priors(
    base: Mapping[str, float], supports: Mapping[str, tuple[float, float]] | None = None
) -> dict[str, Prior]:
    """The documented prior of every quantity of :data:`~bogie.fleet.constants.CALIBRATION_QUANTITIES`, given the
    fleet's values ``base`` (:func:`bogie.fleet.calibration.problem.base_values`: the sensor type's error) and, per
    moved inhibitor quantity, the ``supports`` of the fleet's distribution
    (:meth:`bogie.fleet.sampling.tilted.Tilted.mean_range`,
    in the quantity's unit): its mean's prior is flat over it (None or absent: no prior for it)."""
    priors = {
        "chassis_tilt_mean_deg": Prior(
            "normal", 0.0, TILT_PRIOR_SD_DEG,
            "an assumption built on sourced geometry (docs/calibration.md, 'The chassis tilt'): no survey of "
            "trailer pitch found (searched); a tilt is atan(dh / 8.1 m), dh the kingpin's height off the trailer's "
            "design height, 8.1 m the kingpin-to-bogie distance of a 13.6 m semi-trailer (Transport Engineer; "
            "97/27/EC's 8,135 mm limit, Don-Bur); UK tractors at 1,250 mm (Don-Bur 2017), trailers built for 1,150 "
            "mm (Krone), one make 1,285-1,335 mm (2024): a fleet's pairing can sit about 100 mm (0.7 degree) off "
            "either way; sd that of the fleet's tilts (tilt_mixture), centred on level (no direction sourced)",
        ),
        "chassis_tilt_sd_deg": Prior(
            "normal", 0.0, TILT_PRIOR_SD_DEG,
            "the same argument for the spread across a fleet: matched pairs within about +-85 mm (+-0.6 degree), a "
            "standard trailer behind a low-deck tractor (910-990 mm) -160 to -340 mm (-1.1 to -2.4 degree); an "
            "assumed mix of 90 % matched, 7 % low-deck, 3 % mega trailers has sd 0.6 degree; a half-normal of that "
            "scale (truncated at the fit's lower bound)",
        ),
        "air_share": Prior("uniform", 0.0, 1.0, "no source for the surveyed fleet's share of air-sprung groups: flat"),
        "site_iri_m_km": Prior(
            "uniform", 0.0, 4.0,
            "COST 323's site classes I-III end at an IRI of 4.0 m/km (docs/wim-site.md): a WIM site in service lies "
            "within them; flat, take a site's roughness from its site record when known",
        ),  # fmt: skip
        "sensor_error_pct": Prior(
            "lognormal", _finite_or(base.get("sensor_error_pct"), 2.0), math.log(2.0),
            "centred on the sensor type's own error s_a (bogie.road.wim.SENSOR_ERRORS, itself an assumption within "
            "Cebon and Winkler 1991's < 4 % RMS for strip sensors), a factor of two either way at one sd (an "
            "assumption: no source sizes that uncertainty)",
        ),  # fmt: skip
        "site_bias_pct": Prior(
            "normal", 0.0, SITE_BIAS_SD_PCT,
            "Rys 2019 (Sensors 19:3272, section 4.2): the mean steering-axle loads of 77 WIM stations range from 50 to "
            "61 kN, 'which implies that systematic error does occur'; a range of 11 kN over 77 normal draws (about "
            "4.8 sd) is an sd of 2.3 kN, 4.1 % of the 55.5 kN midpoint: an upper estimate of the bias's sd (the "
            "stations' real steering loads differ too); ASTM E1318's 10 % gross-weight tolerance at 95 % read as a "
            "bound on bias alone gives 5.1 %. Centred on none (a site calibrated as it should be); take a site's own "
            "calibration record when known",
        ),  # fmt: skip
    }  # fmt: skip
    for quantity, (kind, source) in _INHIBITOR_MEANS.items():
        if quantity in (supports or {}):
            priors[quantity] = Prior(kind, *supports[quantity], source)
    unknown = set(priors) - set(CALIBRATION_QUANTITIES)
    assert not unknown, unknown
    return priors


def _finite_or(value: float | None, default: float) -> float:
    return float(value) if value is not None and math.isfinite(value) and value > 0.0 else default


def log_prior(priors: Mapping[str, Prior], values: Mapping[str, float]) -> float:
    """The sum of the priors' log densities at ``values`` (a quantity without a prior: flat)."""
    return float(sum(priors[q].log_density(v) for q, v in values.items() if q in priors))


#: draws from a normal or log-normal prior before giving up on bounds that hold almost none of its mass [-]: a
#: convention (bounds holding 1 % of the prior's mass fail once in 2e4 draws)
DRAW_TRIES = 1000


def _draw_one(prior: Prior | None, low: float, high: float, rng: np.random.Generator) -> float:
    if prior is not None and prior.kind in ("uniform", "loguniform"):
        low, high = max(low, prior.a), min(high, prior.b)
    if low > high:
        return math.nan
    if prior is None or prior.kind == "uniform":
        return low + (high - low) * float(rng.random())
    if prior.kind == "loguniform":
        return math.exp(math.log(low) + (math.log(high) - math.log(low)) * float(rng.random()))
    for _ in range(DRAW_TRIES):
        e = float(rng.standard_normal())
        x = prior.a + prior.b * e if prior.kind == "normal" else prior.a * math.exp(prior.b * e)
        if low <= x <= high:
            return x
    return math.nan


def prior_draws(
    priors: Mapping[str, Prior], names: tuple[str, ...] | list[str], bounds: list[tuple[float, float]], n: int,
    rng: np.random.Generator,
) -> np.ndarray:  # fmt: skip
    """``n`` points drawn from the priors of ``names`` truncated to their ``bounds`` (rows: points; a quantity without
    a prior: uniform within its bounds), each quantity drawn on its own (the priors are independent: a product,
    :func:`log_prior`), point by point from ``rng``. A quantity whose bounds hold none (or almost none) of its prior's
    mass is an error naming it."""
    out = np.empty((n, len(names)))
    for k in range(n):
        for i, (name, (low, high)) in enumerate(zip(names, bounds)):
            out[k, i] = _draw_one(priors.get(name), float(low), float(high), rng)
            if math.isnan(out[k, i]):
                p = priors[name]
                raise ValueError(
                    f"{name}: its bounds [{low:g}, {high:g}] hold none of its prior {p.kind}({p.a:g}, {p.b:g}) "
                    f"within {DRAW_TRIES} draws"
                )
    return out
