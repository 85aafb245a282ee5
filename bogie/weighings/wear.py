"""What unequal sharing costs the road: relative pavement wear and overloaded axles hidden in legal groups.

One definition for observed (WIM, weighbridge) and simulated groups, as :mod:`bogie.weighings.stats` is for the
survey statistics; the derivation and the sources are in ``docs/pavement.md``.

**Pavement wear.** The generalised power law: an axle of load W does the damage of (W / W_s)^k standard axles of
load W_s (the AASHO Road Test's fourth power, k = 4, for the pavement's overall serviceability; the exponents of a
mechanistic design guide for other kinds of damage, :data:`DAMAGE_EXPONENTS`). A group of n axles with loads
W_1..W_n does D = sum_i (W_i / W_s)^k; shared equally, the same group load gives D_eq = n (W_mean / W_s)^k. The
**extra wear** that inequality causes is D - D_eq [standard axles], and as a share of what the group would do
shared equally,

    D / D_eq - 1 = mean_i (W_i / W_mean)^k - 1,

which does not depend on W_s and is zero for equal loads, positive otherwise (W^k is convex for k >= 1: Jensen).
A tri-axle at 1.1, 1.0 and 0.9 times its mean does (1.1^4 + 1 + 0.9^4) / 3 - 1 = 4.0 % extra at k = 4. Over many
groups the share is the ratio of the totals, sum D / sum D_eq - 1: the extra wear of the fleet over the wear of the
same fleet with every group shared equally.

*Assumption* (named in ``docs/pavement.md``): each axle counts as a load of its own. A design guide that takes a
multi-axle group's load as one (Austroads' group standard loads) sees no effect of sharing within the group at all;
the per-axle sum is the reading under which sharing matters, as the AASHO equivalence of single axles does.

**Axles above the single-axle limit within legal groups** (an indicator, not an offence: the law weighs a group's
axles as one, docs/pavement.md). A group whose load is within its legal group load while one of its axles is over
the limit of a single axle; the limits by each group's position and spacing from Directive 96/53/EC
(:func:`bogie.weighings.legal.group_limits`) unless single limits are given.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
from numba import njit
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.intervals import percentile_interval, wilson_interval
from bogie.params import GRAVITY
from bogie.rounding import json_number
from bogie.settings import check_value, refusal
from bogie.weighings._records import REL_TOL
from bogie.weighings.legal import EU_NON_DRIVING_AXLE_KG, group_limits
from bogie.weighings.pavement import with_group_baseline
from bogie.weighings.stats import _width, axle_columns

__all__ = [
    "DAMAGE_EXPONENTS",
    "EU_LEGAL_AXLE_KG",
    "EU_LEGAL_GROUP_KG",
    "STANDARD_AXLE_KG",
    "WEAR_COLUMNS",
    "group_wear",
    "hidden_overloads",
    "wear_dict",
    "wear_statistics",
]

#: damage exponent k of each kind of pavement damage: ``overall`` (the AASHO Road Test's fourth power, Austroads'
#: ESA), ``asphalt`` (asphalt fatigue, 5), ``subgrade`` (rutting and shape loss, 7), ``cemented`` (cemented
#: material fatigue, 12): Austroads, Guide to Pavement Technology Part 2 (AGPT02), chapter 7's standard axle
#: repetitions SAR5, SAR7 and SAR12 (sources in docs/pavement.md) [-]
DAMAGE_EXPONENTS: Mapping[str, int] = {"overall": 4, "asphalt": 5, "subgrade": 7, "cemented": 12}
#: the standard axle W_s: 80 kN, the AASHO Road Test's 18-kip single axle and Austroads' standard single axle with
#: dual tyres, in kg at the project's g (:data:`bogie.params.GRAVITY`) [kg]
STANDARD_AXLE_KG: float = 80_000.0 / GRAVITY
#: legal group loads of trailer axle groups, Directive 96/53/EC Annex I: 3.4, a trailer's tandem with its axles
#: 1.3 m to under 1.8 m apart, 18 t; 3.5, a trailer's tri-axle with spacings over 1.3 m up to 1.4 m, 24 t [kg]
EU_LEGAL_GROUP_KG: Mapping[str, float] = {"tandem": 18_000.0, "triaxle": 24_000.0}
#: legal load of a single non-driving axle, Directive 96/53/EC Annex I 3.1, 10 t (declared once, in
#: :mod:`bogie.weighings.legal`) [kg]
EU_LEGAL_AXLE_KG: float = EU_NON_DRIVING_AXLE_KG
#: the columns of :func:`wear_statistics` per exponent name ``<k>`` (see there)
WEAR_COLUMNS: tuple[str, ...] = (
    "extra_wear_{k}", "extra_wear_{k}_low", "extra_wear_{k}_high",
    "extra_sa_per_1000_{k}", "extra_sa_per_1000_{k}_low", "extra_sa_per_1000_{k}_high",
)  # fmt: skip


#: the most bootstrap indices drawn at once (a block of resamples): 2^21 int64 indices, 16 MiB, and a gather of
#: each damage array as large; a convention that bounds the memory whatever the survey's size
BOOTSTRAP_BLOCK = 1 << 21
#: the most groups of a cell whose wear intervals are bootstrapped [-]; above, the intervals are the delta method's
#: normal ones (docs/pavement.md, "Intervals"): at 20,000 groups the ratio's sampling distribution is normal to far
#: better than the percentile bootstrap's own Monte Carlo error at 1,000 resamples (about 0.08 of a standard error
#: at the 2.5 % point), and the bootstrap's cost, resamples x groups, is what made a year of a WIM site slow (issue
#: 41 Must 4: 85 % of ``bogie weighings``' time). A convention of this project, tested against the bootstrap
BOOTSTRAP_MAX_GROUPS = 20_000


def group_wear(loads: ArrayLike, n_axles: ArrayLike, k: float, standard_axle: float = 1.0) -> dict[str, NDArray]:
    """The pavement wear of each group of axle loads, and of the same group shared equally.

    Parameters
    ----------
    loads
        (groups, width) axle loads, front first; entries past a group's ``n_axles`` are ignored [any unit].
    n_axles
        Axles of each group, 2 or more, at most ``width`` [-].
    k
        The damage exponent, 1 or more [-].
    standard_axle
        W_s, in the loads' unit: the damage is counted in standard axles of this load.

    Returns
    -------
    dict of numpy.ndarray
        ``damage`` D = sum_i (W_i / W_s)^k and ``damage_equal`` D_eq = n (W_mean / W_s)^k [standard axles];
        ``extra`` D - D_eq [standard axles]; ``relative`` D / D_eq - 1 [-] (0 for equal loads; NaN for a group of
        no load).
    """
    w = np.atleast_2d(np.asarray(loads, dtype=float))
    n = np.asarray(n_axles, dtype=np.int64)
    if not (math.isfinite(k) and k >= 1.0):
        raise ValueError(f"k = {k!r}: a damage exponent is a number of 1 or more [-] (4: the fourth-power law)")
    if not (math.isfinite(standard_axle) and standard_axle > 0.0):
        raise ValueError(f"standard_axle = {standard_axle!r}: the standard axle's load is positive, in the loads' unit")
    if n.shape != (w.shape[0],) or np.any(n < 2) or np.any(n > w.shape[1]):
        raise ValueError(f"n_axles must give each of the {w.shape[0]} groups 2 to {w.shape[1]} axles [-]")
    present = np.arange(w.shape[1]) < n[:, None]
    x = np.where(present, w, 0.0) / standard_axle
    damage = np.where(present, numerics.power(x, k), 0.0).sum(axis=1)  # not x**k: numpy's power is the CPU's
    mean = x.sum(axis=1) / n
    equal = n * numerics.power(mean, k)
    with np.errstate(invalid="ignore", divide="ignore"):
        relative = damage / equal - 1.0
    return {"damage": damage, "damage_equal": equal, "extra": damage - equal, "relative": relative}


def hidden_overloads(
    loads: ArrayLike, n_axles: ArrayLike, legal_group: ArrayLike, legal_axle: ArrayLike
) -> dict[str, NDArray]:
    """Which groups are within their legal group load while an axle is over the legal load of one axle.

    Parameters
    ----------
    loads
        (groups, width) axle loads, front first; entries past a group's ``n_axles`` are ignored [any unit].
    n_axles
        Axles of each group [-].
    legal_group
        Each group's legal group load (one value, or one per group), in the loads' unit.
    legal_axle
        The legal load of one axle (one value, or one per group), in the loads' unit.

    Returns
    -------
    dict of numpy.ndarray of bool
        ``group_over`` (group load above its legal load), ``axle_over`` (some axle above the axle's legal load),
        ``hidden`` (an axle over while the group is within: the overload a group weighing does not see).
    """
    w = np.atleast_2d(np.asarray(loads, dtype=float))
    n = np.asarray(n_axles, dtype=np.int64)
    present = np.arange(w.shape[1]) < n[:, None]
    total = np.where(present, w, 0.0).sum(axis=1)
    heaviest = np.where(present, w, -np.inf).max(axis=1)
    # a load at its legal limit is within it (REL_TOL: a sum of loads read at a file's resolution rounds in a last bit)
    group_over = total > np.broadcast_to(np.asarray(legal_group, dtype=float), total.shape) * (1.0 + REL_TOL)
    axle_over = heaviest > np.broadcast_to(np.asarray(legal_axle, dtype=float), total.shape) * (1.0 + REL_TOL)
    return {"group_over": group_over, "axle_over": axle_over, "hidden": axle_over & ~group_over}


def wear_statistics(
    groups: pd.DataFrame,
    legal_group: Mapping[str, float] | None = None,
    legal_axle: float | None = None,
    by: str | Sequence[str] = "group",
    unit_per_kg: float = 1.0,
    exponents: Mapping[str, float] = DAMAGE_EXPONENTS,
    resamples: int = 1000,
    confidence_level: float = 0.95,
    seed: int = 0,
    bootstrap_max_groups: int = BOOTSTRAP_MAX_GROUPS,
    spacing_step_m: float = 0.0,
) -> pd.DataFrame:
    """What unequal sharing costs the road, per value of ``by``: extra wear and hidden overloads, with intervals.

    Parameters
    ----------
    groups
        Wide table, one row per group: ``group`` (``tandem``, ``triaxle``, ...: the key of ``legal_group``),
        ``n_axles``, ``axle_load_1 ..`` (front first) and the ``by`` columns; an optional ``status`` column leaves
        out (and counts in ``n_failed``) every row whose status is not ``"ok"``.
    legal_group, legal_axle
        Stated single limits [kg]: each ``group`` value's legal load (a size not named: no overload figures) and one
        axle's; None (default): Directive 96/53/EC's by each row's ``position`` and spacings
        (:func:`bogie.weighings.legal.group_limits`, read at ``spacing_step_m``).
    by
        Column(s) to tabulate by, e.g. ``["group", "position", "suspension"]``.
    unit_per_kg
        The loads' unit per kilogram: 1 for kg, :data:`bogie.params.GRAVITY` for newtons [unit/kg].
    exponents
        Name -> damage exponent k (:data:`DAMAGE_EXPONENTS`).
    resamples
        Bootstrap resamples of the groups within each cell for the wear intervals (0: none) [-].
    confidence_level
        Level of the intervals (percentile bootstrap; Wilson's for the overload share) [-].
    seed
        Seed of the bootstrap (each cell draws from its own child stream) [-].
    bootstrap_max_groups
        A cell of more groups gets the delta method's normal intervals (:data:`BOOTSTRAP_MAX_GROUPS`) [-].
    spacing_step_m
        The step the spacings were read at (0: as read) [m].

    Returns
    -------
    pandas.DataFrame
        One row per ``by`` value (sorted): ``n_groups`` (groups used), ``n_failed`` (rows left out); per exponent
        name ``<k>``: ``extra_wear_<k>`` (sum D / sum D_eq - 1, the extra wear as a share of the equal-shared
        groups' [-]) and ``extra_sa_per_1000_<k>`` (1000 x the mean of D - D_eq: the extra standard axles of 80 kN
        per 1,000 groups [-]), each with ``_low`` and ``_high``; when ``by`` has ``group``, ``extra_wear_group_<k>``
        with ``_low`` and ``_high``, the extra wear against Austroads' group baseline
        (:func:`bogie.weighings.pavement.with_group_baseline`) [-]; ``n_hidden``, ``share_hidden_overload`` (groups
        within their legal load with an axle over the axle's) with ``_low`` and ``_high``, ``share_group_over``.
    """
    keys = [by] if isinstance(by, str) else list(by)
    width = _checked_width(groups, confidence_level, resamples)
    limits = group_limits(groups, legal_group, legal_axle, spacing_step_m)
    ok, cell_arrays = _cell_source(groups, width, limits, unit_per_kg)
    figures = (exponents, resamples, confidence_level, bootstrap_max_groups)
    frame = pd.DataFrame(_cell_rows(groups, keys, ok, cell_arrays, seed, figures))
    return with_group_baseline(frame, exponents) if "group" in keys else frame


def _checked_width(groups: pd.DataFrame, confidence_level: float, resamples: int) -> int:
    """The axle columns of :func:`wear_statistics`' ``groups`` [-], once its ``confidence_level``, ``resamples`` and
    columns are checked (a ValueError naming what is wrong)."""
    check_value("confidence_level", confidence_level, "-", low=0.0, high=1.0, low_open=True, high_open=True)
    if resamples < 0:
        raise ValueError(refusal("resamples", resamples, low=0, whole=True))
    width = _width(groups)
    if width < 2 or "n_axles" not in groups.columns or "group" not in groups.columns:
        raise ValueError(
            f"groups has columns {list(groups.columns)}: needs group, n_axles and axle_load_1, axle_load_2, ..."
        )
    return width


def _cell_source(
    groups: pd.DataFrame, width: int, limits: tuple[np.ndarray, np.ndarray], unit_per_kg: float
) -> tuple[np.ndarray, Callable[[np.ndarray], tuple[np.ndarray, ...]]]:
    """Whether each row of ``groups`` is used (its ``status`` ``"ok"``, or no ``status`` column), and the function
    giving the (loads [kg], axles, legal group load [kg], single-axle limit [kg]) of the rows of a cell; ``limits``
    each row's two limits (:func:`bogie.weighings.legal.group_limits`)."""
    ok = groups["status"].astype(str).eq("ok").to_numpy() if "status" in groups.columns else np.ones(len(groups), bool)
    columns = [groups[c].to_numpy() for c in axle_columns(width)]  # as stored (float32 where exact), no copy
    n_all = groups["n_axles"].to_numpy()
    legal_all, axle_all = limits

    def cell_arrays(rows: np.ndarray) -> tuple[np.ndarray, ...]:
        # a failed row (null loads) is carried as zeros and never used: its cell counts it in n_failed
        loads = np.nan_to_num(np.column_stack([c[rows] for c in columns]).astype(float), nan=0.0) / unit_per_kg
        return loads, n_all[rows].astype(np.int64), legal_all[rows], axle_all[rows]

    return ok, cell_arrays


def _cell_rows(
    groups: pd.DataFrame, keys: list, ok: np.ndarray, cell_arrays: Callable, seed: int, figures: tuple
) -> list[dict]:
    """:func:`wear_statistics`' rows, one per cell of ``groups`` by ``keys`` (sorted), each cell's bootstrap drawn
    from its own child stream of ``seed``; ``figures``: (exponents, resamples, confidence_level,
    bootstrap_max_groups)."""
    exponents, resamples, confidence_level, bootstrap_max_groups = figures
    root = np.random.SeedSequence(seed)
    rows = []
    cells = groups.groupby(keys, observed=True, sort=True).indices
    streams = root.spawn(len(cells))
    for (cell, rows_all), stream in zip(cells.items(), streams):
        cell = cell if isinstance(cell, tuple) else (cell,)
        index = rows_all[ok[rows_all]]
        row: dict = dict(zip(keys, cell))
        row["n_groups"] = len(index)
        row["n_failed"] = int(len(rows_all) - len(index))
        if resamples and len(index) > bootstrap_max_groups:
            blocks = (cell_arrays(index[start : start + WEAR_BLOCK]) for start in range(0, len(index), WEAR_BLOCK))
            row.update(_large_cell(blocks, exponents, confidence_level))
        else:
            row.update(_small_cell(*cell_arrays(index), stream, exponents, resamples, confidence_level))
        rows.append(row)
    return rows


def _small_cell(loads: NDArray, n: NDArray, legal: NDArray, legal_axle: NDArray, stream: np.random.SeedSequence,
                exponents: Mapping[str, float], resamples: int,
                confidence_level: float) -> dict[str, float]:  # fmt: skip
    """The figures of a cell of :data:`BOOTSTRAP_MAX_GROUPS` groups or fewer (or of any size without resamples):
    the extra wear with its percentile bootstrap intervals (drawn from ``stream``), and the hidden overloads."""
    m = len(n)
    row: dict = {}
    rng = np.random.default_rng(stream)
    cell_wear = {}
    for name, k in exponents.items():
        none = {"damage": np.zeros(0), "damage_equal": np.zeros(0)}
        wear = group_wear(loads, n, float(k), STANDARD_AXLE_KG) if m else none
        cell_wear[name] = (wear["damage"], wear["damage_equal"])
    boot = {name: ([], []) for name in exponents} if resamples and m else None
    if boot is not None:
        # drawn in blocks of rows (each row one resample), at most BOOTSTRAP_BLOCK indices at a time: the same
        # draws as one (resamples, m) call, in the same order, so the same bits, in bounded memory
        rows_per_block = max(1, BOOTSTRAP_BLOCK // m)
        for start in range(0, resamples, rows_per_block):
            draws = rng.integers(0, m, (min(rows_per_block, resamples - start), m))
            for name in exponents:
                d, e = cell_wear[name]
                boot[name][0].append(d[draws].sum(axis=1) / e[draws].sum(axis=1) - 1.0)
                boot[name][1].append(1000.0 * (d - e)[draws].mean(axis=1))
    for name in exponents:
        d, e = cell_wear[name]
        share = d.sum() / e.sum() - 1.0 if m and e.sum() > 0 else math.nan
        per_1000 = 1000.0 * float(np.mean(d - e)) if m else math.nan
        row[f"extra_wear_{name}"], row[f"extra_sa_per_1000_{name}"] = share, per_1000
        if boot is not None:
            shares, extra = np.concatenate(boot[name][0]), np.concatenate(boot[name][1])
            row[f"extra_wear_{name}_low"], row[f"extra_wear_{name}_high"] = percentile_interval(
                shares, confidence_level
            )
            row[f"extra_sa_per_1000_{name}_low"], row[f"extra_sa_per_1000_{name}_high"] = percentile_interval(
                extra, confidence_level
            )
        else:
            for col in (f"extra_wear_{name}", f"extra_sa_per_1000_{name}"):
                row[f"{col}_low"] = row[f"{col}_high"] = math.nan
    known = np.isfinite(legal)
    over = hidden_overloads(loads[known], n[known], legal[known], legal_axle[known])
    row.update(_overload_figures(int(over["hidden"].sum()), int(over["group_over"].sum()), int(known.sum()),
                                 confidence_level))  # fmt: skip
    return row


def _overload_figures(hidden: int, group_over: int, judged: int, confidence_level: float) -> dict[str, float]:
    """The hidden overloads' count, share and Wilson interval, and the share of groups over their legal load, of
    ``judged`` groups (those of a size with a legal load)."""
    (low,), (high,) = wilson_interval(np.array([hidden]), np.array([judged]), confidence_level)
    return {
        "n_hidden": hidden, "share_hidden_overload": hidden / judged if judged else math.nan,
        "share_hidden_overload_low": float(low), "share_hidden_overload_high": float(high),
        "share_group_over": group_over / judged if judged else math.nan,
    }  # fmt: skip


@njit(cache=True, nogil=True)
def _wear_moments(loads, n, exponents, standard_axle, moments):  # pragma: no cover - compiled
    """Add the groups' damage D and equal-shared damage E for each exponent (as :func:`group_wear`: x = W / W_s,
    D = sum x^k, E = n mean(x)^k, libm's pow) to ``moments[k] = (count, mean D, mean E, M2 D, M2 E, C DE)``,
    one group at a time by Welford's update (no cancellation, no arrays of the cell)."""
    for g in range(loads.shape[0]):
        m = n[g]
        total = 0.0
        for i in range(m):
            total += loads[g, i] / standard_axle
        mean_x = total / m
        for j in range(exponents.shape[0]):
            k = exponents[j]
            d = 0.0
            for i in range(m):
                d += math.pow(loads[g, i] / standard_axle, k)
            e = m * math.pow(mean_x, k)
            c = moments[j, 0] + 1.0
            dd = d - moments[j, 1]
            de = e - moments[j, 2]
            moments[j, 0] = c
            moments[j, 1] += dd / c
            moments[j, 2] += de / c
            moments[j, 3] += dd * (d - moments[j, 1])
            moments[j, 4] += de * (e - moments[j, 2])
            moments[j, 5] += dd * (e - moments[j, 2])


#: groups of a large cell taken at a time (:func:`_large_cell`): the memory of a block's arrays, whatever the cell
WEAR_BLOCK = 1 << 18


def _large_cell(blocks: Iterable[tuple[NDArray, ...]], exponents: Mapping[str, float],
                confidence_level: float) -> dict[str, float]:  # fmt: skip
    """The figures of a cell of more than :data:`BOOTSTRAP_MAX_GROUPS` groups, from its ``blocks`` of (loads [kg],
    axles, legal group load [kg], single-axle limit [kg]) in order, in bounded memory:
    the extra wear R = sum D / sum E - 1 and 1000 mean(D - E), with the delta method's normal intervals
    (docs/pavement.md, "Intervals": R's linearisation is (1 / (m mean E)) sum (D_i - (R + 1) E_i), so its standard
    error is sd(D - (R + 1) E) / (sqrt(m) mean E), Cochran, Sampling Techniques, 3rd ed. 1977, section 6.3, the
    ratio estimator; the mean's is sd(D - E) / sqrt(m)), and the hidden overloads. The moments are Welford's, one
    group at a time in a compiled loop (:func:`_wear_moments`)."""
    cell = _LargeCell(exponents, confidence_level)
    for loads, n, legal, legal_axle in blocks:
        cell.add(loads, n, legal, legal_axle)
    return cell.figures()


class _LargeCell:
    """:func:`_large_cell`'s sums, a block at a time (:meth:`add`), and its figures (:meth:`figures`)."""

    def __init__(self, exponents: Mapping[str, float], confidence_level: float) -> None:
        self.names = list(exponents)
        self.ks = np.array([float(exponents[name]) for name in self.names])
        self.moments = np.zeros((len(self.names), 6))
        self.hidden = self.group_over = self.judged = 0
        self.confidence_level = confidence_level

    def add(self, loads: NDArray, n: NDArray, legal: NDArray, legal_axle: NDArray) -> None:
        """Add the groups of a block, in order: loads [kg], axles, legal group load and single-axle limit [kg]."""
        _wear_moments(np.ascontiguousarray(loads), n, self.ks, STANDARD_AXLE_KG, self.moments)
        known = np.isfinite(legal)
        over = hidden_overloads(loads[known], n[known], legal[known], legal_axle[known])
        self.hidden += int(over["hidden"].sum())
        self.group_over += int(over["group_over"].sum())
        self.judged += int(known.sum())

    def figures(self) -> dict[str, float]:
        z = statistics.NormalDist().inv_cdf(0.5 + self.confidence_level / 2.0)
        out: dict[str, float] = {}
        for j, name in enumerate(self.names):
            count, mean_d, mean_e, m2_d, m2_e, c_de = self.moments[j]
            m = int(count)
            vdd, vee, vde = m2_d / (m - 1), m2_e / (m - 1), c_de / (m - 1)
            ratio = mean_d / mean_e
            se_ratio = math.sqrt(max(vdd - 2 * ratio * vde + ratio * ratio * vee, 0.0)) / (math.sqrt(m) * mean_e)
            mean = 1000.0 * (mean_d - mean_e)
            se_mean = 1000.0 * math.sqrt(max(vdd - 2 * vde + vee, 0.0)) / math.sqrt(m)
            share = ratio - 1.0
            out[f"extra_wear_{name}"], out[f"extra_sa_per_1000_{name}"] = share, mean  # the small cells' key order
            out[f"extra_wear_{name}_low"] = share - z * se_ratio
            out[f"extra_wear_{name}_high"] = share + z * se_ratio
            out[f"extra_sa_per_1000_{name}_low"] = mean - z * se_mean
            out[f"extra_sa_per_1000_{name}_high"] = mean + z * se_mean
        out.update(_overload_figures(self.hidden, self.group_over, self.judged, self.confidence_level))
        return out


def wear_dict(table: pd.DataFrame, by: Sequence[str], digits: int = 4) -> dict:
    """:func:`wear_statistics` as nested JSON-ready dicts, ``by`` values as keys in order; NaN as None."""

    def num(x: float) -> float | int | None:
        if isinstance(x, (int, np.integer)):
            return int(x)
        return json_number(x, digits)

    out: dict = {}
    for row in table.to_dict("records"):
        node = out
        for key in by[:-1]:
            node = node.setdefault(str(row[key]), {})
        node[str(row[by[-1]])] = {k: num(v) for k, v in row.items() if k not in by}
    return out
