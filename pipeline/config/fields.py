"""The field helpers of the params.yaml schema and its maps of fixed keys (axle groups, suspensions).

:mod:`pipeline.config.schema` builds its sections from these: a number with its unit (and, for a unit with two SI
forms, which: :mod:`pipeline.config.si`), an integer range, a name from a fixed set, and the models whose keys are
the axle groups of :data:`bogie.fleet.constants.GROUP_AXLES` (``fleet.axle_mix`` ...), which the configuration
holds as :class:`~pipeline.config.si.FrozenMap`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, Literal

from pydantic import AfterValidator, Field, ValidationInfo, create_model, field_validator, model_validator

from bogie.bogie_file import BogieFileError, base_bogie, is_bogie_file
from bogie.fleet.constants import GROUP_AXLES
from bogie.presets import PRESETS
from bogie.settings import TOTAL_TOLERANCE, MapSetting, Setting, declared
from pipeline.config.distributions import Strict
from pipeline.config.errors import config_error
from pipeline.config.si import TONNE, UNITS


def number(unit: str, si: str | None = None, **bounds: float) -> Any:
    """A required number in ``unit`` within ``bounds`` (any of ``ge``, ``gt``, ``le``, ``lt``); ``si``: the SI unit
    of a unit that has two (``t``: ``N`` for a load, ``kg`` for a mass; :mod:`pipeline.config.si`)."""
    return Field(json_schema_extra={"unit": unit, **({"si": si} if si else {})}, **bounds)


def integer(low: int, high: int | None = None) -> Any:
    """A required integer in [low, high] [-]."""
    return Field(ge=low, le=high)


def named(what: str, **constraints: Any) -> Any:
    """A required name (or list of names) from a fixed set; ``what`` names one in the messages (``preset``)."""
    return Field(json_schema_extra={"what": what}, **constraints)


def distinct(what: str) -> AfterValidator:
    def check(names: list[str]) -> list[str]:
        if len(set(names)) != len(names):
            raise config_error("", names, f"lists a {what} twice")
        return names

    return AfterValidator(check)


def power_of_two(n: int) -> int:
    if n & (n - 1):
        raise config_error("", n, "must be a power of 2 (Sobol' sequences balance only then), e.g. 512")
    return n


class _Map(Strict):
    """A mapping of fixed keys (axle groups, suspensions): a :class:`~pipeline.config.si.FrozenMap` in the config."""

    as_map: ClassVar[bool] = True


class _Mix(_Map):
    """A map whose values must sum to ``total`` (the library's :attr:`bogie.settings.MapSetting.total`)."""

    total: ClassVar[float] = 1.0

    @model_validator(mode="after")
    def _sums_to_total(self) -> _Mix:
        fractions = self.model_dump()
        if abs(sum(fractions.values()) - self.total) > TOTAL_TOLERANCE:
            raise config_error(
                "", fractions, f"the fractions must sum to {self.total:g}, they sum to {sum(fractions.values()):g}"
            )
        return self


#: the folder of the project's bogie files: ``fleet.presets`` may name files there only
BOGIES_DIR = "bogies"


def _inside_bogies(name: str) -> None:
    """Refuse a bogie file outside the project's ``bogies/`` (absolute, ``..``, or a symlink leading out), before it is
    opened: the message names where it points, never what it holds."""
    path = Path(name)
    allowed = (Path.cwd() / BOGIES_DIR).resolve()
    if path.is_absolute() or ".." in path.parts or not path.parts or path.parts[0] != BOGIES_DIR:
        raise config_error("", name, f"a bogie file must lie in the project's {BOGIES_DIR}/ folder, named relative "
                           f"to the project root ({BOGIES_DIR}/my_triaxle.yaml; docs/bogie-file.md)")  # fmt: skip
    try:
        target = (Path.cwd() / path).resolve(strict=True)
    except FileNotFoundError:
        return  # the loader says no such file
    except (OSError, RuntimeError) as exc:
        raise config_error("", name, f"cannot be resolved: {exc}") from None
    if not target.is_relative_to(allowed):
        raise config_error("", name, f"points to {target}, outside the project's {BOGIES_DIR}/ ({allowed}; symlinks "
                           f"followed): copy the bogie file into {BOGIES_DIR}/")  # fmt: skip


class GroupPresets(_Map):
    """``fleet.presets``: a group's preset or bogie file, with the group's number of axles; a bogie file in the
    project's ``bogies/`` (:func:`_inside_bogies`)."""

    @field_validator("*")
    @classmethod
    def _axles_match(cls, name: str, info: ValidationInfo) -> str:
        group, n_axles = info.field_name, GROUP_AXLES[info.field_name]
        if name not in PRESETS and not is_bogie_file(name):
            raise config_error(
                "", name, f"must be a preset ({', '.join(PRESETS)}) or a bogie file's path ending in .yaml or .yml, "
                "relative to the project root (docs/bogie-file.md)"
            )  # fmt: skip
        if is_bogie_file(name):
            _inside_bogies(name)
        try:
            bogie = base_bogie(name)
        except BogieFileError as exc:
            raise config_error("", name, f"not a valid bogie file: {exc}") from None
        if bogie.n_axles != n_axles:
            raise config_error("", name, f"has {bogie.n_axles} axles but a {group} has {n_axles}")
        return name


#: a project bound stricter than the library's: (the bound's name ``ge``/``gt``/``le``/``lt``, its value in the key's
#: unit, the reason), given to :func:`library_model` by key
Bound = tuple[str, float, str]


def library_model(
    name: str,
    library: type,
    doc: str,
    units: dict[str, str] | None = None,
    bounds: dict[str, list[Bound]] | None = None,
    names: dict[str, str] | None = None,
    custom: dict[str, tuple[str, Any, Any]] | None = None,
    base: type[Strict] = Strict,
) -> type[Strict]:
    """The params.yaml section of the library settings class ``library``, built from its declarations
    (:func:`bogie.settings.declared`; :func:`declared_fields`): one key per field, in its order. ``custom``: a field
    whose value is more than a number or a name (a mapping, a list of names), by the library's field name: (its
    key, annotation, pydantic field). Every field of ``library`` is a key, declared or custom. The model's
    ``library_class`` is ``library``, so that the configuration holds the library's object."""
    custom = custom or {}
    settings = declared(library)
    made = declared_fields(name, library, list(settings), units, bounds, names)
    fields: dict[str, Any] = {}
    for attr in (f.name for f in dataclasses.fields(library)):
        if attr in custom:
            key, annotation, field = custom[attr]
            fields[key] = (annotation, field)
        elif attr in settings:
            fields.update(made[attr])
        else:
            raise TypeError(f"{name}: {library.__name__}.{attr} is neither declared (bogie.settings) nor custom")
    model = create_model(name, __base__=base, __doc__=doc, **fields)
    model.library_class = library
    return model


def declared_fields(
    model: str,
    library: type | Mapping[str, Setting | MapSetting],
    attrs: list[str],
    units: dict[str, str] | None = None,
    bounds: dict[str, list[Bound]] | None = None,
    names: dict[str, str] | None = None,
    required: dict[str, str] | None = None,
    maps: dict[str, type[Strict]] | None = None,
) -> dict[str, dict[str, tuple[Any, Any]]]:
    """The schema fields of the declared settings ``attrs`` of ``library`` (a settings class, or a function's
    declared arguments by name), by attribute: ``{attr: {key: (annotation, field)}}``, the key the attribute's name
    with the suffix of its unit (:mod:`pipeline.config.si`), its type, range, unit and doc the declaration's; a
    mapping setting (:class:`bogie.settings.MapSetting`) is a model of its keys (:func:`map_model`).

    Only what the YAML adds is given here: ``units``, a field's unit in the YAML where it is not the library's
    (``sensor_axle_error``: ``%`` where the library takes a fraction; ``legal_axle_load``: ``t`` where it takes N),
    and ``bounds``, the project's stricter bounds by key, each with its reason (a bound that is not stricter than the
    library's is refused when the model is made; a mapping's bound holds for each of its values); ``names``, what a
    name field's value is, in the messages (``sensor``: ``sensor type``); ``required``, a setting the library lets be
    None that the project requires, with the reason; ``maps``, the base model of a mapping whose values the project
    checks further (``presets``: a bogie file must lie in ``bogies/``). A key of a setting that may be None may be
    left out (None)."""
    units, bounds, names, required, maps = units or {}, bounds or {}, names or {}, required or {}, maps or {}
    settings = declared(library) if isinstance(library, type) else dict(library)
    owner = library.__name__ if isinstance(library, type) else model
    out: dict[str, dict[str, tuple[Any, Any]]] = {}
    for attr in attrs:
        spec = settings[attr]
        unit = units.get(attr, spec.unit)
        suffix, factor, si = _yaml_unit(unit, spec.unit)
        key = attr + suffix
        if isinstance(spec, MapSetting):
            default = _library_default(library, attr) if spec.optional else None
            made = map_model(model, attr, spec, unit, bounds.get(key, ()), default, maps.get(attr), names.get(attr))
            extra = {"unit": unit, **si}
            factory = {} if default is None else {"default_factory": lambda made=made, d=default: made(**d)}
            out[attr] = {key: (made, Field(description=spec.doc, json_schema_extra=extra, **factory))}
            continue
        optional = spec.optional and attr not in required
        default = {"default": None} if optional else {}
        if spec.choices is not None:
            annotation: Any = Literal[spec.choices]
            field = Field(json_schema_extra={"what": names.get(attr, attr)}, description=spec.doc, **default)
        else:
            annotation = int if spec.whole else float
            limits = _library_limits(spec, factor)
            for which, value, _reason in bounds.get(key, ()):
                _stricter(model, key, limits, which, value)
            field = Field(description=spec.doc, json_schema_extra={"unit": unit, **si}, **limits, **default)
        if optional:
            annotation = annotation | None
        out[attr] = {key: (annotation, field)}
    unknown = set(bounds) - {key for made in out.values() for key in made}
    if unknown:
        raise TypeError(f"{model}: bounds for keys {sorted(unknown)} that {owner} does not declare")
    return out


def _yaml_unit(unit: str, library_unit: str) -> tuple[str, float, dict[str, str]]:
    """A YAML unit's key suffix, its factor to the library's unit, and the ``si`` a tonne needs (a load: N; a mass:
    kg; :mod:`pipeline.config.si`)."""
    suffix, factor, _si = UNITS.get(unit, ("", 1.0, unit))
    if factor is None:
        if library_unit not in TONNE:
            raise TypeError(f"a key in {unit} needs a library unit of {' or '.join(TONNE)}, not {library_unit}")
        return suffix, TONNE[library_unit], {"si": library_unit}
    return suffix, factor, {}


def _library_default(library: Any, attr: str) -> Any:
    """The library class's default of the field ``attr`` (its factory's value)."""
    found = next(f for f in dataclasses.fields(library) if f.name == attr)
    return found.default_factory() if found.default_factory is not dataclasses.MISSING else found.default


def map_model(
    model: str,
    attr: str,
    spec: MapSetting,
    unit: str,
    bounds: tuple[Bound, ...] | list[Bound] = (),
    default: Mapping[str, Any] | None = None,
    base: type[Strict] | None = None,
    what: str | None = None,
) -> type[Strict]:
    """The model of a mapping setting: one field per key of ``spec.keys``, in that order, each required unless the
    library gives a ``default`` (the project requires every key: a fleet names each group), each value declared by
    ``spec.entry`` in the YAML's ``unit`` with the project's ``bounds`` (a mapping of mappings: a model per value);
    summing to ``spec.total`` if it has one. Named after ``attr`` (``axle_mix``: ``AxleMix``)."""
    name = "".join(word.capitalize() for word in attr.split("_"))
    entry = spec.entry
    fields: dict[str, Any] = {}
    for key in spec.keys:
        keep = {} if default is None else {"default_factory": (lambda v=default[key]: v)}
        if isinstance(entry, MapSetting):
            sub = map_model(model, f"{attr}_entry", entry, entry.unit, (), default[key] if default else None)
            if default is not None:
                keep = {"default_factory": lambda sub=sub, v=default[key]: sub(**v)}
            fields[key] = (sub, Field(description=entry.doc, **keep))
        elif entry is None:
            fields[key] = (str, Field(json_schema_extra={"what": what or attr}, **keep))
        else:
            _suffix, factor, si = _yaml_unit(unit, entry.unit)
            limits = _library_limits(entry, factor)
            for which, value, _reason in bounds:
                _stricter(model, f"{attr}.{key}", limits, which, value)
            field = Field(json_schema_extra={"unit": unit, **si}, **limits, **keep)
            fields[key] = (int if entry.whole else float, field)
    parent = base or (_Mix if spec.total is not None else _Map)
    made = create_model(name, __base__=parent, __doc__=spec.doc, **fields)
    if spec.total is not None:
        made.total = spec.total
    return made


def _library_limits(spec: Setting, factor: float) -> dict[str, float]:
    """A declaration's bounds as pydantic's constraints, in the YAML's unit (the library's over ``factor``)."""
    limits = {}
    if spec.low is not None:
        limits["gt" if spec.low_open else "ge"] = spec.low if factor == 1.0 else spec.low / factor
    if spec.high is not None:
        limits["lt" if spec.high_open else "le"] = spec.high if factor == 1.0 else spec.high / factor
    return limits


def _stricter(model: str, key: str, limits: dict[str, float], which: str, value: float) -> None:
    """Put the project bound ``which`` = ``value`` into ``limits``, refusing one that allows what the library's
    refuses."""
    low = which in ("ge", "gt")
    current = [(k, v) for k, v in limits.items() if (k in ("ge", "gt")) == low]
    for k, v in current:
        looser = value < v or (value == v and k == "gt" and which == "ge") if low else \
            value > v or (value == v and k == "lt" and which == "le")  # fmt: skip
        if looser:
            raise TypeError(f"{model}.{key}: the project bound {which} {value:g} is not stricter than the library's "
                            f"{k} {v:g}")  # fmt: skip
        del limits[k]
    limits[which] = value
