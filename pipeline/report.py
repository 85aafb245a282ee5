"""DVC stage ``report``: the PDF sensitivity report -> reports/sensitivity_report.pdf, its figures, plot series.

``python -m pipeline.report`` reads what the earlier stages wrote (the fleet samples, the runs of every study, the
survey and sensitivity tables and their metrics JSON), reruns the reference's named cases it reproduces (about a
second with a warm numba cache) and writes:

- ``reports/sensitivity_report.pdf``: A4 pages, vector figures, numbered (contents: ``docs/report.md``);
- ``reports/figures/report/<page>.png``: every page that holds charts, as PNG;
- ``reports/plots/*.csv``: small series declared as DVC plots (``dvc plots show``).

The words of the summary and of the captions are generated from the numbers (``metrics/*.json``, the tables and the
runs), never fixed text, except for what the reference reported. Failed runs are listed, never a reason to stop.
Every output is written under a temporary name and renamed into place, so a reader sees the old report or the new.
"""

from __future__ import annotations

import argparse
import datetime as dt
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
import pandas as pd
import yaml
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure

from bogie import cases, fe, metrics
from bogie.params import triaxle_stage1
from bogie.plotting import case_history, figure2
from bogie.results import DynamicResult
from bogie.static import nondimensional_loads
from pipeline import report_figures as rf
from pipeline.config import Config, ConfigError, load_config, load_params
from pipeline.protocol import READ_TIME, TARE_FRACTION
from pipeline.sample import STUDIES, TYRE_WEAR_COLUMNS
from pipeline.survey import (
    NOSE_UP_DEG,
    PAIR_TOLERANCE,
    REQUIRED_COLUMNS,
    SHARE_TOLERANCE,
    RunsError,
    inequality_columns,
    read_runs,
    split_failed,
)

TITLE = "Why mechanically equalised trailer bogies do not share load equally"
SUBTITLE = "Sensitivity report: the four inhibitors of axle-load equalisation across a sampled fleet"
#: resolution of the PNG copies of the pages [dot/inch]
PNG_DPI = 110
#: the reference runs the report reproduces
REFERENCE_RUNS: tuple[str, ...] = ("L01", "L02", "L03", "N10", "N19", "N20", "N21")
#: sample columns the design guidance bins the fleet by
DESIGN_COLUMNS: tuple[str, ...] = ("bush_stiffness", "equaliser_arm", "friction_coefficient", "contact_roll_radius")
#: the design guidance's target: this share of bogies within 5 % [-]
DESIGN_TARGET = 0.95
#: fewest bogies in a design cell or bin whose share the captions quote [-]
MIN_CELL = 10


@dataclass(frozen=True)
class ReportInputs:
    """Everything the report is made from.

    Attributes
    ----------
    raw_params, config
        params.yaml as read and as validated (SI).
    facts
        Provenance: ``date``, ``revision`` (short git hash or "unknown"), ``params_sha256``.
    fleet
        The fleet study's samples (data/samples/fleet.parquet), SI.
    runs
        Every study's runs, status columns only (``study``, ``sample_id``, ``group``, ``variant``, ``protocol``,
        ``status``, ``message``, ``wall_time`` [s]).
    ok
        The fleet's succeeded runs with the survey's inequality columns and the design columns.
    survey, sensitivity
        The tables of data/survey and data/sensitivity, by file name.
    survey_metrics, sensitivity_metrics
        metrics/survey.json and metrics/sensitivity.json.
    """

    raw_params: dict[str, Any]
    config: Config
    facts: dict[str, str]
    fleet: pd.DataFrame
    runs: pd.DataFrame
    ok: pd.DataFrame
    survey: dict[str, pd.DataFrame]
    sensitivity: dict[str, pd.DataFrame]
    survey_metrics: dict[str, Any]
    sensitivity_metrics: dict[str, Any]


# ---- reading -----------------------------------------------------------------------------------------------------
def git_revision(where: str | Path = ".") -> str:
    """The short git hash of the checkout at ``where``, "+ local changes" if tracked files differ; else "unknown"."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=where, capture_output=True, text=True, timeout=10, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return f"{head} + local changes" if dirty else head or "unknown"


def build_date() -> str:
    """Today (UTC) as YYYY-MM-DD, or the date of ``SOURCE_DATE_EPOCH`` for a reproducible build."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    now = dt.datetime.fromtimestamp(int(epoch), dt.UTC) if epoch else dt.datetime.now(dt.UTC)
    return now.date().isoformat()


def _tables(directory: Path, required: Sequence[str]) -> dict[str, pd.DataFrame]:
    """The tables of a stage's output directory by file name; a clear error if one the report needs is missing."""
    missing = [name for name in required if not (directory / name).is_file()]
    if missing:
        raise RunsError(f"{directory}/ lacks {', '.join(missing)}: run the stage that writes it first")
    read = {".csv": pd.read_csv, ".parquet": pd.read_parquet}
    return {f.name: read[f.suffix](f) for f in sorted(directory.iterdir()) if f.suffix in read}


def read_inputs(
    params: str | Path,
    samples: str | Path,
    runs: str | Path,
    survey_dir: str | Path,
    sensitivity_dir: str | Path,
    metrics_dir: str | Path,
) -> ReportInputs:
    """Read and check every input of the report (see :class:`ReportInputs`).

    Raises
    ------
    ConfigError, RunsError, OSError
        For bad parameters, a missing or incomplete runs dataset, or a missing table or metrics file.
    """
    params = Path(params)
    config = load_config(params)
    facts = {
        "date": build_date(),
        "revision": git_revision(params.resolve().parent),
        "params_sha256": hashlib.sha256(params.read_bytes()).hexdigest(),
    }
    status = ["study", "sample_id", "group", "variant", "protocol", "status", "message", "wall_time"]
    if not any(Path(runs).glob("study=*/*.parquet")):
        raise RunsError(f"{runs}/ holds no runs; run the simulate stage first")
    every = pd.read_parquet(runs, columns=status)
    every["study"] = every["study"].astype(str)
    fleet_runs = read_runs(runs, "fleet", (*REQUIRED_COLUMNS, *DESIGN_COLUMNS))
    ok = inequality_columns(split_failed(fleet_runs)[0])
    metrics_dir = Path(metrics_dir)
    return ReportInputs(
        raw_params=load_params(params),
        config=config,
        facts=facts,
        fleet=pd.read_parquet(Path(samples) / "fleet.parquet"),
        runs=every,
        ok=ok,
        survey=_tables(Path(survey_dir), ("tilt.csv", "static_vs_wim_pairs.parquet")),
        sensitivity=_tables(Path(sensitivity_dir), ("sobol_indices.csv", "ablation.csv")),
        survey_metrics=json.loads((metrics_dir / "survey.json").read_text()),
        sensitivity_metrics=json.loads((metrics_dir / "sensitivity.json").read_text()),
    )


# ---- derived tables ------------------------------------------------------------------------------------------------
def run_counts(runs: pd.DataFrame) -> pd.DataFrame:
    """Runs, succeeded, failed and summed wall time [s] per study (in the pipeline's study order), then a total row."""
    table = (
        runs.assign(ok=runs["status"] == "ok")
        .groupby("study", observed=True)
        .agg(n_runs=("status", "size"), n_ok=("ok", "sum"), wall_time=("wall_time", "sum"))
    )
    table = table.reindex([s for s in STUDIES if s in table.index]).reset_index()
    table["n_failed"] = table["n_runs"] - table["n_ok"]
    total = pd.DataFrame([{"study": "all", **table[["n_runs", "n_ok", "n_failed", "wall_time"]].sum().to_dict()}])
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


def plot_series(inputs: ReportInputs) -> dict[str, pd.DataFrame]:
    """The small series declared as DVC plots (``reports/plots/<name>``): one column per series, ``_pct`` in %.

    ``sobol.csv``: each factor's S1, ST and half-widths (ranking measure); ``ablation.csv``: per variant, each
    protocol's ablation statistics; ``tolerance.csv``: share of groups outside a tolerance t, per group and protocol;
    ``tilt.csv``: share of groups whose rear axle is the heaviest per 0.5 degree tilt band (static weighbridge).
    """
    sens = inputs.sensitivity_metrics["sobol"]
    sobol = pd.DataFrame([{"factor": rf.FACTOR_LABEL.get(f, f), **v} for f, v in sens["indices"].items()])
    ablation = inputs.sensitivity["ablation.csv"]
    ablation = ablation[(ablation["group"] == "all")]
    wide = ablation.assign(col=ablation["protocol"] + "_" + ablation["statistic"] + "_pct", v=100.0 * ablation["value"])
    wide = wide.pivot_table(index="variant", columns="col", values="v", sort=False).reset_index()
    wide["variant"] = wide["variant"].map(lambda v: rf.FACTOR_LABEL.get(v, v))
    grid = np.arange(0.0, 30.01, 0.5)
    tolerance, tilt = {"tolerance_pct": grid}, {}
    ok, bands = inputs.ok, inputs.survey["tilt.csv"]
    for group in rf.GROUP_LABEL:
        for protocol in ("static", "wim"):
            x = 100.0 * ok.loc[(ok["group"] == group) & (ok["protocol"] == protocol), "pair_difference"].to_numpy()
            share = 100.0 * (x[None, :] > grid[:, None]).mean(axis=1) if len(x) else np.full(len(grid), np.nan)
            tolerance[f"{group}_{protocol}_pct"] = np.round(share, 3)
        band = bands[(bands["group"] == group) & (bands["protocol"] == "static")]
        middle = 0.5 * (band["tilt_deg_low"] + band["tilt_deg_high"]).to_numpy()
        tilt[f"{group}_rear_heaviest_pct"] = pd.Series(100.0 * band["rear_heaviest_share"].to_numpy(), index=middle)
    tilt_frame = pd.DataFrame(tilt).sort_index().rename_axis("tilt_deg").reset_index()
    return {"sobol.csv": sobol, "ablation.csv": wide, "tolerance.csv": pd.DataFrame(tolerance), "tilt.csv": tilt_frame}


# ---- the words: generated from the numbers --------------------------------------------------------------------------
def pct(x: float | None, digits: int = 1) -> str:
    """A fraction as per cent text, "n/a" for a missing value (JSON null)."""
    return "n/a" if x is None or not np.isfinite(x) else f"{100.0 * x:.{digits}f} %"


def _label(name: str) -> str:
    return rf.FACTOR_LABEL.get(name, name)


def _groups(values: Mapping[str, str], noun: str = "groups") -> str:
    """ "a of tandem and b of tri-axle groups" for the groups present."""
    parts = [f"{v} of {rf.GROUP_LABEL.get(g, g)}" for g, v in values.items()]
    return " and ".join(parts) + f" {noun}" if parts else "no groups"


def summary_numbers(survey: Mapping[str, Any], sensitivity: Mapping[str, Any]) -> dict[str, Any]:
    """The numbers of the summary page, taken as they are from metrics/survey.json and metrics/sensitivity.json."""
    keys = (
        "share_outside_5pct",
        "share_outside_10pct",
        "mean_spread_kg",
        "mean_spread_pct",
        "rear_overload_share_nose_up",
    )
    headline = {
        protocol: {group: {k: entry[k] for k in keys} for group, entry in survey[protocol].items()}
        for protocol in ("static", "wim")
        if protocol in survey
    }
    copied = ("ranking", "ranking_measure", "reference_check", "ranking_other_measures", "sobol", "ablation")
    return {**{k: sensitivity[k] for k in copied}, "survey": headline}


def _num(x: float) -> str:
    """Two decimals, without the "-0.00" of a tiny negative estimate."""
    return f"{x + 0.0:.2f}".replace("-0.00", "0.00")


def _interval(x: float, half: float) -> str:
    return f"{_num(x)} ({_num(x - half)} to {_num(x + half)})"


def summary_paragraphs(numbers: Mapping[str, Any]) -> list[str]:
    """The summary in words: ranking, survey headline, nose-up overload, what removing each inhibitor buys."""
    sobol, check = numbers["sobol"], numbers["reference_check"]
    idx, conf = sobol["indices"], f"{100 * sobol['confidence_level']:.0f} %"
    ranked = "; ".join(
        f"{i}. {_label(f)}, ST {_interval(idx[f]['ST'], idx[f]['ST_conf'])}"
        for i, f in enumerate(numbers["ranking"], start=1)
    )
    external = " and ".join(f"{_label(f)} {_num(idx[f]['ST'])}" for f in idx if f not in numbers["ranking"])
    if check.get("agrees") is None:
        verdict = "The reference's claim could not be checked (an index is missing)."
    elif check["agrees"]:
        verdict = "As the reference concluded, spring-end friction ranks below bush stiffness and contact movement" + (
            ", and the intervals separate them."
            if check["resolved"]
            else f"; but the intervals overlap, so at base size {sobol['base_size']} the ordering is not resolved."
        )
    else:
        verdict = (
            "Unlike the reference's conclusion, spring-end friction does not rank below both bush stiffness "
            "and contact movement (docs/sensitivity.md discusses why)."
        )
    out = [
        "## Which inhibitor matters",
        f"By the {numbers['ranking_measure']}, with {conf} intervals, the four inhibitors rank: {ranked}. "
        f"For comparison, the total indices of the external causes in the same design: {external}. {verdict}",
    ]
    survey = numbers["survey"]
    if survey:
        out.append("## What a roadside survey of the fleet finds")
    for protocol, groups in survey.items():
        out5 = _groups({g: pct(v["share_outside_5pct"]) for g, v in groups.items()})
        out10 = _groups({g: pct(v["share_outside_10pct"]) for g, v in groups.items()})
        out.append(
            f"{rf.PROTOCOL_LABEL[protocol].capitalize()}: {out5} are outside 5 % (lightest axle more than 5 % below "
            f"the heaviest) and {out10} outside 10 % (an axle more than 10 % over its equal share). The heaviest "
            "axle carries on average "
            + " and ".join(
                f"{v['mean_spread_kg']:.0f} kg ({v['mean_spread_pct']:.2f} % of the mean axle load) more "
                f"than the lightest on {rf.GROUP_LABEL[g]} groups"
                for g, v in groups.items()
                if v["mean_spread_kg"] is not None
            )
            + "."
        )
    nose = {p: {g: pct(v["rear_overload_share_nose_up"]) for g, v in gs.items()} for p, gs in survey.items()}
    if nose:
        out.append(
            f"Tilted nose up by more than {NOSE_UP_DEG:g}°, the rear axle is the heaviest in "
            + "; ".join(f"{_groups(v)} ({rf.PROTOCOL_LABEL[p]})" for p, v in nose.items())
            + ": the rear overload the laboratory tilt tests found."
        )
    out.append("## What removing each inhibitor buys")
    for protocol, abl in numbers["ablation"].items():
        base = abl["baseline"]
        ranked = [v for v in numbers["ranking"] if v in abl]
        gains = ", ".join(
            f"{pct(abl[v]['mean_max_deviation'], 2)} without {_label(v)} (reduction "
            f"{100 * abl[v]['reduction']:.2f} points, {100 * abl[v]['reduction_low']:.2f} to "
            f"{100 * abl[v]['reduction_high']:.2f})"
            for v in ranked
            if abl[v]["reduction"] is not None
        )
        best = abl.get("largest_single_gain")
        out.append(
            f"{rf.PROTOCOL_LABEL[protocol].capitalize()}, {base['n_bogies']} fleet bogies: the fleet mean of the "
            f"maximum deviation from the mean axle load, {pct(base['mean_max_deviation'], 2)} with every inhibitor "
            f"present, becomes {gains}; and {pct(abl['all']['mean_max_deviation'], 2)} with all four removed. "
            + (
                f"The largest single gain is from removing {_label(best)}: the share outside 5 % goes from "
                f"{pct(base['share_outside_5pct'])} to {pct(abl[best]['share_outside_5pct'])}."
                if best
                else ""
            )
        )
    return out


def summary_table(numbers: Mapping[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The summary's one table: each inhibitor's Sobol' indices and ablation gain (sensitivity protocol)."""
    sobol, protocol = numbers["sobol"], numbers["sobol"]["protocol"]
    abl = numbers["ablation"].get(protocol) or next(iter(numbers["ablation"].values()))
    header = [
        "inhibitor",
        "rank",
        "ST (interval)",
        "S1 (interval)",
        "max. dev.\nwithout it [%]",
        "reduction [points]\n(interval)",
        "outside 5 %\nwithout it [%]",
    ]
    rows = []
    for rank, f in enumerate(numbers["ranking"], start=1):
        i, a = sobol["indices"][f], abl.get(f, {})
        gain = (
            "–"
            if a.get("reduction") is None
            else f"{100 * a['reduction']:.2f} ({100 * a['reduction_low']:.2f} to {100 * a['reduction_high']:.2f})"
        )
        rows.append(
            [
                _label(f),
                str(rank),
                _interval(i["ST"], i["ST_conf"]),
                _interval(i["S1"], i["S1_conf"]),
                pct(a.get("mean_max_deviation"), 2)[:-2],
                gain,
                pct(a.get("share_outside_5pct"))[:-2],
            ]
        )
    a = abl["all"]
    rows.append(
        [
            "all four removed",
            "",
            "",
            "",
            pct(a["mean_max_deviation"], 2)[:-2],
            f"{100 * a['reduction']:.2f} ({100 * a['reduction_low']:.2f} to {100 * a['reduction_high']:.2f})",
            pct(a["share_outside_5pct"])[:-2],
        ]
    )
    b = abl["baseline"]
    rows.append(
        ["none removed", "", "", "", pct(b["mean_max_deviation"], 2)[:-2], "", pct(b["share_outside_5pct"])[:-2]]
    )
    return header, rows


def table_title(numbers: Mapping[str, Any]) -> str:
    """Title of the summary table."""
    s = numbers["sobol"]
    return f"The four inhibitors: Sobol' indices and what removing each buys ({s['protocol']}, {s['group']} design)"


def table_notes(numbers: Mapping[str, Any]) -> list[str]:
    """What the summary table's columns are and where they come from."""
    s = numbers["sobol"]
    n = (numbers["ablation"].get(s["protocol"]) or {}).get("baseline", {}).get("n_bogies", "–")
    return [
        f"ST, S1: total and first-order Sobol' index of {s['measure']} ({s['protocol']}, {s['group']}) from "
        f"{s['n_blocks']} of {s['base_size']} Saltelli blocks ({s['n_failed']} failed runs, their blocks dropped); "
        f"interval: ± the half-width of SALib's bootstrap interval ({s['bootstrap_resamples']} resamples, "
        f"{100 * s['confidence_level']:.0f} %). Ablation ({s['protocol']}, {n} fleet bogies): fleet mean of the "
        "maximum deviation and share outside 5 % with the inhibitor set to its ideal value (zero stiffness, zero "
        "damping, fixed contact point, no friction); reduction = baseline minus that, in percentage points, with "
        "a paired bootstrap interval; negative means worse. Sources: metrics/sensitivity.json, "
        "metrics/survey.json."
    ]


def sensitivity_caption(numbers: Mapping[str, Any]) -> list[str]:
    """Caption of the sensitivity page."""
    s = numbers["sobol"]
    others = "; ".join(
        f"by {rf.MEASURE_LABEL.get(m, m)}: " + " > ".join(_label(f) for f in r)
        for m, r in numbers["ranking_other_measures"].items()
    )
    n = {p: a["baseline"]["n_bogies"] for p, a in numbers["ablation"].items()}
    return [
        f"Top left: first-order (S1, grey) and total (ST, blue) Sobol' indices of the maximum deviation of the "
        f"{rf.GROUP_LABEL.get(s['group'], s['group'])} bogie's axle loads at the "
        f"{rf.PROTOCOL_LABEL.get(s['protocol'], s['protocol'])} ({s['n_blocks']} Saltelli blocks, base size "
        f"{s['base_size']}); whiskers: ± the half-width of the {100 * s['confidence_level']:.0f} % bootstrap "
        "interval. ST − S1 is what a factor adds through interactions; a slightly negative estimate is sampling "
        f"noise (about 0). Top right: ST of each inequality measure; the inhibitors rank {others}.",
        f"Bottom: the ablation, {', '.join(f'{v} fleet bogies ({p})' for p, v in n.items())}, each with one "
        "inhibitor (or all four) set to its ideal value: the fleet mean of the maximum deviation (left) and the "
        "share of groups outside 5 % (right); whiskers: paired bootstrap interval of the change. A Sobol' index "
        "shares the variance over the ranges params.yaml gives each factor; the ablation measures the step from "
        "where the fleet is to the ideal. Read both.",
    ]


def load_share_caption(survey: Mapping[str, Any], groups: Sequence[str], protocols: Sequence[str]) -> list[str]:
    """Caption of the load-share page."""
    at5 = "; ".join(
        f"{rf.PROTOCOL_LABEL[p]}: "
        + _groups({g: pct(survey[p][g]["share_outside_5pct"]) for g in groups if g in survey[p]})
        for p in protocols
    )
    return [
        f"Top: the load share of each axle position (its load over the group's mean axle load; 1 is an equal "
        f"share) over the fleet study's {survey['n_ok']} succeeded weighings ({survey['n_failed']} failed, listed "
        "in Appendix C); each panel spans its central 99 % of axles; grey band: within 10 % of an equal share. "
        "Bottom left: heaviest minus lightest axle "
        "[kg] (box: quartiles and median; whiskers: 5th and 95th percentiles; diamond: mean). Bottom right: the "
        "share of groups whose lightest axle is more than t below the heaviest, for every tolerance t, solid "
        f"static, dashed WIM; at t = 5 %: {at5}."
    ]


def tilt_caption(survey: Mapping[str, Any], groups: Sequence[str], protocols: Sequence[str], main: str) -> list[str]:
    """Caption of the tilt and static-against-WIM page."""
    nose = _groups({g: pct(survey[main][g]["rear_overload_share_nose_up"]) for g in groups if g in survey[main]})
    text = [
        f"Top: every bogie's maximum deviation against its chassis tilt (fifth-wheel height mismatch, nose up "
        f"positive), coloured by its heaviest axle ({rf.PROTOCOL_LABEL[main]}). Middle: the mean load share of each "
        "axle per 0.5° tilt band, solid static, dashed WIM. Nose up moves load to the rear: tilted nose up by more "
        f"than {NOSE_UP_DEG:g}°, the rear axle is the heaviest in {nose}."
    ]
    pairs = survey.get("static_vs_wim") or {}
    if pairs:
        text.append(
            "Bottom: the same bogies weighed both ways (left: maximum deviation; right: each axle's load "
            "share). WIM minus static maximum deviation averages "
            + "; ".join(
                f"{100 * v['mean_dynamic_excess']:.2f} points on {v['n_pairs']} {rf.GROUP_LABEL[g]} groups "
                f"(correlation {v['corr_max_deviation']})"
                for g, v in pairs.items()
            )
            + ". WIM adds the dynamic loads of the road; the weighbridge reads what friction locks in after "
            "the crawl and the stop."
        )
    else:
        text.append(f"Bottom: empty, since only {', '.join(protocols)} ran; static against WIM needs both protocols.")
    return text


#: what the reference said of each reproduced run (its own words, quoted), and which of its figures show it
REFERENCE_SAID = {
    "L01": (
        "Figures 5-8",
        '"At this speed a steady state is achieved with each wheel on the step, with a rapidly '
        'damped oscillation at the start and end of the lift."',
    ),
    "L02": (
        "Figures 9-12",
        'the step is traversed in about a third of a second; "much higher wheel loads are '
        'generated with greater inequality between the two."',
    ),
    "L03": (
        "Figure 15",
        '"good equalisation over the two steady state regions", although "spikes occur in the plot '
        'at the times when a wheel rises over the front edge or falls off the rear edge."',
    ),
    "N10": ("Figure 16", "zero friction and zero bush stiffness"),
    "N19": ("Figure 17", "contact points fixed (linear constraints)"),
    "N20": ("Table 2", "rolling contact (non-linear constraints)"),
    "N21": ("Table 2", "long equaliser arm"),
}


def figure2_caption(points: Mapping[float, tuple[float, float]], alpha: float) -> list[str]:
    """Caption of Figure 2: what the reference reported, then our curves and finite element points."""
    stage1 = triaxle_stage1()
    spacing = stage1.axle_x[1] - stage1.axle_x[0]
    fe_p = ", ".join(f"{v[1]:.3f}" for v in points.values())
    algebra = ", ".join(
        f"{float(metrics.p(nondimensional_loads(q, np.radians(s) * spacing / alpha))):.3f}"
        for s, (q, _) in points.items()
    )
    slopes = ", ".join(f"{s:g}" for s in points)
    return [
        'What the reference reported: the curves of Equations 1 and 2 show "that equalisation of wheel loads is '
        'ineffective unless a relatively flexible equaliser pivot bush is used"; its five starred Stage 1 finite '
        'element points "show good agreement with the Stage 2 algebraic approach, although a small deviation is '
        "apparent for low angles of slope\" (which it put down to the drag links), and the Stage 1 suspension's "
        'q = 4.3 is "so low that effective equalisation of axle loads is impossible".',
        f"Ours: the curves are Equation 1 of a tri-axle bogie with α = {1e3 * alpha:.0f} mm (bogie.static); the "
        f"stars are our finite element model of the Stage 1 bogie without drag links (bogie.fe) at "
        f"q = {next(iter(points.values()))[0]:.1f}: p = {fe_p} for slopes {slopes}° against {algebra} from "
        "Equation 1. Stiffer bushes (small q) and larger slopes give larger p.",
    ]


def linear_caption(name: str, ours: Mapping[str, float], reference: Mapping[str, float]) -> list[str]:
    """Caption of a linear run's page."""
    figures, words = REFERENCE_SAID[name]
    return [
        f"What the reference reported (Table 1, {figures}): peak p = {reference['peak_p']:g}, "
        f"P1 = {reference['peak_p1']:g}; {words}",
        f'Ours (bogie.cases.run("{name}"): the Stage 3 linear model of tandem_trrl() over the 25 mm ramped step '
        f"with Table 1's settings): peak p = {ours['peak_p']:.3f}, P1 = {ours['peak_p1']:.3f}, "
        f"{ours['peak_p'] / reference['peak_p']:.2f} times the reference's p. Panels: the suspension centre's "
        "displacement [mm]; p (Equation 2) and P1 (Equation 4) of the wheel loads over their initial mean; the "
        "wheel loads [kN]. The reference's two-axle geometry (its Figure 3) is lost, so trends rather than values "
        "are compared (docs/validation.md).",
    ]


def step_titles(ours: Mapping[str, Mapping[str, float]], refs: Mapping[str, tuple[float, float]]) -> dict[str, str]:
    """Panel titles of the step runs: what each run is, our and the reference's P1 front / rear [N]."""
    return {
        n: f"{n}: {REFERENCE_SAID[n][1]}\nours {v['p1_front_on_step']:.0f} / {v['p1_rear_on_step']:.0f} N, "
        f"reference {refs[n][0]:.0f} / {refs[n][1]:.0f} N"
        for n, v in ours.items()
    }


def step_caption(
    ours: Mapping[str, Mapping[str, float]], refs: Mapping[str, tuple[float, float]], l03_mean: float
) -> list[str]:
    """Caption of the non-linear step runs page."""

    def front(n: str) -> float:
        return ours[n]["p1_front_on_step"]

    return [
        "What the reference reported (Figures 15-17, Table 2): the linear L03 equalises, while the non-linear N10 "
        f'"shows a substantial difference in wheel loads, amounting to {refs["N10"][0]:.0f}N with the front wheel '
        f'on the step, and {refs["N10"][1]:.0f}N when the rear wheel is lifted". Fixing the contact points (N19, '
        f'{refs["N19"][0]:.0f} / {refs["N19"][1]:.0f} N) gave plots "very similar to Figure 15": "movement of '
        'contact can be a very definite source of poor equalisation, ranking about equally with bush stiffness". '
        f"N20 gave {refs['N20'][0]:.0f} / {refs['N20'][1]:.0f} N and the long arm of N21 "
        f'{refs["N21"][0]:.0f} / {refs["N21"][1]:.0f} N: "an increase in link arm radius reduces the importance '
        'of contact point movement".',
        "Ours: P1 (Equation 4) in kN against time at 0.2 m/s, with the front and then the rear wheel alone on the "
        "25 mm step; panel titles give the mean P1 over the middle of each phase, front / rear. Fixed contact "
        f"points leave {100 * front('N19') / front('N20'):.0f} % of N20's front figure; the long arm "
        f"{100 * front('N21') / front('N20'):.0f} %. L03 (grey) averages {l03_mean:.0f} N over its run. Dotted: "
        "the reference's figures (blue front, green rear).",
    ]


def _cell_text(cell: Any) -> str:
    return (
        f"{100 * cell.share:.0f} % within 5 % (n = {int(cell.n)}) at bush stiffness {cell.x_low:g}-{cell.x_high:g} "
        f"N m/rad and arms {cell.y_low:.0f}-{cell.y_high:.0f} mm"
    )


def design_caption(grids: Mapping[str, pd.DataFrame], lines: Mapping[str, pd.DataFrame], protocol: str) -> list[str]:
    """Caption of the design guidance page: which cells and bins reach the target, and the caveat."""
    target = f"{100 * DESIGN_TARGET:.0f} %"
    out = [
        f"Target: {target} of bogies within 5 % at the {rf.PROTOCOL_LABEL[protocol]}. Maps: the share within 5 % "
        "in each cell of bush stiffness by equaliser arm length, with the number of bogies; bold: at or above the "
        "target. Lines: one parameter at a time, shaded 95 % Wilson intervals. Quoted below: cells and bins of "
        f"at least {MIN_CELL} bogies."
    ]
    for group, cells in grids.items():
        quoted = cells[cells["n"] >= MIN_CELL]
        name = rf.GROUP_LABEL[group].capitalize()
        if quoted.empty:
            out.append(f"{name}: no cell holds {MIN_CELL} bogies; too few runs for guidance.")
            continue
        good = quoted[quoted["share"] >= DESIGN_TARGET]
        best = quoted.loc[quoted["share"].idxmax()]
        reach = (
            f"{len(good)} of {len(quoted)} cells reach the target, e.g. {_cell_text(good.iloc[0])}"
            if len(good)
            else f"no cell of {len(quoted)} reaches the target; the best is {_cell_text(best)}"
        )
        out.append(f"{name}: {reach}.")
    trends = []
    for label, bins in lines.items():
        parts = []
        for group in dict.fromkeys(bins["group"]):
            b = bins[(bins["group"] == group) & (bins["n"] >= MIN_CELL)]
            if len(b):
                parts.append(f"{rf.GROUP_LABEL[group]} {pct(b['share'].iloc[0], 0)} to {pct(b['share'].iloc[-1], 0)}")
        if parts:
            trends.append(f"{label.split(' [')[0]} ({', '.join(parts)})")
    if trends:
        out.append("From the lowest to the highest bin, the share within 5 % goes: " + "; ".join(trends) + ".")
    out.append(
        "Caveat: these are the fleet's runs as sampled, not a controlled experiment: every other factor "
        "(tilt, tyre wear, contact radius, friction, payload, road) varies within a cell or bin as params.yaml "
        "samples it, so a share is what a fleet of that design would show on the road."
    )
    return out


#: sampled quantities shown in Appendix A: column (or columns), params.yaml key, label, edge unit, SI -> edge, log
SAMPLED: tuple[tuple[str, str, str, str, float, bool], ...] = (
    ("bush_stiffness", "bush_stiffness", "bush stiffness", "N m/rad", 1.0, True),
    ("bush_damping", "bush_damping", "bush damping", "N m s/rad", 1.0, True),
    ("friction_coefficient", "friction_coefficient", "spring-end friction coefficient", "-", 1.0, False),
    ("contact_roll_radius", "contact_roll_radius_mm", "contact roll radius", "mm", 1e3, False),
    ("equaliser_arm", "equaliser_arm_mm", "equaliser arm", "mm", 1e3, False),
    ("tyre_wear", "tyre_wear_mm", "tyre wear, every tyre", "mm", 1e3, False),
    ("chassis_tilt", "chassis_tilt_deg", "chassis tilt, nose up +", "degree", float(np.degrees(1.0)), False),
    ("payload_fraction", "payload_fraction", "payload, fraction of the legal group load", "-", 1.0, False),
)


def _spec(raw: Mapping[str, Any] | None) -> str:
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
    """The charts of Appendix A: each sampled quantity of the fleet in edge units, with its params.yaml entry."""
    dists = raw.get("distributions", {})
    panels = []
    for column, key, label, unit, scale, log in SAMPLED:
        if column == "tyre_wear":
            values = np.concatenate([fleet.loc[fleet["n_axles"] > i, c] for i, c in enumerate(TYRE_WEAR_COLUMNS)])
        else:
            values = fleet[column].to_numpy(dtype=float)
        panels.append(
            {
                "title": f"{label}\n{_spec(dists.get(key))}",
                "xlabel": f"{label} [{unit}]",
                "values": scale * values,
                "log": log,
            }
        )
    road = dists.get("road_class", {})
    weights = np.asarray(road.get("weights") or [1.0] * len(road.get("values", [])), dtype=float)
    expected = dict(zip(road.get("values", []), len(fleet) * weights / weights.sum())) if weights.size else None
    counts = (
        fleet["road_class"].value_counts().reindex(road.get("values") or sorted(set(fleet["road_class"])), fill_value=0)
    )
    panels.append(
        {
            "title": f"approach road, ISO 8608 class\n{_spec(road)}",
            "xlabel": "road class",
            "categories": counts.to_dict(),
            "expected": expected,
        }
    )
    mix = dict(config.fleet.axle_mix)
    groups = fleet["group"].value_counts().reindex(list(mix), fill_value=0)
    panels.append(
        {
            "title": "axle group\nmix " + ", ".join(f"{rf.GROUP_LABEL[g]} {w:g}" for g, w in mix.items()),
            "xlabel": "axle group",
            "categories": {rf.GROUP_LABEL[g]: n for g, n in groups.items()},
            "expected": {rf.GROUP_LABEL[g]: len(fleet) * w for g, w in mix.items()},
        }
    )
    return panels


def parameters_caption(fleet: pd.DataFrame, config: Config) -> list[str]:
    """Caption of Appendix A."""
    return [
        f"The {len(fleet)} bogies of the fleet study as sampled ({config.fleet.sampling}: "
        f"{'Latin hypercube' if config.fleet.sampling == 'lhs' else 'scrambled Sobol'}, seed {config.seed}), in "
        "params.yaml's units; each title gives the params.yaml distribution. Tyre wear pools every tyre of every "
        "group (independent per axle). Bars: sampled counts; black marks: the counts the weights expect."
    ]


def definitions(config: Config) -> list[str]:
    """Appendix B: the protocols, the definitions of every reported quantity, the model assumptions in short."""
    st, wim, sens = config.protocol.static, config.protocol.wim, config.sensitivity
    return [
        "## Survey protocols (params.yaml, protocol:)",
        f"- Static weighbridge (static): the empty trailer ({100 * TARE_FRACTION:.0f} % of the design payload weight) "
        f"is loaded to its sampled payload fraction over {st.load_time:g} s on level ground, crawls at "
        f"{st.crawl_speed:g} m/s over {st.approach_length:g} m of random road (ISO 8608, the bogie's class and "
        f"seed) onto a level weighbridge, stops and settles for {st.settle_time:g} s; each axle's reading is its "
        f"mean load over the last {READ_TIME:g} s. Time step {1e3 * st.dt:g} ms.",
        f"- Weigh-in-motion (wim): the laden trailer passes at {wim.speed:g} m/s ({3.6 * wim.speed:.0f} km/h) over "
        f"{wim.approach_length:g} m of random road with a sensor at its end; each axle's load is read as that axle "
        f"crosses it. Time step {1e3 * wim.dt:g} ms.",
        f"- Both run the full non-linear model of one side of the bogie; axle loads are twice the wheel loads. "
        f"Protocols run: {', '.join(config.protocol.run)}; the Sobol' design runs {sens.protocol} only.",
        "## Definitions (docs/outputs.md)",
        "- Load share of axle i: n W_i / sum of W_j (1 = equal share). Maximum deviation: max |W_i - W_mean| / W_mean. "
        "Spread: heaviest minus lightest axle, in kg (over g) and in % of the mean axle load.",
        f"- Outside 5 % (VSB 11): (max W - min W) / max W > {PAIR_TOLERANCE:g}. Outside 10 %: the largest load share "
        f"> {1 + SHARE_TOLERANCE:g}. Nose up: chassis tilt above {NOSE_UP_DEG:g}° (positive nose up).",
        "- p: the reference's Equation 2; P1: its Equation 4 (RMS deviation of the loads about their mean); "
        "road-wear factor: the mean of (W_i / W_mean)^4 (1 = equal loads).",
        "- Failed runs are excluded from every statistic and listed in Appendix C.",
        "## Studies",
        f"- Fleet: {config.fleet.size} bogies ({config.fleet.sampling}, seed {config.seed}), axle mix "
        + ", ".join(f"{rf.GROUP_LABEL[g]} {w:g}" for g, w in config.fleet.axle_mix.items())
        + "; the base bogies are the presets "
        + ", ".join(config.fleet.presets.values())
        + " with the sprung mass that makes their design load the legal group load.",
        f"- Sobol': SALib's Saltelli design of base size {sens.base_size} over {', '.join(sens.factors)} on the "
        f"{rf.GROUP_LABEL[sens.group]} base bogie; every other quantity at its median, one approach road.",
        f"- Ablation: the first {config.ablation.size} fleet bogies, each as the baseline, each inhibitor at its ideal "
        "value (zero bush stiffness, zero damping, fixed contact point, no friction) and all four at once.",
        "## The model in short (docs/models.md)",
        "- One side of an n-axle bogie, both sides alike; the king pin is a fixed pivot; freedoms: chassis pitch, "
        "each equaliser's rotation, each axle's vertical displacement; axles located fore and aft at their design x.",
        '- Leaf springs: massless "mathematical springs" with a linear rate and lever-rule end loads; their chord '
        "grows and their ends flatten linearly with deflection, so the ends slide on their pads.",
        "- Inhibitors: bush rotational stiffness and damping between equaliser and chassis; spring ends that roll on "
        "convex pads (contact point moves by the roll radius times the relative rotation); Coulomb friction with "
        "stick and slip at the spring ends (elastic-plastic return map, limit from the elastic normal load).",
        "- Tyres: linear point contact that can lift off; per-axle wear lowers the wheel. Equaliser stops are not "
        "modelled: at large tilts with free bushes results overstate what a real bogie does.",
        "- Time stepping: Newmark / generalised-alpha with Newton iterations; a run that does not converge is a "
        "failed run with the solver's message, never a number.",
    ]


def failures_table(failed: pd.DataFrame) -> tuple[list[str], list[list[str]], list[float]]:
    """Header, rows and column widths of Appendix C (long messages and id lists wrapped)."""
    rows = []
    for r in failed.itertuples():
        ids = r.sample_ids.split()
        shown = " ".join(ids[:12]) + (f" ... ({len(ids)} in all)" if len(ids) > 12 else "")
        variant = "–" if r.variant == "baseline" and r.study != "ablation" else _label(r.variant)
        rows.append(
            [
                r.study,
                r.protocol,
                rf.GROUP_LABEL.get(r.group, r.group),
                "\n".join(textwrap.wrap(variant, 14)),
                str(r.n),
                "\n".join(textwrap.wrap(shown, 24)),
                "\n".join(textwrap.wrap(str(r.message), 50)),
            ]
        )
    header = ["study", "protocol", "group", "variant", "runs", "sample ids", "message (of the first)"]
    return header, rows, [0.1, 0.08, 0.08, 0.12, 0.05, 0.18, 0.39]


def failures_intro(failed: pd.DataFrame) -> list[str]:
    """The sentence above Appendix C's table."""
    if failed.empty:
        return ["No run failed: every sample of every study gave a reading under every protocol it ran."]
    n = int(failed["n"].sum())
    return [
        f"{n} run{'s' if n != 1 else ''} failed, grouped below by study, protocol, axle group, variant and kind of "
        "message (messages that differ only in their numbers are one kind; the first is shown), with their "
        "sample_id (row of data/samples/<study>.parquet). Every message: the runs dataset's rows with status "
        '"failed". Failed runs are excluded from every statistic; a Sobol\' block with a failed run is dropped whole '
        "(docs/sensitivity.md)."
    ]


def _duration(seconds: float) -> str:
    """A duration as "1.25 h", "12.3 min" or "45.6 s"."""
    if seconds >= 3600.0:
        return f"{seconds / 3600.0:.2f} h"
    return f"{seconds / 60.0:.1f} min" if seconds >= 60.0 else f"{seconds:.1f} s"


def title_facts(
    facts: Mapping[str, str], config: Config, fleet: pd.DataFrame, counts: pd.DataFrame
) -> list[tuple[str, str]]:
    """The key-value lines of the title page."""
    total = counts[counts["study"] == "all"].iloc[0]
    groups = fleet["group"].value_counts()
    sens = config.sensitivity
    return [
        ("Date", facts["date"]),
        ("Git revision", facts["revision"]),
        ("params.yaml sha256", facts["params_sha256"]),
        (
            "Fleet",
            f"{len(fleet):,} bogies: "
            + ", ".join(f"{groups.get(g, 0):,} {rf.GROUP_LABEL[g]}" for g in config.fleet.axle_mix),
        ),
        ("Sobol' design", f"base size {sens.base_size}, {sens.protocol} protocol, {rf.GROUP_LABEL[sens.group]} bogie"),
        ("Ablation", f"{config.ablation.size} fleet bogies x 6 variants"),
        ("Runs", f"{int(total.n_ok):,} succeeded, {int(total.n_failed):,} failed, of {int(total.n_runs):,}"),
        ("Simulation time", _duration(float(total.wall_time)) + ", summed over the runs (worker time)"),
    ]


# ---- the pages -----------------------------------------------------------------------------------------------------
def _p1_newtons(result: DynamicResult) -> np.ndarray:
    """P1 (Equation 4) of a run's wheel loads in newtons, at every step."""
    return np.asarray(metrics.p1(result.wheel_loads))


def reference_runs() -> dict[str, DynamicResult]:
    """Run the reference's named cases the report reproduces (:data:`REFERENCE_RUNS`), by name."""
    return {name: cases.run(name) for name in REFERENCE_RUNS}


def build_pages(
    inputs: ReportInputs, runs: Mapping[str, DynamicResult]
) -> tuple[list[tuple[str, str, Figure]], dict[str, Any]]:
    """Every page of the report, in order, and the summary's numbers.

    Parameters
    ----------
    inputs
        What the pipeline wrote (:func:`read_inputs`).
    runs
        The reference cases' results (:func:`reference_runs`).

    Returns
    -------
    pages : list
        (section, PNG name or "" for a page without charts, Figure), the title page first.
    numbers : dict
        The numbers the summary's sentences are made from, as read from metrics/*.json.
    """
    cfg, ok, sv, ss = inputs.config, inputs.ok, inputs.survey_metrics, inputs.sensitivity_metrics
    groups = [g for g in ("tandem", "triaxle") if g in set(ok["group"])]
    protocols = [p for p in cfg.protocol.run if p in set(ok["protocol"])]
    numbers = summary_numbers(sv, ss)
    pages: list[tuple[str, str, Figure]] = []
    header, rows = summary_table(numbers)
    pages.append(
        (
            "Summary",
            "",
            rf.summary_page(summary_paragraphs(numbers), header, rows, table_title(numbers), table_notes(numbers)),
        )
    )
    abl = inputs.sensitivity["ablation.csv"]
    pages.append(
        (
            "Sensitivity",
            "sensitivity",
            rf.sensitivity_page(
                inputs.sensitivity["sobol_indices.csv"],
                abl[abl["group"] == "all"],
                ss["sobol"]["measure"],
                sensitivity_caption(numbers),
            ),
        )
    )
    pages.append(
        (
            "Survey",
            "survey_load_share",
            rf.load_share_page(ok, groups, protocols, load_share_caption(sv, groups, protocols)),
        )
    )
    main = cfg.sensitivity.protocol if cfg.sensitivity.protocol in protocols else protocols[0]
    pages.append(
        (
            "Survey",
            "survey_tilt",
            rf.tilt_page(
                ok,
                inputs.survey["tilt.csv"],
                inputs.survey["static_vs_wim_pairs.parquet"],
                groups,
                main,
                tilt_caption(sv, groups, protocols, main),
            ),
        )
    )
    f2 = inputs.raw_params.get("figure2") or {}
    slopes = tuple(float(s) for s in f2.get("slopes_deg", (0.0, 0.5, 1.0, 1.5, 2.0)))
    alpha = float(f2.get("chassis_deflection_mm", 57.0)) / 1e3
    points = fe.figure2_points(slopes_deg=slopes, chassis_deflection=alpha)
    fig2 = figure2(q_max=float(f2.get("q_max", 20.0)), slopes_deg=slopes, chassis_deflection=alpha, fe_points=points)
    page = rf.adopt_page(fig2, "Reference: Figure 2, static equalisation (Stages 1 and 2)", (0.1, 0.48, 0.8, 0.45))
    rf.text_block(page, 0.45, figure2_caption(points, alpha))
    pages.append(("Reproduction of the reference", "reference_figure2", page))
    for name in REFERENCE_RUNS[:3]:
        page = rf.adopt_page(
            case_history(runs[name]), f"Reference: linear run {name} (Table 1)", (0.08, 0.3, 0.84, 0.63)
        )
        rf.text_block(page, 0.28, linear_caption(name, cases.summary(name, runs[name]), cases.get(name).reference))
        pages.append(("Reproduction of the reference", f"reference_{name}", page))
    step = REFERENCE_RUNS[3:]
    summaries = {n: cases.summary(n, runs[n]) for n in step}
    refs = {n: (cases.get(n).reference["p1_front_on_step"], cases.get(n).reference["p1_rear_on_step"]) for n in step}
    l03 = runs["L03"]
    pages.append(
        (
            "Reproduction of the reference",
            "reference_step_runs",
            rf.step_runs_page(
                {n: (runs[n].t, _p1_newtons(runs[n])) for n in step},
                (l03.t, _p1_newtons(l03)),
                refs,
                step_titles(summaries, refs),
                step_caption(summaries, refs, float(np.mean(_p1_newtons(l03)))),
            ),
        )
    )
    grids, lines = rf.design_tables(ok, main)
    pages.append(
        (
            "Design guidance",
            "design_guidance",
            rf.design_page(grids, lines, DESIGN_TARGET, design_caption(grids, lines, main)),
        )
    )
    pages.append(
        (
            "Appendix A: parameters as sampled",
            "parameters",
            rf.parameters_page(
                parameter_panels(inputs.fleet, inputs.raw_params, cfg), parameters_caption(inputs.fleet, cfg)
            ),
        )
    )
    pages.append(
        (
            "Appendix B: protocols, definitions, assumptions",
            "",
            rf.text_page("Appendix B: protocols, definitions and model assumptions", definitions(cfg)),
        )
    )
    failed = failed_runs(inputs.runs)
    header, rows, widths = failures_table(failed)
    for k, page in enumerate(
        rf.failures_pages("Appendix C: failed runs", header, rows, failures_intro(failed), widths)
    ):
        pages.append(("Appendix C: failed runs" if k == 0 else "", "", page))
    counts = run_counts(inputs.runs)
    contents, seen = [], set()
    for n, (section, _, _) in enumerate(pages, start=2):
        if section and section not in seen:
            seen.add(section)
            contents.append((section, n))
    title = rf.title_page(TITLE, SUBTITLE, title_facts(inputs.facts, cfg, inputs.fleet, counts), counts, contents)
    return [("Title", "", title), *pages], numbers


# ---- writing -----------------------------------------------------------------------------------------------------
def _swap_dir(tmp: Path, final: Path) -> None:
    """Replace directory ``final`` by ``tmp`` with renames (the old one is removed after)."""
    old = final.with_name(f".{final.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    if final.exists():
        os.replace(final, old)
    os.replace(tmp, final)
    shutil.rmtree(old, ignore_errors=True)


def write_report(
    pages: Sequence[tuple[str, str, Figure]],
    series: Mapping[str, pd.DataFrame],
    pdf_path: str | Path,
    png_dir: str | Path,
    plots_dir: str | Path,
    revision: str,
) -> None:
    """Number the pages and write the PDF, the PNG pages and the plot series, each by temporary name and rename."""
    pdf_path, png_dir, plots_dir = Path(pdf_path), Path(png_dir), Path(plots_dir)
    for d in (pdf_path.parent, png_dir.parent, plots_dir.parent):
        d.mkdir(parents=True, exist_ok=True)
    rf.number_pages([fig for _, _, fig in pages], f"{TITLE} · revision {revision}")
    fd, tmp_pdf = tempfile.mkstemp(prefix=f".{pdf_path.name}.", suffix=".tmp", dir=pdf_path.parent)
    os.close(fd)
    tmp_png = Path(tempfile.mkdtemp(prefix=f".{png_dir.name}.", suffix=".tmp", dir=png_dir.parent))
    tmp_plots = Path(tempfile.mkdtemp(prefix=f".{plots_dir.name}.", suffix=".tmp", dir=plots_dir.parent))
    try:
        metadata = {"Title": TITLE, "Subject": SUBTITLE, "Creator": "bogie pipeline.report", "CreationDate": None}
        with PdfPages(tmp_pdf, metadata=metadata) as pdf:
            for _, _, fig in pages:
                pdf.savefig(fig)
        for _, name, fig in pages:
            if name:
                fig.savefig(tmp_png / f"{name}.png", format="png", dpi=PNG_DPI)
        for name, frame in series.items():
            frame.to_csv(tmp_plots / name, index=False, float_format="%.6g")
        for d in (tmp_png, tmp_plots):
            os.chmod(d, 0o755)  # mkdtemp makes it private
        os.chmod(tmp_pdf, 0o644)
        _swap_dir(tmp_png, png_dir)
        _swap_dir(tmp_plots, plots_dir)
        os.replace(tmp_pdf, pdf_path)
    finally:
        Path(tmp_pdf).unlink(missing_ok=True)
        shutil.rmtree(tmp_png, ignore_errors=True)
        shutil.rmtree(tmp_plots, ignore_errors=True)


def make_report(inputs: ReportInputs, pdf: str | Path, png_dir: str | Path, plots_dir: str | Path) -> dict[str, Any]:
    """Build and write the whole report; returns the summary's numbers and the page count (key ``pages``)."""
    runs = reference_runs()
    with matplotlib.rc_context(rf.STYLE):
        pages, numbers = build_pages(inputs, runs)
        write_report(pages, plot_series(inputs), pdf, png_dir, plots_dir, inputs.facts["revision"])
    return {**numbers, "pages": len(pages)}


def main(argv: list[str] | None = None) -> int:
    """Run the stage from the command line."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.report", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--samples", default="data/samples", help="sample tables (default: data/samples)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--survey", default="data/survey", help="survey tables (default: data/survey)")
    parser.add_argument("--sensitivity", default="data/sensitivity", help="default: data/sensitivity")
    parser.add_argument("--metrics", default="metrics", help="directory of survey.json, sensitivity.json")
    parser.add_argument("--pdf", default="reports/sensitivity_report.pdf", help="the report")
    parser.add_argument("--png", default="reports/figures/report", help="directory of the PNG pages")
    parser.add_argument("--plots", default="reports/plots", help="directory of the DVC plot series")
    args = parser.parse_args(argv)
    try:
        inputs = read_inputs(args.params, args.samples, args.runs, args.survey, args.sensitivity, args.metrics)
    except (ConfigError, RunsError, OSError, KeyError, ValueError, yaml.YAMLError) as exc:
        print(f"report: {exc}", file=sys.stderr)
        return 2
    numbers = make_report(inputs, args.pdf, args.png, args.plots)
    failed = int(inputs.runs["status"].ne("ok").sum())
    print(f"report: wrote {args.pdf} ({numbers['pages']} pages; {failed} failed runs listed), {args.png}, {args.plots}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
