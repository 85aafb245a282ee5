"""The settings of the two weighing protocols: a static weighbridge and a weigh-in-motion pass (:mod:`.protocols`).

Plain values, checked when made (a setting out of its range raises ``ValueError`` naming it, its value and unit); a
module of their own so that what only reads settings (params.yaml's loader, the sample stage) does not import the
simulation.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from bogie.road import wim
from bogie.settings import check_settings, setting

__all__ = ["StaticProtocol", "WimProtocol"]


def _positive(unit: str, doc: str, default: Any = dataclasses.MISSING, zero: bool = False) -> Any:
    """A setting that is a finite number > 0 (>= 0 if ``zero``) in ``unit``."""
    return setting(default, unit=unit, doc=doc, low=0.0, low_open=not zero)


@dataclass(frozen=True)
class StaticProtocol:
    """Static weighbridge: load, crawl over an approach at walking pace, settle; the time step."""

    load_time: float = _positive("s", "Time the payload takes to come on, the bogie at rest.")
    approach_length: float = _positive("m", "Length of the approach the bogie crawls over onto the weighbridge.")
    crawl_speed: float = _positive("m/s", "Speed of the crawl, walking pace.")
    settle_time: float = _positive("s", "Time the bogie settles at rest on the weighbridge before it is read.")
    dt: float = _positive("s", "Time step (and the first adaptive step).")
    step_tolerance: float | None = _positive(
        "m", "Local error allowed per adaptive step on the approach (the load ramp and the settle take a share of it, "
        ":func:`static_phases`); None: fixed steps of ``dt``.", None,
    )  # fmt: skip

    def __post_init__(self) -> None:
        check_settings(self, ValueError, "StaticProtocol.")


@dataclass(frozen=True)
class WimProtocol:
    """Weigh-in-motion pass: the road speed over an approach, the time step; the site and the sensor.

    ``sensor`` is the sensor type (:data:`bogie.road.wim.SENSORS`; ``none``: no error), which gives the sizes of its
    error's two parts (:data:`bogie.road.wim.SENSOR_ERRORS`) unless they are set. A reading is the force averaged
    over the sensor times ``(1 + s_v z_v) (1 + s_a z_i)`` (:func:`bogie.road.wim.sensor_factors`).
    """

    speed: float = _positive("m/s", "Road speed over the approach and the site.")
    approach_length: float = _positive("m", "Length of the sampled road before the site.")
    dt: float = _positive("s", "Time step.")
    site_length_before: float = _positive(
        "m", "Length of the smooth WIM site ahead of the sensor (this and the length after both 0: the sensor lies "
        "in the sampled road).", 0.0, zero=True,
    )  # fmt: skip
    site_length_after: float = _positive("m", "Length of the smooth WIM site past the sensor.", 0.0, zero=True)
    site_iri: float = _positive(
        "m/km", "International Roughness Index of the site's pavement (the IRI's own unit, ASTM E1926; not SI m/m).",
        1.3,
    )  # fmt: skip
    sensor_length: float = _positive("m", "The sensor's weighing length along the road (0: a point sensor).", 0.0,
                                     zero=True)  # fmt: skip
    contact_length: float = _positive("m", "The tyres' contact patch length.", 0.0, zero=True)
    sensor: str = setting(
        "none", unit="-", choices=tuple(wim.SENSORS),
        doc="The sensor type; the sizes of its error's two parts are bogie.road.wim.SENSOR_ERRORS (docs/wim-site.md).",
    )  # fmt: skip
    sensor_vehicle_error: float | None = setting(
        None, unit="-", low=0.0, high=0.5, high_open=True,
        doc="``s_v``, the sd of the sensor's error common to a pass's axles (a fraction: 0.02 is 2 %); None: the "
        "sensor type's.",
    )  # fmt: skip
    sensor_axle_error: float | None = setting(
        None, unit="-", low=0.0, high=0.5, high_open=True,
        doc="``s_a``, the sd of each axle reading's own sensor error (a fraction); None: the sensor type's.",
    )  # fmt: skip

    def __post_init__(self) -> None:
        check_settings(self, ValueError, "WimProtocol.")

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
