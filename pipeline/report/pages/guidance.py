"""The design-guidance pages, drawn from the ``design`` stage's controlled experiment (data/design, design.json).

Two pages when the study ran. The experiment: per group, every design's share within 5 % across the fleet's
operating conditions against how far it lies from today's typical design (the Pareto front joined, the air-sprung
group as a reference line), the share within 5 % against chassis tilt of the typical design, the design with the
widest tilt tolerance and the air group, and a table of each group's Pareto front. The tilt tolerance: the
tolerated nose-up and nose-down tilt of the grid's representative designs against bush stiffness, a panel per
contact roll radius and a line per arm length, and a table. The sentences under them are ``metrics/design.json``'s
``guidance``, generated from the numbers by :func:`bogie.fleet.design.analysis.guidance_sentences`, each put on its
page by its kind (:func:`sentence_kinds`, :data:`SENTENCE_PAGE`). The prose is in ``templates/guidance_*.j2``. When
the stage was skipped, one page says why.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from bogie.fleet.design.analysis import tolerance_width
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import first_fit, new_page, table_axes, text_block, text_page
from pipeline.report.style import GROUP_COLOR, GROUP_LABEL, GROUPS, QUANTITY

__all__ = [
    "FACTORS", "SENTENCE_PAGE", "design_cells", "experiment_page", "front_rows", "pages", "sentence_kinds",
    "sentences", "tolerance_page", "tolerance_rows",
]  # fmt: skip

#: the five design factors in the tables' order (names, units and formats: :data:`pipeline.report.style.QUANTITY`)
FACTORS: tuple[str, ...] = (
    "bush_stiffness", "equaliser_arm", "contact_roll_radius", "friction_coefficient", "spring_friction_band",
)  # fmt: skip
KIND_MARKER = {"typical": "*", "own": "D", "grid": "o", "space": "s"}
KIND_LABEL = {"typical": "today's typical", "own": "your bogie file's", "grid": "grid design",
              "space": "space-filling design"}  # fmt: skip


def _tol(x: Any) -> str:
    return "none" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2f}"


def _pct(x: float) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{100 * x:.0f}"


def _share(row: Mapping[str, Any], which: str) -> str:
    """``83 (70-92)``: a share within 5 % or 10 % [%] and its interval."""
    k = f"share_within_{which}"
    return f"{_pct(row[k])} ({_pct(row[k + '_low'])}-{_pct(row[k + '_high'])})"


def design_cells(row: Mapping[str, Any]) -> list[str]:
    """A design's cells under :data:`DESIGN_HEADER`: its kind, then the five factors in their report units; the air
    group has none of them."""
    if row["suspension"] == "air":
        return ["air-sprung", "-", "-", "-", "-", "-"]
    kind = {"typical": "typical", "own": "your file", "grid": "grid", "space": "space-filling"}[row["kind"]]
    return [kind, *(QUANTITY[f].value(row[f]) for f in FACTORS)]


# ---- the design stage's sentences -----------------------------------------------------------------------------------
#: the page each kind of guidance sentence goes under. Per group,
#: :func:`bogie.fleet.design.analysis.guidance_sentences` writes, in this order: ``tolerance`` (the widest tilt
#: tolerance, or that none is tolerated), ``typical`` (today's typical design, when the group has one), ``own`` (the
#: user's bogie file, when the group's base bogie is one), ``fleet`` (the best design across the fleet's own
#: conditions), ``air`` (the air-sprung group, when it ran)
SENTENCE_PAGE: dict[str, str] = {"tolerance": "tolerance", "typical": "tolerance", "own": "tolerance",
                                 "fleet": "experiment", "air": "experiment"}  # fmt: skip


def sentence_kinds(m: Mapping[str, Any]) -> list[tuple[str, str]]:
    """(group, kind) of each of ``metrics/design.json``'s ``guidance`` sentences, in their order, from the keys
    that say which sentences the design stage wrote: the groups of ``designs``, the ``typical`` kind among
    ``design_summaries`` (one per entry of ``designs``), the groups of ``air``.

    Raises
    ------
    ValueError
        When the sentences are not as many as those keys give (metrics written by another version of the stage).
    """
    summaries = m["design_summaries"]
    if len(summaries) != len(m["designs"]):
        raise ValueError(f"design.json: {len(m['designs'])} designs but {len(summaries)} design_summaries")
    typical = {d["group"] for d, s in zip(m["designs"], summaries, strict=True) if s["kind"] == "typical"}
    own = {d["group"] for d, s in zip(m["designs"], summaries, strict=True) if s["kind"] == "own"}
    kinds: list[tuple[str, str]] = []
    for group in dict.fromkeys(d["group"] for d in m["designs"]):
        kinds.append((group, "tolerance"))
        if group in typical:
            kinds.append((group, "typical"))
        if group in own:
            kinds.append((group, "own"))
        kinds.append((group, "fleet"))
        if group in m["air"]:
            kinds.append((group, "air"))
    if len(kinds) != len(m["guidance"]):
        raise ValueError(
            f"design.json: {len(m['guidance'])} guidance sentences, but its designs and air references give "
            f"{len(kinds)} ({', '.join(f'{g} {k}' for g, k in kinds)})"
        )
    return kinds


def sentences(m: Mapping[str, Any], page: str) -> list[str]:
    """The guidance sentences that go under ``page`` (``experiment`` or ``tolerance``), in the stage's order."""
    return [s for (_, kind), s in zip(sentence_kinds(m), m["guidance"], strict=True) if SENTENCE_PAGE[kind] == page]


# ---- page 1: the experiment ---------------------------------------------------------------------------------------
def _front(ax, group: str, designs: pd.DataFrame, target: float) -> None:
    """Share within 5 % across the fleet's conditions against the distance from the typical design."""
    g = designs[(designs["group"] == group) & (designs["suspension"] == "steel")]
    for kind, marker in KIND_MARKER.items():
        k = g[g["kind"] == kind]
        if not len(k):
            continue
        y = 100 * k["share_within_5pct"]
        err = [y - 100 * k["share_within_5pct_low"], 100 * k["share_within_5pct_high"] - y]
        ax.errorbar(k["distance"], y, yerr=err, fmt=marker, ms=7 if kind == "typical" else 4, color="0.45",
                    ecolor="0.8", elinewidth=0.7, capsize=0, label=KIND_LABEL[kind], zorder=2)  # fmt: skip
    front = g[g["pareto"].astype(bool)].sort_values("distance")
    ax.plot(front["distance"], 100 * front["share_within_5pct"], "-o", color=GROUP_COLOR[group], ms=4, lw=1.2,
            label="Pareto front", zorder=3)  # fmt: skip
    air = designs[(designs["group"] == group) & (designs["suspension"] == "air")]
    if len(air):
        ax.axhline(100 * air["share_within_5pct"].iloc[0], color="0.3", ls=":", lw=1.0, label="air-sprung group")
    ax.axhline(100 * target, color="0.2", ls="--", lw=0.8, label=f"target {100 * target:.0f} %")
    ax.set_ylim(-2, 102)
    ax.set_xlim(left=-0.03)
    ax.set_xlabel("distance from today's typical [fleet ranks]")
    ax.set_ylabel("within 5 % [%]")
    ax.set_title(f"{GROUP_LABEL[group]}: across the fleet's conditions")


def _curves(ax, group: str, designs: pd.DataFrame, curves: pd.DataFrame, target: float) -> None:
    """Share within 5 % against chassis tilt: the typical design, the user's own (a bogie file's, when the group has
    one), the widest tolerance and the air group."""
    g = designs[designs["group"] == group]
    steel = g[g["suspension"] == "steel"].dropna(subset=["tilt_tolerance_nose_up_deg"])
    picks: list[tuple[str, str, str]] = []
    typ = g[g["kind"] == "typical"]
    if len(typ):
        picks.append((typ["design"].iloc[0], "today's typical", "0.45"))
    own = g[g["kind"] == "own"]
    if len(own):
        picks.append((own["design"].iloc[0], "your bogie file", "tab:purple"))
    if len(steel):
        picks.append((steel.loc[tolerance_width(steel).idxmax(), "design"], "widest tolerance", GROUP_COLOR[group]))
    air = g[g["suspension"] == "air"]
    if len(air):
        picks.append((air["design"].iloc[0], "air-sprung", "0.2"))
    for name, label, color in picks:
        c = curves[curves["design"] == name]
        ax.plot(c["tilt_deg"], 100 * c["share_within_5pct"], color=color, lw=1.3,
                ls=":" if label == "air-sprung" else "-", label=label)  # fmt: skip
    ax.axhline(100 * target, color="0.2", ls="--", lw=0.8)
    ax.axvline(0.0, color="0.6", lw=0.5)
    ax.set_ylim(-2, 102)
    ax.set_xlabel("chassis tilt, nose up + [degree]")
    ax.set_ylabel("within 5 % [%]")
    # the curves cross the whole chart: the legend between the title and the chart, not over them; four entries
    # (with the user's own design) in two rows, so that it stays within its chart's width
    ncol = len(picks) if len(picks) <= 3 else 2
    ax.set_title(f"{GROUP_LABEL[group]}: at a set tilt", pad=16 if ncol == len(picks) else 26)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=ncol, fontsize=6.8, frameon=False,
              borderaxespad=0.1)  # fmt: skip


#: the design's columns in the tables: its kind, then each factor's short name and unit
DESIGN_HEADER = ["design", *(f"{QUANTITY[f].short}\n[{QUANTITY[f].unit}]" for f in FACTORS)]
DESIGN_WIDTHS = [0.1, 0.08, 0.06, 0.09, 0.07, 0.06]
FRONT_HEADER = [
    "group",
    *DESIGN_HEADER,
    "distance\n[-]",
    "within 5 %\n[%]",
    "within 10 %\n[%]",
    "tolerance down\n/ up [degree]",
]
FRONT_WIDTHS = [0.07, *DESIGN_WIDTHS, 0.07, 0.12, 0.12, 0.13]


def front_rows(designs: pd.DataFrame) -> list[list[str]]:
    """The table of page 1: each group's Pareto front, best share first, then the air group."""
    rows = []
    for group in dict.fromkeys(designs["group"]):
        g = designs[designs["group"] == group]
        pareto = g[g["pareto"].astype(bool)].sort_values("share_within_5pct", ascending=False, kind="stable")
        for r in [*pareto.to_dict("records"), *g[g["suspension"] == "air"].to_dict("records")]:
            air = r["suspension"] == "air"
            rows.append([
                GROUP_LABEL[group], *design_cells(r), "-" if air else f"{r['distance']:.2f}",
                _share(r, "5pct"),
                _share(r, "10pct"),
                f"{_tol(r['tilt_tolerance_nose_down_deg'])} / {_tol(r['tilt_tolerance_nose_up_deg'])}",
            ])  # fmt: skip
    return rows


def experiment_page(tables: Mapping[str, pd.DataFrame], m: Mapping[str, Any], groups: Sequence[str]) -> Figure:
    """Page 1: the designs against their distance from the typical one, the tilt curves, the Pareto fronts."""
    designs, curves = tables["designs.csv"], tables["tilt_curves.csv"]
    target = float(m["target_share"])
    intro = text.render("guidance_experiment.j2", m=m)
    notes = [*sentences(m, "experiment"), *text.render("guidance_check.j2", check=m["interpolation_check"])]
    rows = front_rows(designs)

    def draw(option: tuple[float, float]) -> tuple[Figure, float]:
        bottom, size = option
        fig = new_page("Design guidance: a controlled experiment", body=(0.07, bottom, 0.86, 0.9 - bottom))
        grid = fig.add_gridspec(2, len(groups))
        for c, group in enumerate(groups):
            _front(fig.add_subplot(grid[0, c]), group, designs, target)
            _curves(fig.add_subplot(grid[1, c]), group, designs, curves, target)
        kinds = [k for k in KIND_MARKER if (designs["kind"] == k).any()]  # "your bogie file's" only with one
        handles = [Line2D([], [], marker=KIND_MARKER[k], ls="", color="0.45", label=KIND_LABEL[k]) for k in kinds] + [
            Line2D([], [], color="0.2", marker="o", label="Pareto front (group colour)"),
            Line2D([], [], color="0.3", ls=":", label="air-sprung group"),
            Line2D([], [], color="0.2", ls="--", label=f"target {100 * target:.0f} %"),
        ]
        fig.legend(
            handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.925), ncol=6, fontsize=6.8, frameon=False
        )
        y = text_block(fig, bottom - 0.012, intro, size=size)
        top = table_axes(fig, y - 0.004, FRONT_HEADER, rows, FRONT_WIDTHS, size=size - 0.6)
        return fig, text_block(fig, top - 0.01, notes, size=size)

    return first_fit(EXPERIMENT_FITS, draw)


#: (bottom of the charts [page fraction], type size [pt]) tried in turn until the text ends above the footer
EXPERIMENT_FITS = ((0.5, 7.8), (0.52, 7.5), (0.55, 7.2), (0.58, 6.9), (0.6, 6.6))


# ---- page 2: the tilt tolerance -------------------------------------------------------------------------------------
def _axes_factors(grid: Sequence[str]) -> tuple[str, str | None, str | None]:
    """The chart's x axis, panels and lines among the grid's factors: bush, contact roll radius and arm when the
    grid has them, else the grid's own order."""
    preferred = [f for f in ("bush_stiffness", "contact_roll_radius", "equaliser_arm") if f in grid]
    order = [*preferred, *[f for f in grid if f not in preferred]]
    return order[0], order[1] if len(order) > 1 else None, order[2] if len(order) > 2 else None


def _level(factor: str, value: float, short: bool = False) -> str:
    """``contact roll radius 40 mm`` (``roll radius 40 mm`` if ``short``): a factor's level in its report unit."""
    q = QUANTITY[factor]
    return f"{q.short if short else q.name} {q.value(value)} {q.unit}"


def _tolerance_panel(ax, grid_rows: pd.DataFrame, x: str, line: str | None, color: str, air: pd.DataFrame) -> None:
    xs, scale = QUANTITY[x].label, QUANTITY[x].scale
    levels = sorted(set(grid_rows[line])) if line else [None]
    styles = ["-", "--", "-.", ":"]
    for k, level in enumerate(levels):
        r = grid_rows if level is None else grid_rows[grid_rows[line] == level]
        r = r.sort_values(x)
        up = r["tilt_tolerance_nose_up_deg"].astype(float)
        down = -r["tilt_tolerance_nose_down_deg"].astype(float)
        label = None if level is None else _level(line, level)
        style = styles[k % len(styles)]
        ax.plot(scale * r[x], up, style, marker="^", ms=3.5, color=color, lw=1.1, label=label)
        ax.plot(scale * r[x], down, style, marker="v", ms=3.5, color=color, lw=1.1)
        none = r[up.isna()]
        ax.plot(scale * none[x], np.zeros(len(none)), "x", color="C3", ms=5, mew=1.2)
    if len(air) and not math.isnan(float(air["tilt_tolerance_nose_up_deg"].iloc[0])):
        a = air.iloc[0]
        ax.axhspan(-a["tilt_tolerance_nose_down_deg"], a["tilt_tolerance_nose_up_deg"], color="0.92", zorder=0, lw=0)
    ax.axhline(0.0, color="0.5", lw=0.5)
    if x == "bush_stiffness":
        ax.set_xscale("log")
    ax.set_xlabel(xs)


TOLERANCE_HEADER = ["group", *DESIGN_HEADER, "nose down\n[degree]", "nose up\n[degree]", "within 5 %,\nlevel [%]",
                    "within 5 %, at\ntolerance [%]"]  # fmt: skip
TOLERANCE_WIDTHS = [0.07, *DESIGN_WIDTHS, 0.1, 0.1, 0.1, 0.13]


def tolerance_rows(designs: pd.DataFrame, best: int = 4) -> list[list[str]]:
    """The table of page 2 per group: today's typical design, the user's own (a bogie file's, when the group has
    one), the ``best`` widest tolerances, the air group."""
    rows = []
    for group in dict.fromkeys(designs["group"]):
        g = designs[(designs["group"] == group) & (designs["suspension"] == "steel")]
        top = g.loc[tolerance_width(g).fillna(-1.0).sort_values(ascending=False, kind="stable").index[:best]]
        named = g[g["kind"].isin(("typical", "own"))].sort_values("kind", key=lambda k: k != "typical", kind="stable")
        picks = [*named.to_dict("records"), *top[~top["kind"].isin(("typical", "own"))].to_dict("records")]
        picks += designs[(designs["group"] == group) & (designs["suspension"] == "air")].to_dict("records")
        for r in picks:
            rows.append([
                GROUP_LABEL[group], *design_cells(r),
                _tol(r["tilt_tolerance_nose_down_deg"]), _tol(r["tilt_tolerance_nose_up_deg"]),
                _pct(r["share_within_5pct_level"]), _pct(r["share_within_5pct_at_tolerance"]),
            ])  # fmt: skip
    return rows


def tolerance_page(tables: Mapping[str, pd.DataFrame], m: Mapping[str, Any], grid: Sequence[str],
                   groups: Sequence[str]) -> Figure:  # fmt: skip
    """Page 2: the tolerated tilt of the representative designs, and the table."""
    designs = tables["designs.csv"]
    x, panel, line = _axes_factors(grid)
    lo, hi = m["tilt_range_deg"]
    grid_designs = designs[designs["kind"] == "grid"]
    panels = sorted(set(grid_designs[panel])) if panel else [None]
    intro = text.render("guidance_tolerance.j2", m=m, lo=lo, hi=hi)
    notes = sentences(m, "tolerance")
    rows = tolerance_rows(designs)

    def draw(option: tuple[float, float]) -> tuple[Figure, float]:
        bottom, size = option
        fig = new_page(
            "Design guidance: how much chassis tilt a bogie tolerates", body=(0.07, bottom, 0.84, 0.88 - bottom)
        )
        sub = fig.add_gridspec(len(groups), len(panels))
        for r, group in enumerate(groups):
            air = designs[(designs["group"] == group) & (designs["suspension"] == "air")]
            for c, level in enumerate(panels):
                ax = fig.add_subplot(sub[r, c])
                rows_ = grid_designs[grid_designs["group"] == group]
                if level is not None:
                    rows_ = rows_[rows_[panel] == level]
                _tolerance_panel(ax, rows_, x, line, GROUP_COLOR[group], air)
                ax.set_ylim(lo - 0.1, hi + 0.1)
                ax.set_title(GROUP_LABEL[group] + ("" if level is None else ", " + _level(panel, level, short=True)),
                             fontsize=8)  # fmt: skip
                if c == 0:
                    ax.set_ylabel("tolerated tilt [degree]")
                else:
                    ax.tick_params(labelleft=False)
                if r == 0 and c == 0 and line:  # one legend for the grid, above it, not over a panel's lines
                    fig.legend(*ax.get_legend_handles_labels(), loc="lower left", bbox_to_anchor=(0.07, 0.895),
                               ncol=4, fontsize=6.5, frameon=False)  # fmt: skip
        y = text_block(fig, bottom - 0.012, intro, size=size)
        top = table_axes(fig, y - 0.004, TOLERANCE_HEADER, rows, TOLERANCE_WIDTHS, size=size - 0.6)
        return fig, text_block(fig, top - 0.01, notes, size=size)

    return first_fit(TOLERANCE_FITS, draw)


TOLERANCE_FITS = ((0.5, 7.8), (0.53, 7.5), (0.56, 7.2), (0.59, 6.9), (0.62, 6.6))


def pages(ctx: Context) -> list[Page]:
    """The design-guidance pages of the ``design`` stage, or one page saying it did not run."""
    m, tables = ctx.inputs.design_metrics, ctx.inputs.design
    if m.get("skipped"):
        paras = text.render("guidance_skipped.j2", reason=m["skipped"])
        return [Page("Design guidance", "", text_page("Design guidance", paras, size=9.0))]
    groups = [g for g in GROUPS if g in set(tables["designs.csv"]["group"])]
    grid = list(ctx.inputs.config.design.grid) if ctx.inputs.config.design else list(FACTORS)[:3]
    return [
        Page("Design guidance", "design_experiment", experiment_page(tables, m, groups)),
        Page("", "design_tolerance", tolerance_page(tables, m, grid, groups)),
    ]
