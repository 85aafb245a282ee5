"""An observed survey from Python: read a file of weighings (or several, each a site), split it into axle groups,
filter, tabulate.

:func:`observed_survey` is what ``bogie weighings`` prints; its statistics are those of
:func:`bogie.weighings.stats.survey_statistics`, the function the pipeline's survey stage applies to the simulated
fleet.

**Memory** (:func:`observed_survey`'s ``keep_groups``). True (default): ``groups`` holds every kept group with all
its columns, in memory. False: ``groups`` is empty (``n_kept`` still counts every kept group); the tandems and
tri-axles are written to a temporary directory as they are made (:class:`bogie.weighings._spill.GroupSpill`, 29
bytes a group, removed at the end) and the statistics, road figures and stations computed from there, the same
figures, so that memory does not depend on the file's length (``bogie weighings``, the pipeline's observed stage).

**The sink** (:func:`observed_survey`'s ``sink``): None, or an object with ``start()`` and ``write(groups)``: given
each chunk's kept groups (every size, all columns) as they are made, after a ``start()`` before every pass over the
file (the pipeline's observed stage writes its groups file so). ``write`` runs on the reader's second thread (one
call at a time, in file order; :func:`bogie.weighings.readers.stream_weighings`), ``start`` on the calling thread.
For a survey of several files the sink also needs ``next_file(site)``, called before each file's first pass: a
``start()`` then discards only what was written since (that file's groups), not the files before it.

**Several files** (issue 46): ``path`` a folder or a list of files, each a site
(:func:`bogie.weighings.files.survey_files`). They are read one after another into one tally, so the statistics,
road figures and positions are those of all their groups pooled, computed once, as if the files were one; a file
read again (its resolution not its first chunk's) goes back to where the tally stood before it
(:meth:`_Tally.begin_file`). ``stations`` then holds each site (``name``, or ``name:station`` for a file of
stations), and ``files`` each file's records. Repeats are looked for within a file, not across files (another site
weighs other passes).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bogie.group_names import GROUP_NAMES
from bogie.weighings import _records
from bogie.weighings._several import check_alike, file_entry, pooled_read
from bogie.weighings._spill import GroupSpill, spilled_statistics, spilled_wear
from bogie.weighings._stream import CHUNK_BYTES
from bogie.weighings.files import survey_files
from bogie.weighings.groups import (
    GROUP_SPACING_M,
    GROUP_TABLE_COLUMNS,
    POSITIONS,
    SIZES,
    axle_groups,
    filter_groups,
    grouping_rule,
)
from bogie.weighings.legal import EU_SOURCE, spacing_step_m
from bogie.weighings.legal import POSITIONS as LEGAL_POSITIONS
from bogie.weighings.readers import ReadResult, stream_weighings
from bogie.weighings.sites import COUNT_KEYS, counts_of_statistics
from bogie.weighings.stats import STATISTICS_COLUMNS, axle_columns, statistics_dict, survey_statistics
from bogie.weighings.wear import DAMAGE_EXPONENTS, wear_dict, wear_statistics

__all__ = ["SURVEYED", "ObservedSurvey", "observed_survey"]

#: the group sizes the statistics are tabulated for
SURVEYED: tuple[str, ...] = GROUP_NAMES


#: the size labels of the position counts, by axles in the group (4 and more: other)
SIZE_LABELS = {1: "single", **SIZES}


@dataclass
class ObservedSurvey:
    """An observed survey: the groups that passed the filters, their statistics and what the reader skipped.

    Attributes
    ----------
    groups
        One row per group (:func:`bogie.weighings.groups.axle_groups`), every size, after the filters (empty for a
        survey streamed with ``keep_groups=False``); for a survey of sites (several files, a file of stations) also
        ``site``, each group's site as :attr:`stations` names it.
    statistics
        :func:`bogie.weighings.stats.survey_statistics` of the tandems and tri-axles, one row each.
    read
        The reader's result: the vehicles and the skipped records.
    positions
        How many groups of each position (steer, drive, trailer) and size (single, tandem, triaxle, other: 4 or
        more axles) the file has,
        before any filter: in a WIM file most laden tandems are tractors' drive tandems, not trailer groups.
    road
        :func:`bogie.weighings.wear.wear_statistics` of the tandems and tri-axles, one row each: the extra pavement
        wear their unequal sharing causes and the overloaded axles hidden in legal groups.
    settings
        What the survey was computed with: the file, its format, the resolution's source, the filters, the
        grouping rule, the legal loads and the damage exponents (``to_dict()["settings"]``).
    stations
        For a file of more than one station (a state-wide TMG file): per station, its vehicles and the statistics
        of its tandems and tri-axles (``{station: {"vehicles": n, "groups": {size: {...}}}}``); for several files,
        the same per site (a file, or a file's station: ``name:station``); empty otherwise.
    n_kept
        The groups kept by the filters, every size [-].
    files
        For several files: per file, its path, site, format and records (:func:`bogie.weighings._several.file_entry`);
        None for one file.
    """

    groups: pd.DataFrame
    statistics: pd.DataFrame
    read: ReadResult
    positions: dict[str, dict[str, int]]
    road: pd.DataFrame
    settings: dict[str, Any] | None = None
    stations: dict[str, dict[str, Any]] | None = None
    n_kept: int | None = None
    files: list[dict[str, Any]] | None = None

    def site_counts(self, name: str) -> dict[str, dict[str, dict[str, Any]]]:
        """Each site's counts for :func:`bogie.weighings.sites.compare_sites`: the file as the site ``name``, or, for a
        file of several stations, each station as ``name:station``; for several files, each site by its own name
        (``name`` unused)."""
        if self.stations:
            prefix = "" if self.files else f"{name}:"
            return {
                f"{prefix}{station}": {
                    size: {key: e.get(key, 0 if key.startswith("n_") else None) for key in COUNT_KEYS}
                    for size, e in entry["groups"].items()
                }
                for station, entry in self.stations.items()
            }  # fmt: skip
        return {name: counts_of_statistics(self.statistics)}

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``bogie weighings --json``: records read and skipped, then the statistics per group size.

        ``{"records": {"read", "skipped", "weight_step_kg"}, "positions": {"steer": {"tandem": n, ...}, ...},
        "groups": {"tandem": {...}, "triaxle": {...}}}``; shares are fractions 0..1; a size with no group has
        ``n_groups`` 0 and None for its numbers; ``weight_step_kg`` is the file's weight resolution in use [kg]
        (None: not whole kilograms), ``resolution`` where it came from and the evidence
        (:meth:`bogie.weighings.resolution.Resolution.to_dict`). ``road`` per size:
        :func:`bogie.weighings.wear.wear_statistics`'s figures (extra wear as a fraction, extra standard axles per
        1,000 groups, hidden overloads, with their intervals).
        """
        stats = statistics_dict(self.statistics)
        road = wear_dict(self.road, ["group"]) if len(self.road) else {}
        empty = {"n_groups": 0, **dict.fromkeys(STATISTICS_COLUMNS[1:]), "load_share_quantiles": {}}
        return {
            "settings": self.settings or {},
            "records": {
                "read": self.read.n_read,
                "skipped": self.read.n_skipped,
                "weight_step_kg": self.read.weight_step_kg,
                "resolution": None if self.read.resolution is None else self.read.resolution.to_dict(),
            },
            "positions": self.positions,
            "groups": {size: stats.get(size, empty) for size in SURVEYED},
            "road": {size: road.get(size, {"n_groups": 0}) for size in SURVEYED},
            **({"stations": self.stations} if self.stations else {}),
            **({"files": self.files} if self.files else {}),
        }


def observed_survey(
    path: str | Path | Sequence[str | Path],
    fmt: str,
    *,
    min_group_load_kg: float = 0.0,
    group_spacing_m: float = GROUP_SPACING_M,
    position: str = "all",
    speed_kmh: Sequence[float] | None = None,
    legal_group_kg: dict[str, float] | None = None,
    legal_axle_kg: float | None = None,
    resolution_kg: float | None = None,
    grouping: str = "spacing",
    chunk_bytes: int = CHUNK_BYTES,
    keep_groups: bool = True,
    sink: Any = None,
) -> ObservedSurvey:
    """Read ``path`` in format ``fmt``, group the axles, filter the groups and compute the survey statistics.

    Parameters
    ----------
    path, fmt
        The file and its format (:func:`bogie.weighings.readers.read_weighings`); or a folder or a list of files, each
        a site, of one format and one weight resolution (the module docstring, "Several files").
    min_group_load_kg, group_spacing_m
        Smallest group load kept [kg]; largest spacing of two axles of one group [m]. Keywords only (issue 42).
    position, speed_kmh
        ``all``, ``steer``, ``drive`` or ``trailer``; (lowest, highest) speed kept [km/h], None keeping every speed.
    legal_group_kg, legal_axle_kg
        Legal load of each group size and of one axle, stated single limits for the axles above the single-axle
        limit within legal groups [kg]; None: Directive 96/53/EC's by each group's position and spacing
        (:func:`bogie.weighings.legal.group_limits`).
    resolution_kg
        The file's weight resolution [kg]; None: detected (:func:`bogie.weighings.readers.read_weighings`).
    grouping
        ``spacing`` (axles at most ``group_spacing_m`` apart) or ``us-tandem`` (23 CFR 658.5's 40-96 in band;
        :func:`bogie.weighings.groups.axle_groups`).
    chunk_bytes
        Bytes of records read at a time (:func:`stream_weighings`): the statistics do not depend on it.
    keep_groups, sink
        True (default): ``groups`` holds every kept group in memory; False: spilled to disk, in bounded memory (the
        module docstring, "Memory"). None, or a sink given each chunk's kept groups (the module docstring).

    Raises
    ------
    ValueError
        A file refused by the reader, a parameter out of its range (named, with its unit), several files unalike.
    """
    files = survey_files(path)
    named = files[0][1] is not None  # a folder (even of one file) or a list: each file a site
    legal = (None if legal_group_kg is None else dict(legal_group_kg), legal_axle_kg)
    tally = _Tally(min_group_load_kg, group_spacing_m, position, speed_kmh, grouping, keep_groups, sink, legal)
    try:
        reads = _read_files(files, fmt, resolution_kg, tally, chunk_bytes)
        read = pooled_read(reads, [site for _, site in files]) if named else reads[0]
        groups, statistics, road, stations = _survey_tables(tally, spacing_step_m(read.format))
    finally:
        tally.close()
    settings = _settings([str(p) for p, _ in files] if named else path, fmt, read, tally)
    several = [file_entry(p, site, r) for (p, site), r in zip(files, reads)] if named else None
    return ObservedSurvey(groups, statistics, read, tally.positions, road, settings, stations, tally.n_kept, several)


def _read_files(files: list[tuple[Path, str | None]], fmt, resolution_kg, tally: _Tally, chunk_bytes) -> list:
    """Stream each of ``files`` into ``tally``; their read results. Held in memory (``keep_groups``), the
    files' records together must be at most :data:`bogie.weighings._records.MAX_FILE_BYTES`; spilled, any length."""
    cap = _records.MAX_FILE_BYTES if tally.keep_groups else None
    if cap is not None and len(files) > 1:
        total = sum(_records.uncompressed_size(p) for p, _ in files)
        if total > cap:
            raise ValueError(
                f"path: the {len(files)} files hold {total / 2**30:.2f} GiB of records, more than the "
                f"{cap / 2**30:g} GiB read with the groups held in memory (bogie.weighings._records.MAX_FILE_BYTES): "
                "read them with keep_groups=False (spilled to disk, any length)"
            )
    reads = []
    for path, site in files:
        if site is not None:
            tally.begin_file(site)
        reads.append(stream_weighings(path, fmt, resolution_kg, tally.start, tally.consume, chunk_bytes, cap))
        if len(reads) > 1:  # a file unlike the first refused before the next is read
            check_alike(reads[0], files[0][1], reads[-1], site)
    return reads


def _survey_tables(tally: _Tally, step_m: float) -> tuple:
    """The groups, statistics, road figures and stations of a read file's ``tally``: from the groups held in memory,
    or (``keep_groups`` False) from those spilled to disk, in bounded memory; ``step_m`` the file's spacing step
    (:func:`bogie.weighings.legal.group_limits`)."""
    if tally.keep_groups:
        groups, surveyed = tally.groups(), tally.surveyed()
        statistics = survey_statistics(surveyed, by="group") if len(surveyed) else pd.DataFrame(columns=["group"])
        road = (
            wear_statistics(surveyed, *tally.legal, spacing_step_m=step_m) if len(surveyed)
            else pd.DataFrame(columns=["group"])
        )  # fmt: skip
        stations = tally.stations(surveyed)
    else:  # from the groups spilled to disk, in bounded memory
        groups = pd.DataFrame(columns=list(_COMPACT[:-1]))
        spill = tally.spill
        if spill.count:  # two independent reads of the spill: the wear on a second thread (compiled, no GIL)
            with ThreadPoolExecutor(1) as pool:
                wear = pool.submit(spilled_wear, spill, *tally.legal, step_m)
                statistics = spilled_statistics(spill)
                road = wear.result()
        else:
            statistics, road = pd.DataFrame(columns=["group"]), pd.DataFrame(columns=["group"])
        stations = tally.spilled_stations()
    return groups, statistics, road, stations


def _settings(path: str | Path | list[str], fmt: str, read: ReadResult, tally: _Tally) -> dict[str, Any]:
    """What the survey was computed with (:attr:`ObservedSurvey.settings`): the file (or the files), its format, the
    resolution's source, the filters and grouping rule of ``tally``, the legal loads and the damage exponents."""
    min_group_load_kg, position, speed_kmh = tally.filters
    group_spacing_m, grouping = tally.grouping
    legal_group_kg, legal_axle_kg = tally.legal
    return {
        "file": path if isinstance(path, list) else str(path), "format": read.format, "format_asked": fmt,
        "resolution": read.describe_resolution(),
        "filters": {"min_group_load_kg": min_group_load_kg, "position": position,
                    "speed_kmh": None if speed_kmh is None else [float(v) for v in speed_kmh]},
        "grouping": grouping_rule(grouping, group_spacing_m),
        "legal_loads_kg": {
            **{size: float(legal_group_kg[size]) for size in SURVEYED if size in (legal_group_kg or {})},
            **({} if legal_axle_kg is None else {"axle": float(legal_axle_kg)}),
            "source": EU_SOURCE if legal_group_kg is None and legal_axle_kg is None else
            "given by the caller" + ("" if legal_group_kg is not None and legal_axle_kg is not None else
                                     "; the rest " + EU_SOURCE),
        },
        "damage_exponents": dict(DAMAGE_EXPONENTS),
    }  # fmt: skip


class _Tally:
    """What :func:`observed_survey` keeps of each chunk of vehicles: the position counts, the kept groups (or, with
    ``keep_groups`` False, the surveyed sizes' axles, loads and station written to a spill on disk), and the
    stations."""

    def __init__(
        self, min_group_load_kg, group_spacing_m, position, speed_kmh, grouping, keep_groups, sink, legal=(None, None)
    ) -> None:  # fmt: skip
        self.filters = (min_group_load_kg, position, speed_kmh)
        self.legal = legal  # (legal group loads by size, single-axle limit) [kg]; None: by position and spacing
        self.grouping = (group_spacing_m, grouping)
        self.keep_groups = keep_groups
        self.sink = sink
        self.site: str | None = None  # the file being read, of a survey of several (None: one file)
        self._mark: tuple | None = None
        self._reset()

    def begin_file(self, site: str) -> None:
        """Before the first pass over the next file of a survey of several (named ``site``): mark where the tally
        stands, so that a pass over this file begins afresh from there, and tell the sink."""
        self.site = site
        spill = None if self.spill is None else self.spill.mark()
        counts = {where: dict(by_size) for where, by_size in self.positions.items()}
        self._mark = (counts, len(self.kept), self.n_kept, dict(self.station_names), Counter(self.vehicles_at), spill)
        if self.sink is not None:
            if not hasattr(self.sink, "next_file"):
                raise ValueError("sink: a survey of several files needs a sink with next_file(site) as well as "
                                 "start() and write(groups) (bogie.weighings.survey, 'The sink')")  # fmt: skip
            self.sink.next_file(site)

    def start(self) -> None:
        """Begin afresh, before every pass over the file (the reader reads it again when its resolution was not the
        first chunk's): from nothing, or for a file of a survey of several from where :meth:`begin_file` marked."""
        if self._mark is None:
            self._reset()
        else:
            counts, n_groups, self.n_kept, names, vehicles_at, spill = self._mark
            self.positions = {where: dict(by_size) for where, by_size in counts.items()}
            del self.kept[n_groups:]
            self.station_names, self.vehicles_at = dict(names), Counter(vehicles_at)
            if spill is not None:
                self.spill.rewind(spill)
        if self.sink is not None:
            self.sink.start()

    def close(self) -> None:
        """Remove the spilled groups, if any."""
        if getattr(self, "spill", None) is not None:
            self.spill.close()
            self.spill = None

    def _reset(self) -> None:
        self.close()
        self.spill = None if self.keep_groups else GroupSpill()
        self.positions = {where: dict.fromkeys((*SIZE_LABELS.values(), "other"), 0) for where in POSITIONS[1:]}
        self.kept: list[pd.DataFrame] = []
        self.n_kept = 0
        self.station_names: dict[str, int] = {}
        self.vehicles_at: Counter = Counter()

    def consume(self, vehicles: pd.DataFrame) -> None:
        """Group, count and filter one chunk's vehicles; keep what the statistics need."""
        every = axle_groups(vehicles, *self.grouping)
        axles = every["n_axles"].to_numpy()
        sizes = {label: axles == k for k, label in SIZE_LABELS.items()}
        sizes["other"] = ~np.isin(axles, list(SIZE_LABELS))
        # the positions by the group's index, as axle_groups labels them (1 steer, 2 drive, 3 and on trailer): an
        # integer comparison, not three over a million strings
        index = np.minimum(every["group_index"].to_numpy(), 3)
        for k, where in enumerate(POSITIONS[1:], start=1):
            at = index == k
            for label, mask in sizes.items():
                self.positions[where][label] += int((at & mask).sum())
        min_group_load_kg, position, speed_kmh = self.filters
        groups = filter_groups(every, min_group_load_kg=min_group_load_kg, position=position, speed_kmh=speed_kmh)
        self.n_kept += len(groups)
        names = self._stations_of(vehicles)
        if names is not None:  # each group's site (its file, its station, or both) and the site's code
            self.vehicles_at.update(names.tolist())
            codes = np.array([self.station_names.setdefault(x, len(self.station_names)) for x in names], np.int32)
            by_line = pd.DataFrame({"site": names, "code": codes}, index=vehicles["line"].to_numpy())
            by_line = by_line.reindex(groups["line"].to_numpy())
            groups = groups.assign(site=by_line["site"].to_numpy(), station_code=by_line["code"].to_numpy())
        if self.sink is not None:
            self.sink.write(groups.drop(columns="station_code", errors="ignore"))
        if self.keep_groups:
            self.kept.append(groups.reset_index(drop=True))
        else:
            _spill(self.spill, groups)

    def _stations_of(self, vehicles: pd.DataFrame) -> np.ndarray | None:
        """Each vehicle's station: the file's ``station`` column, or for a file of a survey of several its site
        (``site:station`` where the file has the column); None for one file without the column."""
        has = "station" in vehicles.columns
        if self.site is None:
            return vehicles["station"].to_numpy() if has else None
        if not has:
            return np.full(len(vehicles), self.site, dtype=object)
        return np.array([f"{self.site}:{s}" for s in vehicles["station"].to_numpy()], dtype=object)

    def _all(self) -> pd.DataFrame:
        if not self.kept:
            return pd.DataFrame(columns=list(GROUP_TABLE_COLUMNS))
        if len(self.kept) > 1:
            self.kept = [pd.concat(self.kept, ignore_index=True)]
        return self.kept[0]

    def groups(self) -> pd.DataFrame:
        """The kept groups (every size; or only the surveyed sizes' compact columns), without the station codes (a
        survey of several sites: with each group's ``site``)."""
        return self._all().drop(columns=["station_code"], errors="ignore")

    def surveyed(self) -> pd.DataFrame:
        """The kept tandems and tri-axles (with their station codes, if any)."""
        frame = self._all()
        return frame[frame["group"].isin(SURVEYED).to_numpy(dtype=bool)]

    def stations(self, surveyed: pd.DataFrame) -> dict[str, dict[str, Any]]:
        """Per station of a file of more than one (a TMG file's ``station`` column): its vehicles and the statistics
        of its kept tandems and tri-axles; empty for a file of one station or none."""
        code = surveyed["station_code"].to_numpy() if len(self.station_names) > 1 else None

        def statistics_of(c: int) -> pd.DataFrame | None:
            mine = surveyed[code == c]
            return survey_statistics(mine, by="group") if len(mine) else None

        return self._per_station(statistics_of)

    def spilled_stations(self) -> dict[str, dict[str, Any]]:
        """:meth:`stations` from the spilled groups."""
        table = None
        if len(self.station_names) > 1 and self.spill.count:
            table = spilled_statistics(self.spill, by_station=True)
        return self._per_station(
            lambda c: table[table["station_code"] == c].drop(columns="station_code") if table is not None else table
        )

    def _per_station(self, statistics_of) -> dict[str, dict[str, Any]]:
        """``{station: {"vehicles", "groups": {size: statistics}}}`` from ``statistics_of(station code)`` (a
        :func:`survey_statistics` table, or None for none); empty for a file of fewer than two stations."""
        if len(self.station_names) < 2:
            return {}
        out: dict[str, dict[str, Any]] = {}
        for name in sorted(self.station_names):
            table = statistics_of(self.station_names[name])
            stats = statistics_dict(table) if table is not None and len(table) else {}
            counts = counts_of_statistics(table) if table is not None and len(table) else {}
            for size, entry in stats.items():  # the shares' counts, exact, for the sites' comparison
                entry.update(n_outside_5pct=counts[size]["n_outside_5pct"], n_over_10pct=counts[size]["n_over_10pct"])
            out[str(name)] = {
                "vehicles": int(self.vehicles_at[name]),
                "groups": {size: stats.get(size, {"n_groups": 0}) for size in SURVEYED},
            }
        return out


#: the columns of a surveyed group the spill keeps when the groups are not (``keep_groups=False``)
_COMPACT = ("group", "n_axles", "axle_load_1", "axle_load_2", "axle_load_3", "station_code")


def _spill(spill: GroupSpill, groups: pd.DataFrame) -> None:
    """Write the tandems and tri-axles of a chunk's kept ``groups`` to the spill: axles, station code, three loads,
    position code and two spacings."""
    axles = groups["n_axles"].to_numpy()
    surveyed = (axles == 2) | (axles == 3)
    loads = np.column_stack([groups[c].to_numpy(dtype=float)[surveyed] for c in axle_columns(3)])
    station = groups["station_code"].to_numpy()[surveyed] if "station_code" in groups else None
    # each group's own position label as its index in the legal table's positions
    position = pd.Categorical(groups["position"].to_numpy()[surveyed], categories=LEGAL_POSITIONS).codes
    assert (position >= 0).all(), "a group's position is not one of the legal table's (axle_groups labels them)"
    spacings = np.column_stack([groups[c].to_numpy(dtype=float)[surveyed] for c in ("spacing_1", "spacing_2")])
    spill.append(axles[surveyed], station, loads, position, spacings)
