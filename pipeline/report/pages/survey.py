"""The survey pages: how unequal the fleet is (load shares, spreads, tolerances), chassis tilt and static against WIM.

Every chart is drawn from the fleet's succeeded runs with the survey's inequality columns (``ok``) and the survey's
tables; the words come from metrics/survey.json.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from bogie.fleet.constants import n_axles
from bogie.fleet.weighing.survey import NOSE_UP_DEG
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import new_page, text_block
from pipeline.report.style import AXLE_COLOR, GROUP_COLOR, GROUP_LABEL, PROTOCOL_LABEL, PROTOCOL_LINE, axle_name

__all__ = ["load_share", "load_share_page", "tilt", "tilt_page"]


def _marker_size(n: int) -> float:
    """Scatter marker area [pt^2]: small for thousands of points, visible for a handful."""
    return float(np.clip(3000.0 / max(n, 1), 6.0, 25.0))


# ---- how unequal ---------------------------------------------------------------------------------------------------
def _share_histogram(ax, sub: pd.DataFrame, group: str, protocol: str) -> None:
    """Histograms of each axle position's load share of one group and protocol."""
    n = n_axles(group)
    shares = sub[[f"load_share_{i + 1}" for i in range(n)]].to_numpy(dtype=float)
    # bins over this panel's central 99 %: the static readings crowd near 1, WIM's spread far wider, and
    # a few wheel-lift readings would otherwise squash every other bin into one
    span = np.percentile(shares, [0.5, 99.5]) if shares.size else (0.8, 1.2)
    edges = np.linspace(span[0], span[1] if span[1] > span[0] else span[0] + 0.1, 41)
    ax.axvspan(0.9, 1.1, color="0.92", lw=0, label="within 10 % of equal")
    for i in range(n):
        name = axle_name(i, n)
        ax.stairs(np.histogram(shares[:, i], edges)[0], edges, color=AXLE_COLOR[name], lw=1.2, label=f"{name} axle")
    ax.set_title(f"{GROUP_LABEL[group]}, {PROTOCOL_LABEL[protocol]} ({len(sub)} groups)")
    ax.set_xlabel("load share (1 = equal share) [-]")
    ax.set_ylabel("axles")
    ax.set_ylim(0.0, 1.45 * ax.get_ylim()[1])  # headroom for the legend above the peak
    ax.legend(loc="upper right")


def _spread_and_tolerance(ax_kg, ax_cum, ok: pd.DataFrame, groups: Sequence[str], protocols: Sequence[str]) -> None:
    """Box plots of the spread [kg]; the share outside every tolerance t (solid static, dashed WIM)."""
    labels, boxes, means = [], [], []
    for group in groups:
        for protocol in protocols:
            sel = (ok["group"] == group) & (ok["protocol"] == protocol)
            x = ok.loc[sel, "pair_difference"].to_numpy(dtype=float) * 100.0
            style = {"color": GROUP_COLOR[group], "ls": PROTOCOL_LINE[protocol], "lw": 1.3}
            if len(x):
                t = np.linspace(0.0, 30.0, 301)
                outside = 100.0 * (x[None, :] > t[:, None]).mean(axis=1)
                ax_cum.plot(t, outside, **style, label=f"{GROUP_LABEL[group]}, {protocol}")
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
        ax_kg.legend(loc="upper right")
    ax_kg.set_xlabel("heaviest minus lightest axle [kg]")
    ax_kg.set_title("Spread between axles")
    ax_cum.axvline(5.0, color="0.3", lw=0.8, ls=":")
    ax_cum.set_xlim(0.0, 30.0)
    ax_cum.set_ylim(0.0, 100.0)
    ax_cum.set_xlabel("tolerance t [%]")
    ax_cum.set_ylabel("groups outside tolerance t [%]")
    ax_cum.set_title("Share outside a tolerance t")
    ax_cum.legend(loc="upper right")


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
        for c, protocol in enumerate(protocols):
            _share_histogram(axes[r, c], ok[(ok["group"] == group) & (ok["protocol"] == protocol)], group, protocol)
        for ax in axes[r, len(protocols) :]:
            ax.remove()
    _spread_and_tolerance(axes[-1, 0], axes[-1, 1], ok, groups, protocols)
    text_block(fig, 0.18, caption, size=8.2)
    return fig


def load_share(ctx: Context) -> list[Page]:
    """Page 4: how unequal the fleet is."""
    sv = ctx.inputs.survey_metrics
    caption = text.render("load_share.j2", survey=sv, groups=ctx.groups, protocols=ctx.protocols)
    fig = load_share_page(ctx.inputs.ok, ctx.groups, ctx.protocols, caption)
    return [Page("Survey", "survey_load_share", fig)]


# ---- tilt, static against WIM ------------------------------------------------------------------------------------
def _tilt_scatter(ax, sub: pd.DataFrame, group: str, protocol: str) -> None:
    """Every bogie's maximum deviation against its tilt, coloured by its heaviest axle."""
    n = n_axles(group)
    for i in range(n):
        name = axle_name(i, n)
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
    ax.set_title(f"{GROUP_LABEL[group]}, {PROTOCOL_LABEL[protocol]}: every bogie", pad=16)
    ax.set_xlabel("chassis tilt, nose up + [degree]")
    ax.set_ylabel("max. deviation from the mean [%]")
    # between the title and the chart: a cloud of bogies can reach any corner
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3, markerscale=2, fontsize=6.5, frameon=False,
              borderaxespad=0.1, columnspacing=0.8, handletextpad=0.2)  # fmt: skip


def _tilt_bands(ax, tilt: pd.DataFrame, group: str) -> None:
    """The mean load share of each axle per tilt band, one line style per protocol."""
    n = n_axles(group)
    handles = []
    for prot in dict.fromkeys(tilt["protocol"]):
        band = tilt[(tilt["group"] == group) & (tilt["protocol"] == prot)]
        mid = 0.5 * (band["tilt_deg_low"] + band["tilt_deg_high"])
        for i in range(n):
            color = AXLE_COLOR[axle_name(i, n)]
            ax.plot(mid, band[f"mean_load_share_{i + 1}"], ls=PROTOCOL_LINE[prot], marker="o", ms=3, color=color)
        handles.append(Line2D([], [], color="0.3", ls=PROTOCOL_LINE[prot], label=PROTOCOL_LABEL[prot]))
    handles = [
        Line2D([], [], color=AXLE_COLOR[axle_name(i, n)], label=f"{axle_name(i, n)} axle") for i in range(n)
    ] + handles
    ax.axhline(1.0, color="0.3", lw=0.6)
    ax.set_title(f"{GROUP_LABEL[group]}: mean load share per 0.5° tilt band")
    ax.set_xlabel("chassis tilt, nose up + [degree]")
    ax.set_ylabel("mean load share [-]")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + 0.45 * (high - low))  # headroom for the legend above the lines
    ax.legend(handles=handles, loc="upper center", ncol=2)


def _pair_scatter(ax_d, ax_s, pairs: pd.DataFrame, groups: Sequence[str]) -> None:
    """The bogies weighed both ways: maximum deviation (log axes) and each axle's load share, static against WIM."""
    ax_d.axline((1.0, 1.0), (10.0, 10.0), color="0.3", lw=0.6, label="equal readings")
    ax_s.axline((1.0, 1.0), slope=1.0, color="0.3", lw=0.6)
    size = _marker_size(len(pairs))
    for group in groups:
        sub = pairs[pairs["group"] == group]
        dev = 100.0 * sub["max_deviation_static"], 100.0 * sub["max_deviation_wim"]
        ax_d.scatter(*dev, s=size, lw=0, alpha=0.7, color=GROUP_COLOR[group], label=GROUP_LABEL[group])
        n = n_axles(group)
        for i in range(n):
            name = axle_name(i, n)
            ax_s.scatter(
                sub[f"load_share_{i + 1}_static"],
                sub[f"load_share_{i + 1}_wim"],
                s=size,
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


def tilt_page(
    ok: pd.DataFrame,
    tilt: pd.DataFrame,
    pairs: pd.DataFrame,
    groups: Sequence[str],
    protocol: str,
    caption: Sequence[str],
) -> Figure:
    """Inequality against chassis tilt (which axle is heaviest), load shares by tilt band, static against WIM.

    Parameters
    ----------
    ok
        Succeeded fleet runs with the survey's inequality columns.
    tilt, pairs
        data/survey/tilt.csv and static_vs_wim_pairs.parquet.
    groups
        The axle groups present, in order.
    protocol
        The protocol of the top row's scatter.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Survey: chassis tilt, and the weighbridge against WIM", body=(0.06, 0.2, 0.88, 0.73))
    axes = fig.subplots(3, len(groups), squeeze=False)
    for c, group in enumerate(groups):
        _tilt_scatter(axes[0, c], ok[(ok["group"] == group) & (ok["protocol"] == protocol)], group, protocol)
        _tilt_bands(axes[1, c], tilt, group)
    ax_d, ax_s = axes[2, 0], axes[2, -1]
    if not pairs.empty:
        _pair_scatter(ax_d, ax_s, pairs, groups)
    ax_d.set_xlabel("max. deviation, static weighbridge [%]")
    ax_d.set_ylabel("max. deviation, WIM [%]")
    # the clouds fill the charts: their legends between the title and the chart, not over the points
    ax_d.set_title("Same bogie, both protocols", pad=22)
    ax_d.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3, fontsize=7, frameon=False, borderaxespad=0.2)
    ax_s.set_xlabel("load share, static weighbridge [-]")
    ax_s.set_ylabel("load share, WIM [-]")
    ax_s.set_title("Each axle's share, both protocols", pad=32)
    ax_s.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3, markerscale=2, fontsize=6.5, frameon=False,
                borderaxespad=0.2, columnspacing=0.8, handletextpad=0.2)  # fmt: skip
    text_block(fig, 0.18, caption, size=8.2)
    return fig


def tilt(ctx: Context) -> list[Page]:
    """Page 5: chassis tilt (the ``main`` protocol's bogies, tilt.csv) and static against WIM (the pairs)."""
    inputs = ctx.inputs
    caption = text.render(
        "tilt.j2",
        survey=inputs.survey_metrics,
        groups=ctx.groups,
        protocols=ctx.protocols,
        main=ctx.main,
        nose_up_deg=NOSE_UP_DEG,
    )
    tables = inputs.survey
    fig = tilt_page(inputs.ok, tables["tilt.csv"], tables["static_vs_wim_pairs.parquet"], ctx.groups, ctx.main, caption)
    return [Page("Survey", "survey_tilt", fig)]
