"""The surveyed groups of a streamed survey on disk, and their statistics from there in bounded memory (issue 41
Must 4: memory independent of the file's length).

- **The spill.** :class:`GroupSpill` appends each chunk's kept tandems and tri-axles (the size as a code, the
  station's code, the three loads, NaN past a tandem's two, the position's code and the two spacings, what
  :func:`bogie.weighings.legal.group_limits` judges by) to files in a temporary directory, 46 bytes a group, and
  reads them back in blocks of :data:`SPILL_BLOCK` groups, in file order; the values whose order statistics are
  sought (the spread and the shares, 32 bytes a group) are written beside them by the first pass.
- **The statistics.** :func:`spilled_statistics` is :func:`bogie.weighings.stats.survey_statistics` of the spilled
  groups per cell (a size, or a station's size), from passes over the spill: counts and sums in the first; each
  median and quantile from exact order statistics, found by refining a histogram of the values around the rank
  wanted (:func:`_order_statistics`) until the value is known, then interpolated as pandas and numpy do
  (:func:`_quantile`). Counts, shares, medians and quantiles are the table's to the bit; the mean spread, a sum of
  block sums, to about 1e-12 relative (``tests/test_weighings_spill.py``).
"""

from __future__ import annotations

import math
import shutil
import tempfile
import weakref
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from bogie.group_names import GROUP_AXLES, GROUP_NAMES
from bogie.weighings.legal import POSITIONS, group_limits
from bogie.weighings.pavement import with_group_baseline
from bogie.weighings.stats import QUANTILES, group_inequality
from bogie.weighings.wear import BOOTSTRAP_MAX_GROUPS, DAMAGE_EXPONENTS, _LargeCell, _small_cell

__all__ = ["SPILL_BLOCK", "GroupSpill", "spilled_statistics", "spilled_wear"]

#: groups read back from the spill at a time [-]: 2^18, about 60 MB of working arrays a block
SPILL_BLOCK = 1 << 18
#: the most histogram bins of all ranks sought at once [-]: 2^21 (48 MiB of counts, least and greatest values)
_BINS_TOTAL = 1 << 21
#: the sizes spilled, by their code (the axles less two)
SPILLED = GROUP_NAMES
# the spill's size code is the axles less two: a group of another size, or another order, would be miscounted
assert all(GROUP_AXLES[name] == code + 2 for code, name in enumerate(SPILLED))
_COLUMNS = ("size", "station", "loads", "position", "spacings")  # int8, int32, 3 float64, int8, 2 float64 a group


class GroupSpill:
    """The surveyed groups written to a temporary directory as they are made, read back in blocks; the directory is
    removed by :meth:`close` (or when the spill is collected)."""

    def __init__(self) -> None:
        self.dir = Path(tempfile.mkdtemp(prefix="bogie-groups-"))
        self._cleanup = weakref.finalize(self, shutil.rmtree, self.dir, True)
        self._files = {name: open(self.dir / name, "wb") for name in _COLUMNS}  # noqa: SIM115 - closed in close()
        self.count = 0
        self.stations = 0
        self.sizes = np.zeros(2, np.int64)  # the tandems and tri-axles spilled

    def append(
        self, n_axles: np.ndarray, station: np.ndarray | None, loads: np.ndarray, position: np.ndarray,
        spacings: np.ndarray,
    ) -> None:  # fmt: skip
        """Add groups of 2 or 3 axles: their axles, station codes (None: no station), loads, shape (m, 3), position
        codes (the index in :data:`bogie.weighings.legal.POSITIONS`) and spacings [m], shape (m, 2), in file
        order."""
        m = len(n_axles)
        station = np.zeros(m, np.int32) if station is None else np.asarray(station, np.int32)
        if m:
            self.stations = max(self.stations, int(station.max()) + 1)
        (np.asarray(n_axles) - 2).astype(np.int8).tofile(self._files["size"])
        station.tofile(self._files["station"])
        np.ascontiguousarray(loads, np.float64).tofile(self._files["loads"])
        np.asarray(position).astype(np.int8).tofile(self._files["position"])
        np.ascontiguousarray(spacings, np.float64).reshape(m, 2).tofile(self._files["spacings"])
        self.count += m
        self.sizes += np.bincount(np.asarray(n_axles, np.int64) - 2, minlength=2)[:2]

    def mark(self) -> tuple:
        """Where the spill stands (its groups, stations, sizes and each file's length): :meth:`rewind` goes back."""
        for fh in self._files.values():
            fh.flush()
        return self.count, self.stations, self.sizes.copy(), {name: fh.tell() for name, fh in self._files.items()}

    def rewind(self, mark: tuple) -> None:
        """Forget every group appended since :meth:`mark` gave ``mark`` (a survey of several files reading one of them
        again: :func:`bogie.weighings.survey.observed_survey`)."""
        self.count, self.stations, sizes, at = mark
        self.sizes = sizes.copy()
        for name, fh in self._files.items():
            fh.flush()
            fh.seek(at[name])
            fh.truncate()

    def blocks(self) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(size code, station code, loads (m, 3)) of :data:`SPILL_BLOCK` groups at a time, in file order."""
        return self._read("loads", 3)

    def shape_blocks(self) -> Iterator[pd.DataFrame]:
        """What the legal limits go by (:func:`bogie.weighings.legal.group_limits`): ``group``, ``position``,
        ``spacing_1`` and ``spacing_2`` of :data:`SPILL_BLOCK` groups at a time, in file order."""
        with open(self.dir / "position", "rb") as positions:
            for size, _station, spacings in self._read("spacings", 2):
                where = np.fromfile(positions, np.int8, len(size))
                yield pd.DataFrame({
                    "group": np.asarray(SPILLED, dtype=object)[size], "position": np.asarray(POSITIONS, object)[where],
                    "spacing_1": spacings[:, 0], "spacing_2": spacings[:, 1],
                })  # fmt: skip

    def value_blocks(self) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """(size code, station code, values (m, 4): :func:`_values`' spread and shares) of :data:`SPILL_BLOCK`
        groups at a time, in file order, as :func:`spilled_statistics`' first pass wrote them."""
        return self._read("values", 4)

    def _read(self, name: str, width: int) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The sizes, stations and the float64 file ``name`` of ``width`` columns, a block at a time."""
        for fh in self._files.values():
            fh.flush()
        with open(self.dir / "size", "rb") as sizes, open(self.dir / "station", "rb") as stations, \
                open(self.dir / name, "rb") as floats:  # fmt: skip
            for _start in range(0, self.count, SPILL_BLOCK):
                size = np.fromfile(sizes, np.int8, SPILL_BLOCK)
                station = np.fromfile(stations, np.int32, len(size))
                yield size, station, np.fromfile(floats, np.float64, width * len(size)).reshape(-1, width)

    def close(self) -> None:
        for fh in self._files.values():
            fh.close()
        self._cleanup()


def _values(loads: np.ndarray, size: np.ndarray) -> tuple[dict, np.ndarray]:
    """The inequality of a block and its values whose order statistics are sought: the spread [%] and the three
    load shares (NaN past a group's axles), shape (m, 4)."""
    ineq = group_inequality(loads, size.astype(np.int64) + 2)
    return ineq, np.column_stack([ineq["spread_pct"], ineq["load_share"]])


def spilled_statistics(
    spill: GroupSpill, by_station: bool = False, quantiles: Sequence[float] = QUANTILES
) -> pd.DataFrame:
    """:func:`bogie.weighings.stats.survey_statistics` of the spilled groups by ``group`` (and ``station_code``
    first, if ``by_station``): the same columns, one row per cell that has groups, sorted."""
    n_cells = 2 * max(spill.stations, 1) if by_station else 2
    count = np.zeros(n_cells, np.int64)
    spread_sum = np.zeros(n_cells)
    outside = np.zeros(n_cells, np.int64)
    over = np.zeros(n_cells, np.int64)
    valid = np.zeros((n_cells, 4), np.int64)
    low = np.full((n_cells, 4), np.inf)
    high = np.full((n_cells, 4), -np.inf)
    # the first histograms in the same pass, over each quantity's bounds: a spread is at most n x 100 %, a share n
    first = _Level([(c, q, 0.0, _BOUNDS[q]) for c in range(n_cells) for q in range(4)], n_cells)
    with open(spill.dir / "values", "wb") as kept:  # for the narrowing passes, computed once
        for size, station, loads in spill.blocks():
            cell = _cells(size, station, by_station)
            ineq, values = _values(loads, size)
            values.tofile(kept)
            count += np.bincount(cell, minlength=n_cells)
            spread_sum += np.bincount(cell, weights=ineq["spread"], minlength=n_cells)
            outside += np.bincount(cell, weights=ineq["outside_5pct"], minlength=n_cells).astype(np.int64)
            over += np.bincount(cell, weights=ineq["over_10pct"], minlength=n_cells).astype(np.int64)
            _ranges(cell, values, valid, low, high)
            first.add(cell, values)
    # the ranks each value needs: the median's of the spread, the quantiles' of each share (numpy's 'linear')
    wanted: dict[tuple[int, int], set[int]] = {}
    for c, q in zip(*np.nonzero(valid)):
        n = int(valid[c, q])
        if q == 0:
            ranks = {(n - 1) // 2, n // 2}
        else:
            ranks = set()
            for p in quantiles:
                j = _virtual_index(n, p)
                ranks |= {n - 1} if j >= n - 1 else {math.floor(j), math.floor(j) + 1}
        wanted[(int(c), int(q))] = ranks
    found = _order_statistics(spill, by_station, n_cells, wanted, valid, low, high, first)
    rows = []
    for c in np.flatnonzero(count):
        row = {**({"station_code": int(c // 2)} if by_station else {}), "group": SPILLED[c % 2]}
        n_spread = int(valid[c, 0])
        middle = (found[(c, 0, (n_spread - 1) // 2)] + found[(c, 0, n_spread // 2)]) / 2.0 if n_spread else math.nan
        row.update(n_groups=int(count[c]), mean_spread_kg=spread_sum[c] / count[c], median_spread_pct=middle,
                   share_outside_5pct=outside[c] / count[c], share_over_10pct=over[c] / count[c])  # fmt: skip
        for i in range(3):
            n = int(valid[c, i + 1])
            for p in quantiles:
                value = _quantile(n, p, lambda r, c=c, i=i: found[(c, i + 1, r)]) if n else math.nan
                row[f"load_share_{i + 1}_p{round(100 * p):02d}"] = value
        rows.append(row)
    return pd.DataFrame(rows)


def _cells(size: np.ndarray, station: np.ndarray, by_station: bool) -> np.ndarray:
    return (2 * station.astype(np.int64) + size) if by_station else size.astype(np.int64)


def _virtual_index(n: int, p: float) -> float:
    """numpy's 'linear' virtual index of quantile ``p`` of ``n`` values (``numpy.quantile``, which pandas'
    ``Series.quantile`` calls)."""
    return (n - 1) * p


def _quantile(n: int, p: float, value) -> float:
    """Quantile ``p`` of ``n`` values whose order statistic of rank r is ``value(r)``: numpy's 'linear' method,
    its arithmetic (``numpy.lib._function_base_impl._lerp``), as pandas' ``Series.quantile`` calls it."""
    h = _virtual_index(n, p)
    if h >= n - 1:
        return value(n - 1)
    j = math.floor(h)
    a, b = value(j), value(j + 1)
    t = h - j
    diff = b - a
    return b - diff * (1 - t) if t >= 0.5 else a + diff * t


@njit(cache=True, nogil=True)
def _ranges(cell, values, valid, low, high):  # pragma: no cover - compiled
    """Count each cell's non-NaN values of each quantity and their least and greatest."""
    for g in range(values.shape[0]):
        c = cell[g]
        for q in range(values.shape[1]):
            v = values[g, q]
            if v == v:
                valid[c, q] += 1
                if v < low[c, q]:
                    low[c, q] = v
                if v > high[c, q]:
                    high[c, q] = v


@njit(cache=True, nogil=True)
def _histogram(cell, values, first, last, s_lo, s_hi, marks, hist, bin_low, bin_high):  # pragma: no cover
    """For each value: among its cell's and quantity's intervals (slots first[c, q] .. last[c, q] - 1, disjoint,
    sorted by their least value), mark the first slot above it (every slot from there on has it below), and count
    it in its bin of the slot that holds it, keeping each bin's least and greatest value."""
    bins = hist.shape[1]
    for g in range(values.shape[0]):
        c = cell[g]
        for q in range(values.shape[1]):
            v = values[g, q]
            a = first[c, q]
            b = last[c, q]
            if v != v or a == b:
                continue
            lo, hi = a, b  # the first slot whose least value is above v
            while lo < hi:
                mid = (lo + hi) >> 1
                if s_lo[mid] <= v:
                    lo = mid + 1
                else:
                    hi = mid
            if lo < b:
                marks[lo] += 1
            k = lo - 1
            if k >= a and v <= s_hi[k]:
                j = int((v - s_lo[k]) / (s_hi[k] - s_lo[k]) * bins)
                if j >= bins:
                    j = bins - 1
                hist[k, j] += 1
                if v < bin_low[k, j]:
                    bin_low[k, j] = v
                if v > bin_high[k, j]:
                    bin_high[k, j] = v


#: the bounds of the quantities whose order statistics are sought: the spread [%] of n <= 3 axles is at most
#: n x 100 % of their mean, a share n W / sum W at most n
_BOUNDS = (300.0, 3.0, 3.0, 3.0)


class _Level:
    """One pass's histograms: a slot for each distinct interval of a cell and quantity (disjoint, sorted by their
    least value), :func:`_histogram`'s arrays, and the narrowing of the ranks sought from them."""

    def __init__(self, slots: list[tuple[int, int, float, float]], n_cells: int) -> None:
        self.slots = sorted(set(slots))
        self.index = {key: k for k, key in enumerate(self.slots)}
        k = len(self.slots)
        bins = max(16, min(1 << 18, _BINS_TOTAL // max(k, 1)))
        self.first = np.zeros((n_cells, 4), np.int64)
        self.last = np.zeros((n_cells, 4), np.int64)
        for j, (c, q, _lo, _hi) in enumerate(self.slots):
            if self.last[c, q] == 0:
                self.first[c, q] = j
            self.last[c, q] = j + 1
        self.lo = np.array([key[2] for key in self.slots])
        self.hi = np.array([key[3] for key in self.slots])
        self.marks = np.zeros(k, np.int64)
        self.hist = np.zeros((k, bins), np.int64)
        self.bin_low = np.full((k, bins), np.inf)
        self.bin_high = np.full((k, bins), -np.inf)

    def add(self, cell: np.ndarray, values: np.ndarray) -> None:
        _histogram(cell, values, self.first, self.last, self.lo, self.hi, self.marks, self.hist, self.bin_low,
                   self.bin_high)  # fmt: skip

    def narrow(self, active: list, found: dict) -> list:
        """Each rank's value if its bin tells it (into ``found``); the others with their bin's ends."""
        below = np.zeros(len(self.slots), np.int64)  # the values below each slot: its own and earlier slots' marks
        for j, (c, q, _lo, _hi) in enumerate(self.slots):
            below[j] = self.marks[j] + (below[j - 1] if j > self.first[c, q] else 0)
        still = []
        for c, q, r, lo, hi in active:
            j = self.index[(c, q, lo, hi)]
            cum = np.cumsum(self.hist[j])
            b = int(np.searchsorted(cum, r - below[j], side="right"))
            at = r - below[j] - (int(cum[b - 1]) if b else 0)  # the rank within bin b
            if at == 0 or self.bin_low[j, b] == self.bin_high[j, b]:
                found[(c, q, r)] = float(self.bin_low[j, b])
            elif at == self.hist[j, b] - 1:
                found[(c, q, r)] = float(self.bin_high[j, b])
            else:
                still.append((c, q, r, float(self.bin_low[j, b]), float(self.bin_high[j, b])))
        return still


def _order_statistics(spill, by_station, n_cells, wanted, valid, low, high, level) -> dict[tuple[int, int, int], float]:
    """The value of each rank sought, {(cell, quantity, rank): value}, exactly: each rank's interval starts as its
    quantity's bounds (``level``, the histograms of the first pass; the values' range if some value is outside
    them) and is narrowed, pass by pass, to the bin of a histogram that holds the rank, its ends the bin's own least
    and greatest values; the value is known when the rank is a bin's first or last, or the bin holds one value. The
    binning is monotone in the value, so the values within a bin's ends are that bin's and each pass narrows an
    interval strictly: it ends. The ranks of one cell and quantity narrow in step, so their intervals are the same
    or disjoint: each distinct one is a slot with one histogram, the ranks in it share it."""
    found: dict[tuple[int, int, int], float] = {}
    active: list[tuple[int, int, int, float, float]] = []  # cell, quantity, rank, lo, hi
    later: list[tuple[int, int, int, float, float]] = []  # those whose values stray outside the bounds
    for (c, q), ranks in wanted.items():
        n = int(valid[c, q])
        inside = low[c, q] >= 0.0 and high[c, q] <= _BOUNDS[q]
        for r in sorted(ranks):
            if r == 0 or low[c, q] == high[c, q]:
                found[(c, q, r)] = float(low[c, q])
            elif r == n - 1:
                found[(c, q, r)] = float(high[c, q])
            elif inside:
                active.append((c, q, r, 0.0, _BOUNDS[q]))
            else:
                later.append((c, q, r, float(low[c, q]), float(high[c, q])))
    active = level.narrow(active, found) + later
    while active:
        level = _Level([(c, q, lo, hi) for c, q, _r, lo, hi in active], n_cells)
        for size, station, values in spill.value_blocks():
            level.add(_cells(size, station, by_station), values)
        active = level.narrow(active, found)
    return found


def spilled_wear(
    spill: GroupSpill,
    legal_group: Mapping[str, float] | None = None,
    legal_axle: float | None = None,
    spacing_step_m: float = 0.0,
    exponents: Mapping[str, float] = DAMAGE_EXPONENTS,
    resamples: int = 1000,
    confidence_level: float = 0.95,
    seed: int = 0,
    bootstrap_max_groups: int = BOOTSTRAP_MAX_GROUPS,
) -> pd.DataFrame:
    """:func:`bogie.weighings.wear.wear_statistics` of the spilled groups by ``group``, the same figures to the bit:
    a size of at most ``bootstrap_max_groups`` groups gathered and bootstrapped, a larger one's moments summed block
    by block in file order, the order of the table's way; the legal limits as
    :func:`bogie.weighings.legal.group_limits` gives them (``legal_group``, ``legal_axle``, ``spacing_step_m``)."""
    count = spill.sizes
    present = [c for c in range(2) if count[c]]
    large = {c: _LargeCell(exponents, confidence_level) for c in present
             if resamples and count[c] > bootstrap_max_groups}  # fmt: skip
    small: dict[int, list] = {c: [] for c in present if c not in large}
    for (size, _station, loads), shape in zip(spill.blocks(), spill.shape_blocks()):  # each size in file order
        limits = np.column_stack(group_limits(shape, legal_group, legal_axle, spacing_step_m))
        for c in present:
            mine = size == c
            m = int(mine.sum())
            if m:
                part = (np.nan_to_num(loads[mine], nan=0.0), np.full(m, c + 2, np.int64), limits[mine, 0],
                        limits[mine, 1])  # fmt: skip
                if c in large:
                    large[c].add(*part)
                else:
                    small[c].append(part)
    rows = []
    for c, stream in zip(present, np.random.SeedSequence(seed).spawn(len(present))):
        row: dict = {"group": SPILLED[c], "n_groups": int(count[c]), "n_failed": 0}
        if c in large:
            row.update(large[c].figures())
        else:
            loads, n, legal_of, axle_of = (np.concatenate(p) for p in zip(*small[c]))
            row.update(_small_cell(loads, n, legal_of, axle_of, stream, exponents, resamples, confidence_level))
        rows.append(row)
    return with_group_baseline(pd.DataFrame(rows), exponents)
