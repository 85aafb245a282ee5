"""Front matter: the title page (build facts, run counts, contents) and the summary (words and one table)."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from bogie.fleet.sampling import VARIANTS
from bogie.fleet.survey import NOSE_UP_DEG
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import A4, LEFT, RIGHT, first_fit, page_header, table_axes, text_block
from pipeline.report.style import GROUP_LABEL, factor_label
from pipeline.report.tables import run_counts

__all__ = ["SUBTITLE", "TITLE", "summary", "summary_page", "summary_table", "title", "title_facts", "title_page"]

TITLE = "Why mechanically equalised trailer bogies do not share load equally"
SUBTITLE = "Sensitivity report: the five inhibitors of axle-load equalisation across a sampled fleet"


# ---- title page ----------------------------------------------------------------------------------------------------
def title_facts(
    facts: Mapping[str, str], config: Any, fleet: pd.DataFrame, counts: pd.DataFrame
) -> list[tuple[str, str]]:
    """The key-value lines of the title page."""
    total = counts[counts["study"] == "all"].iloc[0]
    groups = fleet["group"].value_counts()
    sens = config.sensitivity
    dated = [("Date", facts["date"])] if facts.get("date") else []
    return [
        *dated,
        ("Code sha256", facts["code_sha256"]),
        ("params.yaml sha256", facts["params_sha256"]),
        (
            "Fleet",
            f"{len(fleet):,} bogies: "
            + ", ".join(f"{groups.get(g, 0):,} {GROUP_LABEL[g]}" for g in config.fleet.axle_mix),
        ),
        ("Sobol' design", f"base size {sens.base_size}, {sens.protocol} protocol, {GROUP_LABEL[sens.group]} bogie"),
        ("Ablation", f"{config.ablation.n_bogies} fleet bogies x {len(VARIANTS)} variants"),
        ("Runs", f"{int(total.n_ok):,} succeeded, {int(total.n_failed):,} failed, of {int(total.n_runs):,}"),
    ]


def title_page(
    title: str,
    subtitle: str,
    facts: Sequence[tuple[str, str]],
    counts: pd.DataFrame,
    contents: Sequence[tuple[str, int]],
) -> Figure:
    """Page 1: the title, the facts of the build (code and parameter hashes, ...), run counts and contents."""
    fig = Figure(figsize=A4)
    fig.text(LEFT, 0.90, "\n".join(textwrap.wrap(title, 42)), fontsize=20, weight="bold", va="top", linespacing=1.3)
    fig.text(LEFT, 0.80, subtitle, fontsize=11.5, color="0.25", va="top")
    y = 0.72
    for key, value in facts:
        fig.text(LEFT, y, key, fontsize=9.5, color="0.3", va="top")
        mono = {"family": "DejaVu Sans Mono", "fontsize": 8.5} if "sha" in key else {"fontsize": 9.5}
        fig.text(0.3, y, value, va="top", **mono)
        y -= 0.026
    rows = [[r.study, f"{r.n_runs:,}", f"{r.n_ok:,}", f"{r.n_failed:,}"] for r in counts.itertuples()]
    fig.text(LEFT, y - 0.01, "Runs by study", fontsize=11, weight="bold", va="top")
    header = ["study", "runs", "succeeded", "failed"]
    y = table_axes(fig, y - 0.035, header, rows, [0.28, 0.22, 0.24, 0.22], 8.5) - 0.05
    fig.text(LEFT, y, "Contents", fontsize=11, weight="bold", va="top")
    for name, page in contents:
        y -= 0.024
        fig.text(LEFT + 0.02, y, name, fontsize=9.5, va="top")
        fig.text(RIGHT, y, str(page), fontsize=9.5, va="top", ha="right")
    return fig


def title(ctx: Context, contents: Sequence[tuple[str, int]]) -> Page:
    """The title page, given the contents of the pages after it."""
    inputs = ctx.inputs
    counts = run_counts(inputs.runs)
    facts = title_facts(inputs.facts, inputs.config, inputs.fleet, counts)
    return Page("Title", "", title_page(TITLE, SUBTITLE, facts, counts, contents))


# ---- summary -------------------------------------------------------------------------------------------------------
SUMMARY_HEADER = [
    "inhibitor",
    "rank",
    "ST (interval)",
    "S1 (interval)",
    "max. dev.\nwithout it [%]",
    "reduction [points]\n(interval)",
    "outside 5 %\nwithout it [%]",
]


def summary_table(numbers: Mapping[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The summary's one table: each inhibitor's Sobol' indices and ablation gain (sensitivity protocol)."""
    sobol, protocol = numbers["sobol"], numbers["sobol"]["protocol"]
    abl = numbers["ablation"].get(protocol) or next(iter(numbers["ablation"].values()))

    def gain(a: Mapping[str, Any]) -> str:
        return "–" if a.get("reduction") is None else text.span(a["reduction"], a["reduction_low"], a["reduction_high"])

    def removed(a: Mapping[str, Any]) -> list[str]:
        return [text.pct(a.get("mean_max_deviation"), 2, unit=False), gain(a)]

    rows = []
    for rank, f in enumerate(numbers["ranking"], start=1):
        i, a = sobol["indices"][f], abl.get(f, {})
        rows.append(
            [
                factor_label(f),
                str(rank),
                text.interval(i["ST"], i["ST_conf"]),
                text.interval(i["S1"], i["S1_conf"]),
                *removed(a),
                text.pct(a.get("share_outside_5pct"), unit=False),
            ]
        )
    a, b = abl["all"], abl["baseline"]
    rows.append([factor_label("all"), "", "", "", *removed(a), text.pct(a["share_outside_5pct"], unit=False)])
    baseline = text.pct(b["mean_max_deviation"], 2, unit=False)
    rows.append([factor_label("baseline"), "", "", "", baseline, "", text.pct(b["share_outside_5pct"], unit=False)])
    return list(SUMMARY_HEADER), rows


def summary_page(
    paragraphs: Sequence[str],
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    table_title: str,
    notes: Sequence[str],
) -> Figure:
    """The summary in words, then its one table, in the largest type (of :data:`SUMMARY_SIZES`) that ends above the
    footer (:func:`~pipeline.report.layout.first_fit`)."""

    def draw(size: float) -> tuple[Figure, float]:
        fig = Figure(figsize=A4)
        page_header(fig, "Summary")
        y = text_block(fig, 0.925, paragraphs, size=size)
        fig.text(LEFT, y - 0.005, table_title, fontsize=9.5, weight="bold", va="top")
        widths = [0.19, 0.05, 0.165, 0.165, 0.1, 0.2, 0.13]
        y = table_axes(fig, y - 0.03, header, rows, widths, 7.3)
        return fig, text_block(fig, y - 0.012, notes, size=min(size, 7.5))

    return first_fit(SUMMARY_SIZES, draw)


#: type sizes the summary's text tries, largest first [pt]
SUMMARY_SIZES = (8.9, 8.6, 8.3, 8.0, 7.7)


def summary(ctx: Context) -> list[Page]:
    """Page 2: the summary in words and its table, every number from metrics/*.json."""
    numbers = ctx.numbers
    s = numbers["sobol"]
    n = (numbers["ablation"].get(s["protocol"]) or {}).get("baseline", {}).get("n_bogies", "–")
    header, rows = summary_table(numbers)
    table_title = (
        f"The five inhibitors: Sobol' indices and what removing each buys ({s['protocol']}, {s['group']} design)"
    )
    # the design study's advice to a designer: per group the design with the widest tilt tolerance (docs/design.md)
    design = [line for line in ctx.inputs.design_metrics.get("guidance", []) if line.startswith("With ")]
    paragraphs = text.render("summary.j2", numbers=numbers, nose_up_deg=NOSE_UP_DEG, design=design)
    notes = text.render("summary_notes.j2", s=s, n=n)
    return [Page("Summary", "", summary_page(paragraphs, header, rows, table_title, notes))]
