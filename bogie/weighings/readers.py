"""Readers of observed weighings: the documented CSV layout and the fixed-width WIM formats (``formats.py``).

:func:`read_weighings` returns one row per vehicle in SI units (kg, m, m/s) and the count of every record it
skipped, by reason, with the first few line numbers. A bad record (shorter than its stated axles need,
non-numeric, no axles, a direction code the format does not have, a date that does not exist, an implausible
weight, spacing or speed, a gross weight that is not the sum of the axles, a length shorter than the wheelbase;
a longer line, padded past its stated axles, is normal) is skipped and counted, never silently; a file that is
empty, mostly bad (more than half its records) or in another format is refused with a :class:`ValueError` that
names the format expected and what was found. Layouts and bounds: ``docs/weighings.md``.
"""

from __future__ import annotations

import csv
import datetime as dt
import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings.formats import CSV_COLUMNS, FORMATS, KMH, LAYOUTS, FixedWidthLayout

__all__ = [
    "AXLE_LOAD_RANGE", "MAX_AXLES", "MAX_BAD_FRACTION", "SNIFF_LINES", "SPACING_RANGE", "SPEED_RANGE", "ReadResult",
    "detect_format", "read_weighings",
]  # fmt: skip

#: plausible axle load [kg]: from the unsprung mass of a light axle to 50 kips (22.7 t), above which Elkins and
#: Higgins (2008, quoted by OpenWIM) reject an axle as a WIM error; the EU's heaviest legal axle is 11.5 t
AXLE_LOAD_RANGE: tuple[float, float] = (100.0, 22_680.0)
#: plausible spacing of consecutive axles [m]: no two axles closer than a small tyre's diameter, none further
#: apart than a vehicle is long (the EU maximum length is 18.75 m, Directive 96/53/EC)
SPACING_RANGE: tuple[float, float] = (0.6, 18.75)
#: plausible speed [m/s]: 0 (a static weighbridge) to 160 km/h (Elkins and Higgins reject above 99 mph)
SPEED_RANGE: tuple[float, float] = (0.0, 160.0 * KMH)
#: most axles of one vehicle in any format [-] (MON's 2-digit count); each fixed-width format has its own limit too
#: (``FixedWidthLayout.max_axles``: CASTOR 9, BeDIT 20, DITIS 20, MON 99)
MAX_AXLES: int = 99
#: most axles of one vehicle in the CSV layout [-] (a plausibility bound: no road vehicle has more)
CSV_MAX_AXLES: int = 20
#: a file with more than this fraction of bad records is refused, not read [-]
MAX_BAD_FRACTION: float = 0.5
#: gross weight against the sum of the axle loads: allowed difference, a fraction of the sum plus the fields'
#: resolution (a WIM system's gross weight is the sum of its axle weights, Enright and OBrien 2011) [-]
GROSS_TOLERANCE: float = 0.02
#: line numbers of bad records shown per reason
EXAMPLES: int = 5


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
    """

    vehicles: pd.DataFrame
    format: str
    skipped: Counter = field(default_factory=Counter)
    bad_lines: dict[str, list[int]] = field(default_factory=dict)

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

    def summary(self) -> str:
        """One line: records read and skipped, each reason with its first line numbers."""
        text = f"{self.n_read} records read, {self.n_skipped} skipped"
        return text + (f" ({self.reasons()})" if self.skipped else "")


class _Bad(Exception):
    """A bad record; the message is its reason."""


# ---- checks every format shares ------------------------------------------------------------------------------------
def _check_vehicle(rec: dict, gross_resolution: float = 0.0, load_resolution: float = 0.0) -> None:
    n = rec["n_axles"]
    loads, spacings = rec["loads"], rec["spacings"]
    lo, hi = AXLE_LOAD_RANGE
    if any(not lo <= w <= hi for w in loads):
        raise _Bad(f"implausible axle load (allowed {lo:g}-{hi:g} kg)")
    lo, hi = SPACING_RANGE
    if any(not lo <= s <= hi for s in spacings):
        raise _Bad(f"implausible axle spacing (allowed {lo:g}-{hi:g} m)")
    lo, hi = SPEED_RANGE
    if not math.isnan(rec["speed"]) and not lo <= rec["speed"] <= hi:
        raise _Bad(f"implausible speed (allowed {lo * 3.6:g}-{hi * 3.6:g} km/h)")
    total = sum(loads)
    gross = rec.get("gross_weight", math.nan)
    if not math.isnan(gross) and abs(gross - total) > GROSS_TOLERANCE * total + gross_resolution + n * load_resolution:
        raise _Bad("gross weight is not the sum of the axle loads")
    length = rec.get("length", math.nan)
    if not math.isnan(length) and length > 0 and length < sum(spacings):
        raise _Bad("length shorter than the wheelbase")


def _check_n_axles(n: int, most: int = 99) -> None:
    if n == 0:
        raise _Bad("no axles")
    if not 2 <= n <= most:
        raise _Bad(f"implausible number of axles (allowed 2-{most})")


# ---- fixed width ---------------------------------------------------------------------------------------------------
_DIGITS = frozenset("0123456789")


def _int(text: str) -> int:
    # right-aligned, padded with spaces or zeros: leading spaces, then ASCII digits only (no sign, no inner or
    # trailing space, not all blank)
    s = text.lstrip(" ")
    if not s or not set(s) <= _DIGITS:
        raise _Bad("non-numeric field")
    return int(s)


def _parse_fixed(line: str, layout: FixedWidthLayout) -> dict:
    if len(line) < layout.fixed_width:
        raise _Bad("record shorter than the header")
    raw = {f.name: _int(line[f.start : f.end]) for f in layout.header}
    n = raw["n_axles"]
    _check_n_axles(n, min(MAX_AXLES, layout.max_axles))
    if len(line) < layout.min_record_length(n):
        raise _Bad("record too short for its stated axles")
    axles: dict[str, list[float]] = {}
    for f in layout.axles.fields:
        count = n if f.per == "axle" else n - 1
        starts = [layout.axles.start + layout.axles.stride * i + f.start for i in range(count)]
        axles[f.name] = [_int(line[a : a + f.width]) * f.scale for a in starts]
    n_groups = raw.get("n_groups", math.nan)
    if "n_groups" in raw and not 1 <= n_groups <= n:
        raise _Bad("implausible number of axle groups")
    base = layout.direction_base
    if raw["direction"] not in (base, base + 1):
        raise _Bad(f"direction not {base} or {base + 1}")
    year = raw["year"] + (2000 if layout.year_digits == 2 else 0)  # century not given: 2000-2099
    if "millisecond" in raw:  # MON: milliseconds of the minute
        second, micro = divmod(raw["millisecond"] * 1000, 1_000_000)
    else:
        second, micro = raw["second"], raw["second_100"] * 10_000
    try:
        stamp = dt.datetime(year, raw["month"], raw["day"], raw["hour"], raw["minute"], second, micro)
    except ValueError:
        raise _Bad("invalid date or time") from None
    scale = layout.scales
    rec = {
        "head": raw["head"], "timestamp": stamp, "speed": raw["speed"] * scale["speed"],
        "gross_weight": raw["gross_weight"] * scale["gross_weight"], "length": raw["length"] * scale["length"],
        "n_axles": n, "n_groups": n_groups, "lane": raw["lane"], "direction": raw["direction"] - base + 1,
        "transverse_position": raw["transverse_position"] * scale["transverse_position"],
        "loads": axles["axle_load"], "spacings": axles["spacing"], "axle_widths": axles.get("axle_width"),
    }  # fmt: skip
    _check_vehicle(rec, scale["gross_weight"] / 2, layout.axle_field("axle_load").scale / 2)
    return rec


# ---- CSV -------------------------------------------------------------------------------------------------------------
def _float(text: str, optional: bool = False) -> float:
    s = text.strip()
    if optional and not s:
        return math.nan
    try:
        x = float(s)
    except ValueError:
        raise _Bad("non-numeric field") from None
    if not math.isfinite(x):
        raise _Bad("non-numeric field")
    return x


def _csv_header(header: list[str], path: str) -> dict[str, int]:
    columns = {name.strip(): i for i, name in enumerate(header)}
    missing = [c for c in (*CSV_COLUMNS, "axle_load_1", "axle_load_2", "spacing_1") if c not in columns]
    if missing:
        raise ValueError(
            f"{path}: not the CSV layout (format csv): the header lacks {', '.join(missing)}; expected columns "
            f"{', '.join(CSV_COLUMNS)}, axle_load_1..n [kg], spacing_1..n-1 [m]; found {_shown(','.join(header))}"
        )
    return columns


def _parse_csv(row: list[str], columns: dict[str, int], width: int) -> dict:
    if len(row) != width:
        raise _Bad("wrong length")
    value = _float(row[columns["n_axles"]])
    if value != int(value):
        raise _Bad("non-numeric field")
    n = int(value)
    _check_n_axles(n, CSV_MAX_AXLES)
    need = [f"axle_load_{i}" for i in range(1, n + 1)] + [f"spacing_{i}" for i in range(1, n)]
    if any(c not in columns for c in need):
        raise _Bad("more axles than the file has columns for")
    extra = [c for c, i in columns.items() if c.startswith(("axle_load_", "spacing_")) and c not in need]
    if any(row[columns[c]].strip() not in ("", "0") for c in extra):
        raise _Bad("axle load or spacing past the number of axles")
    try:
        stamp = pd.Timestamp(row[columns["timestamp"]].strip()).to_pydatetime()
    except (ValueError, TypeError):
        raise _Bad("invalid date or time") from None
    if pd.isna(stamp):
        raise _Bad("invalid date or time")
    lane = _float(row[columns["lane"]], optional=True)
    rec = {
        "head": "", "timestamp": stamp, "speed": _float(row[columns["speed_kmh"]], optional=True) * KMH,
        "gross_weight": math.nan, "length": math.nan, "n_axles": n, "n_groups": math.nan,
        "lane": -1 if math.isnan(lane) else int(lane), "direction": -1, "transverse_position": math.nan,
        "loads": [_float(row[columns[f"axle_load_{i}"]]) for i in range(1, n + 1)],
        "spacings": [_float(row[columns[f"spacing_{i}"]]) for i in range(1, n)], "axle_widths": None,
    }  # fmt: skip
    _check_vehicle(rec)
    return rec


# ---- the file ------------------------------------------------------------------------------------------------------
def _shown(text: str, limit: int = 60) -> str:
    return repr(text if len(text) <= limit else text[: limit - 1] + "…")


def _records(lines: list[str], fmt: str, path: str):
    """(line number, record or reason) of every non-blank line; the CSV header is not a record."""
    numbered = [(i + 1, line.rstrip("\r\n")) for i, line in enumerate(lines)]
    numbered = [(i, line) for i, line in numbered if line.strip()]
    if fmt == "csv":
        if not numbered:
            return
        rows = csv.reader([line for _, line in numbered])
        header = next(rows)
        columns = _csv_header(header, path)
        for (i, _), row in zip(numbered[1:], rows):
            try:
                yield i, _parse_csv(row, columns, len(header))
            except _Bad as exc:
                yield i, str(exc)
        return
    layout = LAYOUTS[fmt]
    for i, line in numbered:
        try:
            yield i, _parse_fixed(line, layout)
        except _Bad as exc:
            yield i, str(exc)


def _sniff(lines: list[str], expected: str) -> str:
    """Which other known format the first lines parse as, for the refusal message ('' if none)."""
    head = lines[:20]
    for fmt in FORMATS:
        if fmt == expected:
            continue
        try:
            results = [r for _, r in _records(head, fmt, "")]
        except ValueError:
            continue
        good = sum(isinstance(r, dict) for r in results)
        if results and good > len(results) / 2:
            return f"; its first lines parse as {fmt} records (--format {fmt}?)"
    return ""


def _frame(rows: list[tuple[int, dict]]) -> pd.DataFrame:
    width = max((r["n_axles"] for _, r in rows), default=2)
    data = {
        "line": [i for i, _ in rows],
        **{k: [r[k] for _, r in rows] for k in ("head", "timestamp", "speed", "gross_weight", "length", "n_axles",
                                                  "n_groups", "lane", "direction", "transverse_position")},
    }  # fmt: skip
    loads = np.full((len(rows), width), np.nan)
    spacings = np.full((len(rows), width - 1), np.nan)
    with_widths = any(r["axle_widths"] is not None for _, r in rows)  # DITIS
    widths = np.full((len(rows), width), np.nan)
    for j, (_, r) in enumerate(rows):
        loads[j, : r["n_axles"]] = r["loads"]
        spacings[j, : r["n_axles"] - 1] = r["spacings"]
        if r["axle_widths"] is not None:
            widths[j, : r["n_axles"]] = r["axle_widths"]
    data.update({f"axle_load_{i}": loads[:, i] for i in range(width)})
    data.update({f"spacing_{i}": spacings[:, i] for i in range(width - 1)})
    if with_widths:
        data.update({f"axle_width_{i}": widths[:, i] for i in range(width)})
    frame = pd.DataFrame(data)
    frame["timestamp"] = pd.to_datetime(frame["timestamp"])
    frame["n_groups"] = frame["n_groups"].astype(float)
    frame["transverse_position"] = frame["transverse_position"].astype(float)
    frame["lane"] = frame["lane"].astype(np.int64)  # -1: not given (CSV)
    frame["direction"] = frame["direction"].astype(np.int64)  # 1 or 2; -1: not given (CSV)
    return frame


#: non-blank lines ``fmt="auto"`` tries every layout on [-]
SNIFF_LINES: int = 50


def detect_format(lines: list[str], path: str = "") -> str:
    """The one known format in which more than half of the first :data:`SNIFF_LINES` non-blank lines are good
    records; a :class:`ValueError` naming the candidates when none or more than one fits."""
    head = [line for line in lines if line.strip()][:SNIFF_LINES]
    fits, tried = [], []
    for fmt in FORMATS:
        try:
            results = [r for _, r in _records(head, fmt, path)]
        except ValueError:
            tried.append(f"{fmt}: not its header")
            continue
        good = sum(isinstance(r, dict) for r in results)
        tried.append(f"{fmt}: {good} of {len(results)} good")
        if results and good > len(results) / 2:
            fits.append(fmt)
    if len(fits) == 1:
        return fits[0]
    what = "no known format fits" if not fits else f"more than one format fits ({', '.join(fits)})"
    raise ValueError(
        f"{path}: format auto: {what} the first {len(head)} non-blank lines ({'; '.join(tried)}); "
        f"name one with --format ({', '.join(FORMATS)})"
    )


def read_weighings(path: str | Path, fmt: str = "auto") -> ReadResult:
    """Read a file of weighings (one vehicle a record) in format ``fmt``.

    Parameters
    ----------
    path
        The file (text; fixed-width records one a line, or CSV with a header line).
    fmt
        ``csv``, ``mon``, ``castor``, ``bedit`` or ``ditis`` (layouts in ``docs/weighings.md``), or ``auto``
        (default): the one layout in which most of the first :data:`SNIFF_LINES` non-blank lines parse
        (:func:`detect_format`); ``ReadResult.format`` says which.

    Returns
    -------
    ReadResult
        The good records as a vehicle table (SI) and the bad ones counted by reason.

    Raises
    ------
    ValueError
        For an unknown format, an empty file, a file whose records are more than half bad or that is in another
        format (the message names the format expected and what was found).
    OSError
        If the file cannot be read.
    """
    if fmt != "auto" and fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} unknown; allowed: auto, {', '.join(FORMATS)}")
    path = Path(path)
    with path.open(encoding="utf-8-sig", errors="replace", newline="") as fh:  # a BOM from a spreadsheet
        lines = fh.read().splitlines()
    if fmt == "auto":
        if not any(line.strip() for line in lines):
            raise ValueError(f"{path}: no records: format auto found an empty file")
        fmt = detect_format(lines, str(path))
    name = "CSV layout" if fmt == "csv" else f"{LAYOUTS[fmt].name} records"
    rows: list[tuple[int, dict]] = []
    skipped: Counter = Counter()
    bad_lines: dict[str, list[int]] = {}
    try:
        for i, rec in _records(lines, fmt, str(path)):
            if isinstance(rec, dict):
                rows.append((i, rec))
            else:
                skipped[rec] += 1
                if len(bad_lines.setdefault(rec, [])) < EXAMPLES:
                    bad_lines[rec].append(i)
    except ValueError as exc:  # a CSV header that is not the layout's
        raise ValueError(f"{exc}{_sniff(lines, fmt)}") from None
    result = ReadResult(_frame(rows), fmt, skipped, bad_lines)
    total = result.n_read + result.n_skipped
    if total == 0:
        found = "a header and no record" if any(line.strip() for line in lines) else "an empty file"
        raise ValueError(f"{path}: no records: expected {name} (format {fmt}), found {found}")
    if result.n_skipped > MAX_BAD_FRACTION * total:
        first = next(line for line in lines if line.strip())
        raise ValueError(
            f"{path}: not read as {name} (format {fmt}): {result.n_skipped} of {total} records bad "
            f"({result.reasons()}); first line {_shown(first.rstrip())}" + _sniff(lines, fmt)
        )
    return result
