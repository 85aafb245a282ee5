"""The US truck weight record (FHWA Traffic Monitoring Guide, "W" record), 2001 and 2013 editions: the layouts as
data and the parse of a file's records into the readers' common form (:mod:`bogie.weighings.readers`).

Source: ``/work/shared/reference/tmg-weight-record.md`` (2001: TMG 2001 section 6 table 6-5-1, read from FHWA's
own PDF; 2013/2016: TMG 2016 chapter 7, read through a third party's word-for-word quotes, columns 1-43 firm, the
tail by its stated pattern). Columns here are 0-based offsets (the guide's column minus one). ``docs/weighings.md``,
"The US truck weight record", prints both layouts and says what is assumed.

What differs from the European formats, and how the reader takes it:

- A record starts with ``W``; the station is alphanumeric (with the state's FIPS code, the ``station`` column,
  ``SS-XXXXXX``); the direction is a compass code 1-8 (kept as it is in ``direction``); lane 0 is "lanes
  combined" and valid.
- The time is the beginning of the hour: no minute or second. Two alike trucks in one hour are two vehicles,
  so **no record is dropped as a repeat**; the vehicles alike another of the same hour, station, lane and direction
  are counted (``ReadResult.counted``), not skipped.
- Vehicle class ``-1`` or ``0`` (2001), ``m`` or ``d`` (2013) marks a *dummy* hour record (weight data missing or
  not missing for the hour): counted as such (``ReadResult.counted``), never a vehicle or a bad record; one with
  axles is a bad record.
- A missing number is blank or ``-1``: a missing gross weight skips the gross-weight check; a missing axle weight
  or spacing within the stated axles makes the record bad.
- 2013: pounds and tenths of a foot, converted with the exact definitions (1 lb = 0.45359237 kg, 1 ft = 0.3048 m;
  international yard and pound, 1959); the four-digit year. 2001: 100 kg and 0.1 m; the two-digit year by the POSIX
  pivot, as CASTOR's and BeDIT's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bogie.weighings._records import (
    NON_NUMERIC,
    SHORT_HEADER,
    TOO_SHORT,
    TWO_DIGIT_PIVOT,
    _check_calendar,
    _gather,
    _Lines,
    _Reasons,
)

__all__ = ["FOOT", "POUND", "TMG_LAYOUTS", "TMG_VEHICLE_CLASSES", "TmgLayout"]

#: a pound in kilograms, exactly (the international pound, 1959) [kg]
POUND: float = 0.45359237
#: a foot in metres, exactly (the international foot, 1959) [m]
FOOT: float = 0.3048
#: vehicle classes of a vehicle record [-]: FHWA's 13 classes, and 14 and 15, which TMAS accepts for a state's own
#: class and for unclassified vehicles (an assumption: the reference tables 1-13; read 14-15 as vehicles too)
TMG_VEHICLE_CLASSES: tuple[int, int] = (1, 15)
#: most axles of a record [-]: the 2-digit axle count (the guide tables 13 and says more may follow the pattern)
TMG_MAX_AXLES: int = 99

DUMMY_MISSING = "dummy hour records: weight data missing for the hour (class -1 or m)"
DUMMY_PRESENT = "dummy hour records: weight data not missing for the hour (class 0 or d)"
ALIKE = "vehicles alike an earlier one of the same hour, station, lane and direction (kept: hourly time stamps)"


@dataclass(frozen=True)
class TmgLayout:
    """One edition of the W record: 0-based offset and width of each header field, the per-axle pattern, units."""

    name: str
    edition: str
    year: tuple[int, int]
    month: tuple[int, int]
    day: tuple[int, int]
    hour: tuple[int, int]
    vehicle_class: tuple[int, int]
    gross_weight: tuple[int, int]
    n_axles: tuple[int, int]
    axle_start: int  # the first axle's weight field
    stride: int  # characters per axle
    weight_width: int
    spacing_offset: int  # from the axle's weight field to its spacing field
    spacing_width: int
    weight_unit_kg: float  # one unit of the weight fields [kg]
    spacing_unit_m: float  # one unit of the spacing fields [m]
    weight_base: str  # the unit a resolution is counted in: kg (2001) or lb (2013)
    dummy_missing: bytes  # the class field's code (stripped) of a dummy hour record, data missing
    dummy_present: bytes  # ... data not missing
    state: tuple[int, int] = (1, 2)
    station: tuple[int, int] = (3, 6)
    direction: tuple[int, int] = (9, 1)
    lane: tuple[int, int] = (10, 1)

    @property
    def fixed_width(self) -> int:
        """Characters through the axle count [-]: 2001 30, 2013 34."""
        return self.n_axles[0] + self.n_axles[1]

    def min_record_length(self, n_axles: int) -> int:
        """The shortest record holding ``n_axles`` axles, through the last axle's weight [-]: 2001 6n + 27, 2013
        9n + 30 (the reference's)."""
        return self.axle_start + self.stride * (n_axles - 1) + self.weight_width

    @property
    def year_digits(self) -> int:
        return self.year[1]


TMG_LAYOUTS: dict[str, TmgLayout] = {
    # reference, "2001 edition (metric)": columns 1-30, then 6 characters an axle from column 31
    "tmg2001": TmgLayout(
        name="TMG 2001", edition="2001", year=(11, 2), month=(13, 2), day=(15, 2), hour=(17, 2),
        vehicle_class=(19, 2), gross_weight=(24, 4), n_axles=(28, 2), axle_start=30, stride=6, weight_width=3,
        spacing_offset=3, spacing_width=3, weight_unit_kg=100.0, spacing_unit_m=0.1, weight_base="kg",
        dummy_missing=b"-1", dummy_present=b"0",
    ),
    # reference, "2013/2016 edition (English units)": columns 1-34, then 9 characters an axle from column 35
    "tmg2013": TmgLayout(
        name="TMG 2013", edition="2013", year=(11, 4), month=(15, 2), day=(17, 2), hour=(19, 2),
        vehicle_class=(21, 2), gross_weight=(26, 6), n_axles=(32, 2), axle_start=34, stride=9, weight_width=5,
        spacing_offset=5, spacing_width=4, weight_unit_kg=POUND, spacing_unit_m=FOOT / 10, weight_base="lb",
        dummy_missing=b"m", dummy_present=b"d",
    ),
}  # fmt: skip


def _bytes(lines: _Lines, rows: np.ndarray, offset: int, width: int) -> np.ndarray:
    """The raw bytes ``line[offset:offset + width]`` of each line in ``rows`` (long enough), shape (rows, width)."""
    return lines.buf[lines.start[rows][:, None] + offset + np.arange(width)[None, :]]


def _stripped(raw: np.ndarray) -> list[bytes]:
    """Each row of bytes without its surrounding spaces."""
    return [bytes(r).strip() for r in raw]


def _number(lines: _Lines, rows: np.ndarray, field: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A numeric field of each line in ``rows``: (value, whether a number, whether missing: blank or ``-1``)."""
    offset, width = field
    value, ok = _gather(lines, rows, offset, width)
    raw = _bytes(lines, rows, offset, width)
    blank = (raw == 32).all(axis=1)
    if width < 2:
        return value, ok, blank
    minus_one = (raw[:, -2] == ord("-")) & (raw[:, -1] == ord("1")) & (raw[:, :-2] == 32).all(axis=1)
    return value, ok, blank | minus_one


def _dummy_codes(lines: _Lines, rows: np.ndarray, layout: TmgLayout) -> tuple[np.ndarray, np.ndarray]:
    """Whether the class field of each line in ``rows`` is the edition's dummy code: (data missing, not missing).
    Letters in either case; 2001's ``0`` also written ``00``."""
    code = _stripped(_bytes(lines, rows, *layout.vehicle_class))
    kind = np.array([c.lower() for c in code] + [b""], dtype=object)[:-1]
    missing = kind == layout.dummy_missing
    present = kind == layout.dummy_present
    if layout.dummy_present == b"0":
        present |= kind == b"00"
    return missing, present


def _lengths(lines: _Lines) -> np.ndarray:
    return lines.end - lines.start


def split_dummies(lines: _Lines, layout: TmgLayout) -> tuple[np.ndarray, dict[str, int]]:
    """The rows of ``lines`` that are not dummy hour records without axles, and the count of each kind of dummy.

    A dummy is a ``W`` record long enough for its class field whose class is the edition's dummy code; one whose
    axle count is a number above 0 stays (and is a bad record)."""
    length = _lengths(lines)
    start, width = layout.vehicle_class
    long_enough = np.flatnonzero(length >= start + width)
    missing, present = _dummy_codes(lines, long_enough, layout)
    is_w = lines.buf[lines.start[long_enough]] == ord("W")
    dummy = (missing | present) & is_w
    # a dummy with axles stays, to be refused as a bad record
    n_start, n_width = layout.n_axles
    with_count = dummy & (length[long_enough] >= n_start + n_width)
    rows = long_enough[with_count]
    n, ok = _gather(lines, rows, n_start, n_width) if len(rows) else (np.zeros(0, np.int64), np.zeros(0, bool))
    axles = np.zeros(len(long_enough), bool)
    axles[np.flatnonzero(with_count)] = ok & (n > 0)
    drop = np.zeros(len(lines), bool)
    drop[long_enough[dummy & ~axles]] = True
    counts = {
        DUMMY_MISSING: int((missing & is_w & ~axles).sum()),
        DUMMY_PRESENT: int((present & is_w & ~axles).sum()),
    }
    return np.flatnonzero(~drop), {k: v for k, v in counts.items() if v}


def _header_fields(lines: _Lines, layout: TmgLayout, reasons: _Reasons, length: np.ndarray) -> tuple[dict, np.ndarray]:
    """Check each record's length, its leading ``W`` and its numeric header fields, flagging the bad ones in
    ``reasons``: the fields' values (``raw``, by name; 0 where not read) and whether the gross weight is missing."""
    m = len(lines)
    reasons.flag(length < layout.fixed_width, SHORT_HEADER)
    alive = np.flatnonzero(reasons.ok)
    bad = np.zeros(m, bool)
    bad[alive] = lines.buf[lines.start[alive]] != ord("W")
    reasons.flag(bad, "not a W record (the first character is not W)")
    alive = np.flatnonzero(reasons.ok)
    raw: dict[str, np.ndarray] = {}
    gross_missing = np.zeros(m, bool)
    for name in ("state", "direction", "lane", "year", "month", "day", "hour", "n_axles", "gross_weight"):
        value, ok, missing = _number(lines, alive, getattr(layout, name))
        raw[name] = np.zeros(m, np.int64)
        raw[name][alive] = value
        if name == "gross_weight":
            gross_missing[alive] = missing
            ok = ok | missing
        bad = np.zeros(m, bool)
        bad[alive[~ok]] = True
        reasons.flag(bad, NON_NUMERIC)
    return raw, gross_missing


def _class_and_station(lines: _Lines, layout: TmgLayout, reasons: _Reasons) -> np.ndarray:
    """Check each good record's vehicle class (a number 1-15; a dummy code here is a dummy with axles) and its
    station (alphanumeric or spaces, right-justified), flagging the bad ones in ``reasons``: the vehicle classes
    (0 where not read)."""
    m = len(lines)
    alive = np.flatnonzero(reasons.ok)
    cls, ok, _ = _number(lines, alive, layout.vehicle_class)
    vehicle_class = np.zeros(m, np.int64)
    vehicle_class[alive] = cls
    missing, present = _dummy_codes(lines, alive, layout)
    dummy = np.zeros(m, bool)
    dummy[alive] = missing | present
    reasons.flag(dummy, "dummy hour record (class -1, 0, m or d) with axles")
    low, high = TMG_VEHICLE_CLASSES
    bad = np.zeros(m, bool)
    bad[alive] = ~ok | (cls < low) | (cls > high)
    reasons.flag(bad, f"vehicle class not {low}-{high} (nor a dummy hour record's)")
    # the station: alphanumeric or spaces, right-justified
    alive = np.flatnonzero(reasons.ok)
    station_raw = _bytes(lines, alive, *layout.station)
    alnum = ((station_raw >= 48) & (station_raw <= 57)) | ((station_raw | 32) >= 97) & ((station_raw | 32) <= 122)
    bad = np.zeros(m, bool)
    bad[alive] = ~(alnum | (station_raw == 32)).all(axis=1) | (station_raw == 32).all(axis=1)
    reasons.flag(bad, "station ID not letters and digits")
    return vehicle_class


def _axle_fields(
    lines: _Lines, layout: TmgLayout, reasons: _Reasons, length: np.ndarray, n: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Read each good record's axle weights and spacings (in the layout's units; -1 where not read), flagging in
    ``reasons`` a missing or non-numeric one within the stated ``n`` axles and a record too short for a spacing."""
    m = len(lines)
    alive_mask = reasons.ok
    width = int(n[alive_mask].max()) if alive_mask.any() else 2
    weights = np.full((m, width), -1, np.int64)
    spacings = np.full((m, max(width - 1, 0)), -1, np.int64)
    for k in range(width):
        for values, offset, size, need in (
            (weights, layout.axle_start + layout.stride * k, layout.weight_width, k),
            (spacings, layout.axle_start + layout.stride * k + layout.spacing_offset, layout.spacing_width, k + 1),
        ):
            if need >= width:
                continue
            rows = np.flatnonzero(alive_mask & (n > need))
            # a spacing field past the record's end (the record stops after the last weight) is not read
            rows = rows[length[rows] >= offset + size]
            value, ok, missing = _number(lines, rows, (offset, size))
            values[rows, k] = value
            bad = np.zeros(m, bool)
            bad[rows[missing]] = True
            reasons.flag(bad, "missing axle weight or spacing (blank or -1) within the stated axles")
            bad = np.zeros(m, bool)
            bad[rows[~ok & ~missing]] = True
            reasons.flag(bad, NON_NUMERIC)
    short_gap = np.zeros(m, bool)
    for k in range(max(width - 1, 0)):
        short_gap |= reasons.ok & (n > k + 1) & (spacings[:, k] < 0)
    reasons.flag(short_gap, TOO_SHORT)
    return weights, spacings


def _station_ids(lines: _Lines, layout: TmgLayout, reasons: _Reasons, state: np.ndarray) -> np.ndarray:
    """Each good record's ``station`` column, ``SS-XXXXXX`` (the state's FIPS code and the station ID); '' for a
    bad one."""
    alive = np.flatnonzero(reasons.ok)
    station = np.full(len(lines), "", dtype=object)
    fields = _bytes(lines, alive, *layout.station)
    station[alive] = [f"{s:02d}-{bytes(r).decode('ascii').strip()}" for s, r in zip(state[alive], fields)]
    return station


def parse_tmg(lines: _Lines, layout: TmgLayout) -> dict:
    """Every (non-dummy) record of ``lines`` in ``layout``: the readers' common parsed form (columns, loads,
    spacings, reasons, time stamp fields) and the TMG columns (``station``, ``vehicle_class``)."""
    m = len(lines)
    reasons = _Reasons(m)
    length = _lengths(lines)
    raw, gross_missing = _header_fields(lines, layout, reasons, length)
    vehicle_class = _class_and_station(lines, layout, reasons)
    n = raw["n_axles"]
    reasons.flag(n == 0, "no axles")
    reasons.flag((n < 2) | (n > TMG_MAX_AXLES), f"implausible number of axles (allowed 2-{TMG_MAX_AXLES})")
    reasons.flag(length < layout.axle_start + layout.stride * (n - 1) + layout.weight_width, TOO_SHORT)
    reasons.flag((raw["direction"] < 1) | (raw["direction"] > 8), "direction not 1-8 (the guide's compass codes)")
    weights, spacings = _axle_fields(lines, layout, reasons, length, n)
    year = raw["year"]
    if layout.year_digits == 2:
        year = year + np.where(year >= TWO_DIGIT_PIVOT, 1900, 2000)
    zero = np.zeros(m, np.int64)
    _check_calendar(reasons, year, raw["month"], raw["day"], raw["hour"], zero, zero)
    station = _station_ids(lines, layout, reasons, raw["state"])
    loads = np.where(weights >= 0, weights * layout.weight_unit_kg, np.nan)
    spaced = np.where(spacings >= 0, spacings * layout.spacing_unit_m, np.nan)
    nan = np.full(m, np.nan)
    columns = {
        "head": np.zeros(m, np.int64), "speed": nan, "length": nan, "n_axles": n, "n_groups": nan,
        "gross_weight": np.where(gross_missing, np.nan, raw["gross_weight"] * layout.weight_unit_kg),
        "lane": raw["lane"], "direction": raw["direction"], "transverse_position": nan,
    }  # fmt: skip
    return {
        "reasons": reasons, "columns": columns, "loads": loads, "spacings": spaced, "widths": None,
        "gross_step": layout.weight_unit_kg, "load_step": layout.weight_unit_kg,
        "stamp": (year, raw["month"], raw["day"], raw["hour"], zero, zero),
        "extra": {"station": station, "vehicle_class": vehicle_class},
        "weight_base": layout.weight_base,
    }  # fmt: skip
