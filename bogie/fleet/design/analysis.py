"""The design experiment's analysis: shares within 5 % with Wilson intervals, tilt tolerances, Pareto fronts, words.

:func:`analyse_designs` reads the runs of a controlled design experiment (:mod:`bogie.fleet.design.experiment` makes its
rows and weighs them): each design's share of groups within 5 % and within 10 % at the conditions' own tilts, with
Wilson score intervals; its share within 5 % against chassis tilt, the grid runs' axle loads interpolated linearly on a
:data:`FINE_STEP_DEG` axis; its nose-up and nose-down tilt tolerance (:func:`tilt_tolerance`); the interpolation
checked against the runs at the conditions' own tilts; and each group's Pareto front (:func:`pareto_front`) of share
against the distance from today's typical design. :func:`guidance_sentences` puts the table in words a designer and
an operator can act on. The method is ``docs/design.md``'s.

"Within 5 %" is VSB 11's (max W - min W) / max W <= 5 % (``outside_5pct`` of the runs), "within 10 %" no axle
more than 10 % over its equal share (``over_10pct``): :func:`bogie.weighings.stats.group_inequality`'s definitions.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.constants import GROUP_AXLES
from bogie.fleet.design.settings import FACTORS, DesignError
from bogie.fleet.design.table import wilson_interval
from bogie.metrics import max_deviation
from bogie.settings import check_value
from bogie.weighings.stats import group_inequality

__all__ = [
    "FACTORS", "FINE_STEP_DEG", "FLEET_SLOT", "HELD", "DesignAnalysis", "DesignError", "analyse_designs",
    "describe", "guidance_sentences", "pareto_front", "tilt_tolerance", "tolerance_width",
]  # fmt: skip

#: the other bogie parameters a design holds at the fleet's median (they are not design choices studied here)
HELD: tuple[str, ...] = ("bush_damping", "spring_friction_decay")
#: slot of a run at its condition's own sampled tilt (the other slots are indices into the tilt grid)
FLEET_SLOT = -1
#: step of the fine tilt axis the tolerance is read on [degree]
FINE_STEP_DEG = 0.01

#: the columns :func:`analyse_designs` reads: of the runs, of the designs
RUN_NEEDS: tuple[str, ...] = ("design", "condition", "slot", "status", "chassis_tilt", "outside_5pct", "over_10pct",
                              "max_deviation", "axle_load_1", "axle_load_2")  # fmt: skip
DESIGN_NEEDS: tuple[str, ...] = ("design", "group", "kind", "suspension", *FACTORS, *HELD, "distance")


@dataclass(frozen=True)
class DesignAnalysis:
    """The design study's tables.

    Attributes
    ----------
    designs
        One row per design, best first (:func:`analyse_designs`).
    curves
        Each design's share within 5 % [-] against tilt ``tilt_deg`` [degree].
    check
        The interpolation check: per design and condition, max_deviation [-] and the within-5 % verdict of the run
        at the condition's own tilt and of the loads interpolated from the tilt grid.
    """

    designs: pd.DataFrame
    curves: pd.DataFrame
    check: pd.DataFrame


# ---- the pieces ------------------------------------------------------------------------------------------------
def _within(loads: np.ndarray) -> np.ndarray:
    """Within 5 % (VSB 11), not ``outside_5pct`` of :func:`bogie.weighings.stats.group_inequality`, for axle loads
    along the last axis."""
    flat = loads.reshape(-1, loads.shape[-1])
    outside = group_inequality(flat, np.full(len(flat), loads.shape[-1]))["outside_5pct"]
    return ~outside.reshape(loads.shape[:-1])


def tolerance_width(table: pd.DataFrame) -> pd.Series:
    """Each design's tolerated tilt band, nose down plus nose up [degree]; NaN for a design with no tolerance."""
    return table["tilt_tolerance_nose_up_deg"].astype(float) + table["tilt_tolerance_nose_down_deg"].astype(float)


def tilt_tolerance(fine: np.ndarray, share: np.ndarray, target: float) -> tuple[float | None, float | None, float]:
    """Nose-up and nose-down tilt tolerance [degree] and the share within 5 % at them [-], from a share curve.

    Parameters
    ----------
    fine
        Tilts [degree], increasing, level among them (or nearest level).
    share
        The share within 5 % at each tilt of ``fine`` [-].
    target
        The share a tilt must keep [-].

    Returns
    -------
    tuple
        The nose-up tolerance: the largest tilt t >= 0 with ``share >= target`` everywhere on [0, t] of ``fine``;
        the nose-down one likewise below level, given as a positive number; both None when the share on level
        ground is already below the target. Then the share at tolerance: the smaller of the shares at the two
        limits, or the level share when there is no tolerance.
    """
    zero = int(np.argmin(np.abs(fine)))
    ok = share >= target
    if not ok[zero]:
        return None, None, float(share[zero])
    up = zero
    while up + 1 < len(fine) and ok[up + 1]:
        up += 1
    down = zero
    while down - 1 >= 0 and ok[down - 1]:
        down -= 1
    return float(fine[up]), float(abs(fine[down])), float(min(share[up], share[down]))


def pareto_front(share: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """Designs no other design beats on both counts: a share within 5 % [-] at least as high at a distance [-] at
    most as large, one of them strictly; a boolean per design."""
    keep = np.ones(len(share), dtype=bool)
    for i in range(len(share)):
        better = (share >= share[i]) & (distance <= distance[i]) & ((share > share[i]) | (distance < distance[i]))
        keep[i] = not better.any()
    return keep


# ---- the analysis ----------------------------------------------------------------------------------------------
def _arguments(runs: pd.DataFrame, designs: pd.DataFrame, tilts: Any, target: Any, confidence_level: Any) -> np.ndarray:
    """Refuse what the analysis cannot read, naming it; the tilt grid as floats [degree]."""
    for name, value in (("target_share", target), ("confidence_level", confidence_level)):
        check_value(name, value, low=0.0, high=1.0, low_open=True, high_open=True, error=DesignError)
    grid = np.asarray(tilts, dtype=float)
    if grid.ndim != 1 or len(grid) == 0 or not np.all(np.isfinite(grid)) or np.any(np.diff(grid) <= 0.0):
        raise DesignError(f"tilts = {tilts!r}: must be one or more finite tilts, strictly increasing, in degree")
    for name, frame, needs in (("runs", runs, RUN_NEEDS), ("designs", designs, DESIGN_NEEDS)):
        missing = [c for c in needs if c not in frame.columns]
        if missing:
            raise DesignError(f"{name}: the columns {', '.join(missing)} are missing")
    unknown = sorted(set(designs["group"]) - set(GROUP_AXLES))
    if unknown:
        raise DesignError(f"designs: the groups {', '.join(map(str, unknown))} are unknown; allowed: tandem, triaxle")
    return grid


def _grid_loads(mine: pd.DataFrame, n_tilts: int, n_ax: int) -> np.ndarray:
    """The grid runs' axle loads [N] as loads[condition, tilt, axle]; NaN where a run failed."""
    grid = mine[mine["slot"] >= 0].sort_values(["condition", "slot"])
    n_c = int(mine["condition"].max()) + 1 if len(mine) else 0
    loads = np.full((n_c, n_tilts, n_ax), np.nan)
    g_ok = grid[grid["status"] == "ok"]
    loads[g_ok["condition"].to_numpy(), g_ok["slot"].to_numpy()] = g_ok[
        [f"axle_load_{i + 1}" for i in range(n_ax)]
    ].to_numpy(dtype=float)
    return loads


def _checks(d: Any, fleet: pd.DataFrame, loads: np.ndarray, complete: np.ndarray, tilts: np.ndarray) -> list[dict]:
    """The interpolation check of one design: each condition's own tilt, interpolated on the grid, against its
    direct run (a condition with a failed grid run is left out)."""
    n_c, n_ax = loads.shape[0], loads.shape[2]
    direct = fleet.set_index("condition")
    out = []
    for c, t in zip(direct.index.to_numpy(), np.degrees(direct["chassis_tilt"].to_numpy(dtype=float))):
        if c < n_c and complete[c]:
            est = np.array([np.interp(t, tilts, loads[c, :, i]) for i in range(n_ax)])
            run_loads = direct.loc[c, [f"axle_load_{i + 1}" for i in range(n_ax)]].to_numpy(dtype=float)
            out.append({
                "design": d.design, "group": d.group, "condition": int(c), "tilt_deg": float(t),
                "max_deviation_direct": float(max_deviation(run_loads)),
                "max_deviation_interpolated": float(max_deviation(est)),
                "within_direct": bool(_within(run_loads)), "within_interpolated": bool(_within(est)),
            })  # fmt: skip
    return out


def _one_design(
    d: Any, mine: pd.DataFrame, tilts: np.ndarray, fine: np.ndarray, target: float, confidence_level: float
) -> tuple[dict[str, Any], pd.DataFrame, list[dict]]:
    """One design's row of the table, its share curve and its interpolation check, from its runs ``mine``."""
    n_ax = GROUP_AXLES[d.group]
    ok = mine["status"] == "ok"
    fleet = mine[(mine["slot"] == FLEET_SLOT) & ok]
    n = len(fleet)
    k5 = int((~fleet["outside_5pct"].astype(bool)).sum())
    k10 = int((~fleet["over_10pct"].astype(bool)).sum())
    (lo5, lo10), (hi5, hi10) = wilson_interval(np.array([k5, k10]), np.array([n, n]), confidence_level)
    # the tilt grid: a condition with a failed grid run leaves the curve
    loads = _grid_loads(mine, len(tilts), n_ax)
    complete = ~np.isnan(loads).any(axis=(1, 2))
    interp = np.stack([
        np.stack([np.interp(fine, tilts, loads[c, :, i]) for i in range(n_ax)], axis=-1)
        for c in np.flatnonzero(complete)
    ]) if complete.any() else np.zeros((0, len(fine), n_ax))  # fmt: skip
    share = _within(interp).mean(axis=0) if len(interp) else np.full(len(fine), np.nan)
    up, down, at_tol = tilt_tolerance(fine, share, target) if len(interp) else (None, None, math.nan)
    curve = pd.DataFrame({"design": d.design, "group": d.group, "tilt_deg": fine, "share_within_5pct": share})
    row = {
        **{c: getattr(d, c) for c in ("design", "group", "kind", "suspension", *FACTORS, *HELD, "distance")},
        "n_runs": len(mine), "n_failed": int((~ok).sum()), "n_conditions": n,
        "n_curve_conditions": int(complete.sum()),
        "within_5pct": k5, "share_within_5pct": k5 / n if n else math.nan, "share_within_5pct_low": lo5,
        "share_within_5pct_high": hi5, "within_10pct": k10, "share_within_10pct": k10 / n if n else math.nan,
        "share_within_10pct_low": lo10, "share_within_10pct_high": hi10,
        "mean_max_deviation": float(fleet["max_deviation"].mean()) if n else math.nan,
        "tilt_tolerance_nose_up_deg": up, "tilt_tolerance_nose_down_deg": down,
        "share_within_5pct_at_tolerance": at_tol,
        "share_within_5pct_level": float(share[int(np.argmin(np.abs(fine)))]),
    }  # fmt: skip
    return row, curve, _checks(d, fleet, loads, complete, tilts)


def analyse_designs(
    runs: pd.DataFrame, designs: pd.DataFrame, tilts: np.ndarray, target_share: float, confidence_level: float
) -> DesignAnalysis:
    """Shares, intervals, tilt tolerances and the Pareto fronts of the designs from their runs.

    Parameters
    ----------
    runs
        The experiment's runs (:func:`bogie.fleet.design.experiment.weigh_designs`): columns ``design``, ``condition``,
        ``slot`` (:data:`FLEET_SLOT`: at the condition's own tilt; else the index into ``tilts``), ``status``,
        ``chassis_tilt`` [rad], ``axle_load_1..`` [N], ``outside_5pct``, ``over_10pct``, ``max_deviation`` [-].
        A failed run is left out of its design's shares and counted in ``n_failed``.
    designs
        The designs (:func:`bogie.fleet.design.experiment.design_points`): ``design``, ``group``, ``kind``,
        ``suspension``, the :data:`FACTORS` and :data:`HELD` [SI] and ``distance`` [-].
    tilts
        The tilt grid [degree] the slots index, strictly increasing.
    target_share
        The share within 5 % a design must keep over the conditions [-], in (0, 1).
    confidence_level
        Of the shares' Wilson intervals [-], in (0, 1).

    Returns
    -------
    DesignAnalysis
        ``designs``: one row per design, best first (each group's Pareto front with the highest share within 5 %
        first, then every other steel design of each group by share, then the air references), with the factors,
        counts, shares and intervals [-], ``mean_max_deviation`` [-], the tolerances [degree], the share at them and
        on level ground [-], and ``pareto``; ``curves`` and ``check``.

    Raises
    ------
    DesignError
        If ``target_share`` or ``confidence_level`` is outside (0, 1), ``tilts`` is not increasing, or a column is
        missing.
    """
    tilts = _arguments(runs, designs, tilts, target_share, confidence_level)
    fine = np.round(np.arange(tilts[0], tilts[-1] + 0.5 * FINE_STEP_DEG, FINE_STEP_DEG), 6)
    rows, curves, checks = [], [], []
    for d in designs.itertuples(index=False):
        row, curve, check = _one_design(
            d, runs[runs["design"] == d.design], tilts, fine, target_share, confidence_level
        )
        rows.append(row)
        curves.append(curve)
        checks += check
    table = pd.DataFrame(rows)
    table["pareto"] = False
    for group in dict.fromkeys(table["group"]):
        steel = (table["group"] == group) & (table["suspension"] == "steel") & table["share_within_5pct"].notna()
        idx = np.flatnonzero(steel)
        table.loc[table.index[idx], "pareto"] = pareto_front(
            table["share_within_5pct"].to_numpy()[idx], table["distance"].to_numpy()[idx]
        )
    return DesignAnalysis(_ordered(table), pd.concat(curves, ignore_index=True), pd.DataFrame(checks))


def _ordered(table: pd.DataFrame) -> pd.DataFrame:
    """Best first: each group's Pareto front (highest share within 5 % first), then every other steel design of
    each group by share, then the air references."""
    rank = np.where(table["suspension"] == "air", 2, np.where(table["pareto"], 0, 1))
    order = pd.DataFrame({"rank": rank, "group": [list(GROUP_AXLES).index(g) for g in table["group"]],
                          "share": -table["share_within_5pct"].fillna(-1.0), "distance": table["distance"].fillna(0.0),
                          "design": table["design"]})  # fmt: skip
    index = order.sort_values(["rank", "group", "share", "distance", "design"], kind="stable").index
    return table.loc[index].reset_index(drop=True)


# ---- the words -------------------------------------------------------------------------------------------------
def describe(row: Mapping[str, Any]) -> str:
    """A design in words: ``a free bearing, 40 mm pads and a 250 mm arm (friction 0.26, springs' band 2.0 kN)``."""
    bush = row["bush_stiffness"]
    bearing = "a free bearing" if bush <= 10.0 else f"a {bush:.0f} N m/rad bush"
    radius = 1e3 * row["contact_roll_radius"]
    pads = "fixed contact points (0 mm pads)" if radius < 0.5 else f"{radius:.0f} mm pads"
    arm = row["equaliser_arm"]
    arms = "its own arms of several lengths" if pd.isna(arm) else f"a {1e3 * arm:.0f} mm arm"
    return (
        f"{bearing}, {pads} and {arms} (friction "
        f"{row['friction_coefficient']:.2f}, springs' band {row['spring_friction_band'] / 1e3:.1f} kN)"
    )


def _band(row: Mapping[str, Any], tilts: np.ndarray) -> str:
    """``from 0.4 degrees nose down to 0.9 degrees nose up``; a limit at the tilt range's end says "at least"."""

    def one(v: float, end: float, sense: str) -> str:
        at_end = abs(v - abs(end)) < 1e-9
        return f"{'at least ' if at_end else ''}{v:.1f} degrees {sense}"

    down, up = row["tilt_tolerance_nose_down_deg"], row["tilt_tolerance_nose_up_deg"]
    return f"from {one(down, tilts[0], 'nose down')} to {one(up, tilts[-1], 'nose up')}"


def _has_tolerance(row: Mapping[str, Any]) -> bool:
    value = row["tilt_tolerance_nose_up_deg"]
    return value is not None and not pd.isna(value)


#: each group's name in the sentences: plural, singular
_NAMES: dict[str, tuple[str, str]] = {"tandem": ("tandems", "tandem"), "triaxle": ("tri-axles", "tri-axle")}


def _tolerance_sentences(g: pd.DataFrame, group: str, tilts: np.ndarray, pct: str) -> list[str]:
    """The widest tolerance of a group's steel designs ``g``, and today's typical design's."""
    label, name = _NAMES[group]
    out = []
    tol = g[[_has_tolerance(r) for r in g.to_dict("records")]]
    if len(tol):
        best = tol.loc[tolerance_width(tol).idxmax()]
        out.append(
            f"With {describe(best)}, {pct} of {label} stay within 5 % {_band(best, tilts)}: the widest tilt "
            f"tolerance of the {len(g)} {name} designs."
        )
    else:
        out.append(f"No {name} design studied keeps {pct} of {label} within 5 % even on level ground.")
    typ = g[g["kind"] == "typical"]
    if len(typ):
        t = typ.iloc[0]
        if _has_tolerance(t):
            out.append(
                f"Today's typical {name}, with {describe(t)}, keeps {pct} within 5 % only {_band(t, tilts)}: "
                "an operator running it should keep the fifth-wheel height mismatch within that tilt."
            )
        else:
            out.append(
                f"Today's typical {name}, with {describe(t)}, does not keep {pct} within 5 % even on level ground "
                f"({100 * t['share_within_5pct_level']:.0f} %): no chassis tilt is tolerated."
            )
    return out


def _own_sentence(g: pd.DataFrame, group: str, tilts: np.ndarray, pct: str, file: str | None) -> str | None:
    """The user's own design of a group (kind ``own``: the base bogie's file), beside today's typical and the best;
    None when the group has none."""
    own = g[g["kind"] == "own"]
    if not len(own):
        return None
    o, name = own.iloc[0], _NAMES[group][1]
    typ = g[g["kind"] == "typical"]
    best = g["share_within_5pct"].max()
    others = (f"today's typical {100 * typ.iloc[0]['share_within_5pct']:.0f} %; " if len(typ) else "") + (
        f"the best of the {len(g)} designs {100 * best:.0f} %"
    )  # fmt: skip
    level = f"{100 * o['share_within_5pct_level']:.0f} %"
    tilt = (f"keeps {pct} within 5 % {_band(o, tilts)}" if _has_tolerance(o) else
            f"does not keep {pct} within 5 % even on level ground ({level})")  # fmt: skip
    return (
        f"Your {name}{f' ({file})' if file else ''}, with {describe(o)}, keeps {100 * o['share_within_5pct']:.0f} % "
        f"({100 * o['share_within_5pct_low']:.0f}-{100 * o['share_within_5pct_high']:.0f} %) within 5 % across the "
        f"fleet's own tilts, wear, payloads and roads ({others}), and {tilt}."
    )


def _fleet_sentence(g: pd.DataFrame, group: str, target: float, pct: str) -> str:
    """The best share across the fleet's own conditions of a group's steel designs ``g``, against the target."""
    name = _NAMES[group][1]
    typ = g[g["kind"] == "typical"]
    top = g.sort_values("share_within_5pct", ascending=False, kind="stable").iloc[0]
    typical_share = f"; today's typical design {100 * typ.iloc[0]['share_within_5pct']:.0f} %" if len(typ) else ""
    share = (
        f"{100 * top['share_within_5pct']:.0f} % ({100 * top['share_within_5pct_low']:.0f}-"
        f"{100 * top['share_within_5pct_high']:.0f} %)"
    )
    if top["share_within_5pct"] >= target:
        return (
            f"Across the fleet's own tilts, wear, payloads and roads the best {name} design, with {describe(top)}, "
            f"keeps {share} within 5 %, the {pct} target{typical_share}."
        )
    return (
        f"Across the fleet's own tilts, wear, payloads and roads no {name} design reaches {pct} within 5 %: "
        f"the best, with {describe(top)}, keeps {share}{typical_share}; the chassis tilt must be held as well."
    )


def guidance_sentences(
    table: pd.DataFrame, tilts: Sequence[float], target_share: float, own_files: Mapping[str, str] | None = None
) -> list[str]:
    """Sentences a designer and an operator can act on, generated from the design table (``docs/design.md``).

    Parameters
    ----------
    table
        :attr:`DesignAnalysis.designs`.
    tilts
        The tilt grid [degree]: a tolerance at its end reads "at least".
    target_share
        The share within 5 % a design must keep [-].
    own_files
        Group -> the bogie file its ``own`` design is (the fleet's ``presets``), named in its sentence (None: unnamed).

    Returns
    -------
    list of str
        Per group, in this order: the widest tolerance (or that no design keeps the target on level ground), today's
        typical design's tolerance (if it was studied), the user's own design (if the group's base bogie is a bogie
        file), the best share across the fleet's conditions, the air reference (if studied).
    """
    out = []
    pct = f"{100 * target_share:.0f} %"
    for group in dict.fromkeys(table["group"]):
        g = table[(table["group"] == group) & (table["suspension"] == "steel")]
        out += _tolerance_sentences(g, group, tilts, pct)
        own = _own_sentence(g, group, np.asarray(tilts), pct, (own_files or {}).get(group))
        if own is not None:
            out.append(own)
        out.append(_fleet_sentence(g, group, target_share, pct))
        air = table[(table["group"] == group) & (table["suspension"] == "air")]
        if len(air):
            a = air.iloc[0]
            held = f"keeps {pct} within 5 % {_band(a, tilts)}" if _has_tolerance(a) else (
                f"does not keep {pct} within 5 % on level ground"
            )  # fmt: skip
            out.append(
                f"The air-sprung {_NAMES[group][1]} group on the same trailer {held}, and "
                f"{100 * a['share_within_5pct']:.0f} % across the fleet's conditions."
            )
    return out
