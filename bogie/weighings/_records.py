"""What the readers of weighings share (:mod:`bogie.weighings.readers`): the plausible ranges, the reasons a record
is skipped, a file's bytes as lines, and the calendar checks. Private: the public names are re-exported by the readers.
"""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from bogie.files import regular_file
from bogie.weighings.formats import KMH

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


#: the relative tolerance of a comparison of a value derived from a file's fields with a limit or another value [-]:
#: a field is an integer times its unit (or a decimal), and the conversion and a sum round in the last bits (about
#: 1e-16 relative); 1e-9 is far below any field's resolution (1 kg in 22,680 kg, 1 mm in 18.75 m), so a value
#: written at a limit is at it, not past it. A convention of this project (no published source), named as one
REL_TOL = 1e-9

#: memory of reading a survey with its groups held in memory (``observed_survey(keep_groups=True)``, the calibrate
#: stage's), before its growth [bytes]: the libraries and a chunk's work, 731 MiB peak for any length when the
#: groups are spilled to disk instead (``bench/bench_weighings.py``, 6 December 2026), rounded up
SURVEY_BASE_MEMORY = 768 * 2**20
#: memory that grows with such a survey, per byte of its records (uncompressed) [bytes/byte]: every kept group with
#: all its columns; measured 2.9 (996 MiB peak for 1,000,000 MON records, 91 MB, 6 December 2026: one file, one
#: format, an estimate for the others), rounded up
MEMORY_PER_BYTE = 3.0
#: the largest survey file whose groups are held in memory, uncompressed [bytes]: 1 GiB, about 11 million MON
#: records (:func:`survey_memory`: about 3.8 GiB); a streamed survey (``bogie weighings``, the observed stage) reads
#: any length
MAX_FILE_BYTES = 2**30


def _regular(path: Path) -> os.stat_result:
    """``path``'s status if it is a regular file (:func:`bogie.files.regular_file`), refused before it is opened."""
    return regular_file(path, "give a file of WIM or weighbridge records")


def uncompressed_size(path: str | Path) -> int:
    """The size of a survey file's records [bytes]: the file's, or for a gzip file the size its trailer states
    (modulo 4 GiB, as gzip stores it; at least the compressed size). Reads at most 4 bytes of the file."""
    path = Path(path)
    size = _regular(path).st_size
    with open(path, "rb") as fh:
        if fh.read(2) != _GZIP_MAGIC or size < 18:
            return size
        fh.seek(-4, os.SEEK_END)
        return max(int.from_bytes(fh.read(4), "little"), size)


def survey_memory(path: str | Path) -> int:
    """The peak memory of reading the survey file ``path`` with its groups held in memory [bytes] (an estimate:
    :data:`SURVEY_BASE_MEMORY` plus :func:`uncompressed_size` times :data:`MEMORY_PER_BYTE`)."""
    return SURVEY_BASE_MEMORY + int(uncompressed_size(path) * MEMORY_PER_BYTE)


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
    """The non-blank lines of ``data`` (:class:`_Lines`), found in one compiled pass over the bytes
    (:func:`_split_kernel`; the array version took a third of a second a 16 MiB chunk)."""
    buf = np.frombuffer(data, np.uint8)
    most = data.count(b"\n") + 1
    starts = np.empty(most, np.int64)
    ends = np.empty(most, np.int64)
    lines = np.empty(most, np.int64)
    count = _split_kernel(buf, _BLANK, starts, ends, lines)
    return _Lines(buf, starts[:count], ends[:count], lines[:count])


@njit(cache=True, nogil=True)
def _split_kernel(buf, blank, starts, ends, lines):  # pragma: no cover - compiled
    """Each non-blank line's [start, end) (its line end and a trailing carriage return not included) and 1-based
    number; returns how many. A line is blank when every byte is in ``blank``."""
    count = 0
    number = 0
    start = 0
    size = buf.shape[0]
    while start < size:
        number += 1
        stop = start
        nonblank = False
        while stop < size and buf[stop] != 10:
            if not blank[buf[stop]]:
                nonblank = True
            stop += 1
        if nonblank:
            end = stop
            if end > start and buf[end - 1] == 13:
                end -= 1
            starts[count] = start
            ends[count] = end
            lines[count] = number
            count += 1
        start = stop + 1
    return count


def _stray_bytes(lines: _Lines, allowed: np.ndarray) -> np.ndarray:
    """Whether each line ``[start, end)`` holds a byte not in ``allowed`` (a compiled loop over the lines)."""
    out = np.zeros(len(lines), bool)
    _stray_kernel(lines.buf, lines.start, lines.end, allowed, out)
    return out


@njit(cache=True, nogil=True)
def _stray_kernel(buf, starts, ends, allowed, out):  # pragma: no cover - compiled
    for i in range(starts.shape[0]):
        for p in range(starts[i], ends[i]):
            if not allowed[buf[p]]:
                out[i] = True
                break


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


def _gather(lines: _Lines, rows: np.ndarray, offset: np.ndarray | int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The unsigned integer ``line[offset:offset + width]`` of each line in ``rows`` and whether it is one:
    leading spaces, then ASCII digits only (no sign, no inner or trailing space, not all blank).

    A compiled loop over the rows (:func:`_gather_kernel`; the array version, one gather a character column, took
    a tenth of a second a million records a field)."""
    pos = (lines.start[rows] + offset).astype(np.int64)
    value = np.zeros(len(rows), np.int64)
    ok = np.zeros(len(rows), bool)
    _gather_kernel(lines.buf, pos, width, value, ok)
    return value, ok


@njit(cache=True, nogil=True)
def _gather_kernel(buf, pos, width, value, ok):  # pragma: no cover - compiled
    for r in range(pos.shape[0]):
        v = 0
        seen = False
        good = True
        p = pos[r]
        for j in range(width):
            c = buf[p + j]
            if 48 <= c <= 57:
                v = v * 10 + (c - 48)
                seen = True
            elif c != 32 or seen:  # a space only before the first digit
                good = False
        value[r] = v
        ok[r] = good and seen


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


def _shown(text: str, limit: int = 60) -> str:
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")
