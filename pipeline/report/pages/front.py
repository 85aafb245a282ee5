"""Front matter: the title page (build facts, run counts, contents), the summary a reader acts on (three findings,
one figure, what to do) and the summary in numbers (words and one table)."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from bogie.fleet.sampling.sample import VARIANTS
from bogie.fleet.weighing.survey import NOSE_UP_DEG
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import A4, LEFT, RIGHT, first_fit, page_header, table_axes, text_block
from pipeline.report.pages.sensitivity import ablation_bars
from pipeline.report.style import GROUP_LABEL, factor_label
from pipeline.report.tables import run_counts, worse_without

__all__ = [
    "SUBTITLE",
    "TITLE",
    "findings_page",
    "numbers_page",
    "summary",
    "summary_table",
    "title",
    "title_facts",
    "title_page",
]

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
    y = table_axes(fig, y - 0.035, header, rows, [0.28, 0.22, 0.24, 0.22], 8.5)
    failed = int(counts.loc[counts["study"] == "all", "n_failed"].sum())
    note = (
        "No run failed: every sample of every study gave a reading under every protocol it ran."
        if failed == 0
        else f"{failed:,} runs failed: Appendix C lists them with their reasons."
    )
    fig.text(LEFT, y - 0.012, note, fontsize=9, va="top")
    y -= 0.07
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
    "inhibitor, by rank",
    "ST\n(interval)",
    "S1\n(interval)",
    "max. dev.\nwithout\n[%]",
    "reduction\n[points]\n(interval)",
    "outside 5 %\nwithout [%]",
]
#: the summary table's column widths [page width between the margins]
SUMMARY_WIDTHS = (0.29, 0.17, 0.19, 0.09, 0.15, 0.11)


def _stacked(estimate: str) -> str:
    """An estimate and its interval, "0.21 (0.17 to 0.25)", as two lines of a table cell."""
    return estimate.replace(" (", "\n(", 1)


def summary_table(numbers: Mapping[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The summary's one table: each inhibitor's Sobol' indices and ablation gain (sensitivity protocol)."""
    sobol, protocol = numbers["sobol"], numbers["sobol"]["protocol"]
    abl = numbers["ablation"].get(protocol) or next(iter(numbers["ablation"].values()))

    def gain(a: Mapping[str, Any]) -> str:
        if a.get("reduction") is None:
            return "–"
        return _stacked(text.span(a["reduction"], a["reduction_low"], a["reduction_high"]))

    def removed(a: Mapping[str, Any]) -> list[str]:
        return [text.pct(a.get("mean_max_deviation"), 2, unit=False), gain(a)]

    rows = []
    for rank, f in enumerate(numbers["ranking"], start=1):
        i, a = sobol["indices"][f], abl.get(f, {})
        rows.append(
            [
                f"{rank}. {factor_label(f)}",
                _stacked(text.interval(i["ST"], i["ST_conf"])),
                _stacked(text.interval(i["S1"], i["S1_conf"])),
                *removed(a),
                text.pct(a.get("share_outside_5pct"), unit=False),
            ]
        )
    a, b = abl["all"], abl["baseline"]
    rows.append([factor_label("all"), "", "", *removed(a), text.pct(a["share_outside_5pct"], unit=False)])
    baseline = text.pct(b["mean_max_deviation"], 2, unit=False)
    rows.append([factor_label("baseline"), "", "", baseline, "", text.pct(b["share_outside_5pct"], unit=False)])
    return list(SUMMARY_HEADER), rows


def findings_page(
    findings: Sequence[str], ablation: pd.DataFrame, caption: Sequence[str], action: Sequence[str]
) -> Figure:
    """Page 2: three findings in words, one figure (the ablation's fleet mean maximum deviation by protocol) with its
    caption, then what to do; in the largest type of :data:`SUMMARY_SIZES` that ends above the footer."""

    def draw(size: float) -> tuple[Figure, float]:
        fig = Figure(figsize=A4)
        page_header(fig, "Summary")
        y = text_block(fig, 0.925, findings, size=size)
        height = 0.25
        ax = fig.add_axes((0.36, y - height, RIGHT - 0.36, height - 0.035))
        ablation_bars(ax, ablation, 100.0)
        ax.set_xlabel("fleet mean of the maximum deviation from the mean axle load [%]", fontsize=8)
        ax.set_title("What removing each inhibitor does to the fleet", fontsize=9)
        ax.tick_params(labelsize=7.5)
        y = text_block(fig, y - height - 0.045, caption, size=min(size, 7.5))
        return fig, text_block(fig, y - 0.004, action, size=size)

    return first_fit(SUMMARY_SIZES, draw)


def numbers_page(
    paragraphs: Sequence[str],
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    table_title: str,
    notes: Sequence[str],
) -> Figure:
    """Page 3: the summary's numbers in words, then its one table and the table's notes, in the largest type (of
    :data:`SUMMARY_SIZES`) that ends above the footer (:func:`~pipeline.report.layout.first_fit`)."""

    def draw(size: float) -> tuple[Figure, float]:
        fig = Figure(figsize=A4)
        page_header(fig, "Summary in numbers")
        y = text_block(fig, 0.925, paragraphs, size=size)
        fig.text(LEFT, y - 0.005, table_title, fontsize=9.5, weight="bold", va="top")
        y = table_axes(fig, y - 0.03, header, rows, SUMMARY_WIDTHS, 7.3)
        return fig, text_block(fig, y - 0.012, notes, size=min(size, 7.5))

    return first_fit(SUMMARY_SIZES, draw)


#: type sizes the summary's text tries, largest first [pt]
SUMMARY_SIZES = (9.2, 8.9, 8.6, 8.3, 8.0, 7.7, 7.4)


def fleet_words(fleet: pd.DataFrame, config: Any) -> dict[str, str]:
    """The fleet's bogies per axle group, as text ("600"), in params.yaml's group order."""
    counts = fleet["group"].value_counts()
    return {g: f"{counts.get(g, 0):,}" for g in config.fleet.axle_mix}


def summary(ctx: Context) -> list[Page]:
    """Pages 2 and 3: the answer in one minute (three findings, the ablation's figure, what to do), then the same
    numbers in full (the survey, the ranking, the ablation in words and the summary table), all from metrics/*.json."""
    numbers = ctx.numbers
    s = numbers["sobol"]
    n = (numbers["ablation"].get(s["protocol"]) or {}).get("baseline", {}).get("n_bogies", "–")
    # the design study's advice to a designer and an operator: per group the design with the widest tilt tolerance
    # and the tilt today's typical design needs (docs/design.md)
    guidance = ctx.inputs.design_metrics.get("guidance", [])
    design = [line for line in guidance if line.startswith(("With ", "Today's typical"))]
    worse = worse_without(numbers)
    cal = ctx.inputs.calibration_metrics
    fitted = None if cal.get("skipped", True) else ", ".join(
        f"{q} {e['value']:.3g}" for q, e in (cal.get("fitted") or {}).items()
    )  # fmt: skip
    findings = text.render(
        "summary_findings.j2",
        numbers=numbers,
        nose_up_deg=NOSE_UP_DEG,
        n_bogies=fleet_words(ctx.inputs.fleet, ctx.inputs.config),
        worse=worse,
        observed=ctx.inputs.observed_metrics.get("observed"),
        calibrated=fitted,
        calibration_reason=cal.get("reason", ""),
    )
    abl = ctx.inputs.sensitivity["ablation.csv"]
    rows = abl[(abl["group"] == "all") & (abl["statistic"] == "mean_max_deviation")]
    caption = text.render("summary_figure.j2", numbers=numbers)
    action = text.render(
        "summary_action.j2", numbers=numbers, design=design, savings=ctx.inputs.road_metrics.get("savings")
    )
    first = Page("Summary", "summary", findings_page(findings, rows, caption, action))
    header, table = summary_table(numbers)
    table_title = (
        f"The five inhibitors: Sobol' indices and what removing each buys ({s['protocol']}, {s['group']} design)"
    )
    paragraphs = text.render("summary.j2", numbers=numbers, nose_up_deg=NOSE_UP_DEG, design=[])
    notes = text.render("summary_notes.j2", s=s, n=n)
    return [first, Page("Summary in numbers", "", numbers_page(paragraphs, header, table, table_title, notes))]
