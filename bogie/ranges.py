"""The allowed range and unit of every field of a :class:`bogie.params.Bogie`, and the checks that enforce them.

The one table of ranges (:data:`SCALAR_RANGES`, :data:`AXLE_RANGES`, :data:`EQUALISER_RANGES` of
:class:`FieldRange`) that the steel bogie validates against, that the pipeline's configuration reads its ranges from
and whose checks (:func:`check_scalar`, :func:`check_vector`) the air-sprung bogie shares: each raises
``ValueError`` naming the field, its value, the allowed range and the unit. :mod:`bogie.params` re-exports the
table, so ``from bogie.params import SCALAR_RANGES`` keeps working.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from bogie.settings import _show, check_value


class FieldRange(NamedTuple):
    """The allowed range of a :class:`bogie.params.Bogie` field: ``low < x <= high`` (``low <= x`` if low_inclusive).

    Attributes
    ----------
    low, high
        Limits of the range [unit].
    unit
        SI unit of the field (``-`` for a dimensionless one).
    low_inclusive
        Whether ``low`` itself is allowed; ``high`` always is.
    """

    low: float
    high: float
    unit: str
    low_inclusive: bool

    def contains(self, value: float) -> bool:
        """Whether ``value`` [unit] lies in the range (NaN never does)."""
        return (value >= self.low if self.low_inclusive else value > self.low) and value <= self.high


#: allowed range and unit of every scalar field, by field name
SCALAR_RANGES: dict[str, FieldRange] = {
    "road_spring_stiffness": FieldRange(0.0, 1e9, "N/m", False),
    "tyre_stiffness": FieldRange(0.0, 1e10, "N/m", False),
    "tyre_damping": FieldRange(0.0, 1e7, "N s/m", True),
    "tyre_radius": FieldRange(0.05, 2.0, "m", True),
    "axle_mass": FieldRange(0.0, 5000.0, "kg", True),
    "equaliser_inertia": FieldRange(0.0, 100.0, "kg m^2", True),
    "payload_mass": FieldRange(0.0, 1e6, "kg", False),
    "payload_cg_x": FieldRange(0.0, 50.0, "m", False),
    "chassis_pitch_inertia": FieldRange(0.0, 1e9, "kg m^2", False),
    "pad_drop": FieldRange(0.0, 3.0, "m", True),
    "equaliser_front_tip_drop": FieldRange(-0.5, 0.5, "m", True),
    "equaliser_rear_tip_drop": FieldRange(-0.5, 0.5, "m", True),
    "spring_length_rate": FieldRange(0.0, 2.0, "m/m", True),
    "spring_end_slope_rate": FieldRange(-20.0, 20.0, "rad/m", True),
    "contact_tangential_stiffness": FieldRange(0.0, 1e10, "N/m", False),
    "chassis_tilt": FieldRange(-math.radians(10.0), math.radians(10.0), "rad", True),
    "bush_stiffness": FieldRange(0.0, 1e7, "N m/rad", True),
    "bush_damping": FieldRange(0.0, 1e6, "N m s/rad", True),
    "contact_roll_radius": FieldRange(0.0, 0.5, "m", True),
    "friction_coefficient": FieldRange(0.0, 1.5, "-", True),
    "radius_rod_drop": FieldRange(-0.5, 0.5, "m", True),
    "equaliser_stop": FieldRange(0.0, math.pi, "rad", False),
    "equaliser_stop_stiffness": FieldRange(0.0, 1e9, "N m/rad", True),
    "spring_friction_band": FieldRange(0.0, 2e4, "N", True),
    "spring_friction_decay": FieldRange(1e-4, 0.05, "m", True),
}

#: allowed range and unit of each value of the per-axle fields (one value per axle), by field name
AXLE_RANGES: dict[str, FieldRange] = {
    "axle_x": FieldRange(0.0, 50.0, "m", False),
    "spring_front_half_length": FieldRange(0.05, 2.0, "m", True),
    "spring_rear_half_length": FieldRange(0.05, 2.0, "m", True),
    "tyre_wear": FieldRange(0.0, 0.05, "m", True),
    "radius_rod_length": FieldRange(0.2, 3.0, "m", True),
}
#: allowed range and unit of each value of the per-equaliser fields (one value per equaliser), by field name
EQUALISER_RANGES: dict[str, FieldRange] = {
    "equaliser_front_arm": FieldRange(0.01, 1.0, "m", True),
    "equaliser_rear_arm": FieldRange(0.01, 1.0, "m", True),
}


def check_scalar(name: str, value: Any, low: float, high: float, unit: str, low_inclusive: bool) -> float:
    """``value`` as a float if it is a real number (not a bool or a text) in ``low < value <= high`` (``low <=`` if
    ``low_inclusive``), finite; else :func:`bogie.settings.check_value`'s ValueError naming ``name``, the value, the
    allowed range and ``unit``."""
    if type(value) is float:
        # the usual case, a float in range, returned as it is without the one check's general path (a bogie is
        # validated once per weighing and its ~40 scalars took a fifth of the Python around the kernel)
        if math.isfinite(value) and (value >= low if low_inclusive else value > low) and value <= high:
            return value
    # anything else: a real number, Python's or numpy's (a 0-d array too), as a float; not a bool (True is not 1 N
    # m/rad) nor a numeric text
    return check_value(name, value, unit, low=low, high=high, low_open=not low_inclusive)


def check_positive(name: str, value: Any, unit: str, allow_zero: bool = False) -> float:
    """``value`` as a float if it is a real number, finite and > 0 (>= 0 if ``allow_zero``); else
    :func:`bogie.settings.check_value`'s ValueError naming ``name``, the value and ``unit``."""
    return check_value(name, value, unit, low=0.0, low_open=not allow_zero)


def check_vector(
    name: str, value: Any, length: int, what: str, low: float, high: float, unit: str, low_inclusive: bool
) -> tuple[float, ...]:
    """``value`` as a tuple of ``length`` floats, one per ``what`` (axle, equaliser), each :func:`check_scalar`'s
    (named ``name[k]``); else a ValueError naming ``name``, what was given and what is wanted."""
    if type(value) is tuple and all(type(v) is float for v in value):
        pass  # a tuple of floats (what validation stores): one dimension, no numpy round trip needed
    elif isinstance(value, str | bytes) or np.ndim(value) == 0:
        raise ValueError(f"{name} = {_show(value)} must be a sequence of {length} values (one per {what}) in {unit}")
    values = tuple(value)
    if len(values) != length:
        raise ValueError(
            f"{name} has {len(values)} values but the bogie has {length} {what}s: give one per {what} in {unit}"
        )
    return tuple(check_scalar(f"{name}[{k}]", v, low, high, unit, low_inclusive) for k, v in enumerate(values))
