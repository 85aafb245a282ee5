"""DVC stage ``survey``: roadside-survey statistics of the fleet study -> data/survey/ and metrics/survey.json.

``python -m pipeline.survey`` reads the fleet study's runs (``data/runs/study=fleet``) and tabulates, per protocol
(static weighbridge, weigh-in-motion) and axle group (tandem, tri-axle), what a road authority's survey of that
fleet would find: the distribution of each axle position's load share, the heaviest-minus-lightest spread, the
share of groups outside the 5 % and 10 % tolerances, which axle is overloaded against chassis tilt, inequality
against tilt and tyre-wear bands, the static weighbridge against WIM, the road-wear factor, the groups with an
axle over the legal limit while the group is legal, and the design guidance (the share within 5 % binned by the
design parameters, with Wilson intervals; the report draws it). Every statistic is a plain function of a runs DataFrame;
``main`` only reads, calls and writes. Definitions, units and file layout: ``docs/outputs.md``.

Failed runs (``status == "failed"``, zeros in their numbers) are excluded from every statistic and counted in
``counts.csv`` and ``failures.csv``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import yaml

from bogie.params import GRAVITY
from bogie.weighings.stats import group_inequality, survey_statistics
from bogie.weighings.writers import write_weighings
from pipeline.atomic import atomic_outputs, io_error
from pipeline.config import ConfigError, load_config
from pipeline.constants import GROUP_AXLES, MAX_AXLES, SUSPENSIONS
from pipeline.sample import TYRE_WEAR_COLUMNS, bogie_from_sample
from pipeline.schema import SchemaError, check_runs, read_runs_frame
from pipeline.survey_design import DESIGN_COLUMNS, design_table

#: the study a roadside survey samples
SURVEY_STUDY = "fleet"
AXLE_LOAD_COLUMNS: tuple[str, ...] = tuple(f"axle_load_{i}" for i in range(MAX_AXLES))
LOAD_SHARE_COLUMNS: tuple[str, ...] = tuple(f"load_share_{i}" for i in range(MAX_AXLES))
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


class RunsError(ValueError):
    """The runs dataset is missing, incomplete or not in the expected form."""


# ---- reading -----------------------------------------------------------------------------------------------------
def read_runs(runs_dir: str | Path, study: str, columns: Sequence[str] = REQUIRED_COLUMNS) -> pd.DataFrame:
    """The runs of one study from the hive-partitioned dataset ``runs_dir/study=<study>/part-*.parquet``.

    Each part file is verified (:func:`pipeline.schema.read_runs_frame`: its SHA-256 and page checksums, the runs
    schema's fields) and the rows checked against the null rule: no null in a successful row, only nulls in the
    results of a failed one. Every stage that reads runs reads them here.

    Raises
    ------
    RunsError
        If the study has no part file, a file fails verification (named, with what failed), or the nulls break the
        rule.
    """
    runs_dir = Path(runs_dir)
    partition = runs_dir / f"study={study}"
    if not any(partition.glob("*.parquet")):
        raise RunsError(f"no runs of study {study!r}: {partition}/ holds no Parquet file; run the simulate stage first")
    try:
        frame = read_runs_frame(runs_dir, study)
        check_runs(frame, f"runs of study {study!r} in {runs_dir}")
    except SchemaError as exc:
        raise RunsError(str(exc)) from None
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise RunsError(f"runs of study {study!r} in {runs_dir} lack the columns {', '.join(missing)}")
    return frame


def check_complete(runs: pd.DataFrame, n_samples: int, protocols: Sequence[str], study: str = "fleet") -> None:
    """Check that the runs hold each of ``n_samples`` samples once under each protocol (simulate has finished).

    Raises
    ------
    RunsError
        Naming how many runs are missing or duplicated and a few of their sample ids.
    """
    have = runs.groupby([runs["protocol"].astype(str), "sample_id"], observed=True).size()
    expected = pd.MultiIndex.from_product([list(protocols), range(n_samples)], names=["protocol", "sample_id"])
    missing = expected.difference(have.index)
    extra = have.index.difference(expected).union(have[have > 1].index)
    if len(missing) or len(extra):
        shown = ", ".join(f"{p} {i}" for p, i in list(missing)[:5])
        raise RunsError(
            f"the {study} runs are incomplete: {len(missing)} of {len(expected)} (sample, protocol) runs missing"
            + (f" (e.g. {shown})" if shown else "")
            + (f", {len(extra)} unexpected or repeated" if len(extra) else "")
            + "; run the simulate stage to completion (make repro) first"
        )


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
        Succeeded runs with ``n_axles``, ``axle_load_0..2`` [N] (0 for a missing axle), ``chassis_tilt`` [rad] and
        ``tyre_wear_0..2`` [m].

    Returns
    -------
    pandas.DataFrame
        ``runs`` with added columns: ``spread_pct`` (heaviest minus lightest axle over the mean axle load [%]),
        ``pair_difference`` ((max - min) / max [-]), ``max_load_share`` (largest LSC [-]), ``outside_5pct``
        (pair_difference > 0.05), ``outside_10pct`` (max_load_share > 1.10), ``heaviest_axle`` (0 = front; a tie
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
    out["outside_10pct"] = ineq["over_10pct"]
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
        return frame[frame["n_axles"] > int(quantity.rsplit("_", 1)[1])]
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
        share_outside_5pct=("outside_5pct", "mean"), share_outside_10pct=("outside_10pct", "mean"), **extra,
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


def _corr(a: pd.Series, b: pd.Series) -> float:
    # a constant series (e.g. two identical bogies) has no correlation: NaN, not a numpy warning
    if len(a) < 2 or a.std() == 0 or b.std() == 0:
        return math.nan
    return float(np.corrcoef(a, b)[0, 1])


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
    shared = survey_statistics(ok, by=KEYS, unit_per_kg=GRAVITY).rename(
        columns={"share_over_10pct": "share_outside_10pct"}
    )[[*KEYS, "share_outside_5pct", "share_outside_10pct", "mean_spread_kg"]]
    table = table.merge(shared, on=KEYS, how="left")[
        [*KEYS, "share_outside_5pct", "share_outside_10pct", "mean_max_deviation", "mean_spread_pct",
         "mean_spread_kg", "mean_road_wear_factor", "rear_overload_share_nose_up", "n_nose_up", "share_on_stop"]
    ]  # fmt: skip
    table = table.merge(legal[[*KEYS, "frac_axle_over_group_legal"]], on=KEYS, how="left")
    # (protocol, group) pairs where every run failed still get a row, with counts and NaN statistics
    return run_counts(runs).merge(table, on=KEYS, how="left")


#: the statistics of the suspension table, as :func:`bogie.weighings.stats.survey_statistics` names them
_SUSPENSION_STATISTICS: tuple[str, ...] = (
    "share_outside_5pct", "share_over_10pct", "mean_spread_kg", "median_spread_pct",
)  # fmt: skip


def suspension_table(ok: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """The survey's statistics per protocol, group and suspension (steel-equalised, air-sprung).

    A survey's own file does not say which suspension a group has; the simulated fleet does, so this splits what
    the survey sees (the rows of :func:`summary_table`, both suspensions together) into the two kinds. One row per
    (protocol, group, suspension) of :data:`~pipeline.constants.SUSPENSIONS`, every pair present: ``n_runs``,
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
        frame = frame.merge(stats[[*keys, *_SUSPENSION_STATISTICS]], on=keys, how="left")
    else:
        frame = frame.assign(**dict.fromkeys(_SUSPENSION_STATISTICS, math.nan))
    return frame


# ---- the whole survey ----------------------------------------------------------------------------------------------
def survey(runs: pd.DataFrame, legal_axle_load: float, legal_group_load: Mapping[str, float]) -> dict[str, Any]:
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
        Output file name -> DataFrame (see ``docs/outputs.md``).
    """
    ok = inequality_columns(readings(runs))
    legal = legal_limits(ok, legal_axle_load, legal_group_load)
    pairs, pair_summary = static_vs_wim(ok)
    return {
        "summary.csv": summary_table(ok, runs, legal),
        "by_suspension.csv": suspension_table(ok, runs),
        "counts.csv": run_counts(runs),
        "failures.csv": failure_table(runs),
        "distributions.csv": distribution_stats(ok),
        "histograms.csv": histograms(ok),
        "tilt.csv": tilt_table(ok),
        "tyre_wear.csv": wear_table(ok),
        "static_vs_wim.csv": pair_summary,
        "static_vs_wim_pairs.parquet": pairs,
        "legal.csv": legal,
    }


def rounded(x: Any, digits: int) -> float | None:
    """``x`` rounded for JSON; None for NaN or a missing value (JSON has no NaN)."""
    if x is None or pd.isna(x):
        return None
    return round(float(x), digits) + 0.0  # + 0.0 turns -0.0 into 0.0


#: headline column -> decimals in metrics/survey.json
_HEADLINE_DIGITS = {
    "share_outside_5pct": 4, "share_outside_10pct": 4, "mean_max_deviation": 4, "mean_spread_pct": 2,
    "mean_spread_kg": 1, "mean_road_wear_factor": 4, "rear_overload_share_nose_up": 4,
    "frac_axle_over_group_legal": 4, "share_on_stop": 4,
}  # fmt: skip


def headline_metrics(tables: Mapping[str, pd.DataFrame]) -> dict[str, Any]:
    """The small dict of metrics/survey.json: totals, then protocol -> group -> headline numbers, rounded."""
    summary = tables["summary.csv"]
    metrics: dict[str, Any] = {
        "n_runs": int(summary["n_runs"].sum()),
        "n_ok": int(summary["n_ok"].sum()),
        "n_failed": int(summary["n_failed"].sum()),
        "n_airborne": int(summary["n_airborne"].sum()),
    }
    for row in summary.itertuples(index=False):
        entry = {key: rounded(getattr(row, key), digits) for key, digits in _HEADLINE_DIGITS.items()}
        entry.update(n_ok=int(row.n_ok), n_failed=int(row.n_failed), n_airborne=int(row.n_airborne))
        metrics.setdefault(row.protocol, {})[row.group] = entry
    by_kind: dict[str, Any] = {}
    for row in tables["by_suspension.csv"].to_dict("records"):
        entry = {"n_ok": int(row["n_ok"]), "n_failed": int(row["n_failed"]), "n_airborne": int(row["n_airborne"])}
        entry.update({key: rounded(row[key], 4 if key.startswith("share") else 1) for key in _SUSPENSION_STATISTICS})
        by_kind.setdefault(row["protocol"], {}).setdefault(row["group"], {})[row["suspension"]] = entry
    metrics["by_suspension"] = by_kind
    pairs = tables["static_vs_wim.csv"]
    if not pairs.empty:
        metrics["static_vs_wim"] = {
            row.group: {
                "mean_dynamic_excess": rounded(row.mean_dynamic_excess, 4),
                "corr_max_deviation": rounded(row.corr_max_deviation, 3),
                "n_pairs": int(row.n_pairs),
            }
            for row in pairs.itertuples(index=False)
        }
    return metrics


# ---- output --------------------------------------------------------------------------------------------------------
# ---- the fleet's WIM readings as records ------------------------------------------------------------------------
#: the export's synthetic clock: the first record's time, then one record every EXPORT_HEADWAY_S. The fleet study has
#: no traffic flow; the times only order the records and keep each distinct (a reader counts a repeat as bad)
EXPORT_START = "2026-01-01T00:00:00"
EXPORT_HEADWAY_S = 10


def wim_records(runs: pd.DataFrame, samples: pd.DataFrame, speed: float) -> tuple[pd.DataFrame, dict[str, int]]:
    """The fleet study's WIM readings as a vehicle table of :func:`bogie.weighings.writers.write_weighings`.

    One record per WIM reading kept by the survey (not failed, no wheel in the air), in ``sample_id`` order: the
    bogie's axles only (the tractor and the rest of the vehicle are not simulated), its axle loads [kg] as the WIM
    read them, its axle spacings [m] from the bogie's geometry, the WIM pass's ``speed`` [m/s], lane 1, direction 1,
    on the synthetic clock :data:`EXPORT_START` + :data:`EXPORT_HEADWAY_S` per record. Returns the table and the
    counts ``{"n_readings", "n_failed", "n_airborne", "n_written"}``.
    """
    wim = runs[runs["protocol"].astype(str) == "wim"]
    failed = wim["status"].astype(str) != "ok"
    airborne = ~failed & wim["wheel_airborne"].fillna(False).astype(bool)
    kept = wim[~failed & ~airborne].sort_values("sample_id", kind="stable")
    counts = {
        "n_readings": len(wim), "n_failed": int(failed.sum()), "n_airborne": int(airborne.sum()),
        "n_written": len(kept),
    }  # fmt: skip
    n = kept["n_axles"].to_numpy(dtype=np.int64)
    width = int(n.max()) if len(kept) else 2
    by_id = samples.set_index("sample_id")
    spacings = np.full((len(kept), width - 1), np.nan)
    for j, sample_id in enumerate(kept["sample_id"].to_numpy()):
        axle_x = bogie_from_sample(by_id.loc[sample_id].to_dict()).axle_x
        spacings[j, : len(axle_x) - 1] = np.diff(axle_x)
    vehicles = pd.DataFrame({
        "timestamp": pd.Timestamp(EXPORT_START) + pd.to_timedelta(EXPORT_HEADWAY_S * np.arange(len(kept)), unit="s"),
        "speed": np.full(len(kept), speed), "lane": 1, "direction": 1, "n_axles": n,
    })  # fmt: skip
    for i in range(width):
        load = kept[f"axle_load_{i}"].to_numpy(dtype=float) / GRAVITY
        vehicles[f"axle_load_{i}"] = np.where(n > i, load, np.nan)
    for i in range(width - 1):
        vehicles[f"spacing_{i}"] = spacings[:, i]
    return vehicles, counts


def _write_table(frame: pd.DataFrame, path: Path) -> None:
    if path.suffix == ".parquet":
        frame.to_parquet(path, index=False)
    else:
        frame.to_csv(path, index=False, float_format="%.6g")


def write_outputs(
    tables: Mapping[str, pd.DataFrame], out_dir: str | Path, metrics: Mapping[str, Any], metrics_path: str | Path,
    records: tuple[str, pd.DataFrame, str] | None = None,
) -> None:  # fmt: skip
    """Write the tables into ``out_dir`` and the metrics JSON, all or nothing; ``records`` (file name, vehicle table,
    format) is written with :func:`bogie.weighings.writers.write_weighings` into ``out_dir`` too.

    The tables go to a temporary sibling directory that replaces ``out_dir`` by renames, and the JSON to a
    temporary file renamed last: a reader sees the old outputs or the new ones, never a mix or half a file, and an
    error while writing leaves the old outputs in place. Parent directories are created.
    """
    with atomic_outputs(files=[metrics_path], dirs=[out_dir]) as ((tmp_json,), (tmp_dir,)):
        with open(tmp_json, "w", encoding="utf-8") as fh:
            json.dump(metrics, fh, indent=2, allow_nan=False)
            fh.write("\n")
        for name, frame in tables.items():
            _write_table(frame, tmp_dir / name)
        if records is not None:
            name, vehicles, fmt = records
            write_weighings(vehicles, tmp_dir / name, fmt)


def main(argv: list[str] | None = None) -> int:
    """Run the stage: read the fleet runs, compute the survey, write data/survey/ and metrics/survey.json."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.survey", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--samples", default="data/samples", help="sample tables (default: data/samples)")
    parser.add_argument("--out", default="data/survey", help="output directory (default: data/survey)")
    parser.add_argument("--metrics", default="metrics/survey.json", help="metrics file (default: metrics/survey.json)")
    args = parser.parse_args(argv)
    try:
        config = load_config(args.params)
        runs = read_runs(args.runs, SURVEY_STUDY, (*REQUIRED_COLUMNS, *DESIGN_COLUMNS))
        check_complete(runs, config.fleet.n_bogies, config.protocol.run, SURVEY_STUDY)
    except (ConfigError, RunsError, OSError, yaml.YAMLError) as exc:
        print(f"survey: {exc}", file=sys.stderr)
        return 2
    tables = survey(runs, config.fleet.legal_axle_load, config.fleet.legal_group_load)
    metrics = headline_metrics(tables)
    tables["design_guidance.csv"] = design_table(inequality_columns(readings(runs)))
    records = None
    fmt = config.survey.export_format
    if fmt is not None:
        try:
            samples = pq.read_table(Path(args.samples) / f"{SURVEY_STUDY}.parquet").to_pandas()
        except OSError as exc:
            print(f"survey: {exc}", file=sys.stderr)
            return 2
        vehicles, counts = wim_records(runs, samples, config.protocol.wim.speed)
        records = (f"fleet_wim.{fmt}", vehicles, fmt)
        metrics["export"] = {"format": fmt, "file": f"fleet_wim.{fmt}", **counts}
    try:
        write_outputs(tables, args.out, metrics, args.metrics, records)
    except (OSError, ValueError) as exc:  # ValueError: a reading that does not fit the format's fields
        print(io_error("survey", exc) if isinstance(exc, OSError) else f"survey: {exc}", file=sys.stderr)
        return 2
    n_ok, n_runs, n_failed = metrics["n_ok"], metrics["n_runs"], metrics["n_failed"]
    print(f"survey: {n_ok} of {n_runs} runs succeeded ({n_failed} failed); wrote {args.out} and {args.metrics}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
