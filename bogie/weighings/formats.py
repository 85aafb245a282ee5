"""The record layouts the readers know: the documented CSV columns and the fixed-width WIM exchange formats.

Every fixed-width layout is data, not code: one :class:`FixedWidthLayout` per format, its fields in record order,
each with its width in characters and the factor that turns its integer into SI (kg, m, m/s). ``docs/weighings.md``
prints each layout with an example record and says where it comes from. **No authoritative specification of MON,
CASTOR, BeDIT or DITIS was available to this project**: the widths and units below are the ones the project's
issue 13 states (MON: a 9-character head, a 4-digit year, milliseconds, a number of axle groups, 5-character axle
weights [kg] and spacings [mm]) and, for everything else, assumptions marked ``assumed`` in each layout's
``assumed`` tuple. Correct a layout here, against the format's documentation, and the reader follows.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CSV_COLUMNS", "FORMATS", "LAYOUTS", "Field", "FixedWidthLayout", "KMH", "DMS"]

#: km/h -> m/s [m/s per km/h]
KMH = 1.0 / 3.6
#: dm/s -> m/s [m/s per dm/s]
DMS = 0.1


@dataclass(frozen=True)
class Field:
    """One fixed-width numeric field: ``width`` characters, an unsigned integer, times ``scale`` gives SI."""

    width: int
    scale: float = 1.0
    unit: str = "-"


@dataclass(frozen=True)
class FixedWidthLayout:
    """A fixed-width record: head, date, time, speed, gross weight, length, number of axles, [number of axle
    groups], lane, direction, then ``n`` axle weights and ``n - 1`` axle spacings, in that order.

    ``date`` is ``"YYYYMMDD"`` or ``"YYMMDD"`` (two-digit years are 2000-2099); ``time_fraction`` the digits after
    HHMMSS (3: milliseconds, 2: hundredths, 0: none). Scales turn the integers into kg, m and m/s.
    """

    name: str
    head: int
    date: str
    time_fraction: int
    speed: Field
    gross_weight: Field
    length: Field
    n_axles: int
    n_groups: int  # 0: the format has no number of axle groups
    lane: int
    direction: int
    axle_load: Field
    spacing: Field
    source: str
    assumed: tuple[str, ...]

    @property
    def fixed_width(self) -> int:
        """Characters before the first axle weight [-]."""
        return (
            self.head + len(self.date) + 6 + self.time_fraction + self.speed.width + self.gross_weight.width
            + self.length.width + self.n_axles + self.n_groups + self.lane + self.direction
        )  # fmt: skip

    def record_length(self, n_axles: int) -> int:
        """Characters of a record of ``n_axles`` axles (without the line end) [-]."""
        return self.fixed_width + n_axles * self.axle_load.width + (n_axles - 1) * self.spacing.width


_ISSUE = "bogie issue 13 (no format specification was available; see docs/weighings.md)"

LAYOUTS: dict[str, FixedWidthLayout] = {
    "mon": FixedWidthLayout(
        name="MON", head=9, date="YYYYMMDD", time_fraction=3,
        speed=Field(4, DMS, "dm/s"), gross_weight=Field(6, 1.0, "kg"), length=Field(5, 1e-3, "mm"),
        n_axles=2, n_groups=2, lane=1, direction=1,
        axle_load=Field(5, 1.0, "kg"), spacing=Field(5, 1e-3, "mm"),
        source=f"{_ISSUE}: 9-character head, 4-digit year, milliseconds, number of axle groups, 5-character axle "
        "weights [kg] and spacings [mm]",
        assumed=("field order", "month, day, hour, minute, second 2 digits each", "speed 4 digits [dm/s]",
                 "gross weight 6 digits [kg]", "length 5 digits [mm]", "number of axles 2 digits",
                 "number of axle groups 2 digits", "lane 1 digit", "direction 1 character",
                 "all weights, then all spacings"),
    ),
    "castor": FixedWidthLayout(
        name="CASTOR", head=6, date="YYMMDD", time_fraction=2,
        speed=Field(3, KMH, "km/h"), gross_weight=Field(4, 100.0, "100 kg"), length=Field(3, 0.1, "dm"),
        n_axles=2, n_groups=0, lane=1, direction=1,
        axle_load=Field(3, 100.0, "100 kg"), spacing=Field(3, 0.1, "dm"),
        source=f"{_ISSUE}: the issue names kg/100, dm and km/h among the formats' units without saying which "
        "format uses which",
        assumed=("every width", "every unit", "field order", "two-digit year (2000-2099)",
                 "time to hundredths of a second (the COST 323 recommendation hh:mm:ss:cc)"),
    ),
    "bedit": FixedWidthLayout(
        name="BeDIT", head=8, date="YYYYMMDD", time_fraction=2,
        speed=Field(4, DMS, "dm/s"), gross_weight=Field(6, 1.0, "kg"), length=Field(4, 0.1, "dm"),
        n_axles=2, n_groups=0, lane=2, direction=1,
        axle_load=Field(5, 1.0, "kg"), spacing=Field(4, 0.1, "dm"),
        source=_ISSUE,
        assumed=("every width", "every unit", "field order"),
    ),
    "ditis": FixedWidthLayout(
        name="DITIS", head=6, date="YYYYMMDD", time_fraction=0,
        speed=Field(3, KMH, "km/h"), gross_weight=Field(4, 100.0, "100 kg"), length=Field(5, 1e-3, "mm"),
        n_axles=2, n_groups=0, lane=1, direction=1,
        axle_load=Field(3, 100.0, "100 kg"), spacing=Field(5, 1e-3, "mm"),
        source=_ISSUE,
        assumed=("every width", "every unit", "field order"),
    ),
}  # fmt: skip

#: the CSV layout's required columns (issue 13 item 1a): timestamp (ISO 8601), speed [km/h], lane, number of
#: axles, then axle_load_1..n [kg] and spacing_1..n-1 [m]; a file may have more axle columns and other columns
CSV_COLUMNS: tuple[str, ...] = ("timestamp", "speed_kmh", "lane", "n_axles")

#: every format the readers take, CSV first
FORMATS: tuple[str, ...] = ("csv", *LAYOUTS)
