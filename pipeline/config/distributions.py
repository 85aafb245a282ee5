"""The params.yaml form of a distribution: one pydantic model per ``kind``, a union tagged by ``kind``.

Each model holds the parameters exactly as written in params.yaml, in the unit of the quantity's key; its
:meth:`DistributionSpec.build` makes the sampling class of :mod:`bogie.fleet.sampling.distributions` from them, which
checks the rules that span parameters (``low < high``, one weight per value) and raises
:class:`~bogie.fleet.sampling.distributions.ParameterError`. The conversion to SI and the check against the physical
range of the quantity are done per quantity by :mod:`pipeline.config.schema`.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field

from bogie.fleet.sampling.distributions import (
    Choice,
    Constant,
    Distribution,
    LogNormal,
    LogUniform,
    Normal,
    TruncNormal,
    Uniform,
)
from bogie.road import ISO8608_CLASSES

#: ISO 8608 road roughness classes, smoothest first
#: the ISO 8608 road classes, as bogie.road defines them
ROAD_CLASSES: tuple[str, ...] = tuple(ISO8608_CLASSES)

#: a road class label
RoadClass = Literal[ROAD_CLASSES]  # type: ignore[valid-type]


def dimensionless(**constraints: Any) -> Any:
    """A parameter without unit whatever the quantity (``sigma``, ``weights``) [-]."""
    return Field(json_schema_extra={"unit": "-"}, **constraints)


class Strict(BaseModel):
    """Base of every params.yaml model: exact types (no bool or text for a number), no unknown key, immutable."""

    model_config = ConfigDict(
        strict=True, extra="forbid", frozen=True, allow_inf_nan=False, use_attribute_docstrings=True
    )


class DistributionSpec(Strict):
    """One entry of ``distributions:`` as written; every parameter is in the unit of the quantity's key."""

    sampler: ClassVar[type[Distribution]]

    def build(self) -> Distribution:
        """The sampling distribution, in the unit of the quantity's key.

        Raises
        ------
        bogie.fleet.sampling.distributions.ParameterError
            If the parameters do not make a distribution (``high <= low``, a weight per value missing...).
        """
        args = {name: getattr(self, name) for name in type(self).model_fields if name != "kind"}
        return self.sampler(**{k: tuple(v) if isinstance(v, list) else v for k, v in args.items()})


class ConstantSpec(DistributionSpec):
    """``{kind: constant, value}``: every sample is ``value``."""

    kind: Literal["constant"]
    value: float
    sampler: ClassVar[type[Distribution]] = Constant


class UniformSpec(DistributionSpec):
    """``{kind: uniform, low, high}``."""

    kind: Literal["uniform"]
    low: float
    high: float
    sampler: ClassVar[type[Distribution]] = Uniform


class LogUniformSpec(DistributionSpec):
    """``{kind: loguniform, low, high}`` with low > 0."""

    kind: Literal["loguniform"]
    low: float = Field(gt=0.0)
    high: float
    sampler: ClassVar[type[Distribution]] = LogUniform


class NormalSpec(DistributionSpec):
    """``{kind: normal, mean, sd}`` with sd > 0 (unbounded)."""

    kind: Literal["normal"]
    mean: float
    sd: float = Field(gt=0.0)
    sampler: ClassVar[type[Distribution]] = Normal


class TruncNormalSpec(DistributionSpec):
    """``{kind: truncnormal, mean, sd, low, high}``: the mean and sd of the parent normal, sd > 0."""

    kind: Literal["truncnormal"]
    mean: float
    sd: float = Field(gt=0.0)
    low: float
    high: float
    sampler: ClassVar[type[Distribution]] = TruncNormal


class LogNormalSpec(DistributionSpec):
    """``{kind: lognormal, median, sigma, low: optional, high: optional}``; sigma of ln x [-], truncated if given."""

    kind: Literal["lognormal"]
    median: float = Field(gt=0.0)
    sigma: float = dimensionless(gt=0.0)
    low: float = Field(0.0, ge=0.0)
    high: float = math.inf
    sampler: ClassVar[type[Distribution]] = LogNormal


class ChoiceSpec(DistributionSpec):
    """``{kind: choice, values, weights: optional}``: one of the numbers ``values``, with relative ``weights``."""

    kind: Literal["choice"]
    values: list[float] = Field(min_length=1)
    weights: list[float] | None = dimensionless(default=None)
    sampler: ClassVar[type[Distribution]] = Choice


class LabelConstantSpec(DistributionSpec):
    """``{kind: constant, value}`` for a categorical quantity: every sample is the label ``value``."""

    kind: Literal["constant"]
    value: RoadClass
    sampler: ClassVar[type[Distribution]] = Constant


class LabelChoiceSpec(DistributionSpec):
    """``{kind: choice, values, weights: optional}`` for a categorical quantity: one of the labels ``values``."""

    kind: Literal["choice"]
    values: list[RoadClass] = Field(min_length=1)
    weights: list[float] | None = dimensionless(default=None)
    sampler: ClassVar[type[Distribution]] = Choice


#: a distribution of a numeric quantity, by ``kind``
NumericSpec = Annotated[
    ConstantSpec | UniformSpec | LogUniformSpec | NormalSpec | TruncNormalSpec | LogNormalSpec | ChoiceSpec,
    Field(discriminator="kind"),
]

#: a distribution of a categorical quantity (road class), by ``kind``
LabelSpec = Annotated[LabelChoiceSpec | LabelConstantSpec, Field(discriminator="kind")]
