"""Survey statistics of axle groups: one definition for observed (WIM, weighbridge) and simulated groups.

The definitions are the report's (``docs/outputs.md``, ``docs/weighings.md``): for a group of n axles with loads
W_1..W_n,

- load share of axle i, LSC_i = n W_i / sum_j W_j [-] (1 = its equal share);
- spread = max W - min W, in kg, and in percent of the mean axle load;
- **outside 5 %** (VSB 11 road-friendly rule): (max W - min W) / max W > 0.05;
- **over 10 %** (load-sharing rule): an axle above 1.10 times the group's mean, max_i LSC_i > 1.10.

The table of groups is *wide*: one row per group, ``n_axles`` and ``axle_load_1 .. axle_load_<k>`` (front axle
first; columns past a group's own axles are ignored, whatever they hold). numpy and pandas only.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from bogie.rounding import json_number
from bogie.weighings._records import REL_TOL

__all__ = [
    "PAIR_TOLERANCE", "QUANTILES", "SHARE_TOLERANCE", "STATISTICS_BLOCK", "STATISTICS_COLUMNS", "at_resolution",
    "axle_columns", "group_inequality", "statistics_dict", "survey_statistics",
]  # fmt: skip

#: VSB 11 road-friendly suspension: no axle more than 5 % from any other, (max - min) / max <= 0.05 [-]
PAIR_TOLERANCE: float = 0.05
#: load-sharing suspension rule: no axle more than 10 % over its equal share, max LSC <= 1.10 [-]
SHARE_TOLERANCE: float = 0.10
#: quantiles of the load share tabulated per axle position [-] (the survey's 5, 25, 50, 75, 95 percentiles)
QUANTILES: tuple[float, ...] = (0.05, 0.25, 0.50, 0.75, 0.95)
#: the columns of :func:`survey_statistics` before the load-share quantiles
STATISTICS_COLUMNS: tuple[str, ...] = (
    "n_groups", "mean_spread_kg", "median_spread_pct", "share_outside_5pct", "share_over_10pct",
)  # fmt: skip


def at_resolution(loads: ArrayLike, step_kg: float | None) -> NDArray:
    """Loads [kg] as a scale of resolution ``step_kg`` reads them: each rounded to the nearest multiple of the step
    (ties to even, numpy's rounding; a tie has probability 0 for a simulated load). None returns the loads as they
    are. NaN stays NaN.

    Issue 27 Must 3: at 100 kg a tandem's "outside 5 %" is a matter of a few steps, so a simulated survey compared
    with an observed one is read at the observed file's resolution
    (:attr:`bogie.weighings.readers.ReadResult.weight_step_kg`) before any statistic.
    """
    loads = np.asarray(loads, dtype=float)
    if step_kg is None:
        return loads.copy()
    if not (np.isfinite(step_kg) and step_kg > 0.0):
        raise ValueError(f"step_kg = {step_kg!r} kg: a weight resolution is a positive number of kilograms")
    return np.round(loads / step_kg) * step_kg


def axle_columns(n: int) -> list[str]:
    """The axle load columns of a wide group table with room for ``n`` axles: ``axle_load_1 .. axle_load_<n>``."""
    return [f"axle_load_{i + 1}" for i in range(n)]


def _width(table: pd.DataFrame) -> int:
    n = 0
    while f"axle_load_{n + 1}" in table.columns:
        n += 1
    return n


def group_inequality(loads: ArrayLike, n_axles: ArrayLike) -> dict[str, NDArray]:
    """Per-group inequality quantities of axle loads.

    Parameters
    ----------
    loads
        Axle loads, one row per group, front axle first, shape (n_groups, k) [any unit: N, kg]; entries past a
        group's ``n_axles`` are ignored.
    n_axles
        Axles of each group (2 <= n_axles <= k) [-].

    Returns
    -------
    dict of numpy arrays, one value per group
        ``heaviest``, ``lightest``, ``mean`` (mean axle load) and ``spread`` (heaviest - lightest) in the unit of
        ``loads``; ``spread_pct`` (spread over the mean axle load [%]); ``pair_difference`` ((max - min) / max
        [-]); ``max_load_share`` (max LSC [-]); ``outside_5pct`` and ``over_10pct`` (bool); ``heaviest_axle``
        (0 = front; a tie goes to the front-most); ``load_share`` (LSC of each axle, shape (n_groups, k), NaN past
        the group's axles).
    """
    loads = np.asarray(loads, dtype=float)
    n = np.asarray(n_axles, dtype=np.int64)
    present = np.arange(loads.shape[1]) < n[:, None]
    heaviest = np.where(present, loads, -np.inf).max(axis=1)
    lightest = np.where(present, loads, np.inf).min(axis=1)
    total = np.where(present, loads, 0.0).sum(axis=1)
    mean = total / n
    pair_difference = (heaviest - lightest) / heaviest
    max_load_share = heaviest / mean
    return {
        "heaviest": heaviest,
        "lightest": lightest,
        "mean": mean,
        "spread": heaviest - lightest,
        "spread_pct": 100.0 * (heaviest - lightest) / mean,
        "pair_difference": pair_difference,
        "max_load_share": max_load_share,
        # a group at a limit is within it: the ratios of loads read at a file's resolution round in the last bit
        "outside_5pct": pair_difference > PAIR_TOLERANCE * (1.0 + REL_TOL),
        "over_10pct": max_load_share > (1.0 + SHARE_TOLERANCE) * (1.0 + REL_TOL),
        "heaviest_axle": np.argmax(np.where(present, loads, -np.inf), axis=1),
        # as bogie.metrics.lsc: n W_i / sum_j W_j
        "load_share": np.where(present, n[:, None] * loads / total[:, None], np.nan),
    }


def survey_statistics(
    groups: pd.DataFrame,
    by: str | Sequence[str] = "group",
    unit_per_kg: float = 1.0,
    quantiles: Sequence[float] = QUANTILES,
) -> pd.DataFrame:
    """The survey statistics of a table of axle groups, per value of ``by``.

    Parameters
    ----------
    groups
        Wide table, one row per group: ``n_axles`` [-], ``axle_load_1 ..`` (front first) and the ``by`` columns.
        Every row is used: filter (laden groups, positions, speeds) and drop bad readings first.
    by
        Column(s) to tabulate by, e.g. ``"group"`` (tandem, triaxle) or ``["protocol", "group"]``.
    unit_per_kg
        The loads' unit per kilogram: 1 for loads in kg, :data:`bogie.params.GRAVITY` for newtons [unit/kg].
    quantiles
        Quantiles of the load share of each axle position [-].

    Returns
    -------
    pandas.DataFrame
        One row per ``by`` value (sorted): ``n_groups``; ``mean_spread_kg`` [kg]; ``median_spread_pct`` [%];
        ``share_outside_5pct``, ``share_over_10pct`` (fractions 0..1 of the groups); and for each axle position
        i (1 = front) and quantile q, ``load_share_<i>_p<100 q>`` (LSC [-], over the groups that have axle i;
        NaN where none does).
    """
    keys = [by] if isinstance(by, str) else list(by)
    width = _width(groups)
    if width < 2 or "n_axles" not in groups.columns:
        raise ValueError(
            f"groups has columns {list(groups.columns)}: needs n_axles and axle_load_1, axle_load_2, ... (wide)"
        )
    if len(groups) > STATISTICS_BLOCK:
        return _blockwise_statistics(groups, keys, width, unit_per_kg, quantiles)
    ineq = group_inequality(groups[axle_columns(width)].to_numpy(dtype=float), groups["n_axles"].to_numpy())
    frame = groups[keys].assign(
        spread_kg=ineq["spread"] / unit_per_kg, spread_pct=ineq["spread_pct"],
        outside_5pct=ineq["outside_5pct"], over_10pct=ineq["over_10pct"],
    )  # fmt: skip
    shares = [f"load_share_{i + 1}" for i in range(width)]
    frame[shares] = ineq["load_share"]
    grouped = frame.groupby(keys, observed=True, sort=True)
    table = grouped.agg(
        n_groups=("spread_kg", "size"), mean_spread_kg=("spread_kg", "mean"),
        median_spread_pct=("spread_pct", "median"), share_outside_5pct=("outside_5pct", "mean"),
        share_over_10pct=("over_10pct", "mean"),
    )  # fmt: skip
    for share in shares:
        # pandas' quantile skips NaN: each axle position over the groups that have it (linear interpolation)
        q = grouped[share].quantile(list(quantiles)).unstack()
        for level in q.columns:
            table[f"{share}_p{round(100 * level):02d}"] = q[level]
    table = table.reset_index()
    for key in keys:  # a categorical label (axle_groups') tabulates as its strings, as the blockwise way gives them
        if isinstance(table[key].dtype, pd.CategoricalDtype):
            table[key] = table[key].astype(str)
    return table


#: groups above which :func:`survey_statistics` works cell by cell and block by block (a year of a WIM site holds
#: millions of groups: the table's way took 1.5 GB for 9 million)
STATISTICS_BLOCK = 1 << 20


def _blockwise_statistics(
    groups: pd.DataFrame, keys: list[str], width: int, unit_per_kg: float, quantiles: Sequence[float]
) -> pd.DataFrame:
    """:func:`survey_statistics` of a large table in bounded memory: per cell, the inequality of each block of
    :data:`STATISTICS_BLOCK` groups, counted and summed; the spreads in percent and the load shares kept, one value
    a group, for the median and the quantiles (pandas' linear interpolation, NaN skipped, as the table's way).
    Counts, shares and quantiles are the table's way's to the bit; the mean spread, a sum of block sums, to about
    1e-12 relative (``tests/test_weighings_stream.py``)."""
    columns = [groups[c].to_numpy() for c in axle_columns(width)]  # as stored (float32 where exact), no copy
    n_all = groups["n_axles"].to_numpy()
    rows = []
    for cell, index in groups.groupby(keys, observed=True, sort=True).indices.items():
        cell = cell if isinstance(cell, tuple) else (cell,)
        m = len(index)
        spread_pct = np.empty(m)
        shares = np.empty((m, width))
        spread_sum, outside, over = 0.0, 0, 0
        for start in range(0, m, STATISTICS_BLOCK):
            rows_b = index[start : start + STATISTICS_BLOCK]
            loads = np.column_stack([c[rows_b] for c in columns]).astype(float)
            ineq = group_inequality(loads, n_all[rows_b].astype(np.int64))
            spread_sum += float((ineq["spread"] / unit_per_kg).sum())
            outside += int(ineq["outside_5pct"].sum())
            over += int(ineq["over_10pct"].sum())
            spread_pct[start : start + len(rows_b)] = ineq["spread_pct"]
            shares[start : start + len(rows_b)] = ineq["load_share"]
        row = {
            **dict(zip(keys, cell)), "n_groups": m, "mean_spread_kg": spread_sum / m,
            "median_spread_pct": pd.Series(spread_pct).median(), "share_outside_5pct": outside / m,
            "share_over_10pct": over / m,
        }  # fmt: skip
        for i in range(width):
            q = pd.Series(shares[:, i]).quantile(list(quantiles))
            for level, value in q.items():
                row[f"load_share_{i + 1}_p{round(100 * level):02d}"] = value
        rows.append(row)
    return pd.DataFrame(rows)


def statistics_dict(stats: pd.DataFrame, by: str = "group", digits: int = 4) -> dict[str, dict]:
    """:func:`survey_statistics` (tabulated by one column) as plain dicts for JSON, rounded to ``digits``.

    ``{value of by: {"n_groups", "mean_spread_kg", "median_spread_pct", "share_outside_5pct", "share_over_10pct",
    "load_share_quantiles": {"axle_1": {"p05": .., ..}, ..}}}``; axles numbered from 1 (front), only those the
    groups have; a missing number is None (JSON has no NaN).
    """

    def num(x: float) -> float | None:
        return json_number(x, digits)

    out: dict[str, dict] = {}
    for row in stats.to_dict("records"):
        entry: dict = {"n_groups": int(row["n_groups"])}
        entry.update({k: num(row[k]) for k in STATISTICS_COLUMNS[1:]})
        quantiles: dict[str, dict[str, float | None]] = {}
        for key, value in row.items():
            if key.startswith("load_share_") and not pd.isna(value):
                axle, q = key.removeprefix("load_share_").split("_")
                quantiles.setdefault(f"axle_{int(axle)}", {})[q] = num(value)
        entry["load_share_quantiles"] = quantiles
        out[str(row[by])] = entry
    return out
