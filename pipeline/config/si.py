"""From the schema to the configuration: each params.yaml key is declared once, in :mod:`pipeline.config.schema`.

The configuration's classes (:mod:`pipeline.config.sections`) are made from the schema's models, and a validated
file is converted to them by :func:`to_config`, so that a key is never written out again. A key becomes an attribute
by the unit its schema field declares (``json_schema_extra={"unit": ...}``):

=========  ========  ==========================================================================================
unit       suffix    the attribute
=========  ========  ==========================================================================================
``t``      ``_t``    the field's ``si``: ``N`` (a load, x 1000 g) or ``kg`` (a mass, x 1000); it must say which
``s``      ``_s``    [s]
``m``      ``_m``    [m]
``m/s``    ``_m_s``  [m/s]
``m/km``   ``_m_km`` [m/km]: the IRI's own unit everywhere, the library's too (ASTM E1926)
``degree`` ``_deg``  kept in degrees, with its suffix: the tilt grids step in exact decimal degrees (0.25, 0.5) and
                     are tabulated and reported in them; in radians the grid's levels would not be those numbers
``%``      ``_pct``  a fraction [-] (x 0.01)
``[-]``              unchanged
=========  ========  ==========================================================================================

The attribute's name is the key without its suffix (``legal_axle_load_t`` -> ``legal_axle_load`` [N]); what has no
unit (counts, names, addresses) is kept as it is, a list as a tuple, a mapping of fixed keys as a
:class:`FrozenMap`. A field whose value takes more than a unit (the Sobol' factors by their SI names, the design
grid in SI, the calibration bounds as pairs) carries a :class:`ToConfig` in its annotation. A model whose values are
a library class's settings names it in ``library_class`` (``protocol.static`` -> ``bogie.fleet.StaticProtocol``);
its keys, converted, are then that class's own field names.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from pydantic import BaseModel
from pydantic.fields import FieldInfo

from bogie.params import GRAVITY
from bogie.settings import FrozenMap

__all__ = ["FrozenMap", "ToConfig", "attribute", "config_class", "to_config"]


@dataclasses.dataclass(frozen=True)
class ToConfig:
    """In a field's annotation: how its validated value becomes the configuration's (``convert``), and in what unit
    (``unit``, for the class's docstring)."""

    convert: Callable[[Any], Any]
    unit: str = "-"


#: params.yaml unit -> (the key's suffix, the factor to SI or None when the field's ``si`` chooses, the SI unit)
UNITS: dict[str, tuple[str, float | None, str]] = {
    "t": ("_t", None, ""),
    "s": ("_s", 1.0, "s"),
    "m": ("_m", 1.0, "m"),
    "m/s": ("_m_s", 1.0, "m/s"),
    "m/km": ("_m_km", 1.0, "m/km"),
    "degree": ("", 1.0, "degree"),
    "%": ("_pct", 0.01, "-"),
}
#: a tonne in the SI unit a ``t`` field declares
TONNE: dict[str, float] = {"N": 1000.0 * GRAVITY, "kg": 1000.0}


def _extra(info: FieldInfo) -> dict[str, Any]:
    extra = info.json_schema_extra
    return extra if isinstance(extra, dict) else {}


def _rule(key: str, info: FieldInfo, in_map: bool = False) -> tuple[str, float, str]:
    """The attribute name, the factor to SI and the SI unit of the field ``key`` (of a map of fixed keys: the key
    as it is, its map's key carries the suffix)."""
    extra = _extra(info)
    unit = str(extra.get("unit", "-"))
    if unit not in UNITS:
        return key, 1.0, unit
    suffix, factor, si = UNITS[unit]
    if in_map:
        suffix = ""
    elif not key.endswith(suffix):
        raise TypeError(f"schema field {key!r} is in {unit} but its name does not end in {suffix!r}")
    if factor is None:
        si = str(extra.get("si", ""))
        if si not in TONNE:
            raise TypeError(f"schema field {key!r} is in {unit}: its json_schema_extra must give si, one of {TONNE}")
        factor = TONNE[si]
    return key.removesuffix(suffix), factor, si


def _converter(info: FieldInfo) -> ToConfig | None:
    return next((m for m in info.metadata if isinstance(m, ToConfig)), None)


def attribute(key: str, info: FieldInfo) -> tuple[str, str]:
    """The configuration's attribute for the schema field ``key``: its name and its unit."""
    name, _, unit = _rule(key, info)
    custom = _converter(info)
    return name, custom.unit if custom is not None else unit


def _section_model(annotation: Any) -> type[BaseModel] | None:
    """The model of a field that holds a section (``Survey | None`` -> Survey), else None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    models = [a for a in getattr(annotation, "__args__", ()) if isinstance(a, type) and issubclass(a, BaseModel)]
    return models[0] if len(models) == 1 else None


def _value(value: Any, factor: float) -> Any:
    if isinstance(value, BaseModel):
        return to_config(value)
    if isinstance(value, list | tuple):
        return tuple(_value(v, factor) for v in value)
    if factor != 1.0 and isinstance(value, int | float) and not isinstance(value, bool):
        return value * factor
    return value


_CLASSES: dict[type[BaseModel], type] = {}


def config_class(
    model: type[BaseModel],
    name: str | None = None,
    skip: tuple[str, ...] = (),
    properties: dict[str, property] | None = None,
) -> type:
    """The frozen dataclass a validated ``model`` converts to: one attribute per key, named and in the unit of the
    table above; an optional section (``None`` allowed) defaults to None. Made once per model; the model's
    ``library_class`` if it names one. ``name`` names the class (module
    :mod:`pipeline.config.sections`); the keys in ``skip`` are left out (sections other stages read themselves);
    ``properties`` adds read-only attributes computed from the others (not fields: not stored, compared, hashed or
    written to ``data/config.json``)."""
    if model in _CLASSES:
        return _CLASSES[model]
    library = getattr(model, "library_class", None)
    if library is not None:
        _CLASSES[model] = library
        return library
    fields, lines = [], []
    for key, info in model.model_fields.items():
        if key in skip:
            continue
        attr, unit = attribute(key, info)
        optional = not info.is_required() and info.default is None
        fields.append((attr, Any, dataclasses.field(default=None)) if optional else (attr, Any))
        sub = _section_model(info.annotation)
        if sub is not None and _converter(info) is None:
            what = "mapping" + _map_unit(sub) if _is_map(sub) else f":class:`{config_class(sub).__name__}`"
        else:
            what = f"[{unit}]"
        text = f"{info.description} " if info.description else ""
        lines.append(f"{attr}\n    {text}(params.yaml ``{key}``; {what}{'; None if not given' if optional else ''})")
    for attr, prop in (properties or {}).items():
        lines.append(f"{attr}\n    {prop.__doc__} (computed from the sections above)")
    section = getattr(model, "__doc__", "") or ""
    doc = (
        f"{section.splitlines()[0] if section else model.__name__} In SI (:mod:`pipeline.config.si`), made from "
        f":class:`pipeline.config.schema.{model.__name__}`.\n\n"
        "Attributes\n----------\n" + "\n".join(lines)
    )
    cls = dataclasses.make_dataclass(
        name or f"{model.__name__}Config", fields, frozen=True, namespace={"__doc__": doc, **(properties or {})}
    )
    cls.__module__ = "pipeline.config.sections"
    _CLASSES[model] = cls
    return cls


def to_config(params: BaseModel) -> Any:
    """A validated schema model (a section, or the whole file) in the configuration's units and names.

    A model whose class has no configuration class of its own (a map of fixed keys such as ``axle_mix``) becomes a
    :class:`FrozenMap` of its converted values.
    """
    model = type(params)
    values = {}
    for key, info in model.model_fields.items():
        name, factor, _ = _rule(key, info, _is_map(model))
        value = getattr(params, key)
        custom = _converter(info)
        values[name] = custom.convert(value) if custom is not None else _value(value, factor)
    if _is_map(model):
        return FrozenMap(values)
    cls = config_class(model)
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{k: v for k, v in values.items() if k in names})


def _map_unit(model: type[BaseModel]) -> str:
    """`` of <unit>`` of a map's values, or of its maps' values."""
    info = next(iter(model.model_fields.values()))
    sub = _section_model(info.annotation)
    if sub is not None:
        return " of mappings" + _map_unit(sub)
    unit = _rule("", info, in_map=True)[2]
    return f" {unit}" if unit.startswith("[") else f" [{unit}]"


def _is_map(model: type[BaseModel]) -> bool:
    """A model of fixed keys that are data (axle groups, suspensions), not settings: ``as_map`` in its class."""
    return bool(getattr(model, "as_map", False))
