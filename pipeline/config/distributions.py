"""The params.yaml form of a distribution: one pydantic model per ``kind``, a union tagged by ``kind``.

Each model is made from the library's distribution class of its kind (:func:`spec_model`): its keys are the class's
parameters, with their defaults, and nothing else is declared here. It holds the parameters exactly as written in
params.yaml, in the unit of the quantity's key (but those the class names ``dimensionless``); its
:meth:`DistributionSpec.build` makes the sampling class of :mod:`bogie.fleet.sampling.distributions` from them, which
checks every parameter's rule (``sd > 0``, ``low < high``, one weight per value) and raises
:class:`~bogie.fleet.sampling.distributions.ParameterError`. The conversion to SI and the check against the physical
range of the quantity are done per quantity by :mod:`pipeline.config.schema`.
"""

from __future__ import annotations

import dataclasses
import functools
import operator
import typing
from typing import Annotated, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, create_model

from bogie.fleet.sampling.distributions import KINDS, Choice, Constant, Distribution
from bogie.road import ISO8608_CLASSES

#: ISO 8608 road roughness classes, smoothest first
#: the ISO 8608 road classes, as bogie.road defines them
ROAD_CLASSES: tuple[str, ...] = tuple(ISO8608_CLASSES)

#: a road class label
RoadClass = Literal[ROAD_CLASSES]  # type: ignore[valid-type]


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


def _annotation(hint: Any, labels: bool) -> Any:
    """The params.yaml type of a library distribution's parameter: a number (a road class label for a categorical
    quantity), a list for a tuple."""
    if hint is float:
        return float
    if hint == (float | str) or hint is Any:  # a value: a label of a categorical quantity
        return RoadClass if labels else float
    if typing.get_origin(hint) is tuple:
        return list[_annotation(typing.get_args(hint)[0], labels)]
    args = typing.get_args(hint)
    if type(None) in args:
        return _annotation(next(a for a in args if a is not type(None)), labels) | None
    raise TypeError(f"a distribution parameter of type {hint!r} has no params.yaml form")


def spec_model(sampler: type[Distribution], labels: bool = False) -> type[DistributionSpec]:
    """The params.yaml model of the library's distribution ``sampler``: ``kind`` and one key per parameter of the
    class, in its order, with its default; the values are checked by the class itself when :meth:`build` makes it
    (:class:`~bogie.fleet.sampling.distributions.ParameterError`), so that a parameter's rule is written once, there.
    ``labels``: for a categorical quantity (a road class label for a number)."""
    hints = typing.get_type_hints(sampler)
    fields: dict[str, Any] = {"kind": (Literal[sampler.kind], ...)}
    required, _optional = sampler.parameter_names()
    for f in dataclasses.fields(sampler):
        default = {} if f.name in required else {"default": f.default}
        unit = {"json_schema_extra": {"unit": "-"}} if f.name in sampler.dimensionless else {}
        bound = {"gt": 0.0} if f.name in sampler.positive else {"ge": 0.0} if f.name in sampler.nonnegative else {}
        fields[f.name] = (_annotation(hints[f.name], labels), Field(**default, **unit, **bound))
    written = ", ".join(["kind: " + sampler.kind, *(f.name for f in dataclasses.fields(sampler))])
    summary = (sampler.__doc__ or "").strip().splitlines()[0]
    model = create_model(
        f"{'Label' if labels else ''}{sampler.__name__}Spec", __base__=DistributionSpec,
        __doc__=f"``{{{written}}}``: {summary}", **fields,
    )  # fmt: skip
    model.sampler = sampler
    return model


#: a distribution of a numeric quantity, by ``kind``
NumericSpec = Annotated[functools.reduce(operator.or_, map(spec_model, KINDS.values())), Field(discriminator="kind")]

#: a distribution of a categorical quantity (road class), by ``kind``
LabelSpec = Annotated[spec_model(Choice, labels=True) | spec_model(Constant, labels=True), Field(discriminator="kind")]
