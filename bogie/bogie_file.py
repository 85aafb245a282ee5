"""A bogie described in a YAML file: every field of :class:`bogie.params.Bogie` in human units (``docs/bogie-file.md``).

Each key names its unit by its suffix, as params.yaml does (``axle_x_m``, ``spring_front_half_length_mm``,
``road_spring_stiffness_kn_mm``, ``equaliser_stop_deg`` ...: :data:`FILE_KEYS`). A file that names a preset to start
from (``base: triaxle_stage1``) takes that preset's value for every key it leaves out; a file without ``base`` must
give every key, so that no value is ever a silent default. :func:`load_bogie` reads one and returns the validated
:class:`~bogie.params.Bogie` or raises :class:`BogieFileError` naming every bad key at once, with its value, the
allowed range and the unit; it returns nothing partial. The axle count is the length of ``axle_x_m``.

The conversion to SI is exact where it can be: a value in mm, kN or kN/mm is read as the decimal the file writes and
scaled by a power of ten with one rounding (``155`` mm is the float ``0.155``), so a file that writes a preset's
numbers gives that preset's bits; degrees go through :func:`math.radians`, as the presets' stop angle does.

:func:`base_bogie` and :func:`base_fields` take either a preset name or a file's path: what a fleet's ``presets``
(:class:`bogie.fleet.Fleet`) and its sample rows' ``preset`` column may hold.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
from decimal import Decimal
from pathlib import Path
from typing import Any, NamedTuple

import yaml

from bogie.guarded_yaml import read_text_file, read_yaml
from bogie.params import Bogie
from bogie.presets import PRESETS, preset, preset_fields
from bogie.ranges import AXLE_RANGES, EQUALISER_RANGES, SCALAR_RANGES, FieldRange
from bogie.settings import refusal

__all__ = [
    "BASE_KEY", "FILE_KEYS", "BogieFileError", "FileKey", "base_bogie", "base_fields", "is_bogie_file", "load_bogie",
    "read_bogie_text",
]  # fmt: skip

#: the key naming the preset whose values the absent keys take
BASE_KEY = "base"
#: the suffixes a bogie file may have
SUFFIXES = (".yaml", ".yml")


class FileKey(NamedTuple):
    """One key of a bogie file: the :class:`~bogie.params.Bogie` field it gives and its unit.

    Attributes
    ----------
    key
        The key in the file, its unit's suffix included.
    unit
        The unit of its values in the file.
    scale
        SI value per file value (a power of ten, exact as a decimal), or None for degrees (:func:`math.radians`).
    """

    key: str
    unit: str
    scale: Decimal | None


def _k(key: str, unit: str, scale: str | None = "1") -> FileKey:
    return FileKey(key, unit, None if scale is None else Decimal(scale))


#: field of :class:`~bogie.params.Bogie` -> its key in a bogie file, in the Bogie's field order
FILE_KEYS: dict[str, FileKey] = {
    "axle_x": _k("axle_x_m", "m"),
    "spring_front_half_length": _k("spring_front_half_length_mm", "mm", "1e-3"),
    "spring_rear_half_length": _k("spring_rear_half_length_mm", "mm", "1e-3"),
    "equaliser_front_arm": _k("equaliser_front_arm_mm", "mm", "1e-3"),
    "equaliser_rear_arm": _k("equaliser_rear_arm_mm", "mm", "1e-3"),
    "road_spring_stiffness": _k("road_spring_stiffness_kn_mm", "kN/mm", "1e6"),
    "tyre_stiffness": _k("tyre_stiffness_kn_mm", "kN/mm", "1e6"),
    "tyre_radius": _k("tyre_radius_mm", "mm", "1e-3"),
    "axle_mass": _k("axle_mass_kg", "kg"),
    "payload_mass": _k("payload_mass_kg", "kg"),
    "payload_cg_x": _k("payload_cg_x_m", "m"),
    "chassis_pitch_inertia": _k("chassis_pitch_inertia_kg_m2", "kg m^2"),
    "tyre_wear": _k("tyre_wear_mm", "mm", "1e-3"),
    "tyre_damping": _k("tyre_damping_kn_s_m", "kN s/m", "1e3"),
    "equaliser_inertia": _k("equaliser_inertia_kg_m2", "kg m^2"),
    "pad_drop": _k("pad_drop_mm", "mm", "1e-3"),
    "equaliser_front_tip_drop": _k("equaliser_front_tip_drop_mm", "mm", "1e-3"),
    "equaliser_rear_tip_drop": _k("equaliser_rear_tip_drop_mm", "mm", "1e-3"),
    "spring_length_rate": _k("spring_length_rate", "m/m"),
    "spring_end_slope_rate": _k("spring_end_slope_rate_rad_m", "rad/m"),
    "contact_tangential_stiffness": _k("contact_tangential_stiffness_kn_mm", "kN/mm", "1e6"),
    "chassis_tilt": _k("chassis_tilt_deg", "degree", None),
    "bush_stiffness": _k("bush_stiffness_n_m_rad", "N m/rad"),
    "bush_damping": _k("bush_damping_n_m_s_rad", "N m s/rad"),
    "contact_roll_radius": _k("contact_roll_radius_mm", "mm", "1e-3"),
    "friction_coefficient": _k("friction_coefficient", "-"),
    "radius_rod_length": _k("radius_rod_length_mm", "mm", "1e-3"),
    "radius_rod_drop": _k("radius_rod_drop_mm", "mm", "1e-3"),
    "equaliser_stop": _k("equaliser_stop_deg", "degree", None),
    "equaliser_stop_stiffness": _k("equaliser_stop_stiffness_kn_m_rad", "kN m/rad", "1e3"),
    "spring_friction_band": _k("spring_friction_band_kn", "kN", "1e3"),
    "spring_friction_decay": _k("spring_friction_decay_mm", "mm", "1e-3"),
}
_FIELD_OF_KEY = {k.key: f for f, k in FILE_KEYS.items()}
#: per-axle fields that may be an empty list: the Bogie's rule then gives their values (a rod from the bracket ahead)
_MAY_BE_EMPTY = ("radius_rod_length",)


class BogieFileError(ValueError):
    """A bogie file that cannot be read or does not describe a valid bogie: the message names the file and every bad
    key with its value, the allowed range and the unit."""


def _range_in_file_units(rng: FieldRange, key: FileKey) -> dict[str, Any]:
    """The range ``rng`` [SI] in the file's unit, as :func:`bogie.settings.refusal`'s bounds (the message only: the
    check is :meth:`FieldRange.contains` on the SI value)."""

    def show(si: float) -> float:
        return math.degrees(si) if key.scale is None else si / float(key.scale)

    return {"low": show(rng.low), "high": show(rng.high), "low_open": not rng.low_inclusive}


def _to_si(value: Any, key: FileKey) -> float:
    """``value`` (an int or a float as YAML reads it) in SI; ``TypeError`` if it is not a number."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError
    if key.scale is None:
        return math.radians(float(value))
    if not math.isfinite(value):
        return float(value)
    # the decimal the file writes (repr round-trips a float), scaled exactly, rounded once
    return float(Decimal(repr(value) if isinstance(value, float) else value) * key.scale)


def _kind(value: Any) -> str:
    return "text" if isinstance(value, str) else "a true/false" if isinstance(value, bool) else type(value).__name__


def _scalar(field: str, value: Any, problems: list[str], label: str | None = None) -> float | None:
    key = FILE_KEYS[field]
    rng = SCALAR_RANGES.get(field) or AXLE_RANGES.get(field) or EQUALISER_RANGES[field]
    label = label or key.key
    bounds = _range_in_file_units(rng, key)
    try:
        si = _to_si(value, key)
    except TypeError:
        hint = ""
        if isinstance(value, str) and "e" in value.lower():
            try:
                float(value)
                mantissa, _, exponent = value.lower().partition("e")
                mantissa += "" if "." in mantissa else ".0"
                exponent = exponent if exponent.startswith(("+", "-")) else f"+{exponent}"
                hint = f"YAML needs a dot and the exponent's sign: write {mantissa}e{exponent}"
            except ValueError:
                pass
        problems.append(refusal(label, value, key.unit, **bounds, note=hint))
        return None
    if not (math.isfinite(si) and rng.contains(si)):
        problems.append(refusal(label, value, key.unit, **bounds))
        return None
    return si


def _vector(field: str, value: Any, length: int, what: str, problems: list[str]) -> tuple[float, ...] | None:
    key = FILE_KEYS[field]
    if field in _MAY_BE_EMPTY and value == []:
        return ()
    if not isinstance(value, list) or len(value) != length:
        count = f"{len(value)} values" if isinstance(value, list) else f"{value!r}"
        empty = " (or [] for a rod from the bracket ahead)" if field in _MAY_BE_EMPTY else ""
        problems.append(f"{key.key} = {count}: give a list of {length} values, one per {what}, in {key.unit}{empty}")
        return None
    values = [_scalar(field, v, problems, f"{key.key}[{i}]") for i, v in enumerate(value)]
    return None if any(v is None for v in values) else tuple(v for v in values if v is not None)


def read_bogie_text(text: str, source: str = "<bogie file>") -> Bogie:
    """The bogie a bogie file's text describes (:func:`load_bogie` without the file).

    Parameters
    ----------
    text
        The YAML text.
    source
        Where it comes from, for the messages.

    Raises
    ------
    BogieFileError
        Bad YAML, a document that is not a mapping, unknown keys (all named), missing keys when there is no
        ``base`` (all named), values of the wrong type or out of range (all named, with range and unit), or a
        bogie whose fields do not fit together (the chain does not close, say).
    """
    data = _read_mapping(text, source)
    base = _base_fields_of(data, source)
    n = _axle_count(data, base, source)
    fields = _file_fields(data, base, n, source)
    try:
        return Bogie(**fields)
    except ValueError as exc:
        named = [f"{f} is {k.key} [{k.unit}]" for f, k in FILE_KEYS.items() if f in str(exc)]
        raise BogieFileError(
            f"{source}: the bogie does not hold together: {exc} (SI units; in this file {'; '.join(named)})"
        ) from None


def _read_mapping(text: str, source: str) -> dict:
    """The bogie file's YAML mapping; :class:`BogieFileError` for bad YAML, another document or unknown keys."""
    try:
        data = read_yaml(text, source)  # a key given twice, deep nesting, alias bombs and huge integers refused
    except yaml.YAMLError as exc:
        raise BogieFileError(f"{source}: not valid YAML: {exc}") from None
    except ValueError as exc:  # DuplicateKeyError, DocumentTooLargeError: they name the file
        raise BogieFileError(str(exc)) from None
    if not isinstance(data, dict):
        raise BogieFileError(f"{source}: must be a mapping of keys to values (docs/bogie-file.md), not {_kind(data)}")
    unknown = [k for k in data if k != BASE_KEY and k not in _FIELD_OF_KEY]
    if unknown:
        hints = []
        for k in unknown:
            close = difflib.get_close_matches(str(k), [BASE_KEY, *_FIELD_OF_KEY], n=1)
            hints.append(f"{k!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        raise BogieFileError(
            f"{source}: unknown keys {', '.join(hints)}; a bogie file's keys are {BASE_KEY} and "
            f"{', '.join(_FIELD_OF_KEY)} (units in the suffix, docs/bogie-file.md)"
        )
    return data


def _base_fields_of(data: dict, source: str) -> dict[str, Any] | None:
    """The fields of the file's ``base`` preset, or None without one (then every key must be given)."""
    if BASE_KEY in data:
        name = data[BASE_KEY]
        if not isinstance(name, str) or name not in PRESETS:
            raise BogieFileError(f"{source}: {BASE_KEY} = {name!r}: must be a preset name, one of {', '.join(PRESETS)}")
        return preset_fields(name)
    missing = [k.key for k in FILE_KEYS.values() if k.key not in data]
    if missing:
        raise BogieFileError(
            f"{source}: missing keys {', '.join(missing)}: without '{BASE_KEY}: <preset>' every key must be given "
            f"(presets: {', '.join(PRESETS)})"
        )
    return None


def _axle_count(data: dict, base: dict[str, Any] | None, source: str) -> int:
    """The file's number of axles; with another count than its base's, every per-axle and per-equaliser key given."""
    axle_key = FILE_KEYS["axle_x"].key
    if axle_key in data:
        raw = data[axle_key]
        if not isinstance(raw, list) or len(raw) < 2:
            raise BogieFileError(f"{source}: {axle_key} = {raw!r}: give a list of at least 2 axle positions in m")
        n = len(raw)
    else:
        assert base is not None
        n = len(base["axle_x"])
    if base is not None and n != len(base["axle_x"]):
        lacking = [FILE_KEYS[f].key for f in (*AXLE_RANGES, *EQUALISER_RANGES)
                   if FILE_KEYS[f].key not in data and not (f in _MAY_BE_EMPTY and not base[f])]  # fmt: skip
        if lacking:
            raise BogieFileError(
                f"{source}: {axle_key} gives {n} axles but {BASE_KEY} {data[BASE_KEY]} has {len(base['axle_x'])}: "
                f"give {', '.join(lacking)} too (one value per axle, or per equaliser)"
            )
    return n


def _file_fields(data: dict, base: dict[str, Any] | None, n: int, source: str) -> dict[str, Any]:
    """Every Bogie field in SI units, from the file or its base; all bad values named in one :class:`BogieFileError`."""
    problems: list[str] = []
    fields: dict[str, Any] = {}
    for field, key in FILE_KEYS.items():
        if key.key not in data:
            fields[field] = base[field] if base is not None else None
        elif field in AXLE_RANGES:
            fields[field] = _vector(field, data[key.key], n, "axle", problems)
        elif field in EQUALISER_RANGES:
            fields[field] = _vector(field, data[key.key], n - 1, "equaliser", problems)
        else:
            fields[field] = _scalar(field, data[key.key], problems)
    if problems:
        raise BogieFileError(f"{source}: {'; '.join(problems)}")
    return fields


def load_bogie(path: str | os.PathLike[str]) -> Bogie:
    """The bogie a bogie file describes (``docs/bogie-file.md``), validated.

    Parameters
    ----------
    path
        The YAML file (``.yaml`` or ``.yml``); a relative path is relative to the working directory.

    Returns
    -------
    Bogie
        The bogie, SI, with as many axles as the file's ``axle_x_m`` (or its ``base``) lists.

    Raises
    ------
    BogieFileError
        A file that does not exist or cannot be read, or any problem :func:`read_bogie_text` names.
    """
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise BogieFileError(f"{path}: a bogie file must end in {' or '.join(SUFFIXES)}")
    try:
        text = read_text_file(path)  # a regular file of at most 1 MiB: a FIFO, a device, /dev/zero refused
    except FileNotFoundError:
        raise BogieFileError(f"{path}: no such bogie file (relative to {Path.cwd()})") from None
    except ValueError as exc:  # not a regular file, too large, not UTF-8
        raise BogieFileError(f"{path}: cannot be read as a bogie file: {exc}") from None
    except OSError as exc:
        raise BogieFileError(f"{path}: cannot be read: {exc}") from None
    return read_bogie_text(text, str(path))


def is_bogie_file(name: str) -> bool:
    """Whether a base-bogie name is a file's path (it ends in ``.yaml`` or ``.yml``) rather than a preset's name."""
    return str(name).lower().endswith(SUFFIXES)


def base_bogie(name: str) -> Bogie:
    """A fleet's base bogie: the preset of that name, or the bogie of that file (:func:`load_bogie`).

    Raises
    ------
    ValueError
        A name that is neither a preset nor a ``.yaml``/``.yml`` path (:class:`BogieFileError` for a bad file).
    """
    if name in PRESETS:
        return preset(name)
    if not is_bogie_file(name):
        raise ValueError(
            f"unknown base bogie {name!r}: must be a preset ({', '.join(PRESETS)}) or a bogie file's path ending in "
            f"{' or '.join(SUFFIXES)} (docs/bogie-file.md)"
        )
    return load_bogie(name)


def base_fields(name: str) -> dict[str, Any]:
    """The fields of :func:`base_bogie` as a new dict, as :func:`bogie.presets.preset_fields` gives a preset's: change
    some and build one :class:`Bogie` from it. A file is read at each call (a caller that wants it once caches)."""
    if name in PRESETS:
        return preset_fields(name)
    base = base_bogie(name)
    return {f.name: getattr(base, f.name) for f in dataclasses.fields(Bogie)}
