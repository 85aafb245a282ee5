"""The observed page: an observed survey's load shares and spreads against the simulated fleet's, and the caveats.

Every chart is drawn from the tables of the ``observed`` stage (data/observed: the observed groups and the fleet's
readings under the same filters); the words come from metrics/observed.json. Without an observed survey the page
draws the simulated side alone and says how to give one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from bogie.fleet.constants import n_axles
from bogie.weighings.sites import FAMILY_LEVEL, FEWEST, share_text
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import first_fit, new_page, table_pages, text_block
from pipeline.report.style import GROUP_LABEL, GROUPS, SOURCE_COLOR, SOURCE_LABEL, load_share_axes

__all__ = ["SIZES", "SITE_HEADER", "SOURCES", "observed_page", "page", "site_table", "sources"]

#: the group sizes compared
SIZES: tuple[str, ...] = GROUPS
#: the sides compared, in the order drawn
SOURCES: tuple[str, ...] = ("observed", "static", "wim")


def sources(groups: pd.DataFrame, simulated: pd.DataFrame, size: str) -> dict[str, pd.DataFrame]:
    """The groups of one size on each side: the observed groups, the simulated static and WIM readings.

    A side with no group of that size is left out (no observed survey, a protocol not run, a filter that leaves
    nothing).
    """
    sides = {"observed": groups[groups["group"] == size]}
    for protocol in ("static", "wim"):
        sides[protocol] = simulated[(simulated["group"] == size) & (simulated["protocol"] == protocol)]
    return {name: sides[name] for name in SOURCES if len(sides[name])}


def _nothing(ax, what: str) -> None:
    ax.text(0.5, 0.5, what, ha="center", va="center", transform=ax.transAxes, color="0.4")
    ax.set_axis_off()


def _load_share_boxes(ax, sides: Mapping[str, pd.DataFrame], size: str) -> None:
    """Box plots of each axle position's load share, one box per side (quartiles, 5th-95th percentile whiskers)."""
    n = n_axles(size)
    title = f"{GROUP_LABEL[size].capitalize()}: load share per axle"
    if not sides:
        ax.set_title(title)
        _nothing(ax, f"no {GROUP_LABEL[size]} group passes the filters")
        return
    width = 0.8 / len(SOURCES)
    for k, name in enumerate(SOURCES):
        if name not in sides:
            continue
        data = [sides[name][f"load_share_{i + 1}"].to_numpy(dtype=float) for i in range(n)]
        pos = np.arange(n) + (k - (len(SOURCES) - 1) / 2) * width
        color = SOURCE_COLOR[name]
        ax.boxplot(
            data,
            positions=pos,
            widths=0.85 * width,
            whis=(5, 95),
            showfliers=False,
            patch_artist=True,
            boxprops={"facecolor": color, "alpha": 0.35, "edgecolor": color},
            whiskerprops={"color": color},
            capprops={"color": color},
            medianprops={"color": color, "lw": 1.6},
        )
    load_share_axes(ax, n)
    handles = [Patch(facecolor=SOURCE_COLOR[s], alpha=0.5, label=f"{SOURCE_LABEL[s]}, {len(sides[s])} groups")
               for s in sides]  # fmt: skip
    ax.set_title(title, pad=8 + 10 * -(-len(handles) // 2))  # above the legend's rows
    # between the title and the chart: the boxes of the three sides can reach any height
    ax.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=6.5,
              frameon=False, borderaxespad=0.1, columnspacing=0.8, handletextpad=0.3)  # fmt: skip


def _spread_distribution(ax, sides: Mapping[str, pd.DataFrame], size: str) -> None:
    """The share of groups with a spread up to x [kg], every side (empirical distribution functions)."""
    title = f"{GROUP_LABEL[size].capitalize()}: heaviest minus lightest axle"
    if not sides:
        ax.set_title(title)
        _nothing(ax, f"no {GROUP_LABEL[size]} group passes the filters")
        return
    for name, sub in sides.items():
        x = np.sort(sub["spread_kg"].to_numpy(dtype=float))
        y = 100.0 * np.arange(1, len(x) + 1) / len(x)
        ax.step(np.r_[0.0, x], np.r_[0.0, y], where="post", color=SOURCE_COLOR[name], lw=1.4,
                label=f"{SOURCE_LABEL[name]} (mean {np.mean(x):.0f} kg)")  # fmt: skip
    ax.set_xlim(left=0.0)
    ax.set_ylim(0.0, 100.0)
    ax.set_xlabel("spread [kg]")
    ax.set_ylabel("groups up to this spread [%]")
    handles = ax.get_legend_handles_labels()[0]
    ax.set_title(title, pad=8 + 10 * -(-len(handles) // 2))  # above the legend's rows
    # between the title and the chart: a small survey's steps can cross any corner
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=6.5, frameon=False, borderaxespad=0.1,
              columnspacing=0.8)  # fmt: skip


def observed_page(groups: pd.DataFrame, simulated: pd.DataFrame, caption: Sequence[str]) -> Figure:
    """Load shares (box plots) and spreads (distribution functions) of the observed and simulated groups.

    Parameters
    ----------
    groups
        data/observed/groups.parquet: the observed groups after the filters (may be empty).
    simulated
        data/observed/simulated.parquet: the fleet's readings after the same filters.
    caption
        Paragraphs under the charts.
    """

    def draw(fit: tuple[float, float]) -> tuple[Figure, float]:
        bottom, type_size = fit
        fig = new_page("Observed against simulated", body=(0.06, bottom, 0.88, 0.93 - bottom))
        axes = fig.subplots(2, len(SIZES), squeeze=False)
        for c, size in enumerate(SIZES):
            sides = sources(groups, simulated, size)
            _load_share_boxes(axes[0, c], sides, size)
            _spread_distribution(axes[1, c], sides, size)
        return fig, text_block(fig, bottom - 0.015, caption, size=type_size)

    return first_fit(FITS, draw)


#: (bottom of the charts [page fraction], type size of the text [pt]) tried in turn until the text ends above the
#: footer (:func:`~pipeline.report.layout.first_fit`): the caveats grow with what the runs modelled, and a survey
#: adds its own lines
FITS = ((0.5, 7.9), (0.5, 7.5), (0.53, 7.5), (0.53, 7.1), (0.56, 7.1), (0.58, 6.8))


#: the columns of the sites' table, and their widths [table fraction]
SITE_HEADER = ("group", "site", "groups", "outside 5 % [%]\n(95 % interval)", "over 10 % [%]\n(95 % interval)",
               "mean spread\n[kg]", "flag")  # fmt: skip
SITE_WIDTHS = (0.09, 0.26, 0.07, 0.18, 0.18, 0.11, 0.11)


def site_table(rows: Sequence[Mapping]) -> list[list[str]]:
    """The rows of the sites' table from metrics/observed.json's ``observed.sites`` (the library's
    :func:`bogie.weighings.sites.compare_sites`, in its order: by size, the most unequal sharing first)."""
    out = []
    for r in rows:
        shares = [share_text(r[s], r[f"{s}_low"], r[f"{s}_high"]).strip() for s in ("share_outside_5pct",
                                                                                    "share_over_10pct")]  # fmt: skip
        spread = "-" if r["mean_spread_kg"] is None else f"{r['mean_spread_kg']:.0f}"
        flag = "disagrees" if r["disagrees"] else ("few" if r["few"] else "")
        out.append([GROUP_LABEL.get(r["group"], r["group"]), r["site"], str(r["n_groups"]), *shares, spread, flag])
    return out


def sites_pages(observed: Mapping) -> list[Page]:
    """The sites side by side (issue 46 Must 1): a file of several stations, each a site; none otherwise."""
    rows = observed.get("sites") or []
    if not rows:
        return []
    flagged = sorted({f"{r['site']} ({GROUP_LABEL.get(r['group'], r['group'])})" for r in rows if r["disagrees"]})
    intro = text.render("sites.j2", m=observed, flagged=flagged, fewest=FEWEST, level=f"{FAMILY_LEVEL:g}")
    title = "Observed: the sites side by side"
    figures = table_pages(title, SITE_HEADER, site_table(rows), intro, SITE_WIDTHS)
    return [Page(title if k == 0 else "", "", fig) for k, fig in enumerate(figures)]


def page(ctx: Context) -> list[Page]:
    """The observed page: from data/observed and metrics/observed.json; then the sites side by side, if the survey
    holds several."""
    inputs = ctx.inputs
    caption = text.render("observed.j2", m=inputs.observed_metrics, sizes=SIZES)
    tables = inputs.observed
    fig = observed_page(tables["groups.parquet"], tables["simulated.parquet"], caption)
    return [
        Page("Observed against simulated", "observed", fig),
        *sites_pages(inputs.observed_metrics.get("observed") or {}),
    ]
