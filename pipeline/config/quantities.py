"""The sampled quantities of params.yaml's ``distributions:``: each key's unit, its conversion to SI and its range.

A :class:`Quantity` per key (``chassis_tilt_deg``: degrees to radians, the range of the ``Bogie`` field it sets);
:func:`si_distribution` builds a key's distribution in SI and checks that every sample lies in the quantity's physical
range; :func:`distribution_field` is the pydantic field of a key and :data:`Distributions` the section's model
(:mod:`pipeline.config.schema` holds the other sections).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any

from pydantic import Field, ValidatorFunctionWrapHandler, WrapValidator, create_model

from bogie.fleet.sampling.distributions import Choice, Constant, Distribution, ParameterError
from bogie.params import AXLE_RANGES, SCALAR_RANGES, FieldRange
from pipeline.config.distributions import ROAD_CLASSES, DistributionSpec, LabelSpec, NumericSpec, Strict
from pipeline.config.errors import config_error


def _identity(x: float) -> float:
    return x


def _mm_to_m(x: float) -> float:
    # a division keeps round millimetre values bit-equal to the metre limits (50 / 1000 == 0.05)
    return x / 1000.0


def _m_to_mm(x: float) -> float:
    return x * 1000.0


def _kn_to_n(x: float) -> float:
    return x * 1000.0


def _n_to_kn(x: float) -> float:
    return x / 1000.0


@dataclass(frozen=True)
class Quantity:
    """One sampled quantity: its params.yaml key and unit, its SI name (Bogie field, sample column) and range.

    Attributes
    ----------
    key, yaml_unit
        Its key under ``distributions:`` and the unit of the values there.
    name, unit
        Its SI name and SI unit.
    range
        The values a sample may take [SI unit].
    to_si, from_si
        Conversion of a value from the params.yaml unit to SI, and back.
    labels
        The labels of a categorical quantity (its samples are labels, not numbers).
    """

    key: str
    name: str
    yaml_unit: str
    range: FieldRange
    to_si: Callable[[float], float] = _identity
    from_si: Callable[[float], float] = _identity
    labels: tuple[str, ...] = ()

    @property
    def range_text(self) -> str:
        """The allowed range in params.yaml units, e.g. ``[0, 50] mm``."""
        r = self.range
        unit = "" if self.yaml_unit in ("-", "[-]") else f" {self.yaml_unit}"
        return f"{'[' if r.low_inclusive else '('}{self.from_si(r.low):g}, {self.from_si(r.high):g}]{unit}"


def _bogie_quantity(
    key: str,
    name: str,
    yaml_unit: str | None = None,
    to_si: Callable[[float], float] = _identity,
    from_si: Callable[[float], float] = _identity,
) -> Quantity:
    field_range = {**SCALAR_RANGES, **AXLE_RANGES}[name]
    return Quantity(key, name, yaml_unit or field_range.unit, field_range, to_si, from_si)


#: every entry of ``distributions:``, by params.yaml key; Bogie quantities take their range from bogie.params
QUANTITIES: dict[str, Quantity] = {
    q.key: q
    for q in (
        _bogie_quantity("bush_stiffness", "bush_stiffness"),
        _bogie_quantity("bush_damping", "bush_damping"),
        _bogie_quantity("friction_coefficient", "friction_coefficient"),
        _bogie_quantity("contact_roll_radius_mm", "contact_roll_radius", "mm", _mm_to_m, _m_to_mm),
        _bogie_quantity("tyre_wear_mm", "tyre_wear", "mm", _mm_to_m, _m_to_mm),
        _bogie_quantity("chassis_tilt_deg", "chassis_tilt", "degree", math.radians, math.degrees),
        _bogie_quantity("spring_friction_band_kn", "spring_friction_band", "kN", _kn_to_n, _n_to_kn),
        _bogie_quantity("spring_friction_decay_mm", "spring_friction_decay", "mm", _mm_to_m, _m_to_mm),
        # every equaliser arm of a bogie, the axle spacing kept (params.with_equaliser_arms)
        Quantity("equaliser_arm_mm", "equaliser_arm", "mm", FieldRange(0.05, 0.5, "m", True), _mm_to_m, _m_to_mm),
        # up to half as much again as the legal load: overloaded trailers are part of what a survey finds
        Quantity("payload_fraction", "payload_fraction", "-", FieldRange(0.0, 1.5, "-", False)),
        Quantity("road_class", "road_class", "ISO 8608 class", FieldRange(0.0, 0.0, "-", True), labels=ROAD_CLASSES),
    )
}


def _check_support(q: Quantity, dist: Distribution, raw: Any) -> None:
    """Refuse a distribution (in SI) that can sample outside the physical range of its quantity."""
    raw = raw if isinstance(raw, dict) else {}
    where = f"outside the allowed range {q.range_text} of {q.name}"
    if isinstance(dist, Constant):
        if not q.range.contains(dist.value):
            raise config_error("value", raw.get("value", dist.value), f"is {where}")
        return
    if isinstance(dist, Choice):
        for i, v in enumerate(dist.values):
            if not q.range.contains(v):
                raise config_error(f"values[{i}]", raw["values"][i], f"is {where}")
        return
    lo, hi = dist.support
    if math.isinf(lo) or math.isinf(hi):
        bounds = "low and high" if math.isinf(lo) else "high"
        hint = "use kind truncnormal with low and high" if dist.kind == "normal" else f"give {bounds}"
        message = f"is unbounded but {q.name} must stay in {q.range_text}: {hint} inside that range to truncate it"
        raise config_error("kind", raw.get("kind", dist.kind), message)
    if not q.range.contains(lo):
        raise config_error("low", raw.get("low", q.from_si(lo)), f"lets samples fall {where}")
    if not q.range.contains(hi):
        raise config_error("high", raw.get("high", q.from_si(hi)), f"lets samples fall {where}")


def si_distribution(spec: DistributionSpec, q: Quantity, raw: Any = None) -> Distribution:
    """The sampling distribution of quantity ``q`` in SI, checked to keep every sample inside ``q.range``.

    Parameters
    ----------
    spec
        Its entry of ``distributions:``, in the params.yaml unit of ``q``.
    q
        The quantity.
    raw
        The entry as written (for the values the errors quote), if at hand.

    Raises
    ------
    pydantic_core.PydanticCustomError
        If the parameters do not make a distribution, or it can sample outside the range.
    """
    try:
        dist = spec.build()
    except ParameterError as exc:
        value = raw.get(exc.param, exc.value) if isinstance(raw, dict) else exc.value
        # sigma and the weights are dimensionless whatever the quantity
        dimensionless = exc.param.split("[")[0] in ("sigma", "weights") or q.yaml_unit in ("-", "[-]")
        raise config_error(exc.param, value, exc.expected + ("" if dimensionless else f", in {q.yaml_unit}")) from None
    if q.labels:
        return dist
    si = dist.scaled(q.to_si)
    _check_support(q, si, raw)
    return si


def _checked(q: Quantity) -> WrapValidator:
    # the validated value is the distribution in SI, built once here (pipeline.config.si passes it on as it is)
    def check(raw: Any, handler: ValidatorFunctionWrapHandler) -> Distribution:
        return si_distribution(handler(raw), q, raw)

    return WrapValidator(check)


def distribution_field(q: Quantity) -> tuple[Any, Any]:
    what = f"distribution kind for the categorical {q.name}" if q.labels else "distribution kind"
    expected = f"a distribution of {q.name} in {q.yaml_unit}, e.g. {{kind: uniform, ...}}"
    extra = {"unit": q.yaml_unit, "what": what, "expected": expected, **({} if q.labels else {"range": q.range_text})}
    spec = LabelSpec if q.labels else NumericSpec
    return Annotated[spec, _checked(q)], Field(json_schema_extra=extra)


#: ``distributions:``, one entry per quantity, each written in the params.yaml unit of its key and validated into
#: its SI sampling distribution (:func:`si_distribution`)
Distributions = create_model(
    "Distributions",
    __base__=Strict,
    __doc__="``distributions:`` the distribution of every sampled quantity, in the unit of its key.",
    **{key: distribution_field(q) for key, q in QUANTITIES.items()},
)
