"""The constants of a fleet study that several parts share: the axle groups, the suspensions, the protocols."""

from __future__ import annotations

from bogie.group_names import GROUP_AXLES  # the axles of each group the fleet is made of, defined there
from bogie.params import TARE_FRACTION
from bogie.weighings.stats import PAIR_TOLERANCE, SHARE_TOLERANCE

__all__ = [
    "AT_BOUND", "CALIBRATION_QUANTITIES", "GROUP_AXLES", "MAX_AXLES", "MAX_PHASE_STEPS", "PAIR_TOLERANCE", "PILED",
    "PROTOCOLS", "READ_TIME", "ROUTE_MARGIN", "SHARE_TOLERANCE", "SITE_IRI_RANGE", "SURVEY_PROTOCOLS", "SUSPENSIONS",
    "TARE_FRACTION",
    "TILTED_QUANTITIES", "WIM_QUANTITIES", "n_axles",
]  # fmt: skip


#: the suspensions of a group: steel leaf springs linked by equalisers (bogie.params.Bogie), or air springs with
#: connected bags (bogie.air.AirBogie)
SUSPENSIONS: tuple[str, ...] = ("steel", "air")

#: most axles in a group: the runs have columns axle_load_1..MAX_AXLES [-]
MAX_AXLES: int = max(GROUP_AXLES.values())

#: the weighbridge reads the mean over this last part of the settling time [s]
READ_TIME: float = 0.5
#: most time steps of one phase of a weighing (load ramp, crawl, settle, WIM pass): a phase's histories take about
#: 250 bytes a step, so this keeps one run of one worker near 250 MB [-]
MAX_PHASE_STEPS: int = 1_000_000
#: what a route adds to its approach length: the lead before the road, the group's own length (at most 3 m for the
#: presets) and the run-out past the sensor or onto the weighbridge [m]
ROUTE_MARGIN: float = 4.0

#: the weighing protocols: static weighbridge, weigh-in-motion pass
PROTOCOLS: tuple[str, ...] = ("static", "wim")
#: the kinds of observed survey, each with the protocol whose readings it is held against: a WIM file's records are
#: WIM readings, a weighbridge file's are static ones
SURVEY_PROTOCOLS: dict[str, str] = {"wim": "wim", "weighbridge": "static"}

#: the fleet quantities a calibration can fit (:mod:`bogie.fleet.calibration`, ``docs/calibration.md``), each
#: with its physical range and unit
CALIBRATION_QUANTITIES: dict[str, tuple[float, float, str]] = {
    "chassis_tilt_mean_deg": (-5.0, 5.0, "degree"),  # centre (parent mean) of distributions.chassis_tilt_deg
    "chassis_tilt_sd_deg": (0.01, 5.0, "degree"),  # its spread (parent sd)
    "air_share": (0.0, 1.0, "-"),  # fraction of air-sprung groups, every axle group alike
    "site_iri_m_km": (0.3, 10.0, "m/km"),  # the WIM site's roughness
    "sensor_error_pct": (0.0, 30.0, "%"),  # sd of the WIM sensor's own error on each axle reading (s_a; the part
    # common to a pass's axles cancels in the load shares and is not fitted)
    # the mean of distributions.contact_roll_radius_mm, moved by an exponential tilt (bogie.fleet.sampling.tilted); the
    # range is the Bogie field's (bogie.ranges), a fit's must lie strictly within the fleet distribution's support
    "contact_roll_radius_mean_mm": (0.0, 500.0, "mm"),
    # the geometric mean of distributions.bush_stiffness (log-uniform), moved the same way
    "bush_stiffness_geomean": (1e-3, 1e7, "N m/rad"),
    # the WIM site's calibration bias: every reading times 1 + b / 100 (bogie.fleet.calibration.site)
    "site_bias_pct": (-30.0, 30.0, "%"),
}
#: the fitted quantities that move a fleet distribution of an inhibitor (bogie.fleet.sampling.tilted): the sample column
#: each moves, and the factor from its SI unit to the unit of the fitted mean
TILTED_QUANTITIES: dict[str, tuple[str, float]] = {
    "contact_roll_radius_mean_mm": ("contact_roll_radius", 1000.0),
    "bush_stiffness_geomean": ("bush_stiffness", 1.0),
}
#: a fitted value within this fraction of its bounds' width from a bound is "at the bound" [-]; a convention (no
#: source): 2 % of [0.1, 1.5] degree is 0.028 degree, below the tilt table's resolution
AT_BOUND = 0.02
#: the share of bootstrap refits or posterior draws at one bound from which they are "piled against" it [-]; a
#: convention
PILED = 0.25
#: the roughness a WIM site may have [m/km]: 0.3, a very smooth new pavement, to 10, a poor paved road (the IRI scale
#: of Sayers et al. 1986, World Bank TP 46: 6-10 m/km a damaged paved road; ISO 8608 class D and rougher); COST 323's
#: site classes end at 4 m/km, so no WIM site is rougher than 10
SITE_IRI_RANGE: tuple[float, float] = CALIBRATION_QUANTITIES["site_iri_m_km"][:2]
#: the quantities that belong to the WIM protocol
WIM_QUANTITIES: tuple[str, ...] = ("site_iri_m_km", "sensor_error_pct", "site_bias_pct")

# PAIR_TOLERANCE (VSB 11: no axle more than 5 % from any other) and SHARE_TOLERANCE (no axle more than 10 % over its
# equal share) are the survey statistics' (bogie.weighings.stats): one home for simulated and observed groups


def n_axles(group: str) -> int:
    """The number of axles of axle group ``group`` (``tandem`` or ``triaxle``)."""
    try:
        return GROUP_AXLES[group]
    except KeyError:
        raise ValueError(f"axle group {group!r} unknown; allowed: {', '.join(GROUP_AXLES)}") from None
