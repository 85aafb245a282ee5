"""Road inputs: vertical road profiles as functions of distance, and the height under each axle over time.

A profile is a frozen dataclass whose ``__call__(x)`` maps road distance ``x`` [m] (array-like, any shape) to road
height [m] (an ndarray of the same shape), vectorised. The vehicle travels in the direction of increasing road
distance; :func:`axle_heights` delays each trailing axle by its spacing behind the front axle (the wheel-path
delay). Formulas, chosen lengths and the verification of the ISO 8608 generator are in ``docs/road.md``.

A subpackage: the road is its own physics beside the bogie models. :mod:`.profiles` (``Flat``, ``RampedStep``,
``Sinusoid``, :func:`axle_heights`), :mod:`.iso8608` (``ISO8608Profile``, the road classes), :mod:`.measured`
(``MeasuredProfile``) and :mod:`.wim` (the weigh-in-motion site's pavement and sensor, ``docs/wim-site.md``).
"""

from bogie.road.iso8608 import ISO8608_CLASSES, ISO8608_N0, ISO8608Profile
from bogie.road.measured import MeasuredProfile
from bogie.road.profiles import Flat, RampedStep, Sinusoid, axle_heights

__all__ = [
    "ISO8608_CLASSES", "ISO8608_N0", "Flat", "ISO8608Profile", "MeasuredProfile", "RampedStep", "Sinusoid",
    "axle_heights",
]  # fmt: skip
