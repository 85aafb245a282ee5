"""Writer of weighings: the vehicle table of :func:`bogie.weighings.readers.read_weighings` back to a file.

:func:`write_weighings` writes the documented CSV layout or one of the fixed-width WIM formats (MON, CASTOR, BeDIT,
DITIS), every field from the layout data of ``formats.py`` (offset, width, scale to SI), so that reading the file
back gives the table again, rounded to the format's resolution. Everything is checked before anything is written,
and the file is written atomically (a temporary file in the same folder, then ``os.replace``): an error leaves no
file, partial or temporary. The rules (rounding, defaults of absent columns, errors) are in ``docs/weighings.md``,
section "Writing records".

**Per format** (:func:`write_weighings`):

- *Axles*: ``n_axles`` from 2 to the format's limit: CSV 20, CASTOR 9, BeDIT 20, DITIS 20, MON 99.
- *Times* are rounded to the format's resolution: MON 1 ms; CASTOR, BeDIT, DITIS 0.01 s.
- *Columns of some formats*: the fixed-width formats also need ``direction`` (1 or 2). Optional, with the value
  written where the column is absent or NaN: ``n_groups`` (MON only) -> counted: 1 + the spacings as written wider
  than ``GROUP_SPACING_M`` (2.0 m; the rule of ``groups.axle_groups``); ``axle_width_1..n`` [m] (DITIS only) -> 0,
  which this project takes as "not given" (an assumption: the reference has no missing value). CSV writes only its
  layout's columns: ``speed`` NaN and ``lane`` -1 or NaN are written blank.
- *Fixed-width records*: every field zero-padded, right-aligned at its offset; one record a line ending in ``\\n``,
  ASCII; each line ends with its last axle's fields and the (unused) spacing slot after the last axle, written as
  zeros. MON's direction is written ``direction - 1`` (zero-based), BeDIT's too, CASTOR's and DITIS's as 1 or 2.
- *CSV*: header ``timestamp,speed_kmh,lane,n_axles,axle_load_1..N,spacing_1..N-1`` (N the table's largest axle
  count, 1-based), ``timestamp`` ISO 8601 without zone (``Timestamp.isoformat()``), numbers as ``repr(float)`` (the
  shortest text that reads back to the same float), speed in km/h (``speed * 3.6``), cells past a vehicle's axles
  blank.
- *TMG* (``tmg2001``, ``tmg2013``): needs ``station`` ('SS-XXXXXX': state FIPS code and station ID),
  ``vehicle_class`` (1-15), ``lane`` (0-9) and ``direction`` (1-8, the guide's compass codes); the time is written
  as the beginning of its hour, no speed or length, the open field blank, numbers right-justified with leading
  blanks, the record ending with the last axle's weight.
"""

from __future__ import annotations

import gzip
import math
import os
import secrets
from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings._tmg import TMG_LAYOUTS, TMG_MAX_AXLES, TMG_VEHICLE_CLASSES, TmgLayout
from bogie.weighings._write_values import (
    _TIME_STEP_NS,
    TWO_DIGIT_YEARS,
    _axle_counts,
    _axle_values,
    _coded,
    _column,
    _heads,
    _optional,
    _require,
    _round_half_away,
    _rows,
    _scaled,
    _timestamps,
    _val,
)
from bogie.weighings.formats import FORMATS, LAYOUTS, Field, FixedWidthLayout
from bogie.weighings.groups import GROUP_SPACING_M
from bogie.weighings.readers import CSV_MAX_AXLES, YEAR_RANGE

__all__ = ["CSV_MAX_AXLES", "TWO_DIGIT_YEARS", "write_weighings"]


# ---- fixed width ---------------------------------------------------------------------------------------------------
def _time_fields(stamps: pd.DatetimeIndex, fmt: str, layout: FixedWidthLayout) -> dict[str, np.ndarray]:
    """Calendar and time fields of the timestamps rounded to the format's resolution (a tie to the later time)."""
    step = _TIME_STEP_NS[fmt]
    try:
        ns = stamps.as_unit("ns").asi8  # pandas keeps the unit it was given (the reader's: us)
    except (OverflowError, ValueError):
        years = np.asarray(stamps.year)
        bad = np.flatnonzero((years < 1678) | (years > 2261))
        raise ValueError(
            f"{fmt}: timestamp = {stamps[bad[0]].isoformat()} in {_rows(bad)} is outside the years 1678-2261 the "
            "writer handles"
        ) from None
    # floor division: a half rounds up, to the later time
    rounded = pd.DatetimeIndex(((ns + step // 2) // step) * step, dtype="datetime64[ns]")
    year = rounded.year.to_numpy()
    if layout.year_digits == 2:
        low, high = TWO_DIGIT_YEARS
        bad = np.flatnonzero((year < low) | (year > high))
        if len(bad):
            raise ValueError(
                f"{fmt}: timestamp = {stamps[bad[0]].isoformat()} in {_rows(bad)} does not fit its field "
                f"(years {low}-{high}: a two-digit year, read with the POSIX %y pivot 69-99 -> 19xx, 00-68 -> 20xx)"
            )
        year = year % 100
    else:
        bad = np.flatnonzero(year > 10**layout.year_digits - 1)  # numerics-ok: integers
        if len(bad):
            raise ValueError(f"{fmt}: timestamp = {stamps[bad[0]].isoformat()} in {_rows(bad)}: year too large")
    sub_ns = (rounded.asi8 % 1_000_000_000).astype(np.int64)
    second = rounded.second.to_numpy()
    fields = {
        "day": rounded.day.to_numpy(), "month": rounded.month.to_numpy(), "year": year,
        "hour": rounded.hour.to_numpy(), "minute": rounded.minute.to_numpy(), "second": second,
        "second_100": sub_ns // 10_000_000, "millisecond": second * 1000 + sub_ns // 1_000_000,
    }  # fmt: skip
    return {k: np.asarray(v, dtype=np.int64) for k, v in fields.items()}


def _fixed_lines(vehicles: pd.DataFrame, fmt: str) -> list[str]:
    layout = LAYOUTS[fmt]
    header = {f.name: f for f in layout.header}
    stamps = _timestamps(vehicles, fmt)
    n = _axle_counts(vehicles, fmt, min(layout.max_axles, 10 ** header["n_axles"].width - 1))  # numerics-ok: integers
    direction = _coded(vehicles, fmt, "direction", "1 or 2", lambda d: (d == 1) | (d == 2))
    lane_top = 10 ** header["lane"].width - 1  # numerics-ok: integers
    lane = _coded(vehicles, fmt, "lane", f"1-{lane_top}, 1-based", lambda v: (v >= 1) & (v <= lane_top))
    _require(vehicles, fmt, "speed")
    axle_ints = _axle_ints(vehicles, fmt, layout, n)
    values = _time_fields(stamps, fmt, layout)
    values.update(n_axles=n, direction=direction - 1 + layout.direction_base, lane=lane)
    values.update(_header_values(vehicles, fmt, layout, n, axle_ints))
    return _text(fmt, layout, values, axle_ints, n)


def _axle_ints(vehicles: pd.DataFrame, fmt: str, layout: FixedWidthLayout, n: np.ndarray) -> dict[str, np.ndarray]:
    """The per-axle fields as written (integers), NaN-free: (rows, n_max) each."""
    block = {f.name: f for f in layout.axles.fields}
    loads = _axle_values(vehicles, fmt, "axle_load", n, n)
    spacings = _axle_values(vehicles, fmt, "spacing", n, n - 1)
    axle_ints: dict[str, np.ndarray] = {}
    for name, si, count in (("axle_load", loads, n), ("spacing", spacings, n - 1)):
        ints = np.zeros(si.shape, dtype=np.int64)
        for i in range(si.shape[1]):
            rows = np.flatnonzero(count > i)
            ints[rows, i] = _scaled(fmt, f"{name}_{i + 1}", si[rows, i], block[name], rows)
        axle_ints[name] = ints
    if "axle_width" in block:  # DITIS: 0 (not given, our assumption) where absent or NaN
        widths = np.zeros(loads.shape, dtype=np.int64)
        for i in range(loads.shape[1]):
            rows = np.flatnonzero(n > i)
            si = _optional(vehicles, f"axle_width_{i + 1}", 0.0)[rows]
            widths[rows, i] = _scaled(fmt, f"axle_width_{i + 1}", si, block["axle_width"], rows)
        axle_ints["axle_width"] = widths
    return axle_ints


def _header_values(
    vehicles: pd.DataFrame, fmt: str, layout: FixedWidthLayout, n: np.ndarray, axle_ints: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """The header fields but the time, the axle count, direction and lane, as written (integers)."""
    header = {f.name: f for f in layout.header}
    block = {f.name: f for f in layout.axles.fields}
    nrows = len(vehicles)
    everyone = np.arange(nrows)
    values = {
        "head": _scaled(fmt, "head", _heads(vehicles, fmt), header["head"], everyone),
        "speed": _scaled(fmt, "speed", _column(vehicles, "speed"), header["speed"], everyone),
    }
    for name in ("length", "transverse_position"):  # 0: not given
        values[name] = _scaled(fmt, name, _optional(vehicles, name, 0.0), header[name], everyone)
    # gross weight: where absent or NaN, the sum of the axle loads as written (so the reader's check holds)
    summed = axle_ints["axle_load"].sum(axis=1) * block["axle_load"].scale
    gross = _optional(vehicles, "gross_weight", math.nan)
    gross = np.where(np.isnan(gross), summed, gross)
    values["gross_weight"] = _scaled(fmt, "gross_weight", gross, header["gross_weight"], everyone)
    if "n_groups" in header:  # MON: counted from the spacings as written where absent or NaN
        written = axle_ints["spacing"] * block["spacing"].scale
        counted = 1 + np.sum((written > GROUP_SPACING_M) & (np.arange(written.shape[1]) < (n - 1)[:, None]), axis=1)
        given = _column(vehicles, "n_groups") if "n_groups" in vehicles.columns else np.full(nrows, np.nan)
        groups = np.where(np.isnan(given), counted, given)
        bad = np.flatnonzero(groups != np.round(groups))
        if len(bad):
            raise ValueError(f"{fmt}: n_groups = {_val(groups[bad[0]])} in {_rows(bad)} is not a whole number")
        values["n_groups"] = _scaled(fmt, "n_groups", groups, header["n_groups"], everyone)
    return values


def _text(fmt: str, layout: FixedWidthLayout, values: dict, axle_ints: dict, n: np.ndarray) -> list[str]:
    """The records: zero-padded, right-aligned fields; the spacing slot after the last axle written as zeros. Every
    header value is checked to fit its field first."""
    for f in layout.header:
        top = 10**f.width - 1  # numerics-ok: integers
        bad = np.flatnonzero((values[f.name] < 0) | (values[f.name] > top))
        if len(bad):  # calendar fields and codes; the scaled ones are checked above
            raise ValueError(
                f"{layout.name}: {f.name} = {values[f.name][bad[0]]} in {_rows(bad)} does not fit its field"
            )
    header_text = [[f"{v:0{f.width}d}" for v in values[f.name].tolist()] for f in sorted(layout.header, key=_start)]
    heads = ["".join(parts) for parts in zip(*header_text)] if len(n) else []
    ordered = sorted(layout.axles.fields, key=_start)
    lines = []
    for j in range(len(n)):
        parts = [heads[j]]
        for i in range(int(n[j])):
            parts.extend(f"{int(axle_ints[f.name][j, i]) if i < axle_ints[f.name].shape[1] else 0:0{f.width}d}"
                         for f in ordered)  # fmt: skip
        lines.append("".join(parts))
    return lines


def _start(field: Field) -> int:
    return field.start


def _check_contiguous(layout: FixedWidthLayout) -> None:
    """The writer concatenates the fields in offset order: every layout must leave no gap and no overlap."""
    at = 0
    for f in sorted(layout.header, key=_start):
        if f.start != at:
            raise AssertionError(f"{layout.name}: header field {f.name} at {f.start}, expected {at}")
        at = f.end
    at = 0
    for f in sorted(layout.axles.fields, key=_start):
        if f.start != at:
            raise AssertionError(f"{layout.name}: axle field {f.name} at {f.start}, expected {at}")
        at = f.end
    if layout.fixed_width != layout.axles.start or at != layout.axles.stride:
        raise AssertionError(f"{layout.name}: header or axle block width differs from its start or stride")


# ---- CSV -----------------------------------------------------------------------------------------------------------
def _csv_lines(vehicles: pd.DataFrame) -> list[str]:
    fmt = "csv"
    stamps = _timestamps(vehicles, fmt)
    n = _axle_counts(vehicles, fmt, CSV_MAX_AXLES)
    _require(vehicles, fmt, "speed")
    _require(vehicles, fmt, "lane")
    speed = _column(vehicles, "speed")
    lane = _column(vehicles, "lane")
    lane = np.where(lane == -1, np.nan, lane)  # -1: not given, written blank
    bad = np.flatnonzero(~np.isnan(lane) & ((lane < 1) | (lane != np.round(lane)) | np.isinf(lane)))
    if len(bad):
        raise ValueError(f"csv: lane = {_val(lane[bad[0]])} in {_rows(bad)} is not allowed (1-based; -1 or NaN blank)")
    bad = np.flatnonzero((speed < 0) | np.isinf(speed))
    if len(bad):
        raise ValueError(
            f"csv: speed = {_val(speed[bad[0]])} m/s in {_rows(bad)} is not allowed (0 or more; NaN blank)"
        )
    loads = _axle_values(vehicles, fmt, "axle_load", n, n)
    spacings = _axle_values(vehicles, fmt, "spacing", n, n - 1)
    for prefix, si, count, unit in (("axle_load", loads, n, "kg"), ("spacing", spacings, n - 1, "m")):
        for i in range(si.shape[1]):
            rows = np.flatnonzero(count > i)
            values = si[rows, i]
            for mask, why in ((np.isnan(values), "is not given (NaN)"), (~(values >= 0), "is not allowed")):
                where = np.flatnonzero(mask)
                if len(where):
                    raise ValueError(
                        f"csv: {prefix}_{i + 1} = {_val(values[where[0]])} {unit} in {_rows(rows[where])} {why} "
                        f"(a finite number, 0 or more, {unit})"
                    )
    width = int(n.max(initial=2))
    header = ["timestamp", "speed_kmh", "lane", "n_axles"]
    header += [f"axle_load_{i}" for i in range(1, width + 1)] + [f"spacing_{i}" for i in range(1, width)]
    lines = [",".join(header)]
    for j in range(len(vehicles)):
        k = int(n[j])
        cells = [
            stamps[j].isoformat(),
            "" if np.isnan(speed[j]) else repr(float(speed[j] * 3.6)),
            "" if np.isnan(lane[j]) else str(int(lane[j])),
            str(k),
            *(repr(float(x)) for x in loads[j, :k]),
            *([""] * (width - k)),
            *(repr(float(x)) for x in spacings[j, : k - 1]),
            *([""] * (width - k)),
        ]
        lines.append(",".join(cells))
    return lines


# ---- the file ------------------------------------------------------------------------------------------------------
# ---- the US truck weight record ------------------------------------------------------------------------------------
def _tmg_field(fmt: str, name: str, values: np.ndarray, unit: float, width: int, unit_name: str) -> np.ndarray:
    """SI ``values`` as the integers of a TMG field of ``width`` digits in ``unit`` (SI per unit), range-checked."""
    q = _round_half_away(values / unit)
    top = 10**width - 1  # numerics-ok: integers
    for bad, why in ((np.isnan(q), "is not given (NaN)"), ((q < 0) | (q > top), "does not fit its field")):
        where = np.flatnonzero(bad)
        if len(where):
            raise ValueError(f"{fmt}: {name} = {_val(values[where[0]])} in {_rows(where)} {why} (0-{top} "
                             f"{unit_name}, {width} digits)")  # fmt: skip
    return q.astype(np.int64)


def _stations(vehicles: pd.DataFrame, fmt: str) -> list[tuple[int, str]]:
    """The ``station`` column ('SS-XXXXXX': the state's 2-digit FIPS code and a station ID of 1-6 letters and
    digits, as the reader writes it) as (state, ID)."""
    _require(vehicles, fmt, "station")
    out = []
    for j, value in enumerate(vehicles["station"].tolist()):
        text = value if isinstance(value, str) else ""
        state, dash, ident = text.partition("-")
        if not (dash and len(state) == 2 and state.isdigit() and 1 <= len(ident) <= 6 and ident.isascii()
                and ident.isalnum()):  # fmt: skip
            raise ValueError(f"{fmt}: station = {value!r} in row {j} is not 'SS-XXXXXX' (the state's 2-digit FIPS "
                             "code, a dash, a station ID of 1-6 letters and digits)")  # fmt: skip
        out.append((int(state), ident))
    return out


def _tmg_lines(vehicles: pd.DataFrame, fmt: str) -> list[str]:
    """The W records of the table in TMG edition ``fmt`` (the reference's layout; ``_tmg.TMG_LAYOUTS``)."""
    layout: TmgLayout = TMG_LAYOUTS[fmt]
    stamps = _timestamps(vehicles, fmt).floor("h")  # the beginning of the hour the vehicle passed in
    years = stamps.year.to_numpy()
    low, high = YEAR_RANGE if layout.year_digits == 2 else (1000, 9999)
    bad = np.flatnonzero((years < low) | (years > high))
    if len(bad):
        raise ValueError(f"{fmt}: timestamp year {years[bad[0]]} in {_rows(bad)} outside {low}-{high}")
    n = _axle_counts(vehicles, fmt, TMG_MAX_AXLES)
    lane = _coded(vehicles, fmt, "lane", "0-9: 0 lanes combined, 1 the outside lane", lambda v: (v >= 0) & (v <= 9))
    direction = _coded(vehicles, fmt, "direction", "1-8, the guide's compass codes", lambda v: (v >= 1) & (v <= 8))
    lo, hi = TMG_VEHICLE_CLASSES
    cls = _coded(vehicles, fmt, "vehicle_class", f"{lo}-{hi}", lambda v: (v >= lo) & (v <= hi))
    stations = _stations(vehicles, fmt)
    unit_name = "lb" if layout.weight_base == "lb" else "x 100 kg"
    spacing_name = "0.1 ft" if layout.weight_base == "lb" else "0.1 m"
    loads = _axle_values(vehicles, fmt, "axle_load", n, n)
    spacings = _axle_values(vehicles, fmt, "spacing", n, n - 1)
    w = np.zeros(loads.shape, np.int64)
    s = np.zeros(spacings.shape, np.int64)
    for i in range(loads.shape[1]):
        rows = np.flatnonzero(n > i)
        w[rows, i] = _tmg_field(fmt, f"axle_load_{i + 1}", loads[rows, i], layout.weight_unit_kg,
                                layout.weight_width, unit_name)  # fmt: skip
    for i in range(spacings.shape[1]):
        rows = np.flatnonzero(n - 1 > i)
        s[rows, i] = _tmg_field(fmt, f"spacing_{i + 1}", spacings[rows, i], layout.spacing_unit_m,
                                layout.spacing_width, spacing_name)  # fmt: skip
    written_sum = (w * (np.arange(w.shape[1])[None, :] < n[:, None])).sum(axis=1).astype(float) * layout.weight_unit_kg
    gross = _optional(vehicles, "gross_weight", np.nan)
    gross = np.where(np.isnan(gross), written_sum, gross)
    g = _tmg_field(fmt, "gross_weight", gross, layout.weight_unit_kg, layout.gross_weight[1], unit_name)
    out = []
    yw = layout.year_digits
    for j in range(len(vehicles)):
        state, ident = stations[j]
        stamp = stamps[j]
        year = stamp.year % 100 if yw == 2 else stamp.year
        text = (f"W{state:02d}{ident:>6}{direction[j]}{lane[j]}{year:0{yw}d}{stamp.month:02d}{stamp.day:02d}"
                f"{stamp.hour:02d}{cls[j]:2d}   {g[j]:{layout.gross_weight[1]}d}{n[j]:2d}")  # fmt: skip
        for i in range(n[j]):
            text += f"{w[j, i]:{layout.weight_width}d}"
            if i < n[j] - 1:
                text += f"{s[j, i]:{layout.spacing_width}d}"
        out.append(text)
    return out


def _write_atomically(path: Path, data: bytes) -> None:
    """``data`` to ``path`` through a temporary file in the same folder and ``os.replace``; no file left on error."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, as for open()
    try:
        with os.fdopen(descriptor, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def _format_lines(vehicles: pd.DataFrame, fmt: str) -> tuple[list[str], int]:
    """The lines of the file of ``vehicles`` (index reset) in format ``fmt``, and how many are records."""
    if fmt == "csv":
        lines = _csv_lines(vehicles)
        count = len(lines) - 1
    elif fmt in TMG_LAYOUTS:
        lines = _tmg_lines(vehicles, fmt)
        count = len(lines)
    else:
        _check_contiguous(LAYOUTS[fmt])
        lines = _fixed_lines(vehicles, fmt)
        count = len(lines)
    return lines, count


def write_weighings(vehicles: pd.DataFrame, path: str | Path, fmt: str) -> int:
    """Write a vehicle table as a file of weighings in format ``fmt`` (the inverse of ``read_weighings``).

    Every value is converted from SI to its field's unit (divided by the field's scale), rounded to the nearest
    integer, a half away from zero (after rounding the quotient to 6 decimals, so that 0.45 m is 4.5 dm, not
    4.4999999999999991), and checked against the field's range 0 to 10**width - 1. Times are rounded to the
    format's resolution (a half to the later time; per format in the module docstring), the date carried
    (23:59:59.996 on 31 December is 00:00:00.00 on 1 January). The whole table is checked before anything is
    written; the file is written atomically (a temporary file in the same folder, then ``os.replace``), so an
    error leaves neither a partial file nor a temporary one. The same table gives the same bytes every time.

    Parameters
    ----------
    vehicles
        The vehicle table of :func:`bogie.weighings.readers.read_weighings` (any index; row numbers in messages
        are 0-based positions, ``vehicles.iloc[row]``). Required: ``timestamp`` (no time zone; local time),
        ``speed`` [m/s], ``lane`` (1-based), ``n_axles`` (2 to the format's limit), ``axle_load_1..n`` [kg] and
        ``spacing_1..n-1`` [m] (1-based, front first; cells past a row's axles are ignored), and the format's own
        columns (the module docstring, "Per format"). Optional, with the value written where the column is absent
        or NaN: ``gross_weight`` [kg] -> the sum of the axle loads as written (the rounded loads, in the field's
        unit); ``length`` [m] -> 0 (the reader's "not given"); ``transverse_position`` [m] -> 0; ``head`` (an
        integer, or a string of digits) -> 0, also for '' (the CSV reader's head); MON's ``n_groups`` and DITIS's
        ``axle_width_1..n`` (the module docstring).
    path
        The file to write, replaced if it exists. A name ending in ``.gz`` is written gzip-compressed, with
        modification time 0 and no file name in the gzip header (byte-reproducible).
    fmt
        ``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``, ``tmg2001`` or ``tmg2013`` (layouts in
        ``docs/weighings.md``; what each needs and how it is written: the module docstring, "Per format").

    Returns
    -------
    int
        The number of records (vehicles) written [-].

    Raises
    ------
    ValueError
        For an unknown format, a missing required column, or a value that does not fit its field (negative,
        NaN without a default, too large, a year outside 1969-2068 for CASTOR and BeDIT, fewer than 2 or more
        than the format's axles, ``direction`` or ``lane`` -1 (not given) for a fixed-width format, a timestamp
        with a time zone, a head that is not an integer): the message names the format, the column, the first
        offending row (and how many rows, with the first few), the value, the allowed range and the unit.
    OSError
        If the file cannot be written.
    """
    if fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} unknown; allowed: {', '.join(FORMATS)}")
    if not isinstance(vehicles, pd.DataFrame):
        raise TypeError(f"vehicles: expected a pandas DataFrame, got {type(vehicles).__name__}")
    lines, count = _format_lines(vehicles.reset_index(drop=True), fmt)
    data = "".join(line + "\n" for line in lines).encode("ascii")
    path = Path(path)
    if path.name.lower().endswith(".gz"):
        data = gzip.compress(data, mtime=0)  # no file name in the header; mtime 0: byte-reproducible
    _write_atomically(path, data)
    return count
