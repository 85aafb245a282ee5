"""The survey's design-guidance table: the share of groups within 5 % binned by the design parameters.

Part of the ``survey`` stage (:func:`pipeline.survey.main` writes it as ``data/survey/design_guidance.csv``); the
report only reads and draws it. These are the fleet's correlations, not a controlled experiment: every other factor
varies as sampled.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from bogie import numerics
from bogie.fleet.constants import GROUP_AXLES
from bogie.intervals import wilson_interval  # noqa: F401 (re-exported: one definition for the design table)

__all__ = ["DESIGN_BINS", "DESIGN_COLUMNS", "DESIGN_CONFIDENCE", "DESIGN_GRID", "design_table", "wilson_interval"]

#: sample columns the design guidance bins the fleet by -> (unit of its bin edges, SI -> that unit, bins, rounding
#: step of the end edges in that unit); ``bins`` None: log bins on 1, 3, 10, 30, ... (bush stiffness spans decades)
DESIGN_BINS: dict[str, tuple[str, float, int | None, float]] = {
    "bush_stiffness": ("N m/rad", 1.0, None, 0.0),
    "equaliser_arm": ("mm", 1e3, 4, 10.0),
    "friction_coefficient": ("-", 1.0, 5, 0.05),
    "contact_roll_radius": ("mm", 1e3, 6, 10.0),
}
DESIGN_COLUMNS: tuple[str, ...] = tuple(DESIGN_BINS)
#: the two parameters of the design guidance's map (cells of the first by the second)
DESIGN_GRID: tuple[str, str] = ("bush_stiffness", "equaliser_arm")
#: confidence level of the design guidance's intervals [-]
DESIGN_CONFIDENCE = 0.95


def _nice_log_edges(x: np.ndarray) -> np.ndarray:
    """Edges 1, 3, 10, 30, ... times a power of ten that cover ``x`` (positive)."""
    lo, hi = float(np.min(x)), float(np.max(x))
    ladder = np.sort(
        np.outer(
            numerics.power(10.0, np.arange(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 2)), [1.0, 3.0]
        ).ravel()
    )
    edges = ladder[(ladder >= ladder[ladder <= lo].max()) & (ladder <= ladder[ladder >= hi].min())]
    return edges if len(edges) > 1 else np.array([lo, hi * 1.0001 + 1e-12])


def _nice_edges(x: np.ndarray, bins: int, step: float) -> np.ndarray:
    """``bins`` equal bins from ``x``'s minimum to its maximum, ends rounded outward to ``step``."""
    lo, hi = np.floor(np.min(x) / step) * step, np.ceil(np.max(x) / step) * step
    return np.linspace(lo, hi if hi > lo else lo + step, bins + 1)


def _bin_index(x: np.ndarray, edges: np.ndarray) -> np.ndarray:
    # left-closed bins, the last closed: a value on the top edge belongs to the last bin
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)


def _design_rows(keys: dict[str, Any], within: np.ndarray, index: np.ndarray, size: int) -> dict[str, Any]:
    """Counts, share within 5 % and its Wilson interval of the bins ``index`` (0..size-1) of one group."""
    n = np.bincount(index, minlength=size)
    k = np.bincount(index, weights=within, minlength=size)
    low, high = wilson_interval(k, n)
    share = k / np.where(n, n, np.nan)
    return {**keys, "n": n, "n_within": k.astype(np.int64), "share": share, "share_low": low, "share_high": high}


def design_table(ok: pd.DataFrame) -> pd.DataFrame:
    """The design guidance: share of groups within 5 % binned by the design parameters, per protocol and group.

    Bin edges are fixed per protocol over both groups (:data:`DESIGN_BINS`); bins are left-closed, the last closed.

    Parameters
    ----------
    ok
        Succeeded runs with the :func:`inequality_columns` and the :data:`DESIGN_COLUMNS` [SI].

    Returns
    -------
    pandas.DataFrame
        One row per bin: ``protocol``, ``group``, ``kind`` ("cell" of the map of :data:`DESIGN_GRID`, or "bin" of
        one parameter), ``x`` (parameter), ``x_unit``, ``x_low``, ``x_high`` (edges in that unit), ``y``,
        ``y_unit``, ``y_low``, ``y_high`` (the map's second parameter; empty for a bin), ``n`` (groups),
        ``n_within`` (of them within 5 %), ``share`` (NaN when ``n`` is 0) and its Wilson interval
        ``share_low``, ``share_high`` at :data:`DESIGN_CONFIDENCE` [-].
    """
    frames = []
    for protocol in dict.fromkeys(ok["protocol"]):
        runs = ok[ok["protocol"] == protocol]
        within = ~runs["outside_5pct"].to_numpy(dtype=bool)
        values, edges = {}, {}
        for column, (_, scale, bins, step) in DESIGN_BINS.items():
            values[column] = scale * runs[column].to_numpy(dtype=float)
            edges[column] = (
                _nice_log_edges(np.maximum(values[column], 1e-3))
                if bins is None
                else _nice_edges(values[column], bins, step)
            )
        index = {c: _bin_index(values[c], edges[c]) for c in values}
        groups = runs["group"].to_numpy()
        for group in [g for g in GROUP_AXLES if g in set(groups)]:
            g = groups == group
            (xc, yc), keys = DESIGN_GRID, {"protocol": protocol, "group": group}
            xe, ye = edges[xc], edges[yc]
            cell = index[xc][g] * (len(ye) - 1) + index[yc][g]
            cells = _design_rows(keys, within[g], cell, (len(xe) - 1) * (len(ye) - 1))
            i, j = np.divmod(np.arange(len(cells["n"])), len(ye) - 1)
            frames.append(pd.DataFrame({
                "protocol": protocol, "group": group, "kind": "cell", "x": xc, "x_unit": DESIGN_BINS[xc][0],
                "x_low": xe[i], "x_high": xe[i + 1], "y": yc, "y_unit": DESIGN_BINS[yc][0], "y_low": ye[j],
                "y_high": ye[j + 1], **cells,
            }))  # fmt: skip
            for column, e in edges.items():
                bins = _design_rows(keys, within[g], index[column][g], len(e) - 1)
                frames.append(pd.DataFrame({
                    "protocol": protocol, "group": group, "kind": "bin", "x": column, "x_unit": DESIGN_BINS[column][0],
                    "x_low": e[:-1], "x_high": e[1:], "y": "", "y_unit": "", "y_low": np.nan, "y_high": np.nan, **bins,
                }))  # fmt: skip
    columns = ["protocol", "group", "kind", "x", "x_unit", "x_low", "x_high", "y", "y_unit", "y_low", "y_high"]
    columns += ["n", "n_within", "share", "share_low", "share_high"]
    return pd.concat(frames, ignore_index=True)[columns] if frames else pd.DataFrame(columns=columns)
