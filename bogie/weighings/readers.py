"""Readers of observed weighings: the documented CSV layout and the fixed-width WIM formats (``formats.py``).

:func:`read_weighings` returns one row per vehicle in SI units (kg, m, m/s) and the count of every record it
skipped, by reason, with the first few line numbers, and the file's weight resolution. A bad record (shorter than
its stated axles need, a character that is not a digit or a space, no axles, a direction code the format does not
have, a date that does not exist or an implausible year, an implausible weight, spacing, speed or lane, a gross
weight that is not the sum of the axles, a length shorter than the wheelbase, a repeat of an earlier record; a
longer line, padded past its stated axles, is normal) is skipped and counted, never silently; a file that is empty,
mostly bad (more than half its records) or in another format is refused with a :class:`ValueError` that names the
format expected and what was found. Layouts and bounds: ``docs/weighings.md``.

The bytes are parsed in bulk (issue 27 Must 5): the file is one numpy byte array, its records are located by their
line ends, and every field of every record is read with one gather per field (per axle slot for the axle fields),
never line by line in Python. Records end at ``\\n`` only (a trailing ``\\r`` is dropped): a form feed, a vertical tab
or a Unicode line separator inside a record is a bad character of that record, not a line end, so that line numbers
are those of any editor that counts ``\\n``. A file whose first two bytes are gzip's magic number is decompressed first.
"""

from __future__ import annotations

import csv
import gzip
import zlib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings.formats import CSV_COLUMNS, FORMATS, KMH, LAYOUTS, FixedWidthLayout

__all__ = [
    "AXLE_LOAD_RANGE", "CSV_LANE_RANGE", "CSV_MAX_AXLES", "MAX_AXLES", "MAX_BAD_FRACTION", "SNIFF_LINES",
    "SPACING_RANGE", "SPEED_RANGE", "WEIGHT_STEPS_KG", "YEAR_RANGE", "ReadResult", "detect_format", "read_weighings",
]  # fmt: skip

#: plausible axle load [kg]: from the unsprung mass of a light axle to 50 kips (22.7 t), above which Elkins and
#: Higgins (2008, quoted by OpenWIM) reject an axle as a WIM error; the EU's heaviest legal axle is 11.5 t
AXLE_LOAD_RANGE: tuple[float, float] = (100.0, 22_680.0)
#: plausible spacing of consecutive axles [m]: no two axles closer than a small tyre's diameter, none further
#: apart than a vehicle is long (the EU maximum length is 18.75 m, Directive 96/53/EC)
SPACING_RANGE: tuple[float, float] = (0.6, 18.75)
#: plausible speed [m/s]: 0 (a static weighbridge) to 160 km/h (Elkins and Higgins reject above 99 mph)
SPEED_RANGE: tuple[float, float] = (0.0, 160.0 * KMH)
#: plausible year of a record [-]: the hundred years a two-digit year can name under the POSIX ``%y`` rule (69-99
#: are 1969-1999, 00-68 are 2000-2068: strptime's pivot), applied to the four-digit years of MON, DITIS and CSV too,
#: so that a record reads the same in every format. Engineering judgement (an assumption: the reference has no
#: range); it refuses the year 2999 of a mistyped record (issue 27) and admits every WIM record since 1969
YEAR_RANGE: tuple[int, int] = (1969, 2068)
#: the two-digit year pivot: yy >= this is 19yy, below it 20yy (POSIX strptime ``%y``) [-]
TWO_DIGIT_PIVOT: int = 69
#: a CSV lane: a whole number 1-9, the range of the fixed-width formats' one-digit lane field, so that every CSV file
#: can be written in every format [-]
CSV_LANE_RANGE: tuple[int, int] = (1, 9)
#: most axles of one vehicle in any format [-] (MON's 2-digit count); each fixed-width format has its own limit too
#: (``FixedWidthLayout.max_axles``: CASTOR 9, BeDIT 20, DITIS 20, MON 99)
MAX_AXLES: int = 99
#: most axles of one vehicle in the CSV layout [-] (a plausibility bound: no road vehicle has more)
CSV_MAX_AXLES: int = 20
#: a file with more than this fraction of bad records is refused, not read [-]
MAX_BAD_FRACTION: float = 0.5
#: gross weight against the sum of the axle loads: allowed difference, a fraction of the sum plus half a weight
#: step for the gross weight and for each axle (a WIM system's gross weight is the sum of its axle weights,
#: Enright and OBrien 2011) [-]
GROSS_TOLERANCE: float = 0.02
#: the weight steps a file's resolution is detected among [kg]: the largest that divides every axle load of the
#: good records (MON files are seen at 10 kg and at 100 kg; CASTOR, BeDIT and DITIS write kg/100)
WEIGHT_STEPS_KG: tuple[int, ...] = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
#: line numbers of bad records shown per reason
EXAMPLES: int = 5
#: non-blank lines ``fmt="auto"`` tries every layout on [-]
SNIFF_LINES: int = 50

# reasons a record is bad (docs/weighings.md, "Bad records and refused files")
SHORT_HEADER = "record shorter than the header"
TOO_SHORT = "record too short for its stated axles"
NON_NUMERIC = "non-numeric field"
NO_AXLES = "no axles"
BAD_DATE = "invalid date or time"
DUPLICATE = "repeat of an earlier record (same time, lane, direction, speed, axle loads and spacings)"


@dataclass
class ReadResult:
    """What :func:`read_weighings` read.

    Attributes
    ----------
    vehicles
        One row per good record: ``line`` (1-based line of the file), ``head`` (an integer; '' in CSV),
        ``timestamp``, ``speed`` [m/s], ``gross_weight`` [kg], ``length`` [m] (NaN where the format has none),
        ``n_axles``, ``n_groups`` (MON's own count; NaN otherwise), ``lane`` (1-based; -1 not given),
        ``direction`` (1 or 2 in every format: a zero-based code, BeDIT's and MON's 0 or 1, plus 1; -1 not
        given), ``transverse_position`` [m] (NaN where not given), ``axle_load_0..`` [kg] (front first) and
        ``spacing_0..`` [m] (``spacing_i`` between axles i and i + 1), NaN past the vehicle's axles; DITIS also
        ``axle_width_0..`` [m].
    format
        The format read (``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``).
    skipped
        Bad records per reason.
    bad_lines
        The first :data:`EXAMPLES` line numbers of each reason.
    weight_step_kg
        The file's weight resolution [kg]: the largest of :data:`WEIGHT_STEPS_KG` that divides every axle load of
        the records that passed the checks before the gross weight's; None when the loads are not whole kilograms
        (a CSV file of other data) or no record has loads.
    format_step_kg
        The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None for
        CSV (decimal numbers).
    """

    vehicles: pd.DataFrame
    format: str
    skipped: Counter = field(default_factory=Counter)
    bad_lines: dict[str, list[int]] = field(default_factory=dict)
    weight_step_kg: float | None = None

    @property
    def format_step_kg(self) -> float | None:
        """The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None
        for CSV (decimal numbers)."""
        return None if self.format == "csv" else LAYOUTS[self.format].axle_field("axle_load").scale

    @property
    def n_read(self) -> int:
        """Good records [-]."""
        return len(self.vehicles)

    @property
    def n_skipped(self) -> int:
        """Bad records, skipped [-]."""
        return sum(self.skipped.values())

    def reasons(self) -> str:
        """Each reason a record was skipped, its count and first line numbers; '' if none was."""
        return "; ".join(
            f"{reason}: {n}, line{'s' if n > 1 else ''} {', '.join(map(str, self.bad_lines[reason]))}"
            + (", ..." if n > len(self.bad_lines[reason]) else "")
            for reason, n in self.skipped.most_common()
        )

    def resolution(self) -> str:
        """The weight resolution in words: the step, and whether it is the format's or coarser."""
        if self.weight_step_kg is None:
            return "weight resolution: none detected (axle loads not whole kilograms)"
        step = f"{self.weight_step_kg:g} kg"
        if self.format_step_kg is not None and self.weight_step_kg == self.format_step_kg:
            return f"weight resolution {step} (the format's unit)"
        return f"weight resolution {step} (every axle load read is a multiple of {step})"

    def summary(self) -> str:
        """One line: records read and skipped, each reason with its first line numbers."""
        text = f"{self.n_read} records read, {self.n_skipped} skipped"
        return text + (f" ({self.reasons()})" if self.skipped else "")


class _Reasons:
    """The first reason each record is bad (0: good), flagged check by check in the order of the checks."""

    def __init__(self, m: int) -> None:
        self.code = np.zeros(m, np.int16)
        self.names: list[str] = [""]

    @property
    def ok(self) -> np.ndarray:
        return self.code == 0

    def flag(self, mask: np.ndarray, reason: str) -> None:
        mask = np.asarray(mask, bool) & (self.code == 0)
        if mask.any():
            if reason not in self.names:
                self.names.append(reason)
            self.code[mask] = self.names.index(reason)

    def counted(self, line: np.ndarray) -> tuple[Counter, dict[str, list[int]]]:
        skipped: Counter = Counter()
        bad_lines: dict[str, list[int]] = {}
        for k, reason in enumerate(self.names[1:], start=1):
            where = np.flatnonzero(self.code == k)
            if len(where):
                skipped[reason] = len(where)
                bad_lines[reason] = [int(x) for x in line[where[:EXAMPLES]]]
        return skipped, bad_lines


# ---- the bytes of a file ---------------------------------------------------------------------------------------------
#: bytes a blank line may hold: tab, vertical tab, form feed, carriage return, space (and the line end)
_BLANK = np.zeros(256, bool)
_BLANK[[9, 10, 11, 12, 13, 32]] = True
#: bytes a fixed-width record may hold: ASCII digits, the space, the line end (a trailing carriage return apart)
_FIELD_BYTE = np.zeros(256, bool)
_FIELD_BYTE[[10, 32, *range(48, 58)]] = True
_GZIP_MAGIC = b"\x1f\x8b"
_BOM = b"\xef\xbb\xbf"


def _file_bytes(path: Path) -> bytes:
    """The file's bytes: gunzipped if it starts with gzip's magic number, without a UTF-8 byte order mark."""
    data = path.read_bytes()
    if data[:2] == _GZIP_MAGIC:
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError, zlib.error) as exc:
            raise ValueError(f"{path}: starts as a gzip file but does not decompress: {exc}") from None
    return data[3:] if data[:3] == _BOM else data


@dataclass
class _Lines:
    """The non-blank lines of a file: offsets ``[start, end)`` into ``buf`` (line end and trailing ``\\r`` not
    included) and their 1-based line numbers."""

    buf: np.ndarray
    start: np.ndarray
    end: np.ndarray
    line: np.ndarray

    def __len__(self) -> int:
        return len(self.start)

    def take(self, rows: np.ndarray) -> _Lines:
        return _Lines(self.buf, self.start[rows], self.end[rows], self.line[rows])

    def text(self, k: int) -> str:
        return self.buf[self.start[k] : self.end[k]].tobytes().decode("utf-8", errors="replace")


def _split(data: bytes) -> _Lines:
    buf = np.frombuffer(data, np.uint8)
    ends = np.flatnonzero(buf == 10)
    starts = np.concatenate(([0], ends + 1))
    ends = np.concatenate((ends, [len(buf)]))
    if starts[-1] == len(buf):  # the file ends with a line end (or is empty): no last line
        starts, ends = starts[:-1], ends[:-1]
    if not len(starts):
        return _Lines(buf, starts, ends, starts + 1)
    # segment i of reduceat is [start_i, start_i+1): line i and its line end
    mask = _BLANK[buf]
    np.logical_not(mask, out=mask)
    nonblank = np.logical_or.reduceat(mask, starts)
    del mask
    cr = (ends > starts) & (buf[np.maximum(ends - 1, 0)] == 13)
    ends = ends - cr
    keep = np.flatnonzero(nonblank)
    return _Lines(buf, starts[keep], ends[keep], keep.astype(np.int64) + 1)


def _head(data: bytes, n: int) -> bytes:
    """The first ``n`` non-blank lines of ``data``, without reading the rest."""
    lines, pos = [], 0
    while len(lines) < n and pos < len(data):
        end = data.find(b"\n", pos)
        end = len(data) if end < 0 else end
        line = data[pos:end]
        if line.strip(b" \t\r\x0b\x0c"):
            lines.append(line)
        pos = end + 1
    return b"\n".join(lines) + b"\n"


# ---- fixed width ---------------------------------------------------------------------------------------------------
#: a space's byte minus '0''s, wrapped around in uint8 (what :func:`_gather` sees for a space)
_SPACE_MINUS_ZERO = np.uint8(256 + 32 - 48)


def _gather(lines: _Lines, rows: np.ndarray, offset: np.ndarray | int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The unsigned integer ``line[offset:offset + width]`` of each line in ``rows`` and whether it is one:
    leading spaces, then ASCII digits only (no sign, no inner or trailing space, not all blank).

    One character column at a time (a gather of one byte per record), so that memory is a few arrays of the
    number of records, whatever the width."""
    pos = lines.start[rows] + offset
    value = np.zeros(len(rows), np.int64)
    seen = np.zeros(len(rows), bool)
    ok = np.ones(len(rows), bool)
    for j in range(width):
        digit = lines.buf[pos + j] - np.uint8(48)  # wraps around below '0': a digit is < 10
        is_digit = digit < 10
        ok &= is_digit | ((digit == _SPACE_MINUS_ZERO) & ~seen)  # a space only before the first digit
        seen |= is_digit
        value = value * 10 + np.where(is_digit, digit, 0)
    return value, ok & seen


def _days_in_month(year: np.ndarray, month: np.ndarray) -> np.ndarray:
    leap = ((year % 4 == 0) & (year % 100 != 0)) | (year % 400 == 0)
    days = np.array([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31])[np.clip(month, 1, 12) - 1]
    return days + ((month == 2) & leap)


def _timestamps(ok: np.ndarray, year, month, day, hour, minute, microsecond) -> np.ndarray:
    """datetime64[us] of each record's calendar fields; NaT where not ``ok`` (fields checked before)."""
    year, month, day = (np.where(ok, x, d) for x, d in ((year, 1970), (month, 1), (day, 1)))
    months = ((year - 1970) * 12 + month - 1).astype("datetime64[M]")
    stamp = months.astype("datetime64[D]").astype("datetime64[us]") + ((day - 1) * 86_400_000_000).astype(
        "timedelta64[us]"
    )
    stamp = stamp + ((hour * 3600 + minute * 60) * 1_000_000 + microsecond).astype("timedelta64[us]")
    return np.where(ok, stamp, np.datetime64("NaT", "us"))


def _check_calendar(reasons: _Reasons, year, month, day, hour, minute, microsecond) -> None:
    valid = (
        (month >= 1) & (month <= 12) & (day >= 1) & (day <= _days_in_month(year, month)) & (hour <= 23)
        & (minute <= 59) & (microsecond >= 0) & (microsecond < 60_000_000)
    )  # fmt: skip
    reasons.flag(~valid, BAD_DATE)
    low, high = YEAR_RANGE
    reasons.flag((year < low) | (year > high), f"implausible year (allowed {low}-{high})")


def _parse_fixed(lines: _Lines, layout: FixedWidthLayout) -> dict:
    """Every record of ``lines`` in ``layout``: the columns (values of bad records undefined) and the reasons."""
    m = len(lines)
    reasons = _Reasons(m)
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
    # any other byte but a digit or a space, in a field or in the padding past the last axle: a form feed, a tab,
    # a Unicode line separator, binary data
    reasons.flag(_stray_bytes(lines), NON_NUMERIC)
    if "n_groups" in raw:
        reasons.flag((raw["n_groups"] < 1) | (raw["n_groups"] > n), "implausible number of axle groups")
    base = layout.direction_base
    reasons.flag((raw["direction"] != base) & (raw["direction"] != base + 1), f"direction not {base} or {base + 1}")
    year = raw["year"]
    if layout.year_digits == 2:  # the century is not written: POSIX %y
        year = year + np.where(year >= TWO_DIGIT_PIVOT, 1900, 2000)
    if "millisecond" in raw:  # MON: milliseconds of the minute
        micro = raw["millisecond"] * 1000
    else:
        micro = raw["second"] * 1_000_000 + raw["second_100"] * 10_000
    _check_calendar(reasons, year, raw["month"], raw["day"], raw["hour"], raw["minute"], micro)
    scale = layout.scales
    load_unit = layout.axle_field("axle_load").scale
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
        "reasons": reasons, "columns": columns, "loads": loads, "spacings": spacings, "widths": widths,
        "stamp": (year, raw["month"], raw["day"], raw["hour"], raw["minute"], micro),
        "gross_step": scale["gross_weight"], "load_step": load_unit,
    }  # fmt: skip


def _stray_bytes(lines: _Lines) -> np.ndarray:
    """Whether each record ``[start, end)`` holds a byte that is neither an ASCII digit nor a space."""
    m = len(lines)
    if not m:
        return np.zeros(0, bool)
    stray = _FIELD_BYTE[lines.buf]
    np.logical_not(stray, out=stray)
    bounds = np.empty(2 * m, np.int64)
    bounds[0::2], bounds[1::2] = lines.start, lines.end
    if bounds[-1] == len(lines.buf):  # reduceat's indices must be inside the array: the last segment runs to its end
        bounds = bounds[:-1]
    return np.logical_or.reduceat(stray, bounds)[0::2]


# ---- checks every format shares ------------------------------------------------------------------------------------
def _weight_step(loads: np.ndarray, ok: np.ndarray) -> float | None:
    """The largest of :data:`WEIGHT_STEPS_KG` dividing every axle load of the ``ok`` records; None if the loads are
    not whole kilograms or there is none."""
    values = loads[ok]
    values = values[~np.isnan(values)]
    if not len(values) or not (np.round(values) == values).all():
        return None
    whole = np.round(values).astype(np.int64)
    return float(next(step for step in reversed(WEIGHT_STEPS_KG) if step == 1 or not (whole % step).any()))


def _check_vehicles(parsed: dict) -> float | None:
    """The plausibility checks, in their order, on every record not bad yet; returns the weight step detected."""
    reasons: _Reasons = parsed["reasons"]
    col = parsed["columns"]
    loads, spacings = parsed["loads"], parsed["spacings"]
    lo, hi = AXLE_LOAD_RANGE
    reasons.flag(((loads < lo) | (loads > hi)).any(axis=1), f"implausible axle load (allowed {lo:g}-{hi:g} kg)")
    lo, hi = SPACING_RANGE
    reasons.flag(((spacings < lo) | (spacings > hi)).any(axis=1), f"implausible axle spacing (allowed {lo:g}-{hi:g} m)")
    lo, hi = SPEED_RANGE
    speed = col["speed"]
    reasons.flag((speed < lo) | (speed > hi), f"implausible speed (allowed {lo * 3.6:g}-{hi * 3.6:g} km/h)")
    step = _weight_step(loads, reasons.ok)
    total = np.nansum(loads, axis=1)
    gross = col["gross_weight"]
    if not np.isnan(gross).all():
        # half a step of the gross weight's field and of each axle's, at the file's resolution if coarser
        load_half = max(step or 0.0, parsed["load_step"]) / 2
        gross_half = max(step or 0.0, parsed["gross_step"]) / 2
        slack = GROSS_TOLERANCE * total + gross_half + col["n_axles"] * load_half
        reasons.flag(np.abs(gross - total) > slack, "gross weight is not the sum of the axle loads")
    length = col["length"]
    reasons.flag((length > 0) & (length < np.nansum(spacings, axis=1)), "length shorter than the wheelbase")
    return step


def _flag_repeats(parsed: dict, stamps: np.ndarray) -> None:
    """A good record equal to an earlier good one in time, lane, direction, speed, axle loads and spacings is bad:
    a WIM system does not weigh two vehicles in one lane at one instant (a record repeated by a copy or a retry)."""
    reasons: _Reasons = parsed["reasons"]
    good = np.flatnonzero(reasons.ok)
    if len(good) < 2:
        return
    # only records that share their time with another can repeat one: compare the rest of the key for those only
    same_time = pd.Series(stamps[good].view(np.int64)).duplicated(keep=False).to_numpy()
    good = good[same_time]
    if len(good) < 2:
        return
    col = parsed["columns"]
    key = pd.DataFrame({
        "t": stamps[good].view(np.int64), "lane": col["lane"][good], "dir": col["direction"][good],
        "speed": col["speed"][good],
        **{f"w{i}": parsed["loads"][good, i] for i in range(parsed["loads"].shape[1])},
        **{f"s{i}": parsed["spacings"][good, i] for i in range(parsed["spacings"].shape[1])},
    })  # fmt: skip
    repeat = np.zeros(len(reasons.code), bool)
    repeat[good[key.duplicated(keep="first").to_numpy()]] = True
    reasons.flag(repeat, DUPLICATE)


# ---- CSV -------------------------------------------------------------------------------------------------------------
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
    value = np.where(negative, -1.0, 1.0) * whole / 10.0**places
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

    n_value, n_blank, n_ok = number("n_axles")
    reasons.flag(~n_ok | (n_value != np.round(n_value)), NON_NUMERIC)
    n = np.where(reasons.ok, np.nan_to_num(n_value), 0).astype(np.int64)
    reasons.flag(reasons.ok & (n == 0), NO_AXLES)
    reasons.flag((n < 2) | (n > CSV_MAX_AXLES), f"implausible number of axles (allowed 2-{CSV_MAX_AXLES})")
    n = np.where(reasons.ok, n, 0)
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


# ---- the file ------------------------------------------------------------------------------------------------------
def _shown(text: str, limit: int = 60) -> str:
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")


def _utf8(data: bytes) -> bytes:
    """``data`` if it is UTF-8; else decoded with U+FFFD for every undecodable byte and encoded again."""
    if data.isascii():
        return data
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("utf-8", errors="replace").encode("utf-8")
    return data


def _parse(data: bytes, fmt: str, path: str) -> dict:
    """Parse every record of ``data`` in ``fmt`` and check it; a ValueError for a CSV header not the layout's."""
    if fmt == "csv":
        data = _utf8(data)
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_csv(data, lines, path)
        stamps = parsed["stamps"]
    else:
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_fixed(lines, LAYOUTS[fmt])
        parsed["line"] = lines.line
        stamps = None
    parsed["step"] = _check_vehicles(parsed)
    if stamps is None:
        stamps = _timestamps(parsed["reasons"].ok, *parsed["stamp"])
    _flag_repeats(parsed, stamps)
    parsed["stamps"] = stamps
    return parsed


def _frame(parsed: dict) -> pd.DataFrame:
    ok = parsed["reasons"].ok
    n = parsed["columns"]["n_axles"][ok]
    width = int(n.max()) if len(n) else 2
    col = parsed["columns"]
    frame = pd.DataFrame({
        "line": parsed["line"][ok], "head": col["head"][ok], "timestamp": parsed["stamps"][ok],
        **{k: col[k][ok] for k in ("speed", "gross_weight", "length", "n_axles", "n_groups", "lane", "direction",
                                   "transverse_position")},
    })  # fmt: skip
    pad = max(0, width - parsed["loads"].shape[1])
    loads = np.pad(parsed["loads"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
    spacings = np.pad(parsed["spacings"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, : width - 1]
    extra = {f"axle_load_{i}": loads[:, i] for i in range(width)}
    extra.update({f"spacing_{i}": spacings[:, i] for i in range(width - 1)})
    if parsed["widths"] is not None:
        widths = np.pad(parsed["widths"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
        extra.update({f"axle_width_{i}": widths[:, i] for i in range(width)})
    frame = pd.concat([frame, pd.DataFrame(extra)], axis=1)
    frame["timestamp"] = frame["timestamp"].astype("datetime64[us]")
    frame["n_axles"] = frame["n_axles"].astype(np.int64)
    frame["line"] = frame["line"].astype(np.int64)
    frame["lane"] = frame["lane"].astype(np.int64)  # -1: not given (CSV)
    frame["direction"] = frame["direction"].astype(np.int64)  # 1 or 2; -1: not given (CSV)
    return frame


def _fits(head: bytes, fmt: str, path: str) -> tuple[int, int]:
    """(good, all) records of ``head`` in ``fmt``; a ValueError for a CSV header not the layout's."""
    parsed = _parse(head, fmt, path)
    if not parsed:
        return 0, 0
    ok = parsed["reasons"].ok
    return int(ok.sum()), len(ok)


def _sniff(data: bytes, expected: str) -> str:
    """Which other known format the first lines parse as, for the refusal message ('' if none)."""
    head = _head(data, 20)
    for fmt in FORMATS:
        if fmt == expected:
            continue
        try:
            good, total = _fits(head, fmt, "")
        except ValueError:
            continue
        if total and good > total / 2:
            return f"; its first lines parse as {fmt} records (--format {fmt}?)"
    return ""


def _detect(head: bytes, path: str) -> str:
    fits, tried = [], []
    n_lines = 0
    for fmt in FORMATS:
        try:
            good, total = _fits(head, fmt, path)
        except ValueError:
            tried.append(f"{fmt}: not its header")
            continue
        n_lines = max(n_lines, total)
        tried.append(f"{fmt}: {good} of {total} good")
        if total and good > total / 2:
            fits.append(fmt)
    if len(fits) == 1:
        return fits[0]
    what = "no known format fits" if not fits else f"more than one format fits ({', '.join(fits)})"
    shown = len([line for line in head.split(b"\n") if line.strip()])
    raise ValueError(
        f"{path}: format auto: {what} the first {shown} non-blank lines ({'; '.join(tried)}); "
        f"name one with --format ({', '.join(FORMATS)})"
    )


def detect_format(lines: list[str], path: str = "") -> str:
    """The one known format in which more than half of the first :data:`SNIFF_LINES` non-blank lines are good
    records; a :class:`ValueError` naming the candidates when none or more than one fits."""
    data = "\n".join(lines).encode("utf-8", errors="replace")
    return _detect(_head(data, SNIFF_LINES), path)


def read_weighings(path: str | Path, fmt: str = "auto") -> ReadResult:
    """Read a file of weighings (one vehicle a record) in format ``fmt``.

    Parameters
    ----------
    path
        The file (text; fixed-width records one a line, or CSV with a header line); gzip-compressed or not (told by
        its first bytes, not its name).
    fmt
        ``csv``, ``mon``, ``castor``, ``bedit`` or ``ditis`` (layouts in ``docs/weighings.md``), or ``auto``
        (default): the one layout in which most of the first :data:`SNIFF_LINES` non-blank lines parse
        (:func:`detect_format`); ``ReadResult.format`` says which.

    Returns
    -------
    ReadResult
        The good records as a vehicle table (SI), the bad ones counted by reason, the weight resolution.

    Raises
    ------
    ValueError
        For an unknown format, an empty file, a file whose records are more than half bad or that is in another
        format (the message names the format expected and what was found), a gzip file that does not decompress.
    OSError
        If the file cannot be read.
    """
    if fmt != "auto" and fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} unknown; allowed: auto, {', '.join(FORMATS)}")
    path = Path(path)
    data = _file_bytes(path)
    if fmt == "auto":
        head = _head(data, SNIFF_LINES)
        if not head.strip():
            raise ValueError(f"{path}: no records: format auto found an empty file")
        fmt = _detect(head, str(path))
    name = "CSV layout" if fmt == "csv" else f"{LAYOUTS[fmt].name} records"
    try:
        parsed = _parse(data, fmt, str(path))
    except ValueError as exc:  # a CSV header that is not the layout's
        raise ValueError(f"{exc}{_sniff(data, fmt)}") from None
    if not parsed or not len(parsed["reasons"].code):
        found = "a header and no record" if parsed or _head(data, 1).strip() else "an empty file"
        raise ValueError(f"{path}: no records: expected {name} (format {fmt}), found {found}")
    skipped, bad_lines = parsed["reasons"].counted(parsed["line"])
    result = ReadResult(_frame(parsed), fmt, skipped, bad_lines, parsed["step"])
    total = result.n_read + result.n_skipped
    if result.n_skipped > MAX_BAD_FRACTION * total:
        first = _head(data, 1).decode("utf-8", errors="replace").rstrip()
        raise ValueError(
            f"{path}: not read as {name} (format {fmt}): {result.n_skipped} of {total} records bad "
            f"({result.reasons()}); first line {_shown(first)}" + _sniff(data, fmt)
        )
    return result
