"""What the writers of weighings share (:mod:`bogie.weighings.writers`): the values of the vehicle table checked,
rounded and scaled to a format's units, and the messages that name the rows and the allowed range."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from bogie.weighings.formats import Field
from bogie.weighings.readers import YEAR_RANGE

#: years a two-digit year field (CASTOR, BeDIT) can hold: the POSIX ``%y`` pivot, 69-99 -> 1969-1999, 00-68 ->
#: 2000-2068, the reader's plausible years
TWO_DIGIT_YEARS: tuple[int, int] = YEAR_RANGE
#: a quotient (value / scale) is first rounded to this many decimals of its unit, so that a decimal input that
#: binary floating point cannot hold exactly rounds as written (0.45 m / 0.1 = 4.4999999999999991 dm -> 5 dm) [-]
_CLEAN_DECIMALS = 6
#: rows named in an error message
_SHOWN_ROWS = 3
#: time resolution of each fixed-width format [ns]: MON milliseconds, the others hundredths of a second
_TIME_STEP_NS = {"mon": 1_000_000, "castor": 10_000_000, "bedit": 10_000_000, "ditis": 10_000_000}
#: the SI unit of each quantity, for messages
_SI = {"kg": "kg", "kg/100": "kg", "mm": "m", "cm": "m", "dm": "m", "dm/s": "m/s", "km/h": "m/s", "ms": "s"}


# ---- messages ------------------------------------------------------------------------------------------------------
def _num(x: float) -> str:
    """A number for a message: up to 10 significant digits, thousands grouped by a space (99 900)."""
    if not math.isfinite(x):
        return str(x)
    text = f"{x:.10g}"
    if "e" in text:
        return text
    whole, dot, frac = text.partition(".")
    sign = "-" if whole.startswith("-") else ""
    whole = f"{int(whole.lstrip('-')):,}".replace(",", " ")
    return sign + whole + dot + frac


def _val(x: float) -> str:
    """A value for a message, as given: up to 10 significant digits, not grouped (104500, 1.31, nan)."""
    return f"{x:.10g}"


def _rows(rows: np.ndarray) -> str:
    """'row 17' or 'row 17 (3 rows: 17, 20, 31)' or 'row 17 (12 rows: 17, 20, 31, ...)'."""
    first = f"row {rows[0]}"
    if len(rows) == 1:
        return first
    shown = ", ".join(str(r) for r in rows[:_SHOWN_ROWS]) + (", ..." if len(rows) > _SHOWN_ROWS else "")
    return f"{first} ({len(rows)} rows: {shown})"


def _field_range(field: Field) -> str:
    """'0-99 900 kg in kg/100, 3 digits' (the field's range in SI, its unit as written, its width)."""
    top = 10**field.width - 1  # numerics-ok: integers
    if field.scale is None:
        return f"0-{_num(top)}, {field.width} digit{'s' if field.width > 1 else ''}"
    si = _SI.get(field.unit, field.unit)
    return f"0-{_num(round(top * field.scale, 9))} {si} in {field.unit}, {field.width} digits"


# ---- values --------------------------------------------------------------------------------------------------------
def _round_half_away(q: np.ndarray) -> np.ndarray:
    """Nearest integer, a half away from zero, after cleaning the quotient to :data:`_CLEAN_DECIMALS` decimals."""
    q = np.round(q, _CLEAN_DECIMALS)
    return np.sign(q) * np.floor(np.abs(q) + 0.5)


def _column(vehicles: pd.DataFrame, name: str, rows: np.ndarray | None = None) -> np.ndarray:
    """Column ``name`` as float (NaN where missing or not a number), for ``rows`` (positions) or all."""
    values = pd.to_numeric(vehicles[name], errors="coerce").to_numpy(dtype=float)
    return values if rows is None else values[rows]


def _require(vehicles: pd.DataFrame, fmt: str, name: str, rows: np.ndarray | None = None) -> None:
    if name not in vehicles.columns:
        needed = "" if rows is None else f" (needed by the axle count of {_rows(rows)})"
        raise ValueError(f"{fmt}: the table has no column {name}{needed}; required for format {fmt}")


def _integers(vehicles: pd.DataFrame, fmt: str, name: str, what: str) -> np.ndarray:
    """A required column of whole numbers (NaN or a fraction refused), as int64."""
    _require(vehicles, fmt, name)
    values = _column(vehicles, name)
    bad = np.flatnonzero(~np.isfinite(values) | (values != np.round(values)))
    if len(bad):
        raise ValueError(f"{fmt}: {name} = {vehicles[name].iloc[bad[0]]!r} in {_rows(bad)} is not {what}")
    return values.astype(np.int64)


def _scaled(fmt: str, name: str, values: np.ndarray, field: Field, rows: np.ndarray) -> np.ndarray:
    """SI ``values`` (of table rows ``rows``) as the field's integers, checked against its range."""
    unit = _SI.get(field.unit, field.unit) if field.scale is not None else ""
    shown = f" {unit}" if unit else ""
    for bad, why in (
        (np.isnan(values), "is not given (NaN) and has no default"),
        (values < 0, "is negative and does not fit its field"),
    ):
        where = np.flatnonzero(bad)
        if len(where):
            raise ValueError(
                f"{fmt}: {name} = {_val(values[where[0]])}{shown} in {_rows(rows[where])} {why} ({_field_range(field)})"
            )
    q = values if field.scale is None else values / field.scale
    written = _round_half_away(q)
    where = np.flatnonzero(~(written <= 10**field.width - 1))  # numerics-ok: integers
    if len(where):
        raise ValueError(
            f"{fmt}: {name} = {_val(values[where[0]])}{shown} in {_rows(rows[where])} does not fit its field "
            f"({_field_range(field)})"
        )
    return written.astype(np.int64)


def _optional(vehicles: pd.DataFrame, name: str, default: float) -> np.ndarray:
    """Column ``name`` as float, ``default`` where it is absent or NaN."""
    if name not in vehicles.columns:
        return np.full(len(vehicles), float(default))
    values = _column(vehicles, name)
    return np.where(np.isnan(values), default, values)


def _heads(vehicles: pd.DataFrame, fmt: str) -> np.ndarray:
    """The ``head`` column as integers: absent, NaN, None or '' -> 0; an int, a whole float or a string of digits."""
    if "head" not in vehicles.columns:
        return np.zeros(len(vehicles), dtype=float)
    out = np.zeros(len(vehicles), dtype=float)
    for j, value in enumerate(vehicles["head"].tolist()):
        if value is None or (isinstance(value, str) and not value.strip()):
            continue
        if isinstance(value, str):
            text = value.strip()
            if not (text.isascii() and text.isdigit()):
                raise ValueError(f"{fmt}: head = {value!r} in row {j} is not an integer (digits only)")
            out[j] = int(text)
            continue
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{fmt}: head = {value!r} in row {j} is not an integer") from None
        if math.isnan(number):
            continue
        if number != round(number):
            raise ValueError(f"{fmt}: head = {value!r} in row {j} is not an integer")
        out[j] = number
    return out


def _timestamps(vehicles: pd.DataFrame, fmt: str) -> pd.DatetimeIndex:
    _require(vehicles, fmt, "timestamp")
    try:
        stamps = pd.DatetimeIndex(pd.to_datetime(vehicles["timestamp"]))
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{fmt}: timestamp: not read as date and time ({exc})") from None
    if stamps.tz is not None:
        raise ValueError(
            f"{fmt}: timestamp has a time zone ({stamps.tz}); the formats hold local time without one: convert "
            "it first (e.g. .dt.tz_convert('Europe/Brussels').dt.tz_localize(None))"
        )
    bad = np.flatnonzero(stamps.isna())
    if len(bad):
        raise ValueError(f"{fmt}: timestamp = NaT in {_rows(bad)} is not given and has no default")
    return stamps


def _axle_counts(vehicles: pd.DataFrame, fmt: str, most: int) -> np.ndarray:
    n = _integers(vehicles, fmt, "n_axles", "a whole number of axles")
    bad = np.flatnonzero((n < 2) | (n > most))
    if len(bad):
        raise ValueError(
            f"{fmt}: n_axles = {n[bad[0]]} in {_rows(bad)} is not allowed (2-{most} axles, the format's limit)"
        )
    return n


def _coded(vehicles: pd.DataFrame, fmt: str, name: str, allowed: str, ok) -> np.ndarray:
    """A required code column (direction, lane): -1 (not given), absent or NaN refused, ``ok(values)`` must hold."""
    if name not in vehicles.columns:
        raise ValueError(f"{fmt}: the table has no column {name}; format {fmt} needs it ({allowed})")
    values = _column(vehicles, name)
    missing = np.flatnonzero(np.isnan(values) | (values == -1))
    if len(missing):
        first = ", ".join(str(r) for r in missing[:_SHOWN_ROWS]) + (", ..." if len(missing) > _SHOWN_ROWS else "")
        raise ValueError(
            f"{fmt}: {name} = -1 or NaN (not given) in {len(missing)} row{'s' if len(missing) > 1 else ''} "
            f"(first: {first}); format {fmt} needs it ({allowed})"
        )
    bad = np.flatnonzero(~ok(values) | (values != np.round(values)))
    if len(bad):
        raise ValueError(f"{fmt}: {name} = {_val(values[bad[0]])} in {_rows(bad)} is not allowed ({allowed})")
    return values.astype(np.int64)


def _axle_values(vehicles: pd.DataFrame, fmt: str, prefix: str, n: np.ndarray, count: np.ndarray) -> np.ndarray:
    """(rows, max count) SI values of ``prefix_1..``; NaN past each row's ``count``; a needed column must exist."""
    width = int(count.max(initial=0))
    out = np.full((len(n), width), np.nan)
    for i in range(width):
        rows = np.flatnonzero(count > i)
        _require(vehicles, fmt, f"{prefix}_{i + 1}", rows)
        out[rows, i] = _column(vehicles, f"{prefix}_{i + 1}", rows)
    return out
