"""The constants of a fleet study that several parts share: the axle groups, the suspensions, the protocols."""

from __future__ import annotations

from bogie.params import TARE_FRACTION
from bogie.weighings.stats import PAIR_TOLERANCE, SHARE_TOLERANCE

__all__ = [
    "GROUP_AXLES", "MAX_AXLES", "MAX_PHASE_STEPS", "PAIR_TOLERANCE", "PROTOCOLS", "READ_TIME", "ROUTE_MARGIN",
    "SHARE_TOLERANCE", "SUSPENSIONS", "TARE_FRACTION", "n_axles",
]  # fmt: skip

#: axles in each axle group the fleet is made of [-]
GROUP_AXLES: dict[str, int] = {"tandem": 2, "triaxle": 3}

#: the suspensions of a group: steel leaf springs linked by equalisers (bogie.params.Bogie), or air springs with
#: connected bags (bogie.air.AirBogie)
SUSPENSIONS: tuple[str, ...] = ("steel", "air")

#: most axles in a group: the runs have columns axle_load_0..MAX_AXLES-1 [-]
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

# PAIR_TOLERANCE (VSB 11: no axle more than 5 % from any other) and SHARE_TOLERANCE (no axle more than 10 % over its
# equal share) are the survey statistics' (bogie.weighings.stats): one home for simulated and observed groups


def n_axles(group: str) -> int:
    """The number of axles of axle group ``group`` (``tandem`` or ``triaxle``)."""
    try:
        return GROUP_AXLES[group]
    except KeyError:
        raise ValueError(f"axle group {group!r} unknown; allowed: {', '.join(GROUP_AXLES)}") from None
