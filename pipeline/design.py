"""DVC stage ``design``: design guidance from a controlled experiment -> data/design/, metrics/design.json.

``python -m pipeline.design`` reads params.yaml (``design:``; null: the stage writes a metrics file saying it was
not asked for) and answers the two questions users bring (``docs/design.md``):

* a suspension designer's: which combination of bush stiffness, equaliser arm, pad radius (contact movement),
  spring-end friction and the springs' interleaf band keeps ``target_share`` of bogies within 5 % across the
  operating conditions a fleet sees;
* an operator's or a road authority's: for a given bogie, how much chassis tilt (fifth-wheel height mismatch) is
  tolerated before the group leaves the 5 % tolerance.

The experiment is controlled: every design of a group runs over the same ``n_conditions`` operating conditions
(common random numbers: the same sampled chassis tilt, tyre wear of each axle, payload and approach road, drawn
from the fleet's own distributions), by the static protocol. Each condition is run at its own sampled tilt (the
shares within 5 % and 10 % "across the fleet's conditions") and on a grid of tilts from level outward (the tilt
tolerance). The designs: every combination of ``design.grid``'s levels with the other factors at today's typical
values (the medians of the fleet's distributions), that typical design itself, and ``n_space_filling`` designs of a
scrambled Sobol' sequence over all five factors' fleet distributions. The air-sprung group of the same trailer
(:func:`bogie.air.from_steel`) runs over the same conditions as a reference.

The runs go through :func:`pipeline.simulate.simulate_samples` into ``data/design_runs`` (chunked, resumable, byte
for byte the same whatever the number of workers); a failed run is a ``failed`` row there and is left out of its
design's shares, counted in ``n_failed``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml
from scipy.stats import qmc

from bogie.fleet.constants import GROUP_AXLES
from bogie.fleet.design_table import wilson_interval
from bogie.fleet.sampling import COLUMNS, TYRE_WEAR_COLUMNS, design_seed, road_seed, sensor_seed, study_frame
from bogie.metrics import max_deviation
from bogie.weighings.stats import group_inequality
from pipeline.atomic import LockedError, atomic_outputs, io_error, stage_outputs
from pipeline.chunks import NotRunsDatasetError
from pipeline.config import Config, ConfigError, load_config
from pipeline.sample import fleet_model
from pipeline.schema import read_runs_frame
from pipeline.simulate import simulate_samples
from pipeline.survey import rounded

__all__ = [
    "FACTORS", "DesignError", "analyse", "conditions", "design_points", "design_samples", "main", "run",
    "tilt_grid", "tolerance_width", "typical_design",
]  # fmt: skip

#: the design factors, SI sample columns, in the order of ``design.json``'s keys
FACTORS: tuple[str, ...] = (
    "bush_stiffness",
    "equaliser_arm",
    "contact_roll_radius",
    "friction_coefficient",
    "spring_friction_band",
)
#: the other bogie parameters a design holds at the fleet's median (they are not design choices studied here)
HELD: tuple[str, ...] = ("bush_damping", "spring_friction_decay")
#: the operating conditions, in the order of their design's dimensions (the order is part of the draws)
CONDITION_DIMENSIONS: tuple[str, ...] = ("chassis_tilt", "payload_fraction", *TYRE_WEAR_COLUMNS, "road_class")
#: step of the fine tilt axis the tolerance is read on [degree]
FINE_STEP_DEG = 0.01
#: the keys of each entry of ``design.json``'s ``designs``, in order (issue 16)
DESIGN_KEYS: tuple[str, ...] = (
    "group", "bush_stiffness", "equaliser_arm", "contact_roll_radius", "friction_coefficient",
    "spring_friction_band", "tilt_tolerance_nose_up_deg", "tilt_tolerance_nose_down_deg",
    "share_within_5pct_at_tolerance",
)  # fmt: skip
#: slot of a run at its condition's own sampled tilt (the other slots are indices into the tilt grid)
FLEET_SLOT = -1


class DesignError(ValueError):
    """The design study cannot be set up from these parameters (the message names the parameter)."""


# ---- the experiment --------------------------------------------------------------------------------------------
def _rank(dist: Any, x: float) -> float:
    """The fleet rank F(x) in [0, 1] of value ``x`` under ``dist`` (its inverse CDF inverted on a fine grid)."""
    lo, hi = dist.support
    if hi <= lo:
        return 0.5
    u = np.linspace(0.0, 1.0, 20001)
    q = dist.ppf(np.clip(u, 1e-12, 1.0 - 1e-12))
    return float(np.interp(x, q, u))


def typical_design(config: Config) -> dict[str, float]:
    """Today's typical design: the median of each design factor's (and held parameter's) fleet distribution [SI]."""
    return {name: float(config.distributions[name].ppf(np.array([0.5]))[0]) for name in (*FACTORS, *HELD)}


def tilt_grid(config: Config) -> np.ndarray:
    """The tilts of the tolerance grid [degree]: from level outward by ``design.tilt_step`` to the tilt
    distribution's bounds, both ends included (the schema, pipeline.config.rules, makes sure they include level)."""
    low, high = (math.degrees(v) for v in config.distributions["chassis_tilt"].support)
    step = config.design.tilt_step
    up = np.arange(0.0, high - 1e-9, step) if high > 0.0 else np.zeros(0)
    down = -np.arange(step, -low - 1e-9, step) if low < 0.0 else np.zeros(0)
    ends = [v for v in (low, high) if v != 0.0]
    return np.unique(np.round(np.r_[down, up, ends, 0.0], 9))


def conditions(config: Config) -> pd.DataFrame:
    """The ``design.n_conditions`` operating conditions: a Latin hypercube over tilt, payload, each axle's tyre wear
    and the road class, mapped through the fleet's distributions, each with its own approach road [SI]."""
    n = config.design.n_conditions
    u = qmc.LatinHypercube(
        len(CONDITION_DIMENSIONS), rng=np.random.default_rng(design_seed(config.seed, "design"))
    ).random(n)
    values: dict[str, Any] = {"condition": np.arange(n, dtype=np.int64)}
    for j, dim in enumerate(CONDITION_DIMENSIONS):
        dist = config.distributions["tyre_wear" if dim.startswith("tyre_wear_") else dim]
        values[dim] = dist.ppf(u[:, j])
    values["road_seed"] = np.array([road_seed(config.seed, "design", i) for i in range(n)], dtype=np.int64)
    values["sensor_seed"] = np.array([sensor_seed(config.seed, "design", i) for i in range(n)], dtype=np.int64)
    return pd.DataFrame(values)


def _space_filling(config: Config, k: int) -> list[dict[str, float]]:
    """``k`` designs of a scrambled Sobol' sequence over the five factors' fleet distributions [SI]."""
    if k == 0:
        return []
    rng = np.random.default_rng(design_seed(config.seed, "design-points"))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*balance properties of Sobol.*", category=UserWarning)
        u = qmc.Sobol(len(FACTORS), scramble=True, rng=rng).random(k)
    return [
        {f: float(config.distributions[f].ppf(u[i : i + 1, j])[0]) for j, f in enumerate(FACTORS)} for i in range(k)
    ]


def design_points(config: Config) -> pd.DataFrame:
    """Every design studied, per group: ``typical``, the ``grid`` combinations, the ``space-filling`` designs and the
    ``air`` reference; with each factor [SI] and its distance from the typical design in fleet ranks [-].

    The distance is sqrt(sum_f (F_f(x_f) - 1/2)^2) over the five factors, F_f the fleet's distribution of factor f:
    how far into the tails of today's fleet a design lies (0: the typical design; a design at a corner of the fleet's
    ranges: sqrt(5) / 2 = 1.12). A grid design equal to the typical one is not run twice.
    """
    spec = config.design
    typ = typical_design(config)
    grid_names = list(spec.grid)
    combos = [
        dict(zip(grid_names, levels))
        for levels in np.array(np.meshgrid(*spec.grid.values(), indexing="ij")).reshape(len(grid_names), -1).T
    ]
    space = _space_filling(config, spec.n_space_filling)
    rows = []
    for group in spec.groups:
        seen: set[tuple[float, ...]] = set()
        entries = [("typical", typ)]
        entries += [(f"grid-{i:02d}", {**typ, **{k: float(v) for k, v in c.items()}}) for i, c in enumerate(combos)]
        entries += [(f"space-{i:02d}", {**typ, **p}) for i, p in enumerate(space)]
        for name, values in entries:
            key = tuple(round(values[f], 12) for f in FACTORS)
            if key in seen:
                continue
            seen.add(key)
            ranks = [_rank(config.distributions[f], values[f]) for f in FACTORS]
            rows.append({
                "design": f"{group}-{name}", "group": group, "kind": name.split("-")[0], "suspension": "steel",
                **{f: values[f] for f in (*FACTORS, *HELD)},
                "distance": float(math.sqrt(sum((r - 0.5) ** 2 for r in ranks))),
            })  # fmt: skip
        rows.append({
            "design": f"{group}-air", "group": group, "kind": "air", "suspension": "air",
            **{f: typ[f] for f in (*FACTORS, *HELD)}, "distance": math.nan,
        })  # fmt: skip
    return pd.DataFrame(rows)


def design_samples(config: Config, designs: pd.DataFrame, conds: pd.DataFrame, tilts: np.ndarray) -> pd.DataFrame:
    """The sample rows of the experiment (columns of :data:`bogie.fleet.sampling.COLUMNS`, then ``design``,
    ``condition`` and ``slot``): each design at each condition's own tilt (slot :data:`FLEET_SLOT`) and at each tilt
    of ``tilts`` (slot = its index); ``base_id`` is the condition."""
    n_c, n_t = len(conds), len(tilts)
    per = n_c * (n_t + 1)
    d_idx = np.repeat(np.arange(len(designs)), per)
    c_idx = np.tile(np.repeat(np.arange(n_c), n_t + 1), len(designs))
    slot = np.tile(np.tile(np.r_[FLEET_SLOT, np.arange(n_t)], n_c), len(designs))
    sampled = conds["chassis_tilt"].to_numpy(dtype=float)
    tilt = np.where(slot == FLEET_SLOT, sampled[c_idx], np.radians(tilts)[np.maximum(slot, 0)])
    groups = designs["group"].to_numpy(dtype=object)[d_idx]
    values: dict[str, np.ndarray] = {f: designs[f].to_numpy(dtype=float)[d_idx] for f in (*FACTORS, *HELD)}
    values["chassis_tilt"] = tilt
    for c in ("payload_fraction", *TYRE_WEAR_COLUMNS, "road_class", "road_seed", "sensor_seed"):
        values[c] = conds[c].to_numpy()[c_idx]
    suspension = designs["suspension"].to_numpy(dtype=object)[d_idx]
    frame = study_frame(fleet_model(config), "design", groups, values, c_idx.astype(np.int64), suspension)
    frame["design"] = designs["design"].to_numpy(dtype=object)[d_idx]
    frame["condition"] = c_idx.astype(np.int64)
    frame["slot"] = slot.astype(np.int64)
    return frame


# ---- the analysis ----------------------------------------------------------------------------------------------
def _within(loads: np.ndarray) -> np.ndarray:
    """Within 5 % (VSB 11), not ``outside_5pct`` of :func:`bogie.weighings.stats.group_inequality`, for axle loads
    along the last axis."""
    flat = loads.reshape(-1, loads.shape[-1])
    outside = group_inequality(flat, np.full(len(flat), loads.shape[-1]))["outside_5pct"]
    return ~outside.reshape(loads.shape[:-1])


def tolerance_width(table: pd.DataFrame) -> pd.Series:
    """Each design's tolerated tilt band, nose down plus nose up [degree]; NaN for a design with no tolerance."""
    return table["tilt_tolerance_nose_up_deg"].astype(float) + table["tilt_tolerance_nose_down_deg"].astype(float)


def tolerance(fine: np.ndarray, share: np.ndarray, target: float) -> tuple[float | None, float | None, float]:
    """Nose-up and nose-down tilt tolerance [degree] and the share within 5 % at them, from a share curve.

    The nose-up tolerance is the largest tilt t >= 0 with ``share >= target`` everywhere on [0, t] of the ``fine``
    axis (the nose-down one likewise below level, given as a positive number); both None when the share on level
    ground is already below the target. The share at tolerance is the smaller of the shares at the two limits, or
    the level share when there is no tolerance.
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


def _pareto(share: np.ndarray, distance: np.ndarray) -> np.ndarray:
    """Designs no other design beats on both counts: a share within 5 % at least as high at a distance at most as
    large, one of them strictly."""
    keep = np.ones(len(share), dtype=bool)
    for i in range(len(share)):
        better = (share >= share[i]) & (distance <= distance[i]) & ((share > share[i]) | (distance < distance[i]))
        keep[i] = not better.any()
    return keep


@dataclass(frozen=True)
class Analysis:
    """The design study's tables: one row per design, the share curves against tilt, the interpolation check."""

    designs: pd.DataFrame
    curves: pd.DataFrame
    check: pd.DataFrame


def analyse(runs: pd.DataFrame, designs: pd.DataFrame, tilts: np.ndarray, target: float, confidence: float) -> Analysis:
    """Shares, intervals, tilt tolerances and the Pareto fronts of the designs from their runs.

    Parameters
    ----------
    runs
        The experiment's runs (columns ``design``, ``condition``, ``slot``, ``status``, ``axle_load_0..``,
        ``outside_5pct``, ``over_10pct``, ``max_deviation``, ``n_axles``).
    designs
        :func:`design_points`.
    tilts
        The tilt grid [degree] the slots index.
    target, confidence
        The target share within 5 % and the intervals' confidence level [-].
    """
    fine = np.round(np.arange(tilts[0], tilts[-1] + 0.5 * FINE_STEP_DEG, FINE_STEP_DEG), 6)
    rows, curves, checks = [], [], []
    for d in designs.itertuples(index=False):
        mine = runs[runs["design"] == d.design]
        n_ax = GROUP_AXLES[d.group]
        ok = mine["status"] == "ok"
        fleet = mine[(mine["slot"] == FLEET_SLOT) & ok]
        n = len(fleet)
        k5 = int((~fleet["outside_5pct"].astype(bool)).sum())
        k10 = int((~fleet["over_10pct"].astype(bool)).sum())
        (lo5, lo10), (hi5, hi10) = wilson_interval(np.array([k5, k10]), np.array([n, n]), confidence)
        # the tilt grid: loads[condition, tilt, axle]; a condition with a failed grid run leaves the curve
        grid = mine[mine["slot"] >= 0].sort_values(["condition", "slot"])
        n_c = int(mine["condition"].max()) + 1 if len(mine) else 0
        loads = np.full((n_c, len(tilts), n_ax), np.nan)
        g_ok = grid[grid["status"] == "ok"]
        loads[g_ok["condition"].to_numpy(), g_ok["slot"].to_numpy()] = g_ok[
            [f"axle_load_{i}" for i in range(n_ax)]
        ].to_numpy(dtype=float)
        complete = ~np.isnan(loads).any(axis=(1, 2))
        interp = np.stack([
            np.stack([np.interp(fine, tilts, loads[c, :, i]) for i in range(n_ax)], axis=-1)
            for c in np.flatnonzero(complete)
        ]) if complete.any() else np.zeros((0, len(fine), n_ax))  # fmt: skip
        share = _within(interp).mean(axis=0) if len(interp) else np.full(len(fine), np.nan)
        up, down, at_tol = tolerance(fine, share, target) if len(interp) else (None, None, math.nan)
        curves.append(
            pd.DataFrame({"design": d.design, "group": d.group, "tilt_deg": fine, "share_within_5pct": share})
        )
        # the interpolation check: each condition's own tilt, interpolated on the grid, against its direct run
        direct = fleet.set_index("condition")
        for c, t in zip(direct.index.to_numpy(), np.degrees(direct["chassis_tilt"].to_numpy(dtype=float))):
            if c < n_c and complete[c]:
                est = np.array([np.interp(t, tilts, loads[c, :, i]) for i in range(n_ax)])
                run_loads = direct.loc[c, [f"axle_load_{i}" for i in range(n_ax)]].to_numpy(dtype=float)
                checks.append({
                    "design": d.design, "group": d.group, "condition": int(c), "tilt_deg": float(t),
                    "max_deviation_direct": float(max_deviation(run_loads)),
                    "max_deviation_interpolated": float(max_deviation(est)),
                    "within_direct": bool(_within(run_loads)), "within_interpolated": bool(_within(est)),
                })  # fmt: skip
        rows.append({
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
        })  # fmt: skip
    table = pd.DataFrame(rows)
    table["pareto"] = False
    for group in dict.fromkeys(table["group"]):
        steel = (table["group"] == group) & (table["suspension"] == "steel") & table["share_within_5pct"].notna()
        idx = np.flatnonzero(steel)
        table.loc[table.index[idx], "pareto"] = _pareto(
            table["share_within_5pct"].to_numpy()[idx], table["distance"].to_numpy()[idx]
        )
    return Analysis(_ordered(table), pd.concat(curves, ignore_index=True), pd.DataFrame(checks))


def _ordered(table: pd.DataFrame) -> pd.DataFrame:
    """Best first: each group's Pareto front (highest share within 5 % first), then every other steel design of
    each group by share, then the air references."""
    rank = np.where(table["suspension"] == "air", 2, np.where(table["pareto"], 0, 1))
    order = pd.DataFrame({"rank": rank, "group": [list(GROUP_AXLES).index(g) for g in table["group"]],
                          "share": -table["share_within_5pct"].fillna(-1.0), "distance": table["distance"].fillna(0.0),
                          "design": table["design"]})  # fmt: skip
    index = order.sort_values(["rank", "group", "share", "distance", "design"], kind="stable").index
    return table.loc[index].reset_index(drop=True)


# ---- outputs ---------------------------------------------------------------------------------------------------
def design_entry(row: Mapping[str, Any]) -> dict[str, Any]:
    """One entry of ``design.json``'s ``designs``: exactly the keys of :data:`DESIGN_KEYS` (SI, tilts in degrees)."""
    return {
        "group": row["group"],
        "bush_stiffness": rounded(row["bush_stiffness"], 4),
        "equaliser_arm": rounded(row["equaliser_arm"], 6),
        "contact_roll_radius": rounded(row["contact_roll_radius"], 6),
        "friction_coefficient": rounded(row["friction_coefficient"], 4),
        "spring_friction_band": rounded(row["spring_friction_band"], 2),
        "tilt_tolerance_nose_up_deg": rounded(row["tilt_tolerance_nose_up_deg"], 2),
        "tilt_tolerance_nose_down_deg": rounded(row["tilt_tolerance_nose_down_deg"], 2),
        "share_within_5pct_at_tolerance": rounded(row["share_within_5pct_at_tolerance"], 4),
    }


def metrics(analysis: Analysis, config: Config, tilts: np.ndarray, guidance: Sequence[str]) -> dict[str, Any]:
    """``metrics/design.json``: ``designs`` (steel, best of each group first), and the air references, the
    typical design, the experiment's size and the interpolation check."""
    table = analysis.designs
    steel = table[table["suspension"] == "steel"]
    air = table[table["suspension"] == "air"]
    check = analysis.check
    spec = config.design

    def summary(row: Mapping[str, Any]) -> dict[str, Any]:
        return {
            "design": row["design"], "kind": row["kind"], "pareto": bool(row["pareto"]),
            "distance": rounded(row["distance"], 4), "share_within_5pct": rounded(row["share_within_5pct"], 4),
            "share_within_5pct_interval": [rounded(row[f"share_within_5pct_{e}"], 4) for e in ("low", "high")],
            "share_within_10pct": rounded(row["share_within_10pct"], 4),
            "share_within_10pct_interval": [rounded(row[f"share_within_10pct_{e}"], 4) for e in ("low", "high")],
            "n_failed": int(row["n_failed"]),
        }  # fmt: skip

    return {
        "designs": [design_entry(r) for r in steel.to_dict("records")],
        "design_summaries": [summary(r) for r in steel.to_dict("records")],
        "air": {r["group"]: {**design_entry(r), **summary(r)} for r in air.to_dict("records")},
        "typical": typical_design(config),
        "target_share": spec.target_share,
        "confidence_level": spec.confidence_level,
        "protocol": "static",
        "n_conditions": spec.n_conditions,
        "tilt_grid_deg": [float(t) for t in tilts],
        "tilt_range_deg": [float(tilts[0]), float(tilts[-1])],
        "runs": int(table["n_runs"].sum()),
        "failed": int(table["n_failed"].sum()),
        "interpolation_check": {
            "pairs": len(check),
            "largest_max_deviation_difference_pct": rounded(
                100.0 * (check["max_deviation_interpolated"] - check["max_deviation_direct"]).abs().max(), 3
            )
            if len(check)
            else None,
            "within_5pct_disagreements": int((check["within_interpolated"] != check["within_direct"]).sum())
            if len(check)
            else 0,
        },  # fmt: skip
        "guidance": list(guidance),
    }


def describe(row: Mapping[str, Any]) -> str:
    """A design in words: ``a free bearing, 40 mm pads and a 250 mm arm (friction 0.26, springs' band 2.0 kN)``."""
    bush = row["bush_stiffness"]
    bearing = "a free bearing" if bush <= 10.0 else f"a {bush:.0f} N m/rad bush"
    radius = 1e3 * row["contact_roll_radius"]
    pads = "fixed contact points (0 mm pads)" if radius < 0.5 else f"{radius:.0f} mm pads"
    return (
        f"{bearing}, {pads} and a {1e3 * row['equaliser_arm']:.0f} mm arm (friction "
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


def guidance(table: pd.DataFrame, tilts: np.ndarray, target: float) -> list[str]:
    """Sentences a designer and an operator can act on, generated from the design table (docs/design.md)."""
    out = []
    pct = f"{100 * target:.0f} %"
    for group in dict.fromkeys(table["group"]):
        label = {"tandem": "tandems", "triaxle": "tri-axles"}[group]
        name = {"tandem": "tandem", "triaxle": "tri-axle"}[group]
        g = table[(table["group"] == group) & (table["suspension"] == "steel")]
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
        top = g.sort_values("share_within_5pct", ascending=False, kind="stable").iloc[0]
        typical_share = f"; today's typical design {100 * typ.iloc[0]['share_within_5pct']:.0f} %" if len(typ) else ""
        share = (
            f"{100 * top['share_within_5pct']:.0f} % ({100 * top['share_within_5pct_low']:.0f}-"
            f"{100 * top['share_within_5pct_high']:.0f} %)"
        )
        if top["share_within_5pct"] >= target:
            out.append(
                f"Across the fleet's own tilts, wear, payloads and roads the best {name} design, with {describe(top)}, "
                f"keeps {share} within 5 %, the {pct} target{typical_share}."
            )
        else:
            out.append(
                f"Across the fleet's own tilts, wear, payloads and roads no {name} design reaches {pct} within 5 %: "
                f"the best, with {describe(top)}, keeps {share}{typical_share}; the chassis tilt must be held as well."
            )
        air = table[(table["group"] == group) & (table["suspension"] == "air")]
        if len(air):
            a = air.iloc[0]
            held = f"keeps {pct} within 5 % {_band(a, tilts)}" if _has_tolerance(a) else (
                f"does not keep {pct} within 5 % on level ground"
            )  # fmt: skip
            out.append(
                f"The air-sprung {name} group on the same trailer {held}, and {100 * a['share_within_5pct']:.0f} % "
                "across the fleet's conditions."
            )
    return out


def write_outputs(
    tables: Mapping[str, pd.DataFrame], summary: Mapping[str, Any], out_dir: Path, metrics_path: Path
) -> None:
    """data/design/ (one CSV per table) and metrics/design.json, all or nothing."""
    with atomic_outputs(files=[metrics_path], dirs=[out_dir]) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(summary, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():
            frame.to_csv(tmp_dir / f"{name}.csv", index=False, float_format="%.6g", lineterminator="\n")
        if not tables:
            (tmp_dir / "README.txt").write_text(f"design study skipped: {summary['skipped']}\n", encoding="utf-8")


def tables(analysis: Analysis, conds: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The stage's tables by file name (without ``.csv``)."""
    return {"designs": analysis.designs, "tilt_curves": analysis.curves, "conditions": conds, "check": analysis.check}


def skipped_metrics(reason: str) -> dict[str, Any]:
    """The metrics of a stage that was not asked to run: no designs, and why."""
    return {"designs": [], "skipped": reason}


def run(
    config: Config, runs_dir: Path, log: Callable[[str], None] = print
) -> tuple[Analysis, pd.DataFrame, dict[str, Any]]:
    """Run the experiment (resuming from ``runs_dir``) and analyse it; returns the tables and the metrics."""
    spec = config.design
    tilts = tilt_grid(config)
    conds = conditions(config)
    designs = design_points(config)
    samples = design_samples(config, designs, conds, tilts)
    log(
        f"design: {len(designs)} designs ({', '.join(spec.groups)}, air references included) x {len(conds)} "
        f"conditions x ({len(tilts)} grid tilts + each condition's own) = {len(samples)} static runs"
    )
    protocols = {"design": (("static", config.protocol.static),)}
    simulate_samples({"design": samples[list(COLUMNS)]}, protocols, config.execution, runs_dir, log)
    # every part verified (the file's SHA-256, its pages' CRC32s: pipeline.schema.read_runs_frame), as every stage
    # that reads runs does
    runs = read_runs_frame(runs_dir, "design").drop(columns="study")
    runs = runs.drop(columns=[c for c in ("design", "condition", "slot") if c in runs.columns])
    runs = runs.merge(samples[["sample_id", "design", "condition", "slot"]], on="sample_id", how="left", validate="1:1")
    analysis = analyse(runs, designs, tilts, spec.target_share, spec.confidence_level)
    text = guidance(analysis.designs, tilts, spec.target_share)
    return analysis, conds, metrics(analysis, config, tilts, text)


def main(argv: list[str] | None = None) -> int:
    """Run the stage from the command line."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.design", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/design_runs", help="runs dataset directory (default: data/design_runs)")
    parser.add_argument("--out", default="data/design", help="tables directory (default: data/design)")
    parser.add_argument("--metrics", default="metrics/design.json", help="metrics file (default: metrics/design.json)")
    args = parser.parse_args(argv)
    try:
        config = load_config(args.params)
    except (ConfigError, OSError, yaml.YAMLError) as exc:
        print(f"design: {args.params}: {exc}", file=sys.stderr)
        return 2
    out, metrics_path = Path(args.out), Path(args.metrics)
    log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731 - progress to the terminal and logs
    try:
        # a second design is refused here, and what a killed one left beside the outputs is removed
        with stage_outputs("design", files=[metrics_path], dirs=[out], log=log):
            return _stage(config, Path(args.runs), out, metrics_path, log)
    except LockedError as exc:
        print(f"design: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(io_error("design", exc), file=sys.stderr)
        return 2


def _stage(config: Config, runs_dir: Path, out: Path, metrics_path: Path, log: Callable[[str], None]) -> int:
    """The stage's work while it owns its outputs: run, analyse, write; the exit code."""
    try:
        if config.design is None:
            summary, frames = skipped_metrics("design is null in params.yaml (no design study asked for)"), {}
        else:
            analysis, conds, summary = run(config, runs_dir, log)
            frames = tables(analysis, conds)
    except (DesignError, ValueError, NotRunsDatasetError) as exc:
        print(f"design: {exc}", file=sys.stderr)
        return 2
    try:
        write_outputs(frames, summary, out, metrics_path)
    except OSError as exc:
        print(io_error("design", exc), file=sys.stderr)
        return 2
    if not frames:
        runs_dir.mkdir(parents=True, exist_ok=True)  # the stage's other output exists, empty
        print(f"design: skipped, {summary['skipped']}")
        return 0
    for line in summary["guidance"]:
        print(f"design: {line}")
    print(f"design: wrote {out} and {metrics_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
