"""pydantic's validation errors as the project's messages: one line per bad key of params.yaml.

Each line names the dotted key path (``fleet.axle_mix.tandem``, ``protocol.run[1]``), the value as written, and
what was expected: form, range and unit, read from the schema's field constraints and from the ``unit``,
``what`` and ``expected`` entries of each field's ``json_schema_extra``. An unknown key gets a "did you mean"
suggestion. A rule that no field constraint can express raises :func:`config_error` from a validator; its
context names the key below the validator's location, the value and the expected form in words.
"""

from __future__ import annotations

import difflib
import re
import reprlib
import types
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union, get_args, get_origin

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo
from pydantic_core import ErrorDetails, PydanticCustomError

#: the error type of :func:`config_error`, and of :func:`rule_error` (a rule between sections, pipeline.config.rules)
CONFIG_ERROR = "config"
RULE_ERROR = "config_rule"

#: the most characters of a value a message shows: a value of any size (a YAML alias expanded a billion times) is
#: shown in bounded time, its start and an ellipsis
SHOWN_CHARS = 60

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 3, SHOWN_CHARS, SHOWN_CHARS


def shown(value: Any) -> str:
    """``repr(value)`` as a message shows it: at most :data:`SHOWN_CHARS` characters, ``...`` marking a cut."""
    text = _REPR.repr(value)
    return text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 3] + "..."


_NUMBER_TYPES = ("int_type", "float_type", "int_from_float")

#: a number in exponent notation that YAML 1.1 reads as text: no dot in the mantissa or no sign in the exponent
_YAML_TEXT_EXPONENT = re.compile(r"[-+]?(\d+[eE][-+]?\d+|\d*\.\d*[eE]\d+)")


class ConfigError(ValueError):
    """Bad values in params.yaml.

    Parameters
    ----------
    key
        Dotted key path of the first bad key (``distributions.bush_stiffness.low``; empty for the whole file).
    message
        The message, one line per bad key.
    errors
        Every bad key with its line, ``(key, line)``; just ``(key, message)`` if not given.
    """

    def __init__(self, key: str, message: str, errors: Sequence[tuple[str, str]] = ()) -> None:
        self.key = key
        self.errors: tuple[tuple[str, str], ...] = tuple(errors) or ((key, message),)
        super().__init__(message)


def config_error(key: str, value: Any, expected: str) -> PydanticCustomError:
    """The error a validator raises for a rule that spans fields, reported as ``<path>.<key> = <value>: <expected>``.

    Parameters
    ----------
    key
        Key path below the validator's location (``"high"``, ``"values[2]"``, ``"ablation.n_bogies"``), or ``""`` for
        the location itself.
    value
        The offending value, as written in params.yaml.
    expected
        What the value must be, in words, with its unit.
    """
    return PydanticCustomError(CONFIG_ERROR, "{expected}", {"key": key, "value": value, "expected": expected})


def rule_error(key: str, value: Any, expected: str) -> PydanticCustomError:
    """:func:`config_error` for a rule between sections (``key`` from the top level), told apart from field errors."""
    return PydanticCustomError(RULE_ERROR, "{expected}", {"key": key, "value": value, "expected": expected})


# ---- where an error is in the schema -----------------------------------------------------------------------------
@dataclass(frozen=True)
class Place:
    """What the schema says about one error location.

    Attributes
    ----------
    key
        Dotted key path as written in params.yaml (the tags of tagged unions left out).
    node
        The type expected there (a model class, a union of them, a ``Literal``, ``list[...]``, ``int``...), or
        None for a key the schema does not have.
    owner
        The model whose field the last key is (for an unknown key: the model that refused it).
    field
        That field, None for an unknown key or a list item.
    unit
        Unit of the nearest enclosing field that gives one (``-`` if none does).
    what
        What the value is, in words (``preset``, ``ISO 8608 class``), for the messages.
    entry
        For an entry of a mapping field with free keys (``calibrate.fit.air_share``), what the entry must be.
    range
        The physical range of the distribution the key belongs to (``[-10, 10] degree``), if it is in one.
    """

    key: str
    node: Any
    owner: type[BaseModel] | None
    field: FieldInfo | None
    unit: str
    what: str
    entry: str | None = None
    range: str | None = None


def _extra(field: FieldInfo | None, name: str) -> Any:
    extra = field.json_schema_extra if field is not None else None
    return extra.get(name) if isinstance(extra, Mapping) else None


def _without_none(node: Any) -> Any:
    if get_origin(node) in (Union, types.UnionType):
        args = [a for a in get_args(node) if a is not type(None)]
        return args[0] if len(args) == 1 else Union[tuple(args)]  # noqa: UP007 (a runtime union of types)
    return node


def _is_model(node: Any) -> bool:
    return isinstance(node, type) and issubclass(node, BaseModel)


def union_tags(node: Any) -> dict[str, type[BaseModel]]:
    """The members of a union of models tagged by a ``kind: Literal[...]`` field, by tag (empty for other types)."""
    if get_origin(node) not in (Union, types.UnionType):
        return {}
    tags = {}
    for member in get_args(node):
        if _is_model(member) and "kind" in member.model_fields:
            for tag in get_args(member.model_fields["kind"].annotation):
                tags[tag] = member
    return tags


def join_key(parts: Iterable[str | int]) -> str:
    """A location as a key path: ``("protocol", "run", 1)`` -> ``protocol.run[1]``."""
    key = ""
    for part in parts:
        key = f"{key}[{part}]" if isinstance(part, int) else (f"{key}.{part}" if key else str(part))
    return key


def locate(schema: type[BaseModel], loc: Sequence[str | int]) -> Place:
    """Follow an error location ``loc`` through the models of ``schema`` (see :class:`Place`)."""
    node: Any = schema
    owner, field, parts, fields = None, None, [], []
    entry = None
    for part in loc:
        node = _without_none(node)
        if _is_model(node):
            owner, field = node, node.model_fields.get(part) if isinstance(part, str) else None
            parts.append(part)
            node = field.annotation if field is not None else None
            fields.append(field)
        elif isinstance(part, str) and part in union_tags(node):
            node = union_tags(node)[part]  # the tag of a tagged union is not a key of params.yaml
        elif get_origin(node) in (list, tuple):
            node, field = get_args(node)[0], None
            if get_origin(node) is Annotated:  # an item with its own constraints, list[Annotated[float, Field(...)]]
                node, field = get_args(node)[0], next((m for m in get_args(node)[1:] if isinstance(m, FieldInfo)), None)
            parts.append(part)
        elif get_origin(node) is dict:
            entry = entry or _extra(field, "entry")
            node, field = get_args(node)[1], None
            parts.append(part)
        else:
            node, field = None, None
            parts.append(part)
    unit = next((u for f in reversed(fields) if (u := _extra(f, "unit")) is not None), "-")
    named = next((f for f in reversed(fields) if f is not None), None)
    what = _extra(named, "what") or unit
    physical = next((r for f in reversed(fields) if (r := _extra(f, "range")) is not None), None)
    return Place(join_key(parts), _without_none(node), owner, field, unit, what, entry, physical)


# ---- what was expected there ---------------------------------------------------------------------------------
def _unit_text(unit: str) -> str:
    return "" if unit in ("-", "[-]") else f" {unit}"


def _bounds(field: FieldInfo | None) -> dict[str, Any]:
    """The numeric constraints of a field: any of ``ge``, ``gt``, ``le``, ``lt``."""
    found: dict[str, Any] = {}
    for item in field.metadata if field is not None else ():
        for name in ("ge", "gt", "le", "lt"):
            if getattr(item, name, None) is not None:
                found[name] = getattr(item, name)
    return found


def range_text(bounds: Mapping[str, Any], unit: str, integer: bool = False) -> str:
    """The allowed range in words: ``in [0, 50] mm``, ``> 0 N m/rad``, ``in (0, 1)``; empty if unbounded."""
    fmt = "{}" if integer else "{:g}"
    low = next(((k, bounds[k]) for k in ("ge", "gt") if k in bounds), None)
    high = next(((k, bounds[k]) for k in ("le", "lt") if k in bounds), None)
    unit = _unit_text(unit)
    if low and high:
        opening, closing = "[" if low[0] == "ge" else "(", "]" if high[0] == "le" else ")"
        return f"in {opening}{fmt.format(low[1])}, {fmt.format(high[1])}{closing}{unit}"
    if low or high:
        name, value = low or high
        return f"{ {'ge': '>=', 'gt': '>', 'le': '<=', 'lt': '<'}[name] } {fmt.format(value)}{unit}"
    return f"in{unit}" if unit else ""


def _options(node: Any) -> tuple[str, ...]:
    return tuple(str(a) for a in get_args(node)) if get_origin(node) is Literal else ()


def expected(place: Place) -> str:
    """What the value at ``place`` must be, e.g. ``an integer in [1, 10000000]``."""
    node, field = place.node, place.field
    if _extra(field, "expected"):
        return _extra(field, "expected")
    if place.entry and field is None and get_origin(node) in (list, tuple):
        return place.entry
    if _is_model(node):
        return f"a mapping with the keys {', '.join(node.model_fields)}"
    if union_tags(node):
        return "a mapping such as {kind: uniform, low: ..., high: ...}"
    if _options(node):
        return f"one of {', '.join(_options(node))}"
    if get_origin(node) in (list, tuple):
        item = get_args(node)[0]
        if _options(item):
            return f"a non-empty list of {place.what}s from {', '.join(_options(item))}"
        return f"a non-empty list of numbers{_unit_text(place.unit) and f' in{_unit_text(place.unit)}'}"
    if node is int:
        return " ".join(("an integer", range_text(_bounds(field), "-", integer=True))).strip()
    if node is float:
        return " ".join(("a number", range_text(_bounds(field), place.unit))).strip()
    if node is str:
        return "text"
    return "a value of another form"


# ---- one line per error ----------------------------------------------------------------------------------------
def _suggestion(word: Any, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(str(word), list(choices), n=1)
    return f" (did you mean {close[0]}?)" if close else ""


def _is_numeric_text(value: Any) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return isinstance(value, str)


def _line(schema: type[BaseModel], error: ErrorDetails) -> tuple[str, str]:
    """The key path of one pydantic error and its message line."""
    kind, value, ctx = error["type"], error.get("input"), error.get("ctx") or {}
    place = locate(schema, error["loc"])
    key, name = place.key, place.key or "the top level"
    if kind in (CONFIG_ERROR, RULE_ERROR):
        key = f"{place.key}.{ctx['key']}" if place.key and ctx["key"] else place.key or ctx["key"]
        key = key.replace(".[", "[")
        return key, f"{key} = {shown(ctx['value'])}: {ctx['expected']}"
    if kind == "missing":
        hint = ""
        if place.owner is not None and "kind" in place.owner.model_fields:
            required = [n for n, f in place.owner.model_fields.items() if f.is_required() and n != "kind"]
            hint = f" (kind {get_args(place.owner.model_fields['kind'].annotation)[0]} takes {', '.join(required)})"
        return key, f"missing key {key}: expected {expected(place)}{hint}"
    if kind == "extra_forbidden":
        allowed = tuple(place.owner.model_fields) if place.owner is not None else ()
        parent = locate(schema, error["loc"][:-1]).key or "the top level"
        hint = _suggestion(error["loc"][-1], allowed)
        return key, f"unknown key {key}{hint}: {parent} takes {', '.join(allowed)}"
    if kind in ("union_tag_invalid", "union_tag_not_found") and isinstance(value, Mapping):
        tags = ", ".join(union_tags(place.node))
        if kind == "union_tag_not_found":
            return f"{key}.kind", f"missing key {key}.kind: expected one of {tags}"
        return f"{key}.kind", f"{key}.kind = {shown(ctx.get('tag'))}: unknown {place.what}: must be one of {tags}"
    if kind == "literal_error":
        hint = _suggestion(value, _options(place.node)) if isinstance(value, str) else ""
        return key, f"{name} = {shown(value)}: unknown {place.what}{hint}: must be {expected(place)}"
    if kind == "finite_number":
        hint = f"a finite number within {place.range}, the range of the quantity" if place.range else expected(place)
        return key, f"{name} = {shown(value)}: is not a finite number (NaN or infinity): must be {hint}"
    if kind in _NUMBER_TYPES and _is_numeric_text(value):
        text = f"{name} = {shown(value)}: is text, not a number (must be {expected(place)})"
        if _YAML_TEXT_EXPONENT.fullmatch(value.strip()):
            return key, f"{text}; YAML reads 1e3 and 1.0e3 as text, write 1.0e+3"
        if value.strip().lstrip("+-").lower() in ("nan", "inf", "infinity"):
            # unquoted NaN or inf is text to YAML (its own are .nan, .inf), and no quantity takes them anyway
            return key, f"{name} = {shown(value)}: is not a number a quantity takes: must be {expected(place)}"
        return key, f"{text}; write it without quotes"
    if kind == "too_short" and get_origin(place.node) is list and (ctx.get("min_length") or 0) > 1:
        return key, f"{name} = {shown(value)}: must be {expected(place)}: at least {ctx['min_length']} items"
    return key, f"{name} = {shown(value)}: must be {expected(place)}"


def error_lines(schema: type[BaseModel], errors: Iterable[ErrorDetails]) -> list[tuple[str, str]]:
    """Every error as ``(key path, message line)``: unknown keys first (a typo explains a missing key), no repeats.

    Parameters
    ----------
    schema
        The model that was validated.
    errors
        Its errors, as :meth:`pydantic.ValidationError.errors` gives them.
    """
    errors = sorted(errors, key=lambda e: e["type"] != "extra_forbidden")
    lines = [_line(schema, e) for e in errors]
    return list(dict.fromkeys(lines))


def to_config_error(schema: type[BaseModel], exc: ValidationError) -> ConfigError:
    """A :class:`ConfigError` that lists every bad key of ``exc``, one line each; its ``key`` is the first."""
    lines = error_lines(schema, exc.errors())
    return ConfigError(lines[0][0], "\n".join(line for _, line in lines), lines)
