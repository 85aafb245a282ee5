"""The fixed-width layouts' fields of every record in bulk (MON, CASTOR, BeDIT, DITIS): located, gathered, checked
and scaled to SI by a compiled gather, never line by line in Python (:mod:`bogie.weighings.readers` reads with
them)."""

from __future__ import annotations

import numpy as np

from bogie.weighings._records import (
    _FIELD_BYTE,
    MAX_AXLES,
    NO_AXLES,
    NON_NUMERIC,
    SHORT_HEADER,
    TOO_SHORT,
    TWO_DIGIT_PIVOT,
    _check_calendar,
    _gather,
    _Lines,
    _Reasons,
    _stray_bytes,
)
from bogie.weighings.formats import FixedWidthLayout


# ---- fixed width ---------------------------------------------------------------------------------------------------
def _parse_fixed(lines: _Lines, layout: FixedWidthLayout) -> dict:
    """Every record of ``lines`` in ``layout``: the columns (values of bad records undefined) and the reasons."""
    reasons = _Reasons(len(lines))
    raw = _header_fields(lines, layout, reasons)
    axles = _axle_fields(lines, layout, reasons, raw["n_axles"])
    # any other byte but a digit or a space, in a field or in the padding past the last axle: a form feed, a tab,
    # a Unicode line separator, binary data
    reasons.flag(_stray_bytes(lines, _FIELD_BYTE), NON_NUMERIC)
    stamp = _checked_stamp(layout, reasons, raw)
    return {"reasons": reasons, **_scaled(layout, raw, axles), "stamp": stamp}


def _header_fields(lines: _Lines, layout: FixedWidthLayout, reasons: _Reasons) -> dict[str, np.ndarray]:
    """The header's integer fields of every record (0 where unread); flags short records, bad digits and a number of
    axles out of range, and a record too short for its axles."""
    m = len(lines)
    length = lines.end - lines.start
    reasons.flag(length < layout.fixed_width, SHORT_HEADER)
    alive = np.flatnonzero(reasons.ok)
    raw: dict[str, np.ndarray] = {}
    for f in layout.header:
        raw[f.name] = np.zeros(m, np.int64)
        raw[f.name][alive], good = _gather(lines, alive, f.start, f.width)
        bad = np.zeros(m, bool)
        bad[alive[~good]] = True
        reasons.flag(bad, NON_NUMERIC)
    n = raw["n_axles"]
    reasons.flag(n == 0, NO_AXLES)
    most = min(MAX_AXLES, layout.max_axles)
    reasons.flag((n < 2) | (n > most), f"implausible number of axles (allowed 2-{most})")
    last = max(f.end for f in layout.axles.fields if f.per == "axle")
    reasons.flag(length < layout.axles.start + layout.axles.stride * (n - 1) + last, TOO_SHORT)
    return raw


def _axle_fields(lines: _Lines, layout: FixedWidthLayout, reasons: _Reasons, n: np.ndarray) -> dict[str, np.ndarray]:
    """Each per-axle (and per-spacing) field of the records still good, by axle (-1 where the record has none)."""
    m = len(lines)
    alive_mask = reasons.ok
    width = int(n[alive_mask].max()) if alive_mask.any() else 2
    axles: dict[str, np.ndarray] = {}
    for f in layout.axles.fields:
        count = width if f.per == "axle" else width - 1
        values = np.full((m, max(count, 0)), -1, np.int64)
        for k in range(count):
            rows = np.flatnonzero(alive_mask & (n > (k if f.per == "axle" else k + 1)))
            offset = layout.axles.start + layout.axles.stride * k + f.start
            values[rows, k], good = _gather(lines, rows, offset, f.width)
            bad = np.zeros(m, bool)
            bad[rows[~good]] = True
            reasons.flag(bad, NON_NUMERIC)
        axles[f.name] = values
    return axles


def _checked_stamp(layout: FixedWidthLayout, reasons: _Reasons, raw: dict[str, np.ndarray]) -> tuple:
    """The records' time stamps (year, month, day, hour, minute, microsecond of the minute), their groups, direction
    and calendar checked."""
    n = raw["n_axles"]
    if "n_groups" in raw:
        reasons.flag((raw["n_groups"] < 1) | (raw["n_groups"] > n), "implausible number of axle groups")
    base = layout.direction_base
    reasons.flag((raw["direction"] != base) & (raw["direction"] != base + 1), f"direction not {base} or {base + 1}")
    reasons.flag(raw["lane"] < 1, "lane 0 (the formats count lanes from 1)")
    year = raw["year"]
    if layout.year_digits == 2:  # the century is not written: POSIX %y
        year = year + np.where(year >= TWO_DIGIT_PIVOT, 1900, 2000)
    if "millisecond" in raw:  # MON: milliseconds of the minute
        micro = raw["millisecond"] * 1000
    else:
        micro = raw["second"] * 1_000_000 + raw["second_100"] * 10_000
    _check_calendar(reasons, year, raw["month"], raw["day"], raw["hour"], raw["minute"], micro)
    return (year, raw["month"], raw["day"], raw["hour"], raw["minute"], micro)


def _scaled(layout: FixedWidthLayout, raw: dict[str, np.ndarray], axles: dict[str, np.ndarray]) -> dict:
    """The fields in the layout's units: the vehicle columns, the axle loads, spacings and widths (NaN where none)."""
    m, n = len(raw["n_axles"]), raw["n_axles"]
    scale = layout.scales
    load_unit = layout.axle_field("axle_load").scale
    base = layout.direction_base
    columns = {
        "head": raw["head"], "speed": raw["speed"] * scale["speed"],
        "gross_weight": raw["gross_weight"] * scale["gross_weight"], "length": raw["length"] * scale["length"],
        "n_axles": n, "n_groups": raw["n_groups"].astype(float) if "n_groups" in raw else np.full(m, np.nan),
        "lane": raw["lane"], "direction": raw["direction"] - base + 1,
        "transverse_position": raw["transverse_position"] * scale["transverse_position"],
    }  # fmt: skip
    loads = np.where(axles["axle_load"] >= 0, axles["axle_load"] * load_unit, np.nan)
    spacings = np.where(axles["spacing"] >= 0, axles["spacing"] * layout.axle_field("spacing").scale, np.nan)
    widths = None
    if "axle_width" in axles:
        widths = np.where(axles["axle_width"] >= 0, axles["axle_width"] * layout.axle_field("axle_width").scale, np.nan)
    return {
        "columns": columns, "loads": loads, "spacings": spacings, "widths": widths,
        "gross_step": scale["gross_weight"], "load_step": load_unit,
        # the wheelbase check's integers: the length and the spacings in the format's own units
        "length_units": (raw["length"], scale["length"]),
        "spacing_units": (axles["spacing"], layout.axle_field("spacing").scale),
    }  # fmt: skip
