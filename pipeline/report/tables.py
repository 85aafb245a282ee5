"""The report's derived tables: plain functions of the inputs' DataFrames and dicts, no drawing, no words.

Units: SI or fractions in, as the stages wrote them; a table made for a chart is in the chart's units (said per
function). The statistics themselves belong to the stages (the survey's design guidance, the sensitivity's indices):
here they are only selected and reshaped.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.constants import PROTOCOLS
from bogie.fleet.design.table import DESIGN_BINS
from bogie.fleet.sampling.sample import TYRE_WEAR_COLUMNS
from pipeline.config import Config
from pipeline.report.style import GROUP_LABEL, QUANTITY, factor_label
from pipeline.sample import STUDIES

__all__ = [
    "DESIGN_NAMES",
    "SAMPLED",
    "DesignLine",
    "design_quotes",
    "design_tables",
    "failed_runs",
    "parameter_panels",
    "plot_series",
    "run_counts",
    "summary_numbers",
    "worse_without",
]


# ---- runs ----------------------------------------------------------------------------------------------------------
def run_counts(runs: pd.DataFrame) -> pd.DataFrame:
    """Runs, succeeded and failed per study (in the pipeline's study order), then a total row."""
    table = (
        runs.assign(ok=runs["status"] == "ok")
        .groupby("study", observed=True)
        .agg(n_runs=("status", "size"), n_ok=("ok", "sum"))
    )
    table = table.reindex([s for s in STUDIES if s in table.index]).reset_index()
    table["n_failed"] = table["n_runs"] - table["n_ok"]
    total = pd.DataFrame([{"study": "all", **table[["n_runs", "n_ok", "n_failed"]].sum().to_dict()}])
    return pd.concat([table, total], ignore_index=True).astype({"n_runs": int, "n_ok": int, "n_failed": int})


def failed_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """The failed runs grouped by study, protocol, group, variant and kind of message.

    Messages that differ only in their numbers (the time, step and residual of a solver failure) are one kind.

    Returns
    -------
    pandas.DataFrame
        study, protocol, group, variant, ``kind`` (the message with its numbers masked), ``n`` (runs),
        ``sample_ids`` (space-separated, ascending) and ``message`` (that of the first of them).
    """
    failed = runs[runs["status"] != "ok"].sort_values("sample_id")
    keys = ["study", "protocol", "group", "variant", "kind"]
    if failed.empty:
        return pd.DataFrame(columns=[*keys, "n", "sample_ids", "message"])
    failed = failed.assign(kind=failed["message"].str.replace(r"\d+(?:\.\d+)?(?:e[-+]?\d+)?", "#", regex=True))
    table = failed.groupby(keys, observed=True).agg(
        n=("sample_id", "size"), sample_ids=("sample_id", lambda s: " ".join(map(str, s))), message=("message", "first")
    )
    return table.reset_index().sort_values(["study", "n"], ascending=[True, False], ignore_index=True)


# ---- metrics -------------------------------------------------------------------------------------------------------
def summary_numbers(survey: Mapping[str, Any], sensitivity: Mapping[str, Any]) -> dict[str, Any]:
    """The numbers of the summary page, taken as they are from metrics/survey.json and metrics/sensitivity.json."""
    keys = (
        "share_outside_5pct",
        "share_over_10pct",
        "mean_spread_kg",
        "mean_spread_pct",
        "rear_overload_share_nose_up",
    )
    headline = {
        protocol: {group: {k: entry[k] for k in keys} for group, entry in survey[protocol].items()}
        for protocol in PROTOCOLS
        if protocol in survey
    }
    copied = ("ranking", "ranking_measure", "reference_check", "ranking_other_measures", "sobol", "ablation")
    return {**{k: sensitivity[k] for k in copied}, "survey": headline}


# ---- DVC plot series -----------------------------------------------------------------------------------------------
def plot_series(
    sensitivity_metrics: Mapping[str, Any], ablation: pd.DataFrame, ok: pd.DataFrame, tilt: pd.DataFrame
) -> dict[str, pd.DataFrame]:
    """The small series declared as DVC plots (``reports/plots/<name>``): one column per series, ``_pct`` in %.

    ``sobol.csv``: each factor's S1, ST and half-widths (ranking measure); ``ablation.csv``: per variant, each
    protocol's ablation statistics; ``tolerance.csv``: share of groups outside a tolerance t, per group and protocol;
    ``tilt.csv``: share of groups whose rear axle is the heaviest per 0.5 degree tilt band (static weighbridge).

    Parameters
    ----------
    sensitivity_metrics
        metrics/sensitivity.json.
    ablation
        data/sensitivity/ablation.csv.
    ok
        The fleet's succeeded runs with the survey's inequality columns.
    tilt
        data/survey/tilt.csv.
    """
    sens = sensitivity_metrics["sobol"]
    sobol = pd.DataFrame([{"factor": factor_label(f), **v} for f, v in sens["indices"].items()])
    ablation = ablation[(ablation["group"] == "all")]
    wide = ablation.assign(col=ablation["protocol"] + "_" + ablation["statistic"] + "_pct", v=100.0 * ablation["value"])
    wide = wide.pivot_table(index="variant", columns="col", values="v", sort=False).reset_index()
    wide["variant"] = wide["variant"].map(factor_label)
    grid = np.arange(0.0, 30.01, 0.5)
    tolerance, rear = {"tolerance_pct": grid}, {}
    for group in GROUP_LABEL:
        for protocol in PROTOCOLS:
            x = 100.0 * ok.loc[(ok["group"] == group) & (ok["protocol"] == protocol), "pair_difference"].to_numpy()
            share = 100.0 * (x[None, :] > grid[:, None]).mean(axis=1) if len(x) else np.full(len(grid), np.nan)
            tolerance[f"{group}_{protocol}_pct"] = np.round(share, 3)
        band = tilt[(tilt["group"] == group) & (tilt["protocol"] == "static")]
        middle = 0.5 * (band["tilt_deg_low"] + band["tilt_deg_high"]).to_numpy()
        rear[f"{group}_rear_heaviest_pct"] = pd.Series(100.0 * band["rear_heaviest_share"].to_numpy(), index=middle)
    tilt_frame = pd.DataFrame(rear).sort_index().rename_axis("tilt_deg").reset_index()
    return {"sobol.csv": sobol, "ablation.csv": wide, "tolerance.csv": pd.DataFrame(tolerance), "tilt.csv": tilt_frame}


# ---- design guidance -----------------------------------------------------------------------------------------------
#: the words for the design guidance's parameters: their one name (:data:`pipeline.report.style.QUANTITY`)
DESIGN_NAMES = {key: QUANTITY[key].name for key in ("bush_stiffness", "equaliser_arm", "friction_coefficient",
                                                    "contact_roll_radius")}  # fmt: skip


@dataclass(frozen=True)
class DesignLine:
    """The share within 5 % binned by one design parameter, every group (a line chart of the design page).

    ``bins``: ``group``, ``low``, ``high`` (edges in ``unit``), ``n``, ``share`` and its interval ``share_low``,
    ``share_high`` [-]; ``log``: the bins are logarithmic (draw on a log axis, bin middles geometric).
    """

    parameter: str
    name: str
    unit: str
    log: bool
    bins: pd.DataFrame

    @property
    def label(self) -> str:
        """Axis label: name and unit."""
        return f"{self.name} [{self.unit}]"


def design_tables(table: pd.DataFrame, protocol: str) -> tuple[dict[str, pd.DataFrame], list[DesignLine]]:
    """The design guidance of ``protocol`` from the survey's ``design_guidance.csv``, as the design page draws it.

    Returns
    -------
    grids : dict
        Group -> map cells ``x_low``, ``x_high`` (bush stiffness [N m/rad]), ``y_low``, ``y_high`` (equaliser arm
        [mm]), ``n`` and ``share`` within 5 % [-] (NaN when empty).
    lines : list of DesignLine
        One per design parameter, in the survey's order.
    """
    rows = table[table["protocol"] == protocol]
    cells = rows[rows["kind"] == "cell"]
    grids = {
        group: sub[["x_low", "x_high", "y_low", "y_high", "n", "share"]].reset_index(drop=True)
        for group, sub in cells.groupby("group", sort=False)
    }
    bins = rows[rows["kind"] == "bin"].rename(columns={"x_low": "low", "x_high": "high"})
    lines = []
    for parameter, sub in bins.groupby("x", sort=False):
        frame = sub[["group", "low", "high", "n", "share", "share_low", "share_high"]].reset_index(drop=True)
        log = DESIGN_BINS.get(parameter, (None, None, 0))[2] is None
        name = DESIGN_NAMES.get(parameter, parameter)
        lines.append(DesignLine(parameter, name, str(sub["x_unit"].iloc[0]), log, frame))
    return grids, lines


def design_quotes(
    grids: Mapping[str, pd.DataFrame], lines: list[DesignLine], target: float, min_cell: int
) -> tuple[dict[str, dict[str, Any] | None], dict[str, dict[str, tuple[float, float]]]]:
    """What the design caption quotes, from cells and bins of at least ``min_cell`` bogies.

    Returns
    -------
    groups : dict
        Group -> None when no cell is quoted, else ``quoted`` (cells), ``good`` (the cells at or above ``target``,
        as dicts, in table order) and ``best`` (the cell of the largest share).
    trends : dict
        Parameter name -> group -> share of its lowest and of its highest quoted bin (groups with one).
    """
    groups: dict[str, dict[str, Any] | None] = {}
    for group, cells in grids.items():
        quoted = cells[cells["n"] >= min_cell]
        if quoted.empty:
            groups[group] = None
            continue
        good = quoted[quoted["share"] >= target]
        best = quoted.loc[[quoted["share"].idxmax()]].to_dict("records")[0]
        groups[group] = {"quoted": len(quoted), "good": good.to_dict("records"), "best": best}
    trends = {}
    for line in lines:
        parts = {}
        for group in dict.fromkeys(line.bins["group"]):
            b = line.bins[(line.bins["group"] == group) & (line.bins["n"] >= min_cell)]
            if len(b):
                parts[group] = (b["share"].iloc[0], b["share"].iloc[-1])
        if parts:
            trends[line.name] = parts
    return groups, trends


# ---- Appendix A ----------------------------------------------------------------------------------------------------
#: sampled quantities shown in Appendix A: column, params.yaml key, what the title adds to the quantity's one name
#: (:data:`pipeline.report.style.QUANTITY`, with its unit and scale), log axis
SAMPLED: tuple[tuple[str, str, str, bool], ...] = (
    ("bush_stiffness", "bush_stiffness", "", True),
    ("bush_damping", "bush_damping", "", True),
    ("friction_coefficient", "friction_coefficient", "", False),
    ("contact_roll_radius", "contact_roll_radius_mm", "", False),
    ("equaliser_arm", "equaliser_arm_mm", "", False),
    ("spring_friction_band", "spring_friction_band_kn", "", False),
    ("spring_friction_decay", "spring_friction_decay_mm", "", False),
    ("tyre_wear", "tyre_wear_mm", ", every tyre", False),
    ("chassis_tilt", "chassis_tilt_deg", ", nose up +", False),
    ("payload_fraction", "payload_fraction", ", fraction of the legal group load", False),
)


def distribution_text(raw: Mapping[str, Any] | None) -> str:
    """A params.yaml distribution entry as short text, e.g. "loguniform 1-3000"."""
    if not raw:
        return "not in params.yaml"
    kind = raw.get("kind", "?")
    if "low" in raw and "high" in raw and kind in ("uniform", "loguniform"):
        return f"{kind} {raw['low']:g}-{raw['high']:g}"
    if kind == "choice":
        weights = raw.get("weights") or [1] * len(raw["values"])
        return "choice " + ", ".join(f"{v} {w:g}" for v, w in zip(raw["values"], weights))
    return (
        kind
        + " "
        + ", ".join(f"{k} {v:g}" if isinstance(v, int | float) else f"{k} {v}" for k, v in raw.items() if k != "kind")
    )


def parameter_panels(fleet: pd.DataFrame, raw: Mapping[str, Any], config: Config) -> list[dict[str, Any]]:
    """The charts of Appendix A: each sampled quantity of the fleet in edge units, with its params.yaml entry.

    Returns one dict per chart: ``title``, ``xlabel`` and either ``values`` (edge units) and ``log``, or
    ``categories`` (label -> count) and ``expected`` (label -> the count the weights expect, or None).
    """
    dists = raw.get("distributions", {})
    panels: list[dict[str, Any]] = []
    for column, key, qualifier, log in SAMPLED:
        q = QUANTITY[column]
        label = q.name + qualifier
        if column == "tyre_wear":
            values = np.concatenate([fleet.loc[fleet["n_axles"] > i, c] for i, c in enumerate(TYRE_WEAR_COLUMNS)])
        else:
            values = fleet[column].to_numpy(dtype=float)
        title = f"{label}\n{distribution_text(dists.get(key))}"
        panels.append({"title": title, "xlabel": f"{label} [{q.unit}]", "values": q.scale * values, "log": log})
    road = dists.get("road_class", {})
    weights = np.asarray(road.get("weights") or [1.0] * len(road.get("values", [])), dtype=float)
    expected = dict(zip(road.get("values", []), len(fleet) * weights / weights.sum())) if weights.size else None
    counts = (
        fleet["road_class"].value_counts().reindex(road.get("values") or sorted(set(fleet["road_class"])), fill_value=0)
    )
    panels.append(
        {
            "title": f"approach road, ISO 8608 class\n{distribution_text(road)}",
            "xlabel": "road class",
            "categories": counts.to_dict(),
            "expected": expected,
        }
    )
    mix = dict(config.fleet.axle_mix)
    groups = fleet["group"].value_counts().reindex(list(mix), fill_value=0)
    panels.append(
        {
            "title": "axle group\nmix " + ", ".join(f"{GROUP_LABEL[g]} {w:g}" for g, w in mix.items()),
            "xlabel": "axle group",
            "categories": {GROUP_LABEL[g]: n for g, n in groups.items()},
            "expected": {GROUP_LABEL[g]: len(fleet) * w for g, w in mix.items()},
        }
    )
    return panels


def worse_without(numbers: Mapping[str, Any]) -> dict[str, list[str]]:
    """Per protocol, the ablation variants (an inhibitor, or "all") whose removal made the fleet mean maximum deviation
    worse with the whole paired interval of the change on that side (``reduction_high`` below zero), in the ranking's
    order with "all" last; protocols with none are left out."""
    out = {}
    for protocol, abl in numbers["ablation"].items():
        order = [*numbers["ranking"], "all"]
        worse = [
            v for v in order if v in abl and abl[v].get("reduction_high") is not None and abl[v]["reduction_high"] < 0.0
        ]
        if worse:
            out[protocol] = worse
    return out
