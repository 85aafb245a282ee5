"""The record layouts the readers know: the documented CSV columns and the fixed-width WIM exchange formats.

Every fixed-width layout is data, not code: one :class:`FixedWidthLayout` per format, each header field with its own
0-based start offset and width, and the per-axle block (axle weight, DITIS's axle width, spacing) with its start and
stride. Source: ``/work/shared/reference/wim-record-formats.md`` (the BTLS documentation's "Traffic file format"
table, checked there against the character offsets of BTLS' own readers), one section per format, cited on each
entry. ``docs/weighings.md`` prints the four layouts. ``assumed`` lists, per layout, only what that reference does
not say (the places it is silent); every offset, width and unit is the reference's.

Conventions (the reference's preamble): one vehicle a line, no separators; every field an unsigned integer
(Fortran ``In``), right-aligned, padded with spaces or zeros; a field is ``line[start:start + width]``. ``scale``
turns the integer into SI (kg, m, m/s, s); ``None`` marks a count, a code or a calendar field. Axle fields repeat
after the header, axle i (1-based) at ``axles.start + axles.stride * (i - 1)``: a field with ``per="axle"`` is
there for every one of the n axles, one with ``per="gap"`` (the spacing from axle i to i + 1) for i < n only. The
spacing slot after the last axle and any padding after it may or may not be in the file and are ignored; a line
that does not reach the end of the last axle's ``per="axle"`` fields (:meth:`FixedWidthLayout.min_record_length`)
is a bad record.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

__all__ = [
    "CM", "CSV_COLUMNS", "DM", "DMS", "FORMATS", "KG", "KG100", "KMH", "LAYOUTS", "MM", "MS", "REFERENCE", "S100",
    "TMG_FORMATS",
    "AxleBlock", "Field", "FixedWidthLayout",
]  # fmt: skip

#: the reference every fixed-width layout is taken from
REFERENCE = "wim-record-formats.md (shared reference; the BTLS documentation's traffic file format table)"

# ---- units: the integer as written -> SI ---------------------------------------------------------------------------
#: kg -> kg
KG = 1.0
#: "kg/100", hundreds of kilograms (123 = 12 300 kg) -> kg
KG100 = 100.0
#: mm -> m
MM = 1e-3
#: cm -> m
CM = 1e-2
#: dm -> m
DM = 1e-1
#: dm/s -> m/s
DMS = 0.1
#: km/h -> m/s
KMH = 1.0 / 3.6
#: hundredths of a second -> s
S100 = 0.01
#: milliseconds -> s
MS = 1e-3


@dataclass(frozen=True)
class Field:
    """One fixed-width unsigned integer ``line[start:start + width]``; times ``scale`` (if not None) gives SI.

    ``start`` is 0-based; in an :class:`AxleBlock` it is relative to the block of the axle. ``per`` is ``"record"``
    (a header field), ``"axle"`` (one per axle) or ``"gap"`` (one per pair of consecutive axles: n - 1).
    """

    name: str
    start: int
    width: int
    scale: float | None
    unit: str
    per: str = "record"

    @property
    def end(self) -> int:
        """First offset past the field (``[start, end)``) [-]."""
        return self.start + self.width


@dataclass(frozen=True)
class AxleBlock:
    """The per-axle fields: axle i (1-based) starts at ``start + stride * (i - 1)``."""

    start: int  # the header's width
    stride: int  # characters per axle
    fields: tuple[Field, ...]


@dataclass(frozen=True)
class FixedWidthLayout:
    """A fixed-width record: header fields at their own offsets, then one :class:`AxleBlock` per axle.

    ``max_axles`` is the format's own limit; ``direction_base`` 1 (direction written 1 or 2) or 0 (written 0 or 1):
    the reader stores ``written - direction_base + 1``, so the direction is 1 or 2 in every format.
    ``weight_step_kg`` is the format's weight resolution (None: the file's own, MON).
    """

    name: str
    section: str  # the reference's section
    header: tuple[Field, ...]
    axles: AxleBlock
    max_axles: int
    direction_base: int
    weight_step_kg: float | None
    source: str
    assumed: tuple[str, ...]

    @property
    def fixed_width(self) -> int:
        """Characters before the first axle (the header) [-]: CASTOR 34, BeDIT 35, DITIS 37, MON 50."""
        return max(f.end for f in self.header)

    @property
    def year_digits(self) -> int:
        """Digits of the year, the year field's width: 2 (century not given: read as 2000-2099) or 4 [-]."""
        return next(f.width for f in self.header if f.name == "year")

    @functools.cached_property
    def scales(self) -> dict[str, float | None]:
        """Each header field's ``scale`` by name."""
        return {f.name: f.scale for f in self.header}

    def axle_field(self, name: str) -> Field:
        """The per-axle field ``name``."""
        return next(f for f in self.axles.fields if f.name == name)

    def min_record_length(self, n_axles: int) -> int:
        """The shortest line holding ``n_axles`` axles: through the last axle's per-axle fields [-].

        CASTOR 5n + 32, BeDIT 6n + 32, DITIS 9n + 34, MON 10n + 45.
        """
        last = max(f.end for f in self.axles.fields if f.per == "axle")
        return self.axles.start + self.axles.stride * (n_axles - 1) + last


#: the reference does not say these, for any of the four formats (docs/weighings.md, "Where the reference is silent")
_SILENT = (
    "which physical direction each direction code means",
    "whether the lane is numbered within its direction or across the road",
    "the reference point and sign of the transverse position",
    "how a missing value is written (an all-blank field is read as a bad record)",
    "time zone (read as local time, as written)",
)


def _calendar(year_width: int) -> tuple[Field, ...]:
    """CASTOR's, BeDIT's and DITIS's date and time from offset 4: day, month, year (``year_width`` digits), hour,
    minute, second, second/100, I2 each but the year."""
    year_end = 8 + year_width
    return (
        Field("day", 4, 2, None, "-"),
        Field("month", 6, 2, None, "-"),
        Field("year", 8, year_width, None, "-"),
        Field("hour", year_end, 2, None, "-"),
        Field("minute", year_end + 2, 2, None, "-"),
        Field("second", year_end + 4, 2, 1.0, "s"),
        Field("second_100", year_end + 6, 2, S100, "s/100"),
    )


LAYOUTS: dict[str, FixedWidthLayout] = {
    # reference, section "MON (no fixed axle limit; 2-digit axle count)": header 50, 10 characters per axle
    "mon": FixedWidthLayout(
        name="MON", section="MON (no fixed axle limit; 2-digit axle count)",
        header=(
            Field("head", 0, 9, None, "-"),  # I9
            Field("day", 9, 2, None, "-"),
            Field("month", 11, 2, None, "-"),
            Field("year", 13, 4, None, "-"),
            Field("hour", 17, 2, None, "-"),
            Field("minute", 19, 2, None, "-"),
            Field("millisecond", 21, 5, MS, "ms"),  # milliseconds of the minute, 0-59 999: no separate seconds
            Field("n_axles", 26, 2, None, "-"),
            Field("n_groups", 28, 2, None, "-"),  # the WIM system's own count of axle groups
            Field("gross_weight", 30, 6, KG, "kg"),
            Field("speed", 36, 3, KMH, "km/h"),
            Field("length", 39, 5, MM, "mm"),
            Field("lane", 44, 1, None, "-"),  # lane BEFORE direction in MON only
            Field("direction", 45, 1, None, "0|1"),  # zero-based
            Field("transverse_position", 46, 4, MM, "mm"),
        ),
        axles=AxleBlock(start=50, stride=10, fields=(
            Field("axle_load", 0, 5, KG, "kg", "axle"),  # 50 + 10(i-1)
            Field("spacing", 5, 5, MM, "mm", "gap"),  # 55 + 10(i-1)
        )),
        max_axles=99, direction_base=0, weight_step_kg=None,
        source=f"{REFERENCE}, section MON",
        assumed=(*_SILENT, "how the WIM system forms the axle groups it counts (kept, not used for grouping)"),
    ),
    # reference, section "CASTOR (at most 9 axles)": header 34, 5 characters per axle
    "castor": FixedWidthLayout(
        name="CASTOR", section="CASTOR (at most 9 axles)",
        header=(
            Field("head", 0, 4, None, "-"),  # "head (record / site number)", I4
            *_calendar(2),
            Field("speed", 18, 3, DMS, "dm/s"),
            Field("gross_weight", 21, 4, KG100, "kg/100"),
            Field("length", 25, 3, DM, "dm"),
            Field("n_axles", 28, 1, None, "-"),  # I1
            Field("direction", 29, 1, None, "1|2"),
            Field("lane", 30, 1, None, "-"),
            Field("transverse_position", 31, 3, DM, "dm"),
        ),
        axles=AxleBlock(start=34, stride=5, fields=(
            Field("axle_load", 0, 3, KG100, "kg/100", "axle"),  # 34 + 5(i-1)
            Field("spacing", 3, 2, DM, "dm", "gap"),  # 37 + 5(i-1); I2: at most 9.9 m
        )),
        max_axles=9, direction_base=1, weight_step_kg=100.0,
        source=f"{REFERENCE}, section CASTOR",
        assumed=(*_SILENT, "the century of the two-digit year (read as 2000-2099)"),
    ),
    # reference, section "BeDIT (at most 20 axles)": header 35, 6 characters per axle
    "bedit": FixedWidthLayout(
        name="BeDIT", section="BeDIT (at most 20 axles)",
        header=(
            Field("head", 0, 4, None, "-"),
            *_calendar(2),
            Field("speed", 18, 3, DMS, "dm/s"),
            Field("gross_weight", 21, 4, KG100, "kg/100"),
            Field("length", 25, 3, DM, "dm"),
            Field("n_axles", 28, 2, None, "-"),  # I2
            Field("direction", 30, 1, None, "0|1"),  # zero-based
            Field("lane", 31, 1, None, "-"),
            Field("transverse_position", 32, 3, DM, "dm"),
        ),
        axles=AxleBlock(start=35, stride=6, fields=(
            Field("axle_load", 0, 3, KG100, "kg/100", "axle"),  # 35 + 6(i-1)
            Field("spacing", 3, 3, DM, "dm", "gap"),  # 38 + 6(i-1)
        )),
        max_axles=20, direction_base=0, weight_step_kg=100.0,
        source=f"{REFERENCE}, section BeDIT",
        assumed=(*_SILENT, "the century of the two-digit year (read as 2000-2099)"),
    ),
    # reference, section "DITIS (at most 20 axles)": header 37, 9 characters per axle
    "ditis": FixedWidthLayout(
        name="DITIS", section="DITIS (at most 20 axles)",
        header=(
            Field("head", 0, 4, None, "-"),
            *_calendar(4),  # offsets 4, 6, 8 (I4), 12, 14, 16, 18
            Field("speed", 20, 3, DMS, "dm/s"),
            Field("gross_weight", 23, 4, KG100, "kg/100"),
            Field("length", 27, 3, DM, "dm"),
            Field("n_axles", 30, 2, None, "-"),
            Field("direction", 32, 1, None, "1|2"),
            Field("lane", 33, 1, None, "-"),
            Field("transverse_position", 34, 3, CM, "cm"),  # cm here; CASTOR and BeDIT: dm
        ),
        axles=AxleBlock(start=37, stride=9, fields=(
            Field("axle_load", 0, 3, KG100, "kg/100", "axle"),  # 37 + 9(i-1)
            Field("axle_width", 3, 3, CM, "cm", "axle"),  # 40 + 9(i-1): axle width (track)
            Field("spacing", 6, 3, DM, "dm", "gap"),  # 43 + 9(i-1)
        )),
        max_axles=20, direction_base=1, weight_step_kg=100.0,
        source=f"{REFERENCE}, section DITIS",
        assumed=(*_SILENT, "the last axle's width is required (the reference says only that what follows the "
                 "last weight may be ignored)"),
    ),
}  # fmt: skip

#: the CSV layout's required columns (issue 13 item 1a): timestamp (ISO 8601), speed [km/h], lane, number of
#: axles, then axle_load_1..n [kg] and spacing_1..n-1 [m]; a file may have more axle columns and other columns
CSV_COLUMNS: tuple[str, ...] = ("timestamp", "speed_kmh", "lane", "n_axles")

#: the US truck weight record's editions (FHWA Traffic Monitoring Guide, "W" record; layouts in
#: ``bogie.weighings._tmg.TMG_LAYOUTS``)
TMG_FORMATS: tuple[str, ...] = ("tmg2001", "tmg2013")

#: every format the readers take, CSV first
FORMATS: tuple[str, ...] = ("csv", *LAYOUTS, *TMG_FORMATS)
