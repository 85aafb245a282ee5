"""The CSV reader of weighings (the project's documented layout, :data:`bogie.weighings.formats.CSV_COLUMNS`), in
bulk: every cell located with one pass over the bytes, numbers and dates parsed column by column. Private:
:func:`bogie.weighings.readers.read_weighings` is the entry point.
"""

from __future__ import annotations

import csv

import numpy as np

from bogie.weighings._records import (
    BAD_DATE,
    CSV_LANE_RANGE,
    CSV_MAX_AXLES,
    NO_AXLES,
    NON_NUMERIC,
    _check_calendar,
    _Lines,
    _Reasons,
    _shown,
    _timestamps,
)
from bogie.weighings.formats import CSV_COLUMNS, KMH

#: 10^k for the decimal places a field may have (at most 15 digits), exact: 10^k is a float up to k = 22
_POWERS_OF_TEN = np.array([float(10**k) for k in range(16)])  # numerics-ok: Python integers, exact

#: an ISO 8601 local date and time, character by character: the positions of the date's and the time's digits and
#: separators (``YYYY-MM-DD``, then ``[T ]HH:MM``, ``:SS``, ``[.,]fraction`` of 1-9 digits)
_DATE_DIGITS = (0, 1, 2, 3, 5, 6, 8, 9)


def _iso_local(cells: np.ndarray, too_long: np.ndarray, reasons: _Reasons) -> np.ndarray:
    """The datetime64[us] of each ISO 8601 local time of ``cells`` (byte strings), NaT where none; flags a time
    zone, anything else (*invalid date or time*), a date that does not exist and a year outside
    :data:`YEAR_RANGE`, with the calendar check of the fixed-width formats. A fraction finer than a microsecond is
    cut to microseconds."""
    width = max(cells.dtype.itemsize, 28)
    chars = np.zeros((len(cells), width), np.uint8)
    if cells.dtype.itemsize:
        chars[:, : cells.dtype.itemsize] = cells.view(np.uint8).reshape(len(cells), cells.dtype.itemsize)
    length = np.char.str_len(cells)
    digit = (chars - np.uint8(48)) < 10

    def number(first: int, last: int) -> np.ndarray:
        value = np.zeros(len(cells), np.int64)
        for j in range(first, last):
            value = value * 10 + (chars[:, j].astype(np.int64) - 48)
        return value

    date = digit[:, list(_DATE_DIGITS)].all(axis=1) & (chars[:, 4] == 45) & (chars[:, 7] == 45)
    clock = np.isin(chars[:, 10], (84, 32)) & digit[:, [11, 12, 14, 15]].all(axis=1) & (chars[:, 13] == 58)
    seconds = (chars[:, 16] == 58) & digit[:, [17, 18]].all(axis=1)
    fraction_digits = np.clip(length - 20, 0, None)
    fraction = np.isin(chars[:, 19], (46, 44)) & (fraction_digits >= 1) & (fraction_digits <= 9)
    after = np.arange(width)[None, :]
    fraction &= (digit | (after < 20) | (after >= length[:, None])).all(axis=1)
    valid = (
        ~too_long & date & ((length == 10) | (clock & (length == 16)) | (clock & seconds & ((length == 19) | fraction)))
    )
    zoned = ~valid & ~too_long & date & clock & (length > 16) & (
        (chars[np.arange(len(cells)), np.maximum(length - 1, 0)] == 90)
        | np.isin(chars[:, 16:], (43, 45)).any(axis=1)
    )  # fmt: skip
    reasons.flag(zoned, "time zone in a timestamp (write the local time, as the fixed-width formats do)")
    reasons.flag(~valid, BAD_DATE)
    has_time = valid & (length >= 16)
    has_seconds = valid & (length >= 19)
    micro = np.zeros(len(cells), np.int64)
    for j in range(6):  # the fraction's first six digits; missing ones are 0
        micro = micro * 10 + np.where(fraction & (j < fraction_digits), chars[:, 20 + j].astype(np.int64) - 48, 0)
    microsecond = np.where(has_seconds, number(17, 19), 0) * 1_000_000 + np.where(fraction, micro, 0)
    year, month, day = number(0, 4), number(5, 7), number(8, 10)
    hour, minute = np.where(has_time, number(11, 13), 0), np.where(has_time, number(14, 16), 0)
    _check_calendar(reasons, np.where(valid, year, 2000), np.where(valid, month, 1), np.where(valid, day, 1),
                    hour, minute, microsecond)  # fmt: skip
    return _timestamps(reasons.ok, year, month, day, hour, minute, microsecond)


def _csv_header(header: list[str], path: str) -> dict[str, int]:
    columns = {name.strip(): i for i, name in enumerate(header)}
    missing = [c for c in (*CSV_COLUMNS, "axle_load_1", "axle_load_2", "spacing_1") if c not in columns]
    if missing:
        raise ValueError(
            f"{path}: not the CSV layout (format csv): the header lacks {', '.join(missing)}; expected columns "
            f"{', '.join(CSV_COLUMNS)}, axle_load_1..n [kg], spacing_1..n-1 [m]; found {_shown(','.join(header))}"
        )
    return columns


def _decimals(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Plain decimals (``[+-]digits[.digits]``, at most 15 digits) of a byte-string array, in one pass per
    character: (value, whether the cell is one). The value is the integer of its digits over a power of ten, both
    exact in binary, so the division rounds it correctly: the float Python's ``float()`` gives, bit for bit."""
    width = cells.dtype.itemsize
    chars = cells.view(np.uint8).reshape(len(cells), width) if width else np.zeros((len(cells), 0), np.uint8)
    whole = np.zeros(len(cells), np.int64)
    places = np.zeros(len(cells), np.int64)
    digits = np.zeros(len(cells), np.int64)
    dots = np.zeros(len(cells), np.int64)
    ended = np.zeros(len(cells), bool)  # past the cell's last byte (numpy pads with NUL)
    ok = np.ones(len(cells), bool)
    negative = chars[:, 0] == 45 if width else np.zeros(len(cells), bool)
    for j in range(width):
        c = chars[:, j]
        digit = c - np.uint8(48)
        is_digit = (digit < 10) & ~ended
        is_dot = (c == 46) & ~ended
        sign = (j == 0) & np.isin(c, (43, 45))
        nul = c == 0
        ok &= is_digit | is_dot | sign | nul
        ok &= ~(ended & ~nul)  # nothing after a NUL
        ended |= nul
        whole = np.where(is_digit, whole * 10 + digit, whole)
        places += is_digit & (dots > 0)
        digits += is_digit
        dots += is_dot
    ok &= (digits >= 1) & (digits <= 15) & (dots <= 1)
    # exact, not numpy's power; a cell of more than 15 digits (places past the table) is not ok already
    value = np.where(negative, -1.0, 1.0) * whole / _POWERS_OF_TEN[np.minimum(places, len(_POWERS_OF_TEN) - 1)]
    return value, ok


def _numbers(cells: np.ndarray, too_long: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The float of each cell (byte strings), whether it is blank, and whether it is a finite number (blank: not).

    Plain decimals in bulk (:func:`_decimals`); any other cell (an exponent, ``nan``, a letter) as numpy reads a
    byte string (Python's ``float()``), one by one; a cell longer than :data:`_CELL_MAX` is not a number."""
    stripped = np.char.strip(cells)
    blank = (stripped == b"") & ~too_long
    value, plain = _decimals(stripped)
    for k in np.flatnonzero(~plain & ~blank & ~too_long):
        try:
            value[k] = stripped[k : k + 1].astype(np.float64)[0]
        except ValueError:
            value[k] = np.nan
    value[blank | too_long] = np.nan
    return value, blank, np.isfinite(value)


#: the longest CSV cell read as a number or a time [characters]; a longer one is a non-numeric field
_CELL_MAX = 40


def _count_per_line(lines: _Lines, byte: int) -> np.ndarray:
    """How many times ``byte`` occurs in each line ``[start, end)`` (located, not scanned line by line)."""
    m = len(lines)
    counts = np.zeros(m, np.int64)
    for a in range(0, m, _CHUNK_LINES):  # in chunks of lines: the positions of a byte take 8 bytes each
        b = min(a + _CHUNK_LINES, m)
        first = lines.start[a]
        where = np.flatnonzero(lines.buf[first : lines.end[b - 1]] == byte) + first
        row = np.searchsorted(lines.start[a:b], where, side="right") - 1
        inside = (row >= 0) & (where < lines.end[a:b][np.maximum(row, 0)])
        counts[a:b] = np.bincount(row[inside], minlength=b - a)
    return counts


#: lines per chunk of :func:`_count_per_line` [-]
_CHUNK_LINES = 100_000


class _Cells:
    """The cells of a CSV body, one column at a time as a byte-string array of one entry per line (b'' for a line
    that is not a row of the header's width).

    Lines without a quote and with the header's number of commas (all of them, in a clean file) are cut at their
    commas in bulk; a line with a quote is parsed by the csv module, alone (an unclosed quote or a field over its
    128 KiB limit: unreadable)."""

    def __init__(self, data: bytes, body: _Lines, width: int) -> None:
        m = len(body)
        self.body, self.width = body, width
        quoted = _count_per_line(body, 34) > 0
        # one pass over the commas, in chunks of lines: each line's count (the header's width makes a simple row) and
        # the places of a simple row's commas, from its start [bytes]: (simple rows, width - 1)
        self.simple = np.zeros(m, bool)
        parts = []
        for a in range(0, m, _CHUNK_LINES):
            b = min(a + _CHUNK_LINES, m)
            where = np.flatnonzero(body.buf[body.start[a] : body.end[b - 1]] == 44) + body.start[a]
            row = np.searchsorted(body.start[a:b], where, side="right") - 1 + a
            inside = where < body.end[row]
            where, row = where[inside], row[inside]
            self.simple[a:b] = ~quoted[a:b] & (np.bincount(row - a, minlength=b - a) == width - 1)
            keep = self.simple[row]
            parts.append((where[keep] - body.start[row[keep]]).astype(np.int32).reshape(-1, max(width - 1, 0)))
        self.commas = np.concatenate(parts) if parts else np.zeros((0, max(width - 1, 0)), np.int32)
        self.rows = np.flatnonzero(self.simple)
        self.unreadable = np.zeros(m, bool)
        self.right = self.simple.copy()
        self.quoted_rows: dict[int, list[str]] = {}
        for k in np.flatnonzero(quoted):
            try:
                row = next(csv.reader([body.text(k)]))
            except csv.Error:
                self.unreadable[k] = True
                continue
            if len(row) == width:
                self.quoted_rows[int(k)] = row
                self.right[k] = True

    def __call__(self, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Column ``j``: its cells as byte strings (at most :data:`_CELL_MAX` long) and which cells are longer."""
        body, rows = self.body, self.rows
        m = len(body)
        start = body.start[rows] + (self.commas[:, j - 1] + 1 if j > 0 else 0)
        end = body.start[rows] + self.commas[:, j] if j < self.width - 1 else body.end[rows]
        length = end - start
        too_long = np.zeros(m, bool)
        too_long[rows] = length > _CELL_MAX
        quoted = {k: row[j].encode("utf-8", errors="replace") for k, row in self.quoted_rows.items()}
        for k, cell in quoted.items():
            too_long[k] = len(cell) > _CELL_MAX
        width = int(min(max(length.max(initial=0), *(len(c) for c in quoted.values()), 1), _CELL_MAX))
        offsets = np.arange(width)
        gathered = body.buf[np.minimum(start[:, None] + offsets, len(body.buf) - 1)]
        gathered[offsets[None, :] >= length[:, None]] = 0
        if len(rows) == m:
            chars = gathered
        else:
            chars = np.zeros((m, width), np.uint8)
            chars[rows] = gathered
        for k, cell in quoted.items():
            chars[k, : min(len(cell), width)] = np.frombuffer(cell[:width], np.uint8)
        return chars.view(f"S{width}").ravel(), too_long


def _axle_count(n_axles: tuple[np.ndarray, np.ndarray, np.ndarray], reasons: _Reasons) -> np.ndarray:
    """Each record's number of axles (0 for a bad record); flags a bad or implausible one."""
    n_value, _, n_ok = n_axles
    reasons.flag(~n_ok | (n_value != np.round(n_value)), NON_NUMERIC)
    n = np.where(reasons.ok, np.nan_to_num(n_value), 0).astype(np.int64)
    reasons.flag(reasons.ok & (n == 0), NO_AXLES)
    reasons.flag((n < 2) | (n > CSV_MAX_AXLES), f"implausible number of axles (allowed 2-{CSV_MAX_AXLES})")
    return np.where(reasons.ok, n, 0)


def _axle_cells(cells: _Cells, columns: dict[str, int], n: np.ndarray, reasons: _Reasons) -> tuple[dict, np.ndarray]:
    """The axle loads and spacings by axle (NaN past a record's axles) and which records have a cell that is not a
    number where an axle needs one; flags records with more axles than columns, or a value past their axles."""
    m = len(n)
    load_cols = sorted(int(c[10:]) for c in columns if c.startswith("axle_load_") and c[10:].isdigit())
    spacing_cols = sorted(int(c[8:]) for c in columns if c.startswith("spacing_") and c[8:].isdigit())
    have_loads = max((k for i, k in enumerate(load_cols, start=1) if k == i), default=0)  # 1..k all there
    have_spacings = max((k for i, k in enumerate(spacing_cols, start=1) if k == i), default=0)
    reasons.flag((n > have_loads) | (n - 1 > have_spacings), "more axles than the file has columns for")
    # each axle column read once: the cells past a vehicle's axles must be empty or 0, the others numbers
    width_axles = int(n.max()) if m and n.max() >= 2 else 2
    past = np.zeros(m, bool)
    values = {"axle_load": np.full((m, width_axles), np.nan), "spacing": np.full((m, width_axles - 1), np.nan)}
    not_number = np.zeros(m, bool)
    for name, ks, count in (("axle_load", load_cols, n), ("spacing", spacing_cols, n - 1)):
        for k in ks:
            cell, too_long = cells(columns[f"{name}_{k}"])
            value, blank, ok = _numbers(cell, too_long)
            past |= (count < k) & ~(blank | (value == 0.0))
            need = count >= k
            if k <= values[name].shape[1]:
                not_number |= need & ~ok
                values[name][:, k - 1] = np.where(need, value, np.nan)
    reasons.flag(past, "axle load or spacing past the number of axles")
    return values, not_number


def _parse_csv(data: bytes, lines: _Lines, path: str) -> dict:
    try:
        header_cells = next(csv.reader([lines.text(0)]))
    except csv.Error:
        header_cells = [lines.text(0)]
    columns = _csv_header(header_cells, path)
    body = lines.take(np.arange(1, len(lines)))
    line = body.line
    m = len(body)
    reasons = _Reasons(m)
    width = len(header_cells)
    cells = _Cells(data, body, width)
    reasons.flag(cells.unreadable, "unreadable CSV row (an unclosed quote or a huge field)")
    reasons.flag(~cells.right, "wrong length")

    def number(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _numbers(*cells(columns[name]))

    n = _axle_count(number("n_axles"), reasons)
    values, not_number = _axle_cells(cells, columns, n, reasons)
    # the timestamp: ISO 8601 local time, nothing else (no 'now', no 'today', no time zone)
    stamp_cells, stamp_long = cells(columns["timestamp"])
    stamps = _iso_local(np.char.strip(stamp_cells), stamp_long, reasons)
    lane, lane_blank, lane_ok = number("lane")
    reasons.flag(~lane_blank & ~lane_ok, NON_NUMERIC)
    lo, hi = CSV_LANE_RANGE
    bad_lane = ~lane_blank & lane_ok & ((lane != np.round(lane)) | (lane < lo) | (lane > hi))
    reasons.flag(bad_lane, f"implausible lane (allowed a whole number {lo}-{hi}, or empty)")
    speed, speed_blank, speed_ok = number("speed_kmh")
    reasons.flag(~speed_blank & ~speed_ok, NON_NUMERIC)
    reasons.flag(not_number, NON_NUMERIC)
    loads, spacings = values["axle_load"], values["spacing"]
    columns_out = {
        "head": np.full(m, "", object), "speed": np.where(speed_blank, np.nan, speed) * KMH,
        "gross_weight": np.full(m, np.nan), "length": np.full(m, np.nan), "n_axles": n,
        "n_groups": np.full(m, np.nan),
        # a lane outside 1-9 is a bad record already: clipped only so that the cast to integers is defined
        "lane": np.where(lane_blank | ~np.isfinite(lane), -1, np.clip(np.nan_to_num(lane), -1, 99)).astype(np.int64),
        "direction": np.full(m, -1, np.int64), "transverse_position": np.full(m, np.nan),
    }  # fmt: skip
    return {
        "reasons": reasons, "columns": columns_out, "loads": loads, "spacings": spacings, "widths": None,
        "stamps": stamps, "line": line, "gross_step": 0.0, "load_step": 0.0,
    }  # fmt: skip
