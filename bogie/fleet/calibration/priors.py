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

from bogie.fleet.constants import CALIBRATION_QUANTITIES

__all__ = ["KINDS", "SITE_BIAS_SD_PCT", "Prior", "default_priors", "log_prior"]

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
            "normal", 0.0, 0.6,
            "an assumption: no survey of fifth-wheel mismatch found (searched); a trade table (not a standard) gives "
            "tractors' fifth-wheel heights spanning about 150 mm by trailer type (1143-1346 mm), so a trailer behind "
            "another tractor is up to about +-150 mm out over an assumed kingpin-to-bogie length near 8 m: up to "
            "about 1.1 degree either way; a normal of sd 0.6 degree puts 93 % within that, centred on level (no "
            "direction preferred); the reference studied 0-2 degree",
        ),
        "chassis_tilt_sd_deg": Prior(
            "normal", 0.0, 0.6,
            "the same argument for the spread across a fleet: a half-normal of scale 0.6 degree (truncated at the "
            "fit's lower bound)",
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
