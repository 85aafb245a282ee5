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

from collections import Counter
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings import _records
from bogie.weighings._csv import _parse_csv
from bogie.weighings._records import (
    _FIELD_BYTE,
    AXLE_LOAD_RANGE,
    CSV_LANE_RANGE,
    CSV_MAX_AXLES,
    DUPLICATE,
    EXAMPLES,
    GROSS_TOLERANCE,
    MAX_AXLES,
    MAX_BAD_FRACTION,
    MAX_FILE_BYTES,
    MEMORY_PER_BYTE,
    NO_AXLES,
    NON_NUMERIC,
    REL_TOL,
    SHORT_HEADER,
    SNIFF_LINES,
    SPACING_RANGE,
    SPEED_RANGE,
    SURVEY_BASE_MEMORY,
    TOO_SHORT,
    TWO_DIGIT_PIVOT,
    YEAR_RANGE,
    _check_calendar,
    _gather,
    _head,
    _Lines,
    _Reasons,
    _shown,
    _split,
    _stray_bytes,
    _timestamps,
    survey_memory,
    uncompressed_size,
)
from bogie.weighings._stream import CHUNK_BYTES, SeenStore, blocks, key_hashes
from bogie.weighings._tmg import ALIKE, POUND, TMG_LAYOUTS, parse_tmg, split_dummies
from bogie.weighings.formats import FORMATS, LAYOUTS, FixedWidthLayout
from bogie.weighings.resolution import (
    WEIGHT_STEPS_KG,
    ResidueCounts,
    Resolution,
    check_resolution_kg,
    detect_resolution,
)

__all__ = [
    "AXLE_LOAD_RANGE", "CSV_LANE_RANGE", "CSV_MAX_AXLES", "MAX_AXLES", "MAX_BAD_FRACTION", "SNIFF_LINES",
    "SPACING_RANGE", "SPEED_RANGE", "WEIGHT_STEPS_KG", "YEAR_RANGE", "ReadResult", "detect_format", "read_weighings",
    "stream_weighings", "MAX_FILE_BYTES", "MEMORY_PER_BYTE", "SURVEY_BASE_MEMORY", "survey_memory",
    "uncompressed_size",
]  # fmt: skip


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
        given), ``transverse_position`` [m] (NaN where not given), ``axle_load_1..`` [kg] (front first) and
        ``spacing_1..`` [m] (``spacing_i`` between axles i and i + 1), NaN past the vehicle's axles; DITIS also
        ``axle_width_1..`` [m].
    format
        The format read (``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``).
    skipped
        Bad records per reason.
    bad_lines
        The first :data:`EXAMPLES` line numbers of each reason.
    resolution
        The file's weight resolution (:class:`bogie.weighings.resolution.Resolution`): detected from the axle loads
        of the records that passed the checks before the gross weight's, tolerant of a one-unit offset (loads
        ending in 00 or 99 are a 100 kg file), or set by the caller; its evidence and its source.
    weight_step_kg
        The resolution in use [kg] (``resolution.step_kg``); None when the loads are not whole kilograms (a CSV
        file of other data) or no record has loads.
    format_step_kg
        The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None for
        CSV (decimal numbers).
    """

    vehicles: pd.DataFrame
    format: str
    skipped: Counter = field(default_factory=Counter)
    bad_lines: dict[str, list[int]] = field(default_factory=dict)
    resolution: Resolution | None = None
    counted: dict[str, int] = field(default_factory=dict)
    n_vehicles: int | None = None

    @property
    def weight_step_kg(self) -> float | None:
        """The weight resolution in use [kg] (None: none)."""
        return None if self.resolution is None else self.resolution.step_kg

    @property
    def format_step_kg(self) -> float | None:
        """The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None
        for CSV (decimal numbers)."""
        return _unit_kg(self.format)

    @property
    def n_read(self) -> int:
        """Good records [-] (``n_vehicles`` when the vehicles were streamed, not kept)."""
        return len(self.vehicles) if self.n_vehicles is None else self.n_vehicles

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

    def describe_resolution(self) -> str:
        """The weight resolution in words: the step, where it came from and how sure its detection is."""
        if self.resolution is None:
            return "weight resolution: none detected (no axle loads)"
        return self.resolution.describe()

    def summary(self) -> str:
        """One line: records read and skipped, each reason with its first line numbers; what else was counted."""
        text = f"{self.n_read} records read, {self.n_skipped} skipped"
        text += f" ({self.reasons()})" if self.skipped else ""
        return text + "".join(f"; {n} {what}" for what, n in self.counted.items())


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


# ---- checks every format shares ------------------------------------------------------------------------------------
def _residues(parsed: dict, ok: np.ndarray) -> ResidueCounts:
    """The residue counts of the axle loads of the ``ok`` records (:mod:`bogie.weighings.resolution`)."""
    base = parsed.get("weight_base", "kg")
    counts = ResidueCounts(parsed["load_step"] or 1.0, POUND if base == "lb" else 1.0, base)
    counts.add(parsed["loads"][ok])
    return counts


def _check_vehicles(parsed: dict, gross_kg: float | None = None) -> tuple[ResidueCounts, float | None]:
    """The plausibility checks, in their order, on every record not bad yet. Returns the residue counts of the loads
    that passed the checks before the gross weight's, and the weight step the gross-weight check allowed for:
    ``gross_kg``, or (None) the one these counts support."""
    reasons: _Reasons = parsed["reasons"]
    col = parsed["columns"]
    loads, spacings = parsed["loads"], parsed["spacings"]
    # each range's ends are in: a value derived from a field (an integer times its unit) is compared with a tolerance
    # of REL_TOL, so that a field written at an end (18.75 m as 1875 cm) is not lost to a float's last bit
    lo, hi = AXLE_LOAD_RANGE
    reasons.flag(_outside(loads, lo, hi).any(axis=1), f"implausible axle load (allowed {lo:g}-{hi:g} kg)")
    lo, hi = SPACING_RANGE
    reasons.flag(_outside(spacings, lo, hi).any(axis=1), f"implausible axle spacing (allowed {lo:g}-{hi:g} m)")
    lo, hi = SPEED_RANGE
    speed = col["speed"]
    reasons.flag(_outside(speed, lo, hi), f"implausible speed (allowed {lo * 3.6:g}-{hi * 3.6:g} km/h)")
    counts = _residues(parsed, reasons.ok)
    step = detect_resolution(counts).step_kg if gross_kg is None else gross_kg
    total = np.nansum(loads, axis=1)
    gross = col["gross_weight"]
    if not np.isnan(gross).all():
        # half a step of the gross weight's field and of each axle's, at the file's resolution if coarser
        load_half = max(step or 0.0, parsed["load_step"]) / 2
        gross_half = max(step or 0.0, parsed["gross_step"]) / 2
        slack = GROSS_TOLERANCE * total + gross_half + col["n_axles"] * load_half
        # a gross weight 2.2 times the axles' sum: the gross in pounds and the axles in kilograms (or a file of
        # the other edition); said as such, not as any other mismatch
        pounds = np.abs(gross - total / POUND) <= GROSS_TOLERANCE * total / POUND + gross_half
        reasons.flag(pounds & (np.abs(gross - total) > slack), "gross weight 2.2 times the sum of the axle loads: "
                     "pounds where kilograms are expected?")  # fmt: skip
        reasons.flag(np.abs(gross - total) > slack, "gross weight is not the sum of the axle loads")
    reasons.flag(_shorter_than_wheelbase(parsed), "length shorter than the wheelbase")
    return counts, step


def _outside(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``values`` outside [lo, hi], the ends in, to a relative :data:`REL_TOL` (NaN is never outside)."""
    return (values < lo - REL_TOL * abs(lo)) | (values > hi + REL_TOL * abs(hi))


def _shorter_than_wheelbase(parsed: dict) -> np.ndarray:
    """Records whose stated length is shorter than the sum of their axle spacings (a length of 0: not given).

    In a fixed-width format the two are compared as the integers the file holds, in the format's unit (every
    layout writes the length and the spacings in one unit): a length equal to the wheelbase to the unit is not
    shorter. Summing the spacings in metres in floating point lost 2.9 % of a real MON file's records (2.95 + 1.35 =
    4.300000000000001 > 4.3). Where the units differ, or the values are decimals (CSV), the comparison allows
    :data:`REL_TOL`."""
    length = parsed["columns"]["length"]
    if "length_units" in parsed:
        (length_int, length_unit), (spacing_int, spacing_unit) = parsed["length_units"], parsed["spacing_units"]
        if length_unit == spacing_unit:
            wheelbase = np.where(spacing_int > 0, spacing_int, 0).sum(axis=1)
            return (length_int > 0) & (length_int < wheelbase)
    wheelbase = np.nansum(parsed["spacings"], axis=1)
    return (length > 0) & (length < wheelbase * (1.0 - REL_TOL))


def _key_columns(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> dict[str, np.ndarray]:
    """The record columns a repeat shares with the record it repeats, but its axles: time, lane, direction, speed
    (and the station of a TMG file). The one definition of the key, with the axle loads and spacings
    (:func:`_repeat_key` exactly, :func:`_hashes` by hash)."""
    col = parsed["columns"]
    extra = parsed.get("extra", {})
    return {
        "t": stamps[rows].view(np.int64), "lane": col["lane"][rows], "dir": col["direction"][rows],
        "speed": col["speed"][rows], **({"station": extra["station"][rows]} if "station" in extra else {}),
    }  # fmt: skip


def _repeat_key(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> pd.DataFrame:
    """The key of ``rows`` as a table, to compare exactly: :func:`_key_columns`, the axle loads and spacings."""
    return pd.DataFrame({
        **_key_columns(parsed, stamps, rows),
        **{f"w{i}": parsed["loads"][rows, i] for i in range(parsed["loads"].shape[1])},
        **{f"s{i}": parsed["spacings"][rows, i] for i in range(parsed["spacings"].shape[1])},
    })  # fmt: skip


def _hashes(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The 64-bit hashes of the repeat keys (:func:`_repeat_key`) of ``rows``, for the records of earlier chunks."""
    columns = list(_key_columns(parsed, stamps, rows).values())
    return key_hashes(columns, parsed["loads"][rows], parsed["spacings"][rows], parsed["columns"]["n_axles"][rows])


def _alike(parsed: dict, stamps: np.ndarray, seen: SeenStore | None) -> int:
    """How many good records are alike an earlier one (:func:`_repeat_key`; of an earlier chunk, by
    :func:`_hashes`): counted for a file of hourly time stamps, where two alike trucks in one hour are two
    vehicles."""
    good = np.flatnonzero(parsed["reasons"].ok)
    alike = np.zeros(len(good), bool)
    if len(good) >= 2:
        alike = _repeat_key(parsed, stamps, good).duplicated(keep="first").to_numpy()
    if seen is not None and len(good):
        hashes = _hashes(parsed, stamps, good)
        alike = alike | seen.add(stamps[good], hashes)
    return int(alike.sum())


def _flag_repeats(parsed: dict, stamps: np.ndarray, seen: SeenStore | None = None) -> None:
    """A good record equal to an earlier good one in time, lane, direction, speed, axle loads and spacings is bad:
    a WIM system does not weigh two vehicles in one lane at one instant (a record repeated by a copy or a retry)."""
    reasons: _Reasons = parsed["reasons"]
    everyone = np.flatnonzero(reasons.ok)
    repeat = np.zeros(len(reasons.code), bool)
    # only records that share their time with another can repeat one: compare the rest of the key for those only
    if len(everyone) >= 2:
        same_time = pd.Series(stamps[everyone].view(np.int64)).duplicated(keep=False).to_numpy()
        good = everyone[same_time]
        if len(good) >= 2:
            repeat[good[_repeat_key(parsed, stamps, good).duplicated(keep="first").to_numpy()]] = True
    if seen is not None and len(everyone):  # a repeat of a record of an earlier chunk, by its hash
        hashes = _hashes(parsed, stamps, everyone)
        # a repeat within the chunk has the hash of the record it repeats, added here too: adding every hash adds
        # the same set as adding the first of each only
        repeat[everyone[seen.add(stamps[everyone], hashes)]] = True
    reasons.flag(repeat, DUPLICATE)


# ---- the file ------------------------------------------------------------------------------------------------------
def _utf8(data: bytes) -> bytes:
    """``data`` if it is UTF-8; else decoded with U+FFFD for every undecodable byte and encoded again."""
    if data.isascii():
        return data
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("utf-8", errors="replace").encode("utf-8")
    return data


def _parse(data: bytes, fmt: str, path: str, gross_kg: float | None = None, seen: SeenStore | None = None) -> dict:
    """Parse every record of ``data`` in ``fmt`` and check it; a ValueError for a CSV header not the layout's.
    ``gross_kg``: the weight step the gross-weight check allows for (None: the one these records support);
    ``seen``: the hashes of the good records of earlier chunks (None: no earlier chunk)."""
    if fmt == "csv":
        data = _utf8(data)
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_csv(data, lines, path)
        stamps = parsed["stamps"]
    elif fmt in TMG_LAYOUTS:
        lines = _split(data)
        if not len(lines):
            return {}
        keep, dummies = split_dummies(lines, TMG_LAYOUTS[fmt])
        lines = lines.take(keep)
        parsed = parse_tmg(lines, TMG_LAYOUTS[fmt])
        parsed["line"] = lines.line
        parsed["counted"] = dummies
        stamps = None
    else:
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_fixed(lines, LAYOUTS[fmt])
        parsed["line"] = lines.line
        stamps = None
    parsed["counts"], parsed["gross_kg"] = _check_vehicles(parsed, gross_kg)
    if stamps is None:
        stamps = _timestamps(parsed["reasons"].ok, *parsed["stamp"])
    if fmt in TMG_LAYOUTS:  # time stamps to the hour: alike trucks of one hour are vehicles, counted, not dropped
        alike = _alike(parsed, stamps, seen)
        if alike:
            parsed["counted"][ALIKE] = alike
    else:
        _flag_repeats(parsed, stamps, seen)
    parsed["stamps"] = stamps
    return parsed


def _frame(parsed: dict) -> pd.DataFrame:
    ok = parsed["reasons"].ok
    n = parsed["columns"]["n_axles"][ok]
    width = int(n.max()) if len(n) else 2
    col = parsed["columns"]
    base = {
        "line": parsed["line"][ok], "head": col["head"][ok], "timestamp": parsed["stamps"][ok],
        **{k: col[k][ok] for k in ("speed", "gross_weight", "length", "n_axles", "n_groups", "lane", "direction",
                                   "transverse_position")},
    }  # fmt: skip
    pad = max(0, width - parsed["loads"].shape[1])
    loads = np.pad(parsed["loads"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
    spacings = np.pad(parsed["spacings"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, : width - 1]
    extra = {f"axle_load_{i + 1}": loads[:, i] for i in range(width)}
    extra.update({f"spacing_{i + 1}": spacings[:, i] for i in range(width - 1)})
    for name, values in parsed.get("extra", {}).items():  # TMG: station, vehicle_class
        extra[name] = values[ok]
    if parsed["widths"] is not None:
        widths = np.pad(parsed["widths"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
        extra.update({f"axle_width_{i + 1}": widths[:, i] for i in range(width)})
    # copy=False: the columns are fresh arrays; pandas would otherwise copy them into blocks (0.7 s a million rows)
    frame = pd.DataFrame({**base, **extra}, copy=False)
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
    # a TMG file's dummy hour records fit their edition: they are its records too, though not vehicles
    dummies = sum(n for what, n in parsed.get("counted", {}).items() if what.startswith("dummy"))
    return int(ok.sum()) + dummies, len(ok) + dummies


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


def _unit_kg(fmt: str) -> float | None:
    """The weight unit of format ``fmt`` [kg]: its axle load field's scale; None for CSV (decimal numbers)."""
    if fmt in TMG_LAYOUTS:
        return TMG_LAYOUTS[fmt].weight_unit_kg
    return None if fmt == "csv" else LAYOUTS[fmt].axle_field("axle_load").scale


def _format_name(fmt: str) -> str:
    """How a message names the format's records: 'CSV layout', 'MON records', 'TMG 2001 records'."""
    if fmt == "csv":
        return "CSV layout"
    return f"{(TMG_LAYOUTS[fmt] if fmt in TMG_LAYOUTS else LAYOUTS[fmt]).name} records"


def read_weighings(
    path: str | Path, fmt: str = "auto", resolution_kg: float | None = None, chunk_bytes: int = CHUNK_BYTES
) -> ReadResult:
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
    resolution_kg
        The file's weight resolution [kg], in (0, 1000] and a whole multiple of the format's weight unit; None
        (default): detected from the loads (:mod:`bogie.weighings.resolution`), and reported either way.
    chunk_bytes
        Bytes of records parsed at a time (:func:`stream_weighings`); the result does not depend on it.

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
    frames: list[pd.DataFrame] = []

    def start() -> None:
        frames.clear()

    # the whole table is held: a file past MAX_FILE_BYTES is refused (stream it with stream_weighings)
    result = stream_weighings(path, fmt, resolution_kg, start, frames.append, chunk_bytes, _records.MAX_FILE_BYTES)
    result.vehicles = _concat(frames)
    return result


def _concat(frames: list[pd.DataFrame]) -> pd.DataFrame:
    """The chunks' vehicle tables as one, the axle columns of the widest (NaN where a chunk had fewer)."""
    if len(frames) == 1:
        return frames[0]
    frame = pd.concat(frames, ignore_index=True)
    axles = sorted((c for c in frame.columns if c.startswith(("axle_load_", "spacing_", "axle_width_"))),
                   key=lambda c: (c.rsplit("_", 1)[0], int(c.rsplit("_", 1)[1])))  # fmt: skip
    order = [c for c in frame.columns if not c.startswith(("axle_load_", "spacing_", "axle_width_"))]
    tail = [c for c in order if c in ("station", "vehicle_class")]
    head = [c for c in order if c not in tail]
    width = [c for c in axles if c.startswith("axle_load_")] + [c for c in axles if c.startswith("spacing_")]
    width += [c for c in axles if c.startswith("axle_width_")]
    return frame[head + width + tail]


def stream_weighings(
    path: str | Path,
    fmt: str,
    resolution_kg: float | None,
    start: Callable[[], None],
    consume: Callable[[pd.DataFrame], None],
    chunk_bytes: int = CHUNK_BYTES,
    max_bytes: int | None = None,
) -> ReadResult:
    """Read a file of weighings chunk by chunk (:mod:`bogie.weighings._stream`): ``consume`` gets each chunk's
    vehicle table (the good records, as :func:`read_weighings`' rows, in file order), and the result is
    :func:`read_weighings`' without its vehicles (``n_vehicles`` counts them).

    The gross-weight check allows for the file's weight resolution, which is known only at the end: the first
    chunk's is used, and if the whole file's differs, the file is read again with it (``start`` is called before
    every pass, so that the consumer begins afresh). The records are then those of a whole-file read, and so are
    the repeats (of an earlier chunk, by a 64-bit hash of their key). Memory: a few times ``chunk_bytes`` and at most
    :data:`bogie.weighings._stream.SEEN_IN_MEMORY` hashes of the good records (the rest on disk), whatever the file's
    length; ``max_bytes``: refuse a file of more bytes (None: any length; :func:`read_weighings`, which holds the
    whole table, refuses one past :data:`bogie.weighings._records.MAX_FILE_BYTES`).
    """
    if fmt != "auto" and fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} unknown; allowed: auto, {', '.join(FORMATS)}")
    check_resolution_kg(resolution_kg, None)  # its type and range before the file is read; its unit once known
    path = Path(path)
    first_block = next(blocks(path, max_bytes, chunk_bytes))[0]
    if fmt == "auto":
        head = _head(first_block, SNIFF_LINES)
        if not head.strip():
            raise ValueError(f"{path}: no records: format auto found an empty file")
        fmt = _detect(head, str(path))
    name = _format_name(fmt)
    resolution_kg = check_resolution_kg(resolution_kg, _unit_kg(fmt))
    gross_kg = resolution_kg
    while True:
        start()
        tally = _pass(path, fmt, gross_kg, consume, chunk_bytes, first_block, max_bytes)
        if tally["records"] == 0:
            found = "a header and no record" if tally["header"] or _head(first_block, 1).strip() else "an empty file"
            if tally["counted"]:
                found = "dummy hour records only (" + "; ".join(f"{n} {w}" for w, n in tally["counted"].items()) + ")"
            raise ValueError(f"{path}: no records: expected {name} (format {fmt}), found {found}")
        resolution = detect_resolution(tally["counts"], resolution_kg)
        if resolution_kg is not None or resolution.step_kg == tally["gross_kg"]:
            break
        gross_kg = resolution.step_kg  # the first chunk's step was not the file's: read again with the file's
    result = ReadResult(pd.DataFrame(), fmt, tally["skipped"], tally["bad_lines"], resolution, tally["counted"],
                        tally["good"])  # fmt: skip
    total = result.n_read + result.n_skipped
    if result.n_skipped > MAX_BAD_FRACTION * total:
        first = _head(first_block, 1).decode("utf-8", errors="replace").rstrip()
        raise ValueError(
            f"{path}: not read as {name} (format {fmt}): {result.n_skipped} of {total} records bad "
            f"({result.reasons()}); first line {_shown(first)}" + _sniff(first_block, fmt)
        )
    return result


def _pass(
    path: Path, fmt: str, gross_kg: float | None, consume, chunk_bytes: int, first_block: bytes, max_bytes: int | None
) -> dict:
    """One pass over the file's chunks: each parsed and checked, and its vehicles consumed on a second thread while
    the next chunk is parsed (one chunk at a time, in file order: the consumer sees what a single thread would give
    it); the tallies of the pass."""
    seen = SeenStore()
    tally = {"records": 0, "good": 0, "header": False, "skipped": Counter(), "bad_lines": {}, "counted": Counter(),
             "counts": None}  # fmt: skip
    header = b""
    behind = None  # the chunk being consumed
    with ThreadPoolExecutor(1) as pool:
        for k, (block, lines_before) in enumerate(blocks(path, max_bytes, chunk_bytes)):
            data, offset = block, lines_before
            if fmt == "csv":
                if k == 0:
                    end = block.find(b"\n")
                    header = block[: end + 1] if end >= 0 else block + b"\n"
                else:
                    data, offset = header + block, lines_before - 1  # the header is line 1 of the chunk
            try:
                parsed = _parse(data, fmt, str(path), gross_kg, seen)
            except ValueError as exc:  # a CSV header that is not the layout's
                raise ValueError(f"{exc}{_sniff(first_block, fmt)}") from None
            if not parsed:
                continue
            if gross_kg is None:
                gross_kg = parsed["gross_kg"]  # the first chunk's resolution, for the chunks after it
            tally["gross_kg"] = gross_kg if k else parsed["gross_kg"]
            parsed["line"] = parsed["line"] + offset
            if _count(tally, parsed):
                if behind is not None:
                    behind.result()
                behind = pool.submit(consume, _frame(parsed))
        if behind is not None:
            behind.result()
    seen.close()  # on an exception, when the store is collected
    tally.update(counted=dict(tally["counted"]), counts=tally["counts"] or ResidueCounts(None))
    tally.setdefault("gross_kg", gross_kg)
    return tally


def _count(tally: dict, parsed: dict) -> bool:
    """Add a parsed chunk's records, skips (with their first lines), dummy records and weight residues to the pass's
    ``tally``; whether the chunk has a good record."""
    tally["header"] = True
    reasons: _Reasons = parsed["reasons"]
    tally["records"] += len(reasons.code)
    tally["good"] += int(reasons.ok.sum())
    chunk_skipped, chunk_lines = reasons.counted(parsed["line"])
    tally["skipped"].update(chunk_skipped)
    for reason, lines in chunk_lines.items():
        tally["bad_lines"][reason] = (tally["bad_lines"].get(reason, []) + lines)[:EXAMPLES]
    tally["counted"].update(parsed.get("counted", {}))
    if tally["counts"] is None:
        tally["counts"] = parsed["counts"]
    else:
        tally["counts"].merge(parsed["counts"])
    return bool(reasons.ok.any())
