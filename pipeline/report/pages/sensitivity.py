"""The sensitivity page: Sobol' indices of every inequality measure and the ablation of the five inhibitors."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import first_fit, new_page, text_block
from pipeline.report.style import MEASURE_LABEL, PROTOCOL_LABEL, factor_label
from pipeline.report.tables import worse_without

__all__ = ["ablation_bars", "page", "sensitivity_page"]


def _index_bars(ax, main: pd.DataFrame, ranking_measure: str) -> None:
    """S1 and ST of the ranking measure with their half-widths, one pair of bars per factor."""
    y = np.arange(len(main))
    for k, (col, color) in enumerate((("S1", "0.65"), ("ST", "C0"))):
        ax.barh(
            y + (k - 0.5) * 0.38,
            main[col],
            0.36,
            xerr=main[f"{col}_conf"],
            color=color,
            label=col,
            error_kw={"lw": 0.8, "capsize": 2},
        )
    ax.set_yticks(y, [factor_label(f) for f in main["factor"]])
    ax.set_xlabel("Sobol' index [-]")
    ax.set_title(f"{MEASURE_LABEL.get(ranking_measure, ranking_measure)}: first order S1, total ST")
    ax.legend(loc="lower right")
    ax.axvline(0.0, color="0.3", lw=0.6)
    ax.set_ylim(-1.4, len(main) - 0.5)  # a free band at the foot for the legend


def _measure_bars(ax, indices: pd.DataFrame, order: Sequence[str], ranking_measure: str) -> None:
    """ST of every measure, factors in ``order``."""
    y = np.arange(len(order))
    others = [m for m in indices["measure"].unique() if m != ranking_measure]
    for k, measure in enumerate([ranking_measure, *others]):
        sub = indices[indices["measure"] == measure].set_index("factor").reindex(order)
        ax.barh(
            y + (k - 1) * 0.27,
            sub["ST"],
            0.25,
            xerr=sub["ST_conf"],
            color=f"C{k}",
            label=MEASURE_LABEL.get(measure, measure),
            error_kw={"lw": 0.7, "capsize": 1.5},
        )
    ax.set_yticks(y, [])
    ax.set_ylim(-1.4, len(order) - 0.5)
    ax.axvline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel("total index ST [-]")
    ax.set_title("ST of each inequality measure")
    ax.legend(loc="lower right")


def ablation_bars(ax, rows: pd.DataFrame, scale: float) -> None:
    """One statistic of the ablation: a bar per variant and protocol, whisker the variant's paired interval."""
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
    ax.set_yticks(y, [factor_label(v) for v in variants])
    ax.set_ylim(-1.6, len(variants) - 0.5)  # a free band at the foot for the legend
    ax.legend(loc="lower right", ncol=2)


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

    def draw(layout: tuple[float, float]) -> tuple[Figure, float]:
        bottom, size = layout
        fig = new_page("Sensitivity: which inhibitor matters", body=(0.06, bottom, 0.88, 0.93 - bottom))
        (ax_s, ax_m), (ax_a, ax_o) = fig.subplots(2, 2, gridspec_kw={"width_ratios": (1.2, 1.0)})
        main = indices[indices["measure"] == ranking_measure].sort_values("ST")
        _index_bars(ax_s, main, ranking_measure)
        _measure_bars(ax_m, indices, list(main["factor"]), ranking_measure)
        for ax, statistic, scale, label in (
            (ax_a, "mean_max_deviation", 100.0, "fleet mean of max. deviation [%]"),
            (ax_o, "share_outside_5pct", 100.0, "groups outside 5 % [%]"),
        ):
            ablation_bars(ax, ablation[ablation["statistic"] == statistic], scale)
            ax.set_xlabel(label)
        ax_a.set_title("Ablation: mean inequality")
        ax_o.set_title("Ablation: outside 5 %")
        ax_o.set_yticklabels([])
        return fig, text_block(fig, bottom - 0.035, caption, size=size)

    return first_fit(SENSITIVITY_FITS, draw)


#: (bottom of the charts [page fraction], caption type size [pt]) the page tries, first that ends above the footer
SENSITIVITY_FITS = ((0.24, 8.2), (0.26, 8.0), (0.28, 7.8), (0.30, 7.6), (0.32, 7.4))


def page(ctx: Context) -> list[Page]:
    """Page 3: Sobol' indices (data/sensitivity/sobol_indices.csv) and the ablation (ablation.csv, group all)."""
    tables = ctx.inputs.sensitivity
    abl = tables["ablation.csv"]
    caption = text.render("sensitivity.j2", numbers=ctx.numbers, worse=worse_without(ctx.numbers))
    measure = ctx.inputs.sensitivity_metrics["sobol"]["measure"]
    fig = sensitivity_page(tables["sobol_indices.csv"], abl[abl["group"] == "all"], measure, caption)
    return [Page("Sensitivity", "sensitivity", fig)]
