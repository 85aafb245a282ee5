"""Roadside-survey statistics of a runs table: what a road authority's survey of the simulated fleet would find.

Per protocol (static weighbridge, weigh-in-motion) and axle group (tandem, tri-axle): the distribution of each axle
position's load share, the heaviest-minus-lightest spread, the share of groups outside the 5 % and 10 % tolerances,
which axle is overloaded against chassis tilt, inequality against tilt and tyre-wear bands, the static weighbridge
against WIM, the road-wear factor and the groups with an axle over the legal limit while the group is legal
(:func:`survey` gives every table). Every statistic is a plain function of a runs DataFrame
(:func:`bogie.fleet.weigh_fleet`); failed runs (``status == "failed"``) are excluded from every statistic and counted.
Definitions, units and file layout: ``docs/outputs.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.constants import GROUP_AXLES, MAX_AXLES, SUSPENSIONS
from bogie.fleet.sampling.sample import TYRE_WEAR_COLUMNS
from bogie.params import GRAVITY
from bogie.road.cost323 import REQUIRED_SHARE, class_test
from bogie.road.wim import COST323_TOLERANCES
from bogie.weighings.stats import group_inequality, survey_statistics

__all__ = [
    "AXLE_LOAD_COLUMNS", "DISTRIBUTED", "LOAD_SHARE_COLUMNS", "REQUIRED_COLUMNS", "distribution_stats",
    "failure_table", "histograms", "inequality_columns", "legal_limits", "readings", "run_counts", "split_failed",
    "static_vs_wim", "summary_table", "survey_tables", "SUSPENSION_STATISTICS", "suspension_table", "tilt_table",
    "wear_table",
]  # fmt: skip

AXLE_LOAD_COLUMNS: tuple[str, ...] = tuple(f"axle_load_{i + 1}" for i in range(MAX_AXLES))
LOAD_SHARE_COLUMNS: tuple[str, ...] = tuple(f"load_share_{i + 1}" for i in range(MAX_AXLES))
TILT_BIN_DEG = 0.5
WEAR_BAND_MM = 2.0
#: "nose up" for the rear-overload headline: tilt above this [degree]
NOSE_UP_DEG = 0.5
PERCENTILES: tuple[int, ...] = (5, 25, 50, 75, 95)
HISTOGRAM_BINS = 30
#: quantities whose distribution and histogram are tabulated (load shares only for axles the group has)
DISTRIBUTED: tuple[str, ...] = (*LOAD_SHARE_COLUMNS, "spread_pct", "spread_kg", "max_deviation", "road_wear_factor")
#: the columns a runs table must have for the survey
REQUIRED_COLUMNS: tuple[str, ...] = (
    "sample_id", "group", "suspension", "n_axles", "protocol", "status", "message", "chassis_tilt", *TYRE_WEAR_COLUMNS,
    *AXLE_LOAD_COLUMNS, *LOAD_SHARE_COLUMNS, "group_load", "max_deviation", "spread_kg", "road_wear_factor",
    "wheel_airborne", "equaliser_on_stop",
)  # fmt: skip
KEYS = ["protocol", "group"]


def split_failed(runs: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The succeeded rows and the failed rows (``status != "ok"``), each with a fresh index."""
    ok = runs["status"] == "ok"
    return runs[ok].reset_index(drop=True), runs[~ok].reset_index(drop=True)


def readings(runs: pd.DataFrame) -> pd.DataFrame:
    """The rows the survey's statistics use: succeeded, with every wheel on the road at the reading.

    A weighing with an axle at 0 N (``wheel_airborne``: its wheels in the air over the WIM sensor) is a valid run
    but not a reading of the group's load sharing; a WIM system flags such a record. It is counted
    (:func:`run_counts`, ``n_airborne``) and left out.
    """
    ok, _ = split_failed(runs)
    return ok[~ok["wheel_airborne"].astype(bool)].reset_index(drop=True)


# ---- per-row quantities --------------------------------------------------------------------------------------------
def inequality_columns(runs: pd.DataFrame) -> pd.DataFrame:
    """Per-row inequality quantities of succeeded runs, derived from the axle loads
    (:func:`bogie.weighings.stats.group_inequality`, the definitions observed groups share).

    Parameters
    ----------
    runs
        Succeeded runs with ``n_axles``, ``axle_load_1..3`` [N] (0 for a missing axle), ``chassis_tilt`` [rad] and
        ``tyre_wear_1..3`` [m].

    Returns
    -------
    pandas.DataFrame
        ``runs`` with added columns: ``spread_pct`` (heaviest minus lightest axle over the mean axle load [%]),
        ``pair_difference`` ((max - min) / max [-]), ``max_load_share`` (largest LSC [-]), ``outside_5pct``
        (pair_difference > 0.05), ``over_10pct`` (max_load_share > 1.10), ``heaviest_axle`` (0 = front; a tie
        goes to the front-most), ``rear_heaviest``, ``tilt_deg`` [degree, nose up +] and ``wear_diff_mm`` (most
        minus least worn tyre of the group [mm]).
    """
    n = runs["n_axles"].to_numpy(dtype=np.int64)
    ineq = group_inequality(runs[list(AXLE_LOAD_COLUMNS)].to_numpy(dtype=float), n)
    present = np.arange(MAX_AXLES) < n[:, None]
    wear = runs[list(TYRE_WEAR_COLUMNS)].to_numpy(dtype=float)
    wear_max = np.where(present, wear, -np.inf).max(axis=1)
    wear_min = np.where(present, wear, np.inf).min(axis=1)
    out = runs.copy()
    out["spread_pct"] = ineq["spread_pct"]
    out["pair_difference"] = ineq["pair_difference"]
    out["max_load_share"] = ineq["max_load_share"]
    out["outside_5pct"] = ineq["outside_5pct"]
    out["over_10pct"] = ineq["over_10pct"]
    out["heaviest_axle"] = ineq["heaviest_axle"]
    out["rear_heaviest"] = out["heaviest_axle"].to_numpy() == n - 1
    out["tilt_deg"] = np.degrees(runs["chassis_tilt"].to_numpy(dtype=float))
    out["wear_diff_mm"] = 1000.0 * (wear_max - wear_min)
    return out


def band(values: pd.Series | np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Left-closed bands ``[low, low + width)`` of ``values``: returns (low, high) per value.

    Values are rounded to 1e-9 band widths first, so a tilt of exactly 0.5 degree that went through radians and
    back (0.49999999999999994) lands in the band that starts at 0.5, as a reader of the label expects.
    """
    k = np.floor(np.round(np.asarray(values, dtype=float) / width, 9))
    return k * width, (k + 1) * width


# ---- statistics ---------------------------------------------------------------------------------------------------
def run_counts(runs: pd.DataFrame, keys: Sequence[str] = KEYS) -> pd.DataFrame:
    """Runs, succeeded, failed and succeeded with a wheel in the air per protocol and group, or per ``keys``
    (columns n_runs, n_ok, n_failed, n_airborne; n_ok includes the n_airborne, which the statistics leave out)."""
    failed = runs["status"] != "ok"
    airborne = ~failed & runs["wheel_airborne"].fillna(False).astype(bool)
    table = (
        runs.assign(failed=failed, ok=~failed, airborne=airborne).groupby(list(keys), observed=True).agg(
        n_runs=("status", "size"), n_ok=("ok", "sum"), n_failed=("failed", "sum"), n_airborne=("airborne", "sum"))
    )  # fmt: skip
    return table.astype("int64").reset_index()


def failure_table(runs: pd.DataFrame, examples: int = 5) -> pd.DataFrame:
    """Failed runs per protocol, group and message: their number and the first few sample ids."""
    failed = runs[runs["status"] != "ok"]
    columns = [*KEYS, "message", "n_failed", "example_sample_ids"]
    if failed.empty:
        return pd.DataFrame(columns=columns)
    table = failed.groupby([*KEYS, "message"], observed=True)["sample_id"].agg(
        n_failed="size", example_sample_ids=lambda s: " ".join(str(i) for i in sorted(s)[:examples])
    )
    return table.reset_index()[columns].sort_values(["n_failed", *KEYS], ascending=[False, True, True])


def _present(frame: pd.DataFrame, quantity: str) -> pd.DataFrame:
    """Rows where ``quantity`` exists: a load share only for groups that have that axle."""
    if quantity.startswith("load_share_"):
        return frame[frame["n_axles"] >= int(quantity.rsplit("_", 1)[1])]
    return frame


def distribution_stats(ok: pd.DataFrame, quantities: Sequence[str] = DISTRIBUTED) -> pd.DataFrame:
    """Mean, SD and percentiles of each quantity per protocol and group (long table, one row per quantity)."""
    rows = []
    for quantity in quantities:
        for (protocol, group), sub in _present(ok, quantity).groupby(KEYS, observed=True):
            x = sub[quantity].to_numpy(dtype=float)
            row = {"quantity": quantity, "protocol": protocol, "group": group, "n": len(x)}
            row.update(mean=float(np.mean(x)), sd=float(np.std(x, ddof=1)) if len(x) > 1 else math.nan)
            row.update({f"p{q:02d}": float(v) for q, v in zip(PERCENTILES, np.percentile(x, PERCENTILES))})
            rows.append(row)
    return pd.DataFrame(rows)


def histograms(ok: pd.DataFrame, quantities: Sequence[str] = DISTRIBUTED, bins: int = HISTOGRAM_BINS) -> pd.DataFrame:
    """Histogram counts of each quantity per protocol and group, on edges shared by all protocols and groups.

    Shared edges (over every succeeded row of the quantity) let a plot overlay static and WIM, tandem and tri-axle.
    Bins are left-closed except the last, as in :func:`numpy.histogram`.
    """
    rows = []
    for quantity in quantities:
        present = _present(ok, quantity)
        if present.empty:
            continue
        edges = np.histogram_bin_edges(present[quantity].to_numpy(dtype=float), bins=bins)
        for (protocol, group), sub in present.groupby(KEYS, observed=True):
            counts, _ = np.histogram(sub[quantity].to_numpy(dtype=float), bins=edges)
            for lo, hi, c in zip(edges[:-1], edges[1:], counts):
                rows.append(
                    {"quantity": quantity, "protocol": protocol, "group": group, "bin_low": lo, "bin_high": hi,
                     "count": int(c)}
                )  # fmt: skip
    return pd.DataFrame(rows)


def legal_limits(ok: pd.DataFrame, legal_axle_load: float, legal_group_load: Mapping[str, float]) -> pd.DataFrame:
    """Groups over the legal limits per protocol and group.

    Parameters
    ----------
    ok
        Succeeded runs.
    legal_axle_load
        Legal single-axle load, both sides [N]; an axle is over when its load is strictly greater.
    legal_group_load
        Legal group load of each axle group, both sides [N]; a group is within when its load is at most this.

    Returns
    -------
    pandas.DataFrame
        n, n_group_over, n_axle_over, n_axle_over_group_legal and frac_axle_over_group_legal (over all n) [-].
    """
    axle_over = ok[list(AXLE_LOAD_COLUMNS)].max(axis=1) > legal_axle_load
    group_legal = ok["group_load"] <= ok["group"].map(dict(legal_group_load)).astype(float)
    flags = ok[KEYS].assign(n=1, group_over=~group_legal, axle_over=axle_over, both=axle_over & group_legal)
    table = flags.groupby(KEYS, observed=True).agg(
        n=("n", "sum"), n_group_over=("group_over", "sum"), n_axle_over=("axle_over", "sum"),
        n_axle_over_group_legal=("both", "sum"),
    ).reset_index()  # fmt: skip
    table["frac_axle_over_group_legal"] = table["n_axle_over_group_legal"] / table["n"]
    return table


def _banded(ok: pd.DataFrame, column: str, width: float, prefix: str, extra: dict[str, Any]) -> pd.DataFrame:
    low, high = band(ok[column], width)
    frame = ok.assign(**{f"{prefix}_low": low, f"{prefix}_high": high})
    keys = [*KEYS, f"{prefix}_low", f"{prefix}_high"]
    table = frame.groupby(keys, observed=True).agg(
        n=("max_deviation", "size"), mean_max_deviation=("max_deviation", "mean"),
        share_outside_5pct=("outside_5pct", "mean"), share_over_10pct=("over_10pct", "mean"), **extra,
    ).reset_index()  # fmt: skip
    table.insert(len(keys), f"{prefix}_bin", [f"[{a:g}, {b:g})" for a, b in zip(table[keys[2]], table[keys[3]])])
    return table


def tilt_table(ok: pd.DataFrame, width_deg: float = TILT_BIN_DEG) -> pd.DataFrame:
    """Which axle is overloaded against chassis tilt, and how unequal the group is, per tilt bin.

    Parameters
    ----------
    ok
        Succeeded runs with the columns of :func:`inequality_columns`.
    width_deg
        Bin width [degree]; bins ``[k w, (k + 1) w)``, nose up positive.

    Returns
    -------
    pandas.DataFrame
        Per protocol, group and bin (``tilt_deg_low``, ``tilt_deg_high``, label ``tilt_deg_bin``): n, the mean
        load share of each axle position (NaN for an axle the group lacks), ``rear_heaviest_share`` (bogies whose
        heaviest axle is the rear one), mean max_deviation and the shares outside 5 % and 10 %.
    """
    shares = {f"mean_{c}": (c, "mean") for c in LOAD_SHARE_COLUMNS}
    table = _banded(ok, "tilt_deg", width_deg, "tilt_deg", {**shares, "rear_heaviest_share": ("rear_heaviest", "mean")})
    for i, c in enumerate(LOAD_SHARE_COLUMNS):
        # a tandem's third share is 0 in the runs, not a measurement
        table.loc[table["group"].astype(str).map(GROUP_AXLES) <= i, f"mean_{c}"] = np.nan
    return table


def wear_table(ok: pd.DataFrame, width_mm: float = WEAR_BAND_MM) -> pd.DataFrame:
    """Inequality per band of tyre-wear difference (most minus least worn tyre of the group, [mm] bands)."""
    return _banded(ok, "wear_diff_mm", width_mm, "wear_diff_mm", {})


def static_vs_wim(ok: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The static weighbridge against WIM, bogie by bogie (paired by ``sample_id``).

    Returns
    -------
    pairs : pandas.DataFrame
        One row per bogie that succeeded in both protocols: ``max_deviation_static``, ``max_deviation_wim``,
        ``dynamic_excess`` (WIM minus static max_deviation [-]) and for each axle ``load_share_<i>_static``,
        ``load_share_<i>_wim``, ``load_share_<i>_diff`` (WIM minus static [-], 0 for a missing axle).
    summary : pandas.DataFrame
        Per group: n_pairs, the mean max_deviation of each protocol, ``mean_dynamic_excess`` and its SD,
        ``share_wim_worse``, ``corr_max_deviation`` (Pearson, over bogies), ``corr_load_share_<i>`` and
        ``mean_abs_load_share_diff`` (over bogies and the axles they have). Empty if a protocol is absent.
    """
    columns = ["sample_id", "group", "n_axles", "chassis_tilt", "max_deviation", *LOAD_SHARE_COLUMNS]
    static = ok.loc[ok["protocol"] == "static", columns]
    wim = ok.loc[ok["protocol"] == "wim", ["sample_id", "max_deviation", *LOAD_SHARE_COLUMNS]]
    pairs = static.merge(wim, on="sample_id", suffixes=("_static", "_wim"), validate="one_to_one")
    pairs["dynamic_excess"] = pairs["max_deviation_wim"] - pairs["max_deviation_static"]
    for c in LOAD_SHARE_COLUMNS:
        pairs[f"{c}_diff"] = pairs[f"{c}_wim"] - pairs[f"{c}_static"]
    pairs = pairs.sort_values("sample_id").reset_index(drop=True)
    rows = []
    for group, sub in pairs.groupby("group", observed=True):
        n_axles = GROUP_AXLES[group]
        diffs = sub[[f"{c}_diff" for c in LOAD_SHARE_COLUMNS[:n_axles]]].to_numpy()
        row = {
            "group": group, "n_pairs": len(sub),
            "mean_max_deviation_static": sub["max_deviation_static"].mean(),
            "mean_max_deviation_wim": sub["max_deviation_wim"].mean(),
            "mean_dynamic_excess": sub["dynamic_excess"].mean(), "sd_dynamic_excess": sub["dynamic_excess"].std(),
            "share_wim_worse": (sub["dynamic_excess"] > 0).mean(),
            "corr_max_deviation": _corr(sub["max_deviation_static"], sub["max_deviation_wim"]),
        }  # fmt: skip
        for i, c in enumerate(LOAD_SHARE_COLUMNS):
            row[f"corr_{c}"] = _corr(sub[f"{c}_static"], sub[f"{c}_wim"]) if i < n_axles else math.nan
        row["mean_abs_load_share_diff"] = float(np.mean(np.abs(diffs)))
        rows.append(row)
    return pairs, pd.DataFrame(rows)


def wim_class(ok: pd.DataFrame, required_share: float = REQUIRED_SHARE) -> pd.DataFrame:
    """The COST 323 class test of the WIM readings against the static weighings of the same bogies
    (:func:`bogie.road.cost323.class_test`: the whole system, the vehicle's dynamics and the sensor's error together).

    Returns
    -------
    pandas.DataFrame
        Per group (``tandem``, ``triaxle`` and ``all``) and criterion (``group``, ``axle_of_group``): ``n``,
        ``mean_error_pct`` and ``sd_error_pct`` of the relative errors R / W - 1 [%], ``share_within_<class>`` for
        each class of :data:`bogie.road.wim.COST323_TOLERANCES` [-], ``required_share`` [-] and the group's
        ``class_reached`` (None: no class). Empty if a protocol is absent.
    """
    classes = list(COST323_TOLERANCES)
    columns = ["group", "criterion", "n", "mean_error_pct", "sd_error_pct",
               *(f"share_within_{c}" for c in classes), "required_share", "class_reached"]  # fmt: skip
    loads = [f"axle_load_{i + 1}" for i in range(3)]
    static = ok.loc[ok["protocol"] == "static", ["sample_id", "group", "n_axles", *loads]]
    wim = ok.loc[ok["protocol"] == "wim", ["sample_id", *loads]]
    pairs = static.merge(wim, on="sample_id", suffixes=("_static", "_wim"), validate="one_to_one")
    pairs = pairs.sort_values("sample_id")
    parts = [(str(g), sub) for g, sub in pairs.groupby("group", observed=True)] + [("all", pairs)]
    rows = []
    for group, sub in parts:
        if sub.empty:
            continue
        # past a group's axles the runs hold 0: NaN there, an axle the group does not have
        absent = np.arange(len(loads))[None, :] >= sub["n_axles"].to_numpy(dtype=int)[:, None]
        w = np.where(absent, np.nan, sub[[f"{c}_static" for c in loads]].to_numpy(dtype=float))
        r = np.where(absent, np.nan, sub[[f"{c}_wim" for c in loads]].to_numpy(dtype=float))
        test = class_test(w, r, required_share)
        for criterion, e in test.errors.iterrows():
            row = {"group": group, "criterion": criterion, "n": int(e["n"]), "mean_error_pct": 100.0 * e["mean"],
                   "sd_error_pct": 100.0 * e["sd"]}  # fmt: skip
            row.update({f"share_within_{c}": test.shares.loc[c, criterion] for c in classes})
            rows.append({**row, "required_share": test.required_share, "class_reached": test.reached})
    return pd.DataFrame(rows, columns=columns)


def _corr(a: pd.Series, b: pd.Series) -> float:
    # a constant series (e.g. two identical bogies) has no correlation: NaN, not a numpy warning
    if len(a) < 2 or a.std() == 0 or b.std() == 0:
        return math.nan
    # Pearson's r with pairwise sums (numpy.corrcoef's products are BLAS's, whose kernel the CPU picks)
    x, y = a.to_numpy(dtype=float), b.to_numpy(dtype=float)
    dx, dy = x - x.mean(), y - y.mean()
    r = float(np.sum(dx * dy)) / math.sqrt(float(np.sum(dx * dx)) * float(np.sum(dy * dy)))
    return min(max(r, -1.0), 1.0)


def summary_table(ok: pd.DataFrame, runs: pd.DataFrame, legal: pd.DataFrame) -> pd.DataFrame:
    """The headline numbers per protocol and group (the rows of metrics/survey.json).

    The shares outside 5 % and 10 % and the mean spread [kg] are those of
    :func:`bogie.weighings.stats.survey_statistics`, the function an observed survey's groups go through.
    """
    nose_up = ok.assign(rear_nose_up=ok["rear_heaviest"].astype(float).where(ok["tilt_deg"] > NOSE_UP_DEG))
    table = nose_up.groupby(KEYS, observed=True).agg(
        mean_max_deviation=("max_deviation", "mean"), mean_spread_pct=("spread_pct", "mean"),
        mean_road_wear_factor=("road_wear_factor", "mean"),
        rear_overload_share_nose_up=("rear_nose_up", "mean"), n_nose_up=("rear_nose_up", "count"),
        share_on_stop=("equaliser_on_stop", "mean"),
    ).reset_index()  # fmt: skip
    shared = survey_statistics(ok, by=KEYS, unit_per_kg=GRAVITY)[
        [*KEYS, "share_outside_5pct", "share_over_10pct", "mean_spread_kg"]
    ]
    table = table.merge(shared, on=KEYS, how="left")[
        [*KEYS, "share_outside_5pct", "share_over_10pct", "mean_max_deviation", "mean_spread_pct",
         "mean_spread_kg", "mean_road_wear_factor", "rear_overload_share_nose_up", "n_nose_up", "share_on_stop"]
    ]  # fmt: skip
    table = table.merge(legal[[*KEYS, "frac_axle_over_group_legal"]], on=KEYS, how="left")
    # (protocol, group) pairs where every run failed still get a row, with counts and NaN statistics
    return run_counts(runs).merge(table, on=KEYS, how="left")


#: the statistics of the suspension table, as :func:`bogie.weighings.stats.survey_statistics` names them
SUSPENSION_STATISTICS: tuple[str, ...] = (
    "share_outside_5pct", "share_over_10pct", "mean_spread_kg", "median_spread_pct",
)  # fmt: skip


def suspension_table(ok: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """The survey's statistics per protocol, group and suspension (steel-equalised, air-sprung).

    A survey's own file does not say which suspension a group has; the simulated fleet does, so this splits what
    the survey sees (the rows of :func:`summary_table`, both suspensions together) into the two kinds. One row per
    (protocol, group, suspension) of :data:`~bogie.fleet.constants.SUSPENSIONS`, every pair present: ``n_runs``,
    ``n_ok``, ``n_failed``, ``n_airborne`` (:func:`run_counts`) and the statistics of the readings
    (:func:`bogie.weighings.stats.survey_statistics`: shares outside 5 % and over 10 %, mean spread [kg], median
    spread [%]), NaN for a kind with no reading.
    """
    keys = [*KEYS, "suspension"]
    # a table from before suspensions were sampled holds steel groups only
    ok, runs = (t if "suspension" in t else t.assign(suspension="steel") for t in (ok, runs))
    protocols = sorted(runs["protocol"].astype(str).unique())
    groups = [g for g in GROUP_AXLES if g in set(runs["group"].astype(str))]
    frame = pd.DataFrame([(p, g, k) for p in protocols for g in groups for k in SUSPENSIONS], columns=keys)
    counts = run_counts(runs.astype({c: str for c in keys}), keys)
    numbers = ("n_runs", "n_ok", "n_failed", "n_airborne")
    frame = frame.merge(counts, on=keys, how="left").fillna(dict.fromkeys(numbers, 0))
    frame = frame.astype(dict.fromkeys(numbers, "int64"))
    if len(ok):
        stats = survey_statistics(ok.astype({c: str for c in keys}), by=keys, unit_per_kg=GRAVITY)
        frame = frame.merge(stats[[*keys, *SUSPENSION_STATISTICS]], on=keys, how="left")
    else:
        frame = frame.assign(**dict.fromkeys(SUSPENSION_STATISTICS, math.nan))
    return frame


# ---- the whole survey ----------------------------------------------------------------------------------------------
def survey_tables(runs: pd.DataFrame, legal_axle_load: float, legal_group_load: Mapping[str, float]) -> dict[str, Any]:
    """Every survey table of one study's runs.

    Parameters
    ----------
    runs
        The runs of the study, failed rows included (they are counted, not used).
    legal_axle_load
        Legal single-axle load, both sides [N].
    legal_group_load
        Legal load of each axle group, both sides [N].

    Returns
    -------
    dict
        Table name -> DataFrame: ``summary``, ``by_suspension``, ``counts``, ``failures``, ``distributions``,
        ``histograms``, ``tilt``, ``tyre_wear``, ``static_vs_wim``, ``static_vs_wim_pairs``, ``wim_class``, ``legal``
        (the survey stage writes each as ``<name>.csv``, the pairs as Parquet: ``docs/outputs.md``).
    """
    ok = inequality_columns(readings(runs))
    legal = legal_limits(ok, legal_axle_load, legal_group_load)
    pairs, pair_summary = static_vs_wim(ok)
    return {
        "summary": summary_table(ok, runs, legal),
        "by_suspension": suspension_table(ok, runs),
        "counts": run_counts(runs),
        "failures": failure_table(runs),
        "distributions": distribution_stats(ok),
        "histograms": histograms(ok),
        "tilt": tilt_table(ok),
        "tyre_wear": wear_table(ok),
        "static_vs_wim": pair_summary,
        "static_vs_wim_pairs": pairs,
        "wim_class": wim_class(ok),
        "legal": legal,
    }
