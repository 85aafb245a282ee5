"""The fleet-correlation page: the fleet's share within 5 % binned by design parameter (the survey's
``design_guidance.csv``), labelled as what it is. It is not design guidance: every other factor varies as sampled
within a bin. The design guidance is the controlled experiment of :mod:`pipeline.report.pages.guidance`."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import new_page, text_block
from pipeline.report.style import GROUP_COLOR, GROUP_LABEL
from pipeline.report.tables import DesignLine, design_quotes, design_tables

__all__ = ["DESIGN_TARGET", "MIN_CELL", "design_page", "page"]

#: the design guidance's target: this share of bogies within 5 % [-]
DESIGN_TARGET = 0.95
#: fewest bogies in a design cell or bin whose share the captions quote [-]
MIN_CELL = 10


def _share_map(ax, group: str, cells: pd.DataFrame, target: float):
    """The share within 5 % per cell of bush stiffness (log) by arm length, each cell labelled; returns the mesh."""
    xs = np.unique(np.r_[cells["x_low"], cells["x_high"]])
    ys = np.unique(np.r_[cells["y_low"], cells["y_high"]])
    z = cells.pivot_table(index="y_low", columns="x_low", values="share", dropna=False).reindex(
        index=ys[:-1], columns=xs[:-1]
    )
    mesh = ax.pcolormesh(xs, ys, 100.0 * z.to_numpy(), vmin=0.0, vmax=100.0, edgecolors="w", linewidth=0.5)
    for cell in cells.itertuples():
        xm, ym = math.sqrt(cell.x_low * cell.x_high), 0.5 * (cell.y_low + cell.y_high)
        label = "–" if cell.n == 0 else f"{100 * cell.share:.0f}%\nn={cell.n}"
        dark = cell.n and not 0.2 <= cell.share <= 0.85  # the colour map's dark ends need white text
        bold = "bold" if cell.n and cell.share >= target else None
        ax.text(xm, ym, label, ha="center", va="center", fontsize=6.3, color="w" if dark else "k", weight=bold)
    ax.set_xscale("log")
    ax.grid(False)
    ax.set_xlabel("bush stiffness [N m/rad]")
    ax.set_ylabel("equaliser arm [mm]")
    ax.set_title(f"{GROUP_LABEL[group]}: groups within 5 %")
    return mesh


def _share_line(ax, line: DesignLine, target: float) -> None:
    """The share within 5 % per bin of one parameter, per group, with its shaded interval."""
    bins = line.bins
    for group in dict.fromkeys(bins["group"]):
        b = bins[bins["group"] == group]
        mid = np.sqrt(b["low"] * b["high"]) if line.log else 0.5 * (b["low"] + b["high"])
        ax.fill_between(mid, 100 * b["share_low"], 100 * b["share_high"], color=GROUP_COLOR[group], alpha=0.15, lw=0)
        ax.plot(mid, 100 * b["share"], marker="o", ms=3, color=GROUP_COLOR[group], label=GROUP_LABEL[group])
    ax.axhline(100 * target, color="0.2", ls="--", lw=0.8, label=f"target {100 * target:.0f} %")
    if line.log:
        ax.set_xscale("log")
    ax.set_ylim(0.0, 100.0)
    ax.set_xlabel(line.label)
    ax.set_ylabel("within 5 % [%]")


def design_page(
    grids: Mapping[str, pd.DataFrame], lines: Sequence[DesignLine], target: float, caption: Sequence[str]
) -> Figure:
    """Share of groups within 5 % by bush stiffness and arm length (maps), and by single parameters (lines).

    Parameters
    ----------
    grids
        Group -> cells with ``x_low``, ``x_high`` (bush stiffness [N m/rad]), ``y_low``, ``y_high`` (arm [mm]),
        ``n`` and ``share`` (within 5 % [-], NaN for an empty cell).
    lines
        One per parameter (:class:`pipeline.report.tables.DesignLine`): its bins, axis label and log flag.
    target
        Target share within 5 % [-], drawn on every chart.
    caption
        Paragraphs under the charts.
    """
    title = "Fleet correlations by design parameter (no experiment)"
    fig = new_page(title, body=(0.06, 0.31, 0.88, 0.62))
    sub = fig.subfigures(2, 1, height_ratios=(1.0, 1.3))
    maps = sub[0].subplots(1, len(grids), squeeze=False)[0]
    mesh = None
    for ax, (group, cells) in zip(maps, grids.items()):
        mesh = _share_map(ax, group, cells, target)
    if mesh is not None:
        sub[0].colorbar(mesh, ax=list(maps), label="within 5 % [%]", shrink=0.9)
    line_axes = sub[1].subplots(2, 2).ravel()
    for ax, line in zip(line_axes, lines):
        _share_line(ax, line, target)
    handles, labels = line_axes[0].get_legend_handles_labels()
    sub[1].legend(handles, labels, loc="outside upper center", ncol=len(labels))
    text_block(fig, 0.29, caption, size=8.0)
    return fig


def page(ctx: Context) -> list[Page]:
    """The fleet's correlations of the ``main`` protocol; the caption quotes cells and bins of MIN_CELL bogies."""
    grids, lines = design_tables(ctx.inputs.survey["design_guidance.csv"], ctx.main)
    groups, trends = design_quotes(grids, lines, DESIGN_TARGET, MIN_CELL)
    caption = text.render(
        "design.j2", protocol=ctx.main, target=DESIGN_TARGET, min_cell=MIN_CELL, groups=groups, trends=trends
    )
    return [Page("Fleet correlations by design", "design_guidance", design_page(grids, lines, DESIGN_TARGET, caption))]
