"""Page builders of the sensitivity report: plain functions of DataFrames and dicts, each returning A4 Figures.

Every page is one portrait A4 :class:`matplotlib.figure.Figure` (no pyplot state): a section title at the top, the
charts in a body rectangle laid out by matplotlib's constrained layout, and captions below. Page numbers go on in
:func:`number_pages` once the whole report is assembled. Units at the edge: kN, kg, mm, degrees and per cent; the
tables passed in are SI or dimensionless, as the pipeline writes them. Build the pages inside
``matplotlib.rc_context(STYLE)`` so fonts are the same on every page.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.lines import Line2D

#: A4 portrait [inch]
A4 = (8.27, 11.69)
LEFT, RIGHT = 0.08, 0.92
#: where the charts go on a page: (left, bottom, width, height) in page fractions
BODY = (0.06, 0.25, 0.88, 0.68)
STYLE = {
    "font.family": "DejaVu Sans",
    "font.size": 9.0,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 7.5,
    "legend.title_fontsize": 7.5,
    "axes.grid": True,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.5,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "pdf.fonttype": 42,
    "image.cmap": "RdYlGn",
}
GROUP_LABEL = {"tandem": "tandem", "triaxle": "tri-axle"}
GROUP_COLOR = {"tandem": "C0", "triaxle": "C1"}
PROTOCOL_LABEL = {"static": "static weighbridge", "wim": "weigh-in-motion"}
PROTOCOL_LINE = {"static": "-", "wim": "--"}
AXLE_COLOR = {"front": "C2", "middle": "C4", "rear": "C3"}
FACTOR_LABEL = {
    "bush_stiffness": "bush stiffness",
    "bush_damping": "bush damping",
    "contact_roll_radius": "contact movement",
    "friction_coefficient": "spring-end friction",
    "chassis_tilt": "chassis tilt",
    "tyre_wear": "tyre wear",
    "baseline": "none removed",
    "all": "all four removed",
}
MEASURE_LABEL = {"max_deviation": "max. deviation", "p1": "P1", "road_wear_factor": "road-wear factor"}


def axle_name(i: int, n_axles: int) -> str:
    """front, middle or rear for axle position ``i`` (0 = front) of an ``n_axles`` group."""
    return "front" if i == 0 else "rear" if i == n_axles - 1 else "middle"


# ---- page mechanics --------------------------------------------------------------------------------------------
def _header(fig: Figure, title: str) -> None:
    fig.text(LEFT, 0.962, title, fontsize=14, weight="bold", va="top")
    fig.add_artist(Line2D([LEFT, RIGHT], [0.94, 0.94], lw=0.6, color="0.5"))


def new_page(title: str, body: Sequence[float] = BODY) -> Figure:
    """An empty A4 page with its section ``title``; charts added to it are laid out inside ``body``."""
    fig = Figure(figsize=A4, layout=ConstrainedLayoutEngine(rect=tuple(body), h_pad=0.08, w_pad=0.08))
    _header(fig, title)
    return fig


def adopt_page(fig: Figure, title: str, body: Sequence[float] = BODY) -> Figure:
    """Turn a figure made elsewhere (bogie.plotting, constrained layout) into an A4 page with ``title``."""
    fig.set_size_inches(*A4)
    fig.get_layout_engine().set(rect=tuple(body))
    _header(fig, title)
    return fig


def text_block(fig: Figure, y: float, paragraphs: Sequence[str], size: float = 9.0, x: float = LEFT) -> float:
    """Write wrapped paragraphs from height ``y`` (page fraction) down; returns the height below the last line.

    A paragraph starting with "## " is a bold subheading; "- " starts a bullet.
    """
    chars = int((RIGHT - x) * A4[0] * 72.0 / (0.53 * size))  # DejaVu Sans averages about 0.53 em per character
    line = size * 1.45 / 72.0 / A4[1]
    for para in paragraphs:
        bold = para.startswith("## ")
        # a no-break space keeps a number and its per cent sign on one line
        text = para.removeprefix("## ").replace(" %", "\u00a0%")
        indent = "  " if text.startswith("- ") else ""
        lines = textwrap.wrap(text, chars, subsequent_indent=indent, break_on_hyphens=False) or [""]
        fig.text(x, y, "\n".join(lines), fontsize=size, va="top", linespacing=1.45, weight="bold" if bold else None)
        y -= line * len(lines) + line * (0.25 if bold else 0.6)
    return y


def number_pages(pages: Sequence[Figure], footer: str) -> None:
    """Write ``page n of N`` and the ``footer`` text at the foot of every page."""
    for n, fig in enumerate(pages, start=1):
        fig.add_artist(Line2D([LEFT, RIGHT], [0.04, 0.04], lw=0.4, color="0.6"))
        fig.text(LEFT, 0.03, footer, fontsize=7, color="0.35", va="top")
        fig.text(RIGHT, 0.03, f"page {n} of {len(pages)}", fontsize=7.5, ha="right", va="top")


def table_axes(
    fig: Figure,
    top: float,
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    widths: Sequence[float],
    size: float = 7.5,
) -> float:
    """A plain table (header row shaded) hanging from page height ``top``; returns the height of its bottom edge.

    Cells may hold several lines ("\\n"); each row is as tall as its tallest cell.
    """
    line = size * 1.3 / 72.0 / A4[1]
    heights = [line * (1 + max(str(c).count("\n") for c in row)) + 0.8 * line for row in [header, *rows]]
    total = sum(heights)
    ax = fig.add_axes((LEFT, top - total, RIGHT - LEFT, total))
    ax.axis("off")
    ax.set_in_layout(False)
    table = ax.table(
        cellText=[list(r) for r in rows],
        colLabels=list(header),
        colWidths=list(widths),
        loc="upper center",
        cellLoc="left",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(size)
    for (r, _), cell in table.get_celld().items():
        cell.set_linewidth(0.3)
        cell.set_height(heights[r] / total)
        if r == 0:
            cell.set_facecolor("0.9")
            cell.get_text().set_weight("bold")
    return top - total


# ---- front matter ----------------------------------------------------------------------------------------------
def title_page(
    title: str,
    subtitle: str,
    facts: Sequence[tuple[str, str]],
    counts: pd.DataFrame,
    contents: Sequence[tuple[str, int]],
) -> Figure:
    """Page 1: the title, the facts of the build (date, revision, parameter hash, ...), run counts and contents."""
    fig = Figure(figsize=A4)
    fig.text(LEFT, 0.90, "\n".join(textwrap.wrap(title, 42)), fontsize=20, weight="bold", va="top", linespacing=1.3)
    fig.text(LEFT, 0.80, subtitle, fontsize=11.5, color="0.25", va="top")
    y = 0.72
    for key, value in facts:
        fig.text(LEFT, y, key, fontsize=9.5, color="0.3", va="top")
        mono = {"family": "DejaVu Sans Mono", "fontsize": 8.5} if "sha" in key else {"fontsize": 9.5}
        fig.text(0.3, y, value, va="top", **mono)
        y -= 0.026
    rows = [
        [r.study, f"{r.n_runs:,}", f"{r.n_ok:,}", f"{r.n_failed:,}", f"{r.wall_time / 60:,.1f}"]
        for r in counts.itertuples()
    ]
    fig.text(LEFT, y - 0.01, "Runs by study", fontsize=11, weight="bold", va="top")
    header = ["study", "runs", "succeeded", "failed", "simulation time [min]"]
    y = table_axes(fig, y - 0.035, header, rows, [0.22, 0.16, 0.18, 0.16, 0.28], 8.5) - 0.05
    fig.text(LEFT, y, "Contents", fontsize=11, weight="bold", va="top")
    for name, page in contents:
        y -= 0.024
        fig.text(LEFT + 0.02, y, name, fontsize=9.5, va="top")
        fig.text(RIGHT, y, str(page), fontsize=9.5, va="top", ha="right")
    return fig


def summary_page(
    paragraphs: Sequence[str],
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    table_title: str,
    notes: Sequence[str],
) -> Figure:
    """The summary in words, then its one table."""
    fig = Figure(figsize=A4)
    _header(fig, "Summary")
    y = text_block(fig, 0.925, paragraphs, size=8.9)
    fig.text(LEFT, y - 0.005, table_title, fontsize=9.5, weight="bold", va="top")
    widths = [0.17, 0.05, 0.165, 0.175, 0.11, 0.2, 0.13]
    y = table_axes(fig, y - 0.03, header, rows, widths, 7.3)
    text_block(fig, y - 0.012, notes, size=7.5)
    return fig


# ---- sensitivity ---------------------------------------------------------------------------------------------------
def sensitivity_page(
    indices: pd.DataFrame, ablation: pd.DataFrame, ranking_measure: str, caption: Sequence[str]
) -> Figure:
    """Sobol' S1 and ST with their intervals as horizontal bars; the ablation as bars of fleet inequality.

    Parameters
    ----------
    indices
        ``sobol_indices.csv`` (measure, factor, S1, S1_conf, ST, ST_conf).
    ablation
        ``ablation.csv`` rows of group ``all``.
    ranking_measure
        The measure whose S1 and ST are drawn in full.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Sensitivity: which inhibitor matters", body=(0.06, 0.24, 0.88, 0.69))
    (ax_s, ax_m), (ax_a, ax_o) = fig.subplots(2, 2, gridspec_kw={"width_ratios": (1.2, 1.0)})
    main = indices[indices["measure"] == ranking_measure].sort_values("ST")
    y = np.arange(len(main))
    for k, (col, color) in enumerate((("S1", "0.65"), ("ST", "C0"))):
        ax_s.barh(
            y + (k - 0.5) * 0.38,
            main[col],
            0.36,
            xerr=main[f"{col}_conf"],
            color=color,
            label=col,
            error_kw={"lw": 0.8, "capsize": 2},
        )
    ax_s.set_yticks(y, [FACTOR_LABEL.get(f, f) for f in main["factor"]])
    ax_s.set_xlabel("Sobol' index [-]")
    ax_s.set_title(f"{MEASURE_LABEL.get(ranking_measure, ranking_measure)}: first order S1, total ST")
    ax_s.legend(loc="lower right")
    ax_s.axvline(0.0, color="0.3", lw=0.6)
    ax_s.set_ylim(-1.4, len(main) - 0.5)  # a free band at the foot for the legend
    others = [m for m in indices["measure"].unique() if m != ranking_measure]
    order = list(main["factor"])
    for k, measure in enumerate([ranking_measure, *others]):
        sub = indices[indices["measure"] == measure].set_index("factor").reindex(order)
        ax_m.barh(
            y + (k - 1) * 0.27,
            sub["ST"],
            0.25,
            xerr=sub["ST_conf"],
            color=f"C{k}",
            label=MEASURE_LABEL.get(measure, measure),
            error_kw={"lw": 0.7, "capsize": 1.5},
        )
    ax_m.set_yticks(y, [])
    ax_m.set_ylim(-1.4, len(main) - 0.5)
    ax_m.axvline(0.0, color="0.3", lw=0.6)
    ax_m.set_xlabel("total index ST [-]")
    ax_m.set_title("ST of each inequality measure")
    ax_m.legend(loc="lower right")
    for ax, statistic, scale, label in (
        (ax_a, "mean_max_deviation", 100.0, "fleet mean of max. deviation [%]"),
        (ax_o, "share_outside_5pct", 100.0, "groups outside 5 % [%]"),
    ):
        _ablation_bars(ax, ablation[ablation["statistic"] == statistic], scale)
        ax.set_xlabel(label)
    ax_a.set_title("Ablation: mean inequality")
    ax_o.set_title("Ablation: outside 5 %")
    ax_o.set_yticklabels([])
    text_block(fig, 0.215, caption, size=8.2)
    return fig


def _marker_size(n: int) -> float:
    """Scatter marker area [pt^2]: small for thousands of points, visible for a handful."""
    return float(np.clip(3000.0 / max(n, 1), 6.0, 25.0))


def _ablation_bars(ax, rows: pd.DataFrame, scale: float) -> None:
    variants = list(dict.fromkeys(rows["variant"]))[::-1]
    protocols = list(dict.fromkeys(rows["protocol"]))
    y = np.arange(len(variants))
    width = 0.8 / max(len(protocols), 1)
    for k, protocol in enumerate(protocols):
        sub = rows[rows["protocol"] == protocol].set_index("variant").reindex(variants)
        value = sub["value"].to_numpy(dtype=float)
        # the interval of the variant's value: its paired baseline plus the bootstrap interval of the difference
        low = (sub["baseline"] + sub["difference_low"]).to_numpy(dtype=float)
        high = (sub["baseline"] + sub["difference_high"]).to_numpy(dtype=float)
        err = np.clip(np.vstack([value - low, high - value]), 0.0, None) * scale
        offset = (k - (len(protocols) - 1) / 2) * width
        ax.barh(
            y + offset,
            value * scale,
            width * 0.9,
            xerr=err,
            color=f"C{k}",
            alpha=0.85,
            label=PROTOCOL_LABEL.get(protocol, protocol),
            error_kw={"lw": 0.7, "capsize": 1.5},
        )
    ax.set_yticks(y, [FACTOR_LABEL.get(v, v) for v in variants])
    ax.set_ylim(-1.6, len(variants) - 0.5)  # a free band at the foot for the legend
    ax.legend(loc="lower right", ncol=2)


# ---- survey ----------------------------------------------------------------------------------------------------
def load_share_page(
    ok: pd.DataFrame, groups: Sequence[str], protocols: Sequence[str], caption: Sequence[str]
) -> Figure:
    """Load share per axle position (groups x protocols), the spread in kg and the share outside a tolerance.

    Parameters
    ----------
    ok
        Succeeded fleet runs with the survey's inequality columns (``load_share_<i>``, ``spread_kg``,
        ``pair_difference``).
    groups, protocols
        Those present, in order.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Survey: how unequal the fleet is", body=(0.06, 0.2, 0.88, 0.73))
    axes = fig.subplots(len(groups) + 1, max(len(protocols), 2), squeeze=False)
    for r, group in enumerate(groups):
        n_axles = 2 if group == "tandem" else 3
        for c, protocol in enumerate(protocols):
            ax = axes[r, c]
            sub = ok[(ok["group"] == group) & (ok["protocol"] == protocol)]
            shares = sub[[f"load_share_{i}" for i in range(n_axles)]].to_numpy(dtype=float)
            # bins over this panel's central 99 %: the static readings crowd near 1, WIM's spread far wider, and
            # a few wheel-lift readings would otherwise squash every other bin into one
            span = np.percentile(shares, [0.5, 99.5]) if shares.size else (0.8, 1.2)
            edges = np.linspace(span[0], span[1] if span[1] > span[0] else span[0] + 0.1, 41)
            ax.axvspan(0.9, 1.1, color="0.92", lw=0, label="within 10 % of equal")
            for i in range(n_axles):
                name = axle_name(i, n_axles)
                ax.stairs(
                    np.histogram(shares[:, i], edges)[0], edges, color=AXLE_COLOR[name], lw=1.2, label=f"{name} axle"
                )
            ax.set_title(f"{GROUP_LABEL[group]}, {PROTOCOL_LABEL[protocol]} ({len(sub)} groups)")
            ax.set_xlabel("load share (1 = equal share) [-]")
            ax.set_ylabel("axles")
            ax.set_ylim(0.0, 1.45 * ax.get_ylim()[1])  # headroom for the legend above the peak
            ax.legend(loc="upper right")
        for ax in axes[r, len(protocols) :]:
            ax.remove()
    ax_kg, ax_cum = axes[-1, 0], axes[-1, 1]
    labels, boxes, means = [], [], []
    for group in groups:
        for protocol in protocols:
            sel = (ok["group"] == group) & (ok["protocol"] == protocol)
            x = ok.loc[sel, "pair_difference"].to_numpy(dtype=float) * 100.0
            style = {"color": GROUP_COLOR[group], "ls": PROTOCOL_LINE[protocol], "lw": 1.3}
            if len(x):
                t = np.linspace(0.0, 30.0, 301)
                ax_cum.plot(
                    t,
                    100.0 * (x[None, :] > t[:, None]).mean(axis=1),
                    **style,
                    label=f"{GROUP_LABEL[group]}, {protocol}",
                )
                labels.append(f"{GROUP_LABEL[group]}\n{protocol}")
                boxes.append(ok.loc[sel, "spread_kg"].to_numpy(dtype=float))
                means.append(float(np.mean(boxes[-1])))
    if boxes:
        pos = np.arange(len(boxes))[::-1]
        ax_kg.boxplot(
            boxes,
            positions=pos,
            orientation="horizontal",
            whis=(5, 95),
            showfliers=False,
            widths=0.5,
            medianprops={"color": "k"},
        )
        ax_kg.plot(means, pos, "D", color="C3", ms=4, label="mean")
        ax_kg.set_yticks(pos, labels)
        ax_kg.legend(loc="lower right")
    ax_kg.set_xlabel("heaviest minus lightest axle [kg]")
    ax_kg.set_title("Spread between axles")
    ax_cum.axvline(5.0, color="0.3", lw=0.8, ls=":")
    ax_cum.set_xlim(0.0, 30.0)
    ax_cum.set_ylim(0.0, 100.0)
    ax_cum.set_xlabel("tolerance t [%]")
    ax_cum.set_ylabel("groups outside tolerance t [%]")
    ax_cum.set_title("Share outside a tolerance t")
    ax_cum.legend(loc="upper right")
    text_block(fig, 0.18, caption, size=8.2)
    return fig


def tilt_page(
    ok: pd.DataFrame,
    tilt: pd.DataFrame,
    pairs: pd.DataFrame,
    groups: Sequence[str],
    protocol: str,
    caption: Sequence[str],
) -> Figure:
    """Inequality against chassis tilt (which axle is heaviest), load shares by tilt band, static against WIM."""
    fig = new_page("Survey: chassis tilt, and the weighbridge against WIM", body=(0.06, 0.2, 0.88, 0.73))
    axes = fig.subplots(3, len(groups), squeeze=False)
    for c, group in enumerate(groups):
        n_axles = 2 if group == "tandem" else 3
        sub = ok[(ok["group"] == group) & (ok["protocol"] == protocol)]
        ax = axes[0, c]
        for i in range(n_axles):
            name = axle_name(i, n_axles)
            pick = sub[sub["heaviest_axle"] == i]
            ax.scatter(
                pick["tilt_deg"],
                100.0 * pick["max_deviation"],
                s=_marker_size(len(sub)),
                color=AXLE_COLOR[name],
                alpha=0.7,
                lw=0,
                label=f"{name} axle heaviest",
            )
        ax.set_title(f"{GROUP_LABEL[group]}, {PROTOCOL_LABEL[protocol]}: every bogie")
        ax.set_xlabel("chassis tilt, nose up + [degree]")
        ax.set_ylabel("max. deviation from the mean [%]")
        ax.legend(loc="upper center", markerscale=2)
        ax = axes[1, c]
        handles = []
        for prot in dict.fromkeys(tilt["protocol"]):
            band = tilt[(tilt["group"] == group) & (tilt["protocol"] == prot)]
            mid = 0.5 * (band["tilt_deg_low"] + band["tilt_deg_high"])
            for i in range(n_axles):
                ax.plot(
                    mid,
                    band[f"mean_load_share_{i}"],
                    ls=PROTOCOL_LINE[prot],
                    marker="o",
                    ms=3,
                    color=AXLE_COLOR[axle_name(i, n_axles)],
                )
            handles.append(Line2D([], [], color="0.3", ls=PROTOCOL_LINE[prot], label=PROTOCOL_LABEL[prot]))
        handles = [
            Line2D([], [], color=AXLE_COLOR[axle_name(i, n_axles)], label=f"{axle_name(i, n_axles)} axle")
            for i in range(n_axles)
        ] + handles
        ax.axhline(1.0, color="0.3", lw=0.6)
        ax.set_title(f"{GROUP_LABEL[group]}: mean load share per 0.5° tilt band")
        ax.set_xlabel("chassis tilt, nose up + [degree]")
        ax.set_ylabel("mean load share [-]")
        low, high = ax.get_ylim()
        ax.set_ylim(low, high + 0.45 * (high - low))  # headroom for the legend above the lines
        ax.legend(handles=handles, loc="upper center", ncol=2)
    ax_d, ax_s = axes[2, 0], axes[2, -1]
    if not pairs.empty:
        ax_d.axline((1.0, 1.0), (10.0, 10.0), color="0.3", lw=0.6, label="equal readings")
        ax_s.axline((1.0, 1.0), slope=1.0, color="0.3", lw=0.6)
        for group in groups:
            sub = pairs[pairs["group"] == group]
            ax_d.scatter(
                100.0 * sub["max_deviation_static"],
                100.0 * sub["max_deviation_wim"],
                s=_marker_size(len(pairs)),
                lw=0,
                alpha=0.7,
                color=GROUP_COLOR[group],
                label=GROUP_LABEL[group],
            )
            n_axles = 2 if group == "tandem" else 3
            for i in range(n_axles):
                name = axle_name(i, n_axles)
                ax_s.scatter(
                    sub[f"load_share_{i}_static"],
                    sub[f"load_share_{i}_wim"],
                    s=_marker_size(len(pairs)),
                    lw=0,
                    alpha=0.6,
                    color=AXLE_COLOR[name],
                    marker="o" if group == "tandem" else "^",
                    label=f"{GROUP_LABEL[group]}, {name}",
                )
        # log axes: WIM readings run an order of magnitude above the weighbridge's, and both span decades
        both = 100.0 * pairs[["max_deviation_static", "max_deviation_wim"]].to_numpy(dtype=float)
        lo, hi = np.percentile(both[both > 0.0], [0.5, 100.0])
        ax_d.set_xscale("log")
        ax_d.set_yscale("log")
        ax_d.set_xlim(lo / 1.5, hi * 1.5)
        ax_d.set_ylim(lo / 1.5, hi * 1.5)
        shares = pairs[[c for c in pairs.columns if c.startswith("load_share_") and not c.endswith("_diff")]]
        shares = shares.to_numpy(dtype=float)
        shares = shares[shares > 0.0]
        lo, hi = np.percentile(shares, [0.25, 99.75])
        ax_s.set_xlim(lo - 0.02, hi + 0.02)
        ax_s.set_ylim(lo - 0.02, hi + 0.02)
    ax_d.set_xlabel("max. deviation, static weighbridge [%]")
    ax_d.set_ylabel("max. deviation, WIM [%]")
    ax_d.set_title("Same bogie, both protocols")
    ax_d.legend(loc="upper left")
    ax_s.set_xlabel("load share, static weighbridge [-]")
    ax_s.set_ylabel("load share, WIM [-]")
    ax_s.set_title("Each axle's share, both protocols")
    ax_s.legend(loc="upper left", ncol=2, markerscale=2)
    text_block(fig, 0.18, caption, size=8.2)
    return fig


# ---- reproduction of the reference -------------------------------------------------------------------------------
def step_runs_page(
    histories: Mapping[str, tuple[np.ndarray, np.ndarray]],
    linear: tuple[np.ndarray, np.ndarray],
    reference: Mapping[str, tuple[float, float]],
    titles: Mapping[str, str],
    caption: Sequence[str],
) -> Figure:
    """The non-linear step runs against the linear L03: P1 [N] histories, the reference's figures as lines.

    Parameters
    ----------
    histories
        Run name -> (time [s], P1 [N]) of the non-linear runs.
    linear
        (time [s], P1 [N]) of L03.
    reference
        Run name -> the reference's P1 with the front and with the rear wheel on the step [N].
    titles
        Run name -> panel title.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Reference: the non-linear step runs against the linear L03", body=(0.06, 0.36, 0.88, 0.57))
    axes = fig.subplots(2, 2, sharex=True, sharey=True).ravel()
    for ax, (name, (t, p1)) in zip(axes, histories.items()):
        ax.plot(linear[0], linear[1] / 1e3, color="0.55", lw=1.0, ls="--", label="L03 (linear, soft bush)")
        ax.plot(t, p1 / 1e3, color="C3", lw=1.1, label="non-linear run")
        front, rear = reference[name]
        ax.axhline(front / 1e3, color="C0", lw=0.9, ls=":", label="reference, front wheel on step")
        ax.axhline(rear / 1e3, color="C2", lw=0.9, ls=":", label="reference, rear wheel on step")
        ax.set_title(titles[name], fontsize=8.5)
        ax.set_ylabel("P1 (Equation 4) [kN]")
    # one legend, in the panel whose curves stay lowest (the most free space above them)
    quiet = min(
        range(len(histories)), key=lambda k: max(np.max(list(histories.values())[k][1]), *list(reference.values())[k])
    )
    axes[quiet].legend(loc="upper right")
    for ax in axes[2:]:
        ax.set_xlabel("time [s]")
    text_block(fig, 0.34, caption, size=8.2)
    return fig


# ---- design guidance -------------------------------------------------------------------------------------------
def _nice_log_edges(x: np.ndarray) -> np.ndarray:
    """Edges 1, 3, 10, 30, ... times a power of ten that cover ``x`` (positive)."""
    lo, hi = float(np.min(x)), float(np.max(x))
    ladder = np.sort(
        np.outer(10.0 ** np.arange(np.floor(np.log10(lo)) - 1, np.ceil(np.log10(hi)) + 2), [1.0, 3.0]).ravel()
    )
    edges = ladder[(ladder >= ladder[ladder <= lo].max()) & (ladder <= ladder[ladder >= hi].min())]
    return edges if len(edges) > 1 else np.array([lo, hi * 1.0001 + 1e-12])


def _nice_edges(x: np.ndarray, bins: int, step: float) -> np.ndarray:
    """``bins`` equal bins from ``x``'s minimum to its maximum, ends rounded outward to ``step``."""
    lo, hi = np.floor(np.min(x) / step) * step, np.ceil(np.max(x) / step) * step
    return np.linspace(lo, hi if hi > lo else lo + step, bins + 1)


def _wilson(k: np.ndarray, n: np.ndarray, z: float = 1.96) -> tuple[np.ndarray, np.ndarray]:
    """95 % Wilson score interval of a proportion k / n (NaN where n = 0)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def _bin_index(x: np.ndarray, edges: np.ndarray) -> np.ndarray:
    # left-closed bins, the last closed: a value on the top edge belongs to the last bin
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)


def design_tables(ok: pd.DataFrame, protocol: str) -> tuple[dict[str, pd.DataFrame], dict[str, pd.DataFrame]]:
    """Share of groups within 5 % binned by design parameters, from the fleet's succeeded runs of ``protocol``.

    Returns
    -------
    grids : dict
        Group -> cells of bush stiffness [N m/rad] (``x_low``, ``x_high``, log bins) by equaliser arm [mm]
        (``y_low``, ``y_high``): ``n`` and ``share`` within 5 % [-] (NaN when empty).
    lines : dict
        Axis label -> per group and bin of one parameter (edge units): ``low``, ``high``, ``n``, ``share`` and its
        95 % Wilson interval ``share_low``, ``share_high``.
    """
    runs = ok[ok["protocol"] == protocol]
    within = ~runs["outside_5pct"].to_numpy(dtype=bool)
    values = {
        "bush stiffness [N m/rad]": runs["bush_stiffness"].to_numpy(dtype=float),
        "equaliser arm [mm]": 1e3 * runs["equaliser_arm"].to_numpy(dtype=float),
        "friction coefficient [-]": runs["friction_coefficient"].to_numpy(dtype=float),
        "contact roll radius [mm]": 1e3 * runs["contact_roll_radius"].to_numpy(dtype=float),
    }
    if runs.empty:
        return {}, {}
    edges = {
        "bush stiffness [N m/rad]": _nice_log_edges(np.maximum(values["bush stiffness [N m/rad]"], 1e-3)),
        "equaliser arm [mm]": _nice_edges(values["equaliser arm [mm]"], 4, 10.0),
        "friction coefficient [-]": _nice_edges(values["friction coefficient [-]"], 5, 0.05),
        "contact roll radius [mm]": _nice_edges(values["contact roll radius [mm]"], 6, 10.0),
    }
    index = {label: _bin_index(values[label], edges[label]) for label in values}
    groups = runs["group"].to_numpy()
    order = [g for g in GROUP_LABEL if g in set(groups)]
    lines, grids = {}, {}
    for label, e in edges.items():
        rows = []
        for group in order:
            g = groups == group
            n = np.bincount(index[label][g], minlength=len(e) - 1)
            k = np.bincount(index[label][g], weights=within[g], minlength=len(e) - 1)
            low, high = _wilson(k, n)
            rows.append(
                pd.DataFrame(
                    {
                        "group": group,
                        "low": e[:-1],
                        "high": e[1:],
                        "n": n,
                        "share": k / np.where(n, n, np.nan),
                        "share_low": low,
                        "share_high": high,
                    }
                )
            )
        lines[label] = pd.concat(rows, ignore_index=True)
    xe, ye = edges["bush stiffness [N m/rad]"], edges["equaliser arm [mm]"]
    for group in order:
        g = groups == group
        cell = index["bush stiffness [N m/rad]"][g] * (len(ye) - 1) + index["equaliser arm [mm]"][g]
        n = np.bincount(cell, minlength=(len(xe) - 1) * (len(ye) - 1))
        k = np.bincount(cell, weights=within[g], minlength=len(n))
        i, j = np.divmod(np.arange(len(n)), len(ye) - 1)
        grids[group] = pd.DataFrame(
            {
                "x_low": xe[i],
                "x_high": xe[i + 1],
                "y_low": ye[j],
                "y_high": ye[j + 1],
                "n": n,
                "share": k / np.where(n, n, np.nan),
            }
        )
    return grids, lines


def design_page(
    grids: Mapping[str, pd.DataFrame], lines: Mapping[str, pd.DataFrame], target: float, caption: Sequence[str]
) -> Figure:
    """Share of groups within 5 % by bush stiffness and arm length (maps), and by single factors (lines).

    Parameters
    ----------
    grids
        Group -> cells with ``x_low``, ``x_high`` (bush stiffness [N m/rad]), ``y_low``, ``y_high`` (arm [mm]),
        ``n`` and ``share`` (within 5 % [-], NaN for an empty cell).
    lines
        Axis label -> bins with ``group``, ``low``, ``high``, ``n``, ``share``, ``share_low``, ``share_high``;
        a label containing "N m/rad" is drawn on a log axis.
    target
        Target share within 5 % [-], drawn on every chart.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Design guidance: what keeps a bogie within 5 %", body=(0.06, 0.31, 0.88, 0.62))
    sub = fig.subfigures(2, 1, height_ratios=(1.0, 1.3))
    maps = sub[0].subplots(1, len(grids), squeeze=False)[0]
    mesh = None
    for ax, (group, cells) in zip(maps, grids.items()):
        xs = np.unique(np.r_[cells["x_low"], cells["x_high"]])
        ys = np.unique(np.r_[cells["y_low"], cells["y_high"]])
        z = cells.pivot_table(index="y_low", columns="x_low", values="share", dropna=False).reindex(
            index=ys[:-1], columns=xs[:-1]
        )
        mesh = ax.pcolormesh(xs, ys, 100.0 * z.to_numpy(), vmin=0.0, vmax=100.0, edgecolors="w", linewidth=0.5)
        for cell in cells.itertuples():
            xm, ym = math.sqrt(cell.x_low * cell.x_high), 0.5 * (cell.y_low + cell.y_high)
            text = "–" if cell.n == 0 else f"{100 * cell.share:.0f}%\nn={cell.n}"
            dark = cell.n and not 0.2 <= cell.share <= 0.85  # the colour map's dark ends need white text
            ax.text(
                xm,
                ym,
                text,
                ha="center",
                va="center",
                fontsize=6.3,
                color="w" if dark else "k",
                weight="bold" if cell.n and cell.share >= target else None,
            )
        ax.set_xscale("log")
        ax.grid(False)
        ax.set_xlabel("bush stiffness [N m/rad]")
        ax.set_ylabel("equaliser arm [mm]")
        ax.set_title(f"{GROUP_LABEL[group]}: groups within 5 %")
    if mesh is not None:
        sub[0].colorbar(mesh, ax=list(maps), label="within 5 % [%]", shrink=0.9)
    line_axes = sub[1].subplots(2, 2).ravel()
    for ax, (label, bins) in zip(line_axes, lines.items()):
        for group in dict.fromkeys(bins["group"]):
            b = bins[bins["group"] == group]
            mid = np.sqrt(b["low"] * b["high"]) if "N m/rad" in label else 0.5 * (b["low"] + b["high"])
            ax.fill_between(
                mid, 100 * b["share_low"], 100 * b["share_high"], color=GROUP_COLOR[group], alpha=0.15, lw=0
            )
            ax.plot(mid, 100 * b["share"], marker="o", ms=3, color=GROUP_COLOR[group], label=GROUP_LABEL[group])
        ax.axhline(100 * target, color="0.2", ls="--", lw=0.8, label=f"target {100 * target:.0f} %")
        if "N m/rad" in label:
            ax.set_xscale("log")
        ax.set_ylim(0.0, 100.0)
        ax.set_xlabel(label)
        ax.set_ylabel("within 5 % [%]")
    handles, labels = line_axes[0].get_legend_handles_labels()
    sub[1].legend(handles, labels, loc="outside upper center", ncol=len(labels))
    text_block(fig, 0.29, caption, size=8.0)
    return fig


# ---- appendix --------------------------------------------------------------------------------------------------
def parameters_page(panels: Sequence[dict], caption: Sequence[str]) -> Figure:
    """Histograms of the fleet's sampled parameters.

    Parameters
    ----------
    panels
        One dict per chart: ``title``, ``xlabel``, and either ``values`` (numbers, edge units) with optional
        ``log`` (log-spaced bins), or ``categories`` (label -> count) with optional ``expected`` (label -> count).
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Appendix A: the parameters as sampled (fleet study)", body=(0.06, 0.12, 0.88, 0.81))
    axes = fig.subplots(math.ceil(len(panels) / 2), 2).ravel()
    for ax, panel in zip(axes, panels):
        if "categories" in panel:
            labels = list(panel["categories"])
            ax.bar(labels, [panel["categories"][k] for k in labels], color="C0", alpha=0.8, label="sampled")
            if panel.get("expected"):
                ax.plot(labels, [panel["expected"][k] for k in labels], "k_", ms=18, mew=1.5, label="expected")
            ax.set_ylim(0.0, 1.3 * max([*panel["categories"].values(), *(panel.get("expected") or {}).values(), 1]))
            ax.legend(loc="upper left", ncol=2)
        else:
            x = np.asarray(panel["values"], dtype=float)
            lo, hi = float(np.min(x)), float(np.max(x))
            log = panel.get("log") and lo > 0.0
            bins = np.geomspace(lo, hi, 26) if log and hi > lo else 25
            ax.hist(x, bins=bins, color="C0", alpha=0.8)
            if log:
                ax.set_xscale("log")
        ax.set_title(panel["title"], fontsize=8.5)
        ax.set_xlabel(panel["xlabel"])
        ax.set_ylabel("count")
    for ax in axes[len(panels) :]:
        ax.remove()
    text_block(fig, 0.095, caption, size=8.0)
    return fig


def text_page(title: str, paragraphs: Sequence[str], size: float = 8.8) -> Figure:
    """A page of text only (definitions, assumptions)."""
    fig = Figure(figsize=A4)
    _header(fig, title)
    text_block(fig, 0.92, paragraphs, size=size)
    return fig


def failures_pages(
    title: str, header: Sequence[str], rows: Sequence[Sequence[str]], intro: Sequence[str], widths: Sequence[float]
) -> list[Figure]:
    """The failed runs as a table over as many pages as it needs (one page saying so when there are none)."""
    size, bottom = 7.0, 0.07
    line = size * 1.3 / 72.0 / A4[1]

    def height(row: Sequence[str]) -> float:
        return line * (1.8 + max(str(c).count("\n") for c in row))  # as table_axes draws it

    pages: list[Figure] = []
    remaining = list(rows)
    while True:
        fig = Figure(figsize=A4)
        _header(fig, title + (f" (continued, page {len(pages) + 1})" if pages else ""))
        top = text_block(fig, 0.92, [] if pages else intro, size=8.8) - 0.005
        room, chunk = top - bottom - height(header), []
        while remaining and (not chunk or height(remaining[0]) <= room):
            room -= height(remaining[0])
            chunk.append(remaining.pop(0))
        if chunk:
            table_axes(fig, top, header, chunk, widths, size)
        pages.append(fig)
        if not remaining:
            return pages
