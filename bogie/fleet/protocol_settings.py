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
    sensor
        The sensor type (:data:`bogie.road.wim.SENSORS`; ``none``: no error): the sizes of its error's two parts,
        :data:`bogie.road.wim.SENSOR_ERRORS`. A reading is the force averaged over the sensor times
        ``(1 + s_v z_v) (1 + s_a z_i)`` (:func:`bogie.road.wim.sensor_factors`).
    sensor_vehicle_error, sensor_axle_error
        ``s_v``, the sd of the error common to a pass's axles, and ``s_a``, of each axle's own [-] (fractions); None:
        the sensor type's.
    """

    speed: float
    approach_length: float
    dt: float
    site_length_before: float = 0.0
    site_length_after: float = 0.0
    site_iri: float = 1.3
    sensor_length: float = 0.0
    contact_length: float = 0.0
    sensor: str = "none"
    sensor_vehicle_error: float | None = None
    sensor_axle_error: float | None = None

    def __post_init__(self) -> None:
        for name, unit in (("speed", "m/s"), ("approach_length", "m"), ("dt", "s")):
            _positive(self, name, unit)
        for name in ("site_length_before", "site_length_after", "sensor_length", "contact_length"):
            _positive(self, name, "m", "or 0", zero=True)
        _positive(self, "site_iri", "m/km")
        if self.sensor not in wim.SENSORS:
            raise ValueError(f"sensor = {self.sensor!r}: must be one of {', '.join(wim.SENSORS)}")
        for name in ("sensor_vehicle_error", "sensor_axle_error"):
            value = getattr(self, name)
            number = not isinstance(value, bool) and isinstance(value, (int, float))
            if value is not None and not (number and 0.0 <= value < 0.5):
                raise ValueError(f"{name} = {value!r}: must be None or a number in [0, 0.5) [-] (0.02 is 2 %)")

    @property
    def vehicle_error_sd(self) -> float:
        """``s_v``: the sd of the sensor's error common to a pass's axles [-] (given, or the sensor type's)."""
        given = self.sensor_vehicle_error
        return wim.SENSOR_ERRORS[self.sensor][0] if given is None else float(given)

    @property
    def axle_error_sd(self) -> float:
        """``s_a``: the sd of each axle reading's own error [-] (given, or the sensor type's)."""
        given = self.sensor_axle_error
        return wim.SENSOR_ERRORS[self.sensor][1] if given is None else float(given)

    @property
    def error_free(self) -> bool:
        """Whether the sensor reads without error (both parts 0)."""
        return self.vehicle_error_sd == 0.0 and self.axle_error_sd == 0.0
