"""What unequal sharing costs the road, for a simulated fleet, and what acting would save (issue 32).

:func:`fleet_wear` tabulates :func:`bogie.weighings.wear.wear_statistics` (the one definition for observed and
simulated groups) over a fleet's runs: laden groups, per protocol, size and suspension, failed runs counted.
:func:`design_savings` holds the design stage's controlled experiment (``docs/design.md``: every design weighed
over the same operating conditions) against the same figures: today's typical steel design at each condition's
own tilt is the baseline, and each way of acting is paired with it condition by condition,

- ``best``: the steel design that keeps most groups within 5 % across the conditions (the design table's first
  steel row, best first);
- ``air``: the air-sprung group on the same trailer;
- ``tilt_held``: the typical design with the chassis tilt held within its tolerance (each condition's tilt clipped to
  the tolerated band and read from the tilt grid's nearest level inside it; a design with no tolerance, level).

The saving is the baseline's figure minus the scenario's (positive: acting helps), with a percentile bootstrap over
the conditions (the pairs). The derivation and the assumptions are in ``docs/pavement.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from bogie.fleet.constants import GROUP_AXLES, MAX_AXLES
from bogie.fleet.design.analysis import FLEET_SLOT
from bogie.fleet.weighing.runs import RESULT_COLUMNS
from bogie.intervals import percentile_interval
from bogie.params import GRAVITY
from bogie.road.wim import sensor_factors
from bogie.weighings.stats import axle_columns
from bogie.weighings.wear import DAMAGE_EXPONENTS, STANDARD_AXLE_KG, group_wear, hidden_overloads, wear_statistics

__all__ = ["FLEET_SLOT", "SCENARIOS", "design_savings", "fleet_wear", "scenario_runs", "sensor_free"]

#: the ways of acting :func:`design_savings` compares with today's typical design, in order
SCENARIOS: tuple[str, ...] = ("best", "air", "tilt_held")


def fleet_wear(
    runs: pd.DataFrame,
    legal_group: Mapping[str, float],
    legal_axle: float,
    min_group_load_kg: float,
    exponents: Mapping[str, float] = DAMAGE_EXPONENTS,
    resamples: int = 1000,
    confidence_level: float = 0.95,
    seed: int = 0,
) -> pd.DataFrame:
    """The extra wear and hidden overloads of a fleet's laden groups, per protocol, size and suspension.

    Parameters
    ----------
    runs
        A fleet's runs (:data:`bogie.fleet.weighing.runs.RUN_COLUMNS`): axle loads [N], ``status``; a failed run is left
        out and counted in ``n_failed`` of its cell.
    legal_group, legal_axle
        Legal load of each group size and of one axle [kg].
    min_group_load_kg
        Smallest group load of a laden group [kg]; lighter succeeded readings are left out (not counted).
    exponents, resamples, confidence_level, seed
        As :func:`bogie.weighings.wear.wear_statistics`.

    Returns
    -------
    pandas.DataFrame
        :func:`~bogie.weighings.wear.wear_statistics`'s table by ``protocol``, ``group``, ``suspension``.
    """
    ok = runs["status"].astype(str).eq("ok")
    laden = runs["group_load"].astype(float) / GRAVITY >= min_group_load_kg
    kept = runs[~ok | laden].copy()
    for column in ("protocol", "group", "suspension"):
        kept[column] = kept[column].astype(str)
    return wear_statistics(
        kept, legal_group, legal_axle, by=["protocol", "group", "suspension"], unit_per_kg=GRAVITY,
        exponents=exponents, resamples=resamples, confidence_level=confidence_level, seed=seed,
    )  # fmt: skip


def sensor_free(runs: pd.DataFrame, vehicle_sd: float, axle_sd: float) -> pd.DataFrame:
    """The WIM rows of a fleet's ``runs`` as a sensor without error would read them: the reading of the sharing and
    the dynamics at the sensor alone (issue 44 Must 3, docs/pavement.md). The sensor's error is a factor per axle,
    ``(1 + s_v z_v) (1 + s_a z_i)`` of the row's ``sensor_seed`` (:func:`bogie.road.wim.sensor_factors`; ``vehicle_sd``
    and ``axle_sd`` the fractions the WIM protocol read with), so each succeeded row's axle loads are divided by
    theirs and its ``group_load`` is their sum; the other result columns are left out (they were the read ones').
    Failed rows are kept as they are."""
    wim = runs[runs["protocol"].astype(str).eq("wim")].reset_index(drop=True)
    columns = [f"axle_load_{i + 1}" for i in range(MAX_AXLES)]
    loads = np.array(wim[columns].to_numpy(dtype=float), copy=True)  # a view may be read-only
    ok = wim["status"].astype(str).eq("ok").to_numpy()
    n_axles, seeds = wim["n_axles"].to_numpy(dtype=int), wim["sensor_seed"].to_numpy()
    for row in np.flatnonzero(ok):
        n = int(n_axles[row])
        loads[row, :n] = loads[row, :n] / sensor_factors(vehicle_sd, axle_sd, int(seeds[row]), n)
    keep = [c for c in wim.columns if c not in columns and c not in RESULT_COLUMNS]
    out = wim[keep].copy()
    for i, column in enumerate(columns):
        out[column] = loads[:, i]
    out["group_load"] = np.where(ok, np.nansum(loads, axis=1), np.nan)
    return out


def _nearest_level(tilts: np.ndarray, low: float, high: float, target: float) -> float:
    """The grid tilt nearest ``target`` clipped to [low, high]; the level closest to the band if none lies in it."""
    inside = tilts[(tilts >= low - 1e-9) & (tilts <= high + 1e-9)]
    pool = inside if len(inside) else tilts
    clipped = min(max(target, low), high)
    return float(pool[np.argmin(np.abs(pool - clipped))])


def scenario_runs(runs: pd.DataFrame, designs: pd.DataFrame, tilts_deg: Sequence[float]) -> pd.DataFrame:
    """The design experiment's runs of each scenario, one per group and condition.

    Parameters
    ----------
    runs
        The experiment's runs with ``design``, ``condition`` and ``slot``
        (:func:`bogie.fleet.design.experiment.experiment_runs`), axle loads [N], ``status``, ``chassis_tilt_deg``.
    designs
        The design table (``data/design/designs.csv``, best first): ``design``, ``group``, ``kind`` (``typical``,
        ``grid``, ``space``, ``air``), ``tilt_tolerance_nose_up_deg`` and ``_nose_down_deg`` [degree].
    tilts_deg
        The tilt grid [degree], the slots 0, 1, ... of the grid runs.

    Returns
    -------
    pandas.DataFrame
        The runs with ``scenario`` (``typical`` and :data:`SCENARIOS`) and ``held_tilt_deg`` (the tilt the
        ``tilt_held`` scenario read, NaN for the others), one row per group, scenario and condition.
    """
    tilts = np.asarray(tilts_deg, dtype=float)
    out = []
    for group in [g for g in GROUP_AXLES if g in set(designs["group"].astype(str))]:
        rows = designs[designs["group"].astype(str) == group]
        kinds = rows["kind"].astype(str)
        typical = rows[kinds == "typical"]
        steel = rows[kinds.isin(["grid", "space"])]
        air = rows[kinds == "air"]
        if typical.empty:
            continue
        name = typical["design"].iloc[0]
        chosen = {"typical": name, "best": steel["design"].iloc[0] if len(steel) else None,
                  "air": air["design"].iloc[0] if len(air) else None}  # fmt: skip
        for scenario, design in chosen.items():
            if design is None:
                continue
            own = runs[(runs["design"] == design) & (runs["slot"] == FLEET_SLOT)]
            out.append(own.assign(scenario=scenario, held_tilt_deg=math.nan))
        up = typical["tilt_tolerance_nose_up_deg"].astype(float).iloc[0]
        down = typical["tilt_tolerance_nose_down_deg"].astype(float).iloc[0]
        band = (-down, up) if math.isfinite(up) and math.isfinite(down) else (0.0, 0.0)  # no tolerance: level
        design_runs = runs[runs["design"] == name]
        own = design_runs[design_runs["slot"] == FLEET_SLOT]
        held = []
        for row in own.itertuples():
            tilt = float(row.chassis_tilt_deg)
            if band[0] <= tilt <= band[1]:
                held.append(own.loc[[row.Index]].assign(held_tilt_deg=tilt))
                continue
            level = _nearest_level(tilts, band[0], band[1], tilt)
            slot = int(np.argmin(np.abs(tilts - level)))
            grid = design_runs[(design_runs["condition"] == row.condition) & (design_runs["slot"] == slot)]
            held.append(grid.assign(held_tilt_deg=level))
        if held:
            out.append(pd.concat(held).assign(scenario="tilt_held"))
    if not out:
        return runs.iloc[0:0].assign(scenario=pd.Series(dtype=str), held_tilt_deg=pd.Series(dtype=float))
    return pd.concat(out, ignore_index=True)


def design_savings(
    runs: pd.DataFrame,
    designs: pd.DataFrame,
    tilts_deg: Sequence[float],
    legal_group: Mapping[str, float],
    legal_axle: float,
    exponents: Mapping[str, float] = DAMAGE_EXPONENTS,
    resamples: int = 1000,
    confidence_level: float = 0.95,
    seed: int = 0,
) -> pd.DataFrame:
    """What each way of acting saves against today's typical design, paired condition by condition.

    Parameters
    ----------
    runs, designs, tilts_deg
        As :func:`scenario_runs`.
    legal_group, legal_axle
        Legal load of each group size and of one axle [kg].
    exponents, resamples, confidence_level, seed
        As :func:`bogie.weighings.wear.wear_statistics`; the bootstrap resamples the conditions.

    Returns
    -------
    pandas.DataFrame
        One row per group and scenario: ``n_conditions`` (pairs whose both runs succeeded), ``n_failed`` (the other
        conditions); per exponent name ``<k>``: ``extra_wear_<k>_typical`` and ``extra_wear_<k>`` (the extra wear,
        sum D / sum D_eq - 1, of the baseline and of the scenario [-]) and ``saved_wear_<k>`` (their difference,
        in the same unit) with ``_low``/``_high``; ``share_hidden_overload_typical``, ``share_hidden_overload``,
        ``saved_hidden_overload`` with ``_low``/``_high`` [-].
    """
    both = scenario_runs(runs, designs, tilts_deg)
    rows = []
    streams = iter(np.random.SeedSequence(seed).spawn(len(GROUP_AXLES) * len(SCENARIOS)))
    for group in GROUP_AXLES:
        base = both[(both["group"].astype(str) == group) & (both["scenario"] == "typical")].set_index("condition")
        for scenario in SCENARIOS:
            stream = next(streams)
            other = both[(both["group"].astype(str) == group) & (both["scenario"] == scenario)].set_index("condition")
            if base.empty or other.empty:
                continue
            rows.append(
                _paired_row(
                    group,
                    scenario,
                    base,
                    other,
                    stream,
                    legal_group,
                    legal_axle,
                    exponents,
                    resamples,
                    confidence_level,
                )
            )
    return pd.DataFrame(rows)


def _paired_row(
    group: str, scenario: str, base: pd.DataFrame, other: pd.DataFrame, stream: np.random.SeedSequence,
    legal_group: Mapping[str, float], legal_axle: float, exponents: Mapping[str, float], resamples: int,
    confidence_level: float,
) -> dict:  # fmt: skip
    """One row of :func:`design_savings`: the scenario's runs ``other`` against the baseline's ``base`` by condition."""
    common = base.index.intersection(other.index)
    good = [c for c in common if base.at[c, "status"] == "ok" and other.at[c, "status"] == "ok"]
    row: dict = {"group": group, "scenario": scenario, "n_conditions": len(good),
                 "n_failed": len(common) - len(good)}  # fmt: skip
    if not good:
        return row
    a, b = base.loc[good], other.loc[good]
    n = a["n_axles"].to_numpy(dtype=np.int64)
    la = a[axle_columns(int(n.max()))].to_numpy(dtype=float) / GRAVITY
    lb = b[axle_columns(int(n.max()))].to_numpy(dtype=float) / GRAVITY
    rng = np.random.default_rng(stream)
    draws = rng.integers(0, len(good), (resamples, len(good))) if resamples else None
    _wear_savings(row, la, lb, n, exponents, draws, confidence_level)
    legal = legal_group.get(group, math.nan)
    _overload_savings(row, la, lb, n, legal, legal_axle, draws, confidence_level)
    held = np.abs(b["held_tilt_deg"].to_numpy(dtype=float))
    row["held_tilt_deg_max"] = float(np.nanmax(held)) if scenario == "tilt_held" else math.nan
    return row


def _extra_wear(wear: Mapping[str, np.ndarray], idx=slice(None)) -> np.ndarray:
    """The extra wear sum D / sum D_eq - 1 over the rows ``idx`` of ``wear`` (:func:`group_wear`) [-]."""
    return wear["damage"][idx].sum(axis=-1) / wear["damage_equal"][idx].sum(axis=-1) - 1.0


def _wear_savings(
    row: dict, la: np.ndarray, lb: np.ndarray, n: np.ndarray, exponents: Mapping[str, float],
    draws: np.ndarray | None, confidence_level: float,
) -> None:  # fmt: skip
    """Add to ``row`` the extra wear of the loads ``la`` (baseline) and ``lb`` (scenario) [kg] and what is saved."""
    for name, k in exponents.items():
        wa, wb = (group_wear(x, n, float(k), STANDARD_AXLE_KG) for x in (la, lb))
        row[f"extra_wear_{name}_typical"], row[f"extra_wear_{name}"] = _extra_wear(wa), _extra_wear(wb)
        row[f"saved_wear_{name}"] = _extra_wear(wa) - _extra_wear(wb)
        if draws is not None:
            saved = _extra_wear(wa, draws) - _extra_wear(wb, draws)
            low, high = percentile_interval(saved, confidence_level)
            row[f"saved_wear_{name}_low"], row[f"saved_wear_{name}_high"] = low, high


def _overload_savings(
    row: dict, la: np.ndarray, lb: np.ndarray, n: np.ndarray, legal: float, legal_axle: float,
    draws: np.ndarray | None, confidence_level: float,
) -> None:  # fmt: skip
    """Add to ``row`` the share of hidden overloads of the loads ``la`` and ``lb`` [kg] and what is saved [-]."""
    ha = hidden_overloads(la, n, legal, legal_axle)["hidden"].astype(float)
    hb = hidden_overloads(lb, n, legal, legal_axle)["hidden"].astype(float)
    row["share_hidden_overload_typical"], row["share_hidden_overload"] = ha.mean(), hb.mean()
    row["saved_hidden_overload"] = ha.mean() - hb.mean()
    if draws is not None:
        saved = ha[draws].mean(axis=1) - hb[draws].mean(axis=1)
        row["saved_hidden_overload_low"], row["saved_hidden_overload_high"] = percentile_interval(
            saved, confidence_level
        )
