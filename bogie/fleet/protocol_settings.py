"""The settings of the two weighing protocols: a static weighbridge and a weigh-in-motion pass (:mod:`.protocols`).

Plain values, checked when made (a setting out of its range raises ``ValueError`` naming it, its value and unit); a
module of their own so that what only reads settings (params.yaml's loader, the sample stage) does not import the
simulation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from bogie.road import wim
from bogie.road.wim import axle_error_sd

__all__ = ["StaticProtocol", "WimProtocol"]


def _positive(spec: Any, name: str, unit: str, alternative: str = "", zero: bool = False) -> None:
    """Refuse a setting of ``spec`` that is not a finite number > 0 (>= 0 if ``zero``), naming it and its unit."""
    value = getattr(spec, name)
    number = not isinstance(value, bool) and isinstance(value, (int, float))
    if not (number and math.isfinite(value) and (value >= 0.0 if zero else value > 0.0)):
        allowed = "a finite number >= 0" if zero else "a finite number > 0"
        extra = f" ({alternative})" if alternative and not zero else ""
        raise ValueError(f"{type(spec).__name__}.{name} = {value!r}: must be {allowed}{extra} [{unit}]")


@dataclass(frozen=True)
class StaticProtocol:
    """Static weighbridge: load [s], crawl over an approach [m] at walking pace [m/s], settle [s]; time step [s].

    ``step_tolerance`` [m]: the local error allowed per adaptive step on the approach (the load ramp and the settle
    take a share of it, :func:`static_phases`); None: fixed steps of ``dt``, which is also the first adaptive step.
    """

    load_time: float
    approach_length: float
    crawl_speed: float
    settle_time: float
    dt: float
    step_tolerance: float | None = None

    def __post_init__(self) -> None:
        for name, unit in (("load_time", "s"), ("approach_length", "m"), ("crawl_speed", "m/s"),
                           ("settle_time", "s"), ("dt", "s")):  # fmt: skip
            _positive(self, name, unit)
        if self.step_tolerance is not None:
            _positive(self, "step_tolerance", "m", "or None for fixed steps of dt")


@dataclass(frozen=True)
class WimProtocol:
    """Weigh-in-motion pass: road speed [m/s] over an approach [m]; time step [s]; the site and the sensor.

    Attributes
    ----------
    site_length_before, site_length_after
        Length of the smooth WIM site ahead of and past the sensor [m] (both 0: the sensor lies in the sampled road).
    site_iri
        International Roughness Index of the site's pavement [m/km] (the IRI's own unit, ASTM E1926; not SI m/m).
    sensor_length
        The sensor's weighing length along the road [m] (0: a point sensor).
    contact_length
        The tyres' contact patch length [m].
    accuracy_class
        COST 323 accuracy class of the sensor's axle readings (``none``: no error),
        :data:`bogie.road.wim.ACCURACY_CLASSES`.
    confidence_level
        Confidence level at which the class's tolerance holds [-].
    """

    speed: float
    approach_length: float
    dt: float
    site_length_before: float = 0.0
    site_length_after: float = 0.0
    site_iri: float = 1.3
    sensor_length: float = 0.0
    contact_length: float = 0.0
    accuracy_class: str = "none"
    confidence_level: float = 0.95

    def __post_init__(self) -> None:
        for name, unit in (("speed", "m/s"), ("approach_length", "m"), ("dt", "s")):
            _positive(self, name, unit)
        for name in ("site_length_before", "site_length_after", "sensor_length", "contact_length"):
            _positive(self, name, "m", "or 0", zero=True)
        _positive(self, "site_iri", "m/km")
        if self.accuracy_class not in wim.ACCURACY_CLASSES:
            raise ValueError(
                f"accuracy_class = {self.accuracy_class!r}: must be one of {', '.join(wim.ACCURACY_CLASSES)} (COST 323)"
            )
        level = self.confidence_level
        if isinstance(level, bool) or not isinstance(level, (int, float)) or not 0.0 < level < 1.0:
            raise ValueError(f"confidence_level = {level!r}: must lie in (0, 1) [-]")

    @property
    def axle_error_sd(self) -> float:
        """Relative standard deviation of one axle reading's error [-] (:func:`bogie.road.wim.axle_error_sd`)."""
        return axle_error_sd(self.accuracy_class, self.confidence_level)
