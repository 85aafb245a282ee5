"""The appendices: A, the parameters as sampled; B, protocols, definitions and assumptions; C, the failed runs."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from bogie import numerics
from bogie.fleet.constants import PAIR_TOLERANCE, READ_TIME, SHARE_TOLERANCE, TARE_FRACTION
from bogie.fleet.weighing.survey import NOSE_UP_DEG
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import new_page, table_pages, text_block, text_page
from pipeline.report.style import GROUP_LABEL, factor_label
from pipeline.report.tables import failed_runs, parameter_panels

__all__ = ["definitions", "failures", "failures_table", "parameters", "parameters_page"]


# ---- A: parameters -------------------------------------------------------------------------------------------------
def _panel(ax, panel: dict) -> None:
    if "categories" in panel:
        labels = list(panel["categories"])
        ax.bar(labels, [panel["categories"][k] for k in labels], color="C0", alpha=0.8, label="sampled")
        if panel.get("expected"):
            ax.plot(labels, [panel["expected"][k] for k in labels], "k_", ms=18, mew=1.5, label="expected")
        ax.set_ylim(0.0, 1.7 * max([*panel["categories"].values(), *(panel.get("expected") or {}).values(), 1]))
        ax.legend(loc="upper left", ncol=2)
    else:
        x = np.asarray(panel["values"], dtype=float)
        lo, hi = float(np.min(x)), float(np.max(x))
        log = panel.get("log") and lo > 0.0
        bins = numerics.geomspace(lo, hi, 26) if log and hi > lo else 25
        ax.hist(x, bins=bins, color="C0", alpha=0.8)
        if log:
            ax.set_xscale("log")
    ax.set_title(panel["title"], fontsize=8.5)
    ax.set_xlabel(panel["xlabel"])
    ax.set_ylabel("count")


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
        _panel(ax, panel)
    for ax in axes[len(panels) :]:
        ax.remove()
    text_block(fig, 0.095, caption, size=8.0)
    return fig


def parameters(ctx: Context) -> list[Page]:
    """Appendix A: each sampled quantity of the fleet with its params.yaml distribution."""
    inputs, cfg = ctx.inputs, ctx.inputs.config
    panels = parameter_panels(inputs.fleet, inputs.raw_params, cfg)
    caption = text.render("parameters.j2", n=len(inputs.fleet), sampling=cfg.fleet.sampling, seed=cfg.seed)
    return [Page("Appendix A: parameters as sampled", "parameters", parameters_page(panels, caption))]


# ---- B: definitions ------------------------------------------------------------------------------------------------
def definitions(ctx: Context) -> list[Page]:
    """Appendix B: the protocols with params.yaml's settings, the definitions, the studies, the model in short."""
    paragraphs = text.render(
        "definitions.j2",
        config=ctx.inputs.config,
        tare=TARE_FRACTION,
        read_time=READ_TIME,
        pair_tolerance=PAIR_TOLERANCE,
        share_tolerance=SHARE_TOLERANCE,
        nose_up_deg=NOSE_UP_DEG,
        n_airborne=ctx.inputs.survey_metrics.get("n_airborne", 0),
        wim_class=ctx.inputs.survey_metrics.get("wim_class"),
    )
    fig = text_page("Appendix B: protocols, definitions and model assumptions", paragraphs)
    return [Page("Appendix B: protocols, definitions, assumptions", "", fig)]


# ---- C: failed runs ------------------------------------------------------------------------------------------------
#: Appendix C's columns and their widths [table fractions]
FAILURE_COLUMNS = ["study", "protocol", "group", "variant", "runs", "sample ids", "message (of the first)"]
FAILURE_WIDTHS = [0.1, 0.08, 0.08, 0.12, 0.05, 0.18, 0.39]


def failures_table(failed: pd.DataFrame, shown: int = 12) -> list[list[str]]:
    """Rows of Appendix C (:func:`pipeline.report.tables.failed_runs`): at most ``shown`` ids, long cells wrapped."""
    rows = []
    for r in failed.itertuples():
        ids = r.sample_ids.split()
        listed = " ".join(ids[:shown]) + (f" ... ({len(ids)} in all)" if len(ids) > shown else "")
        variant = "–" if r.variant == "baseline" and r.study != "ablation" else factor_label(r.variant)
        rows.append(
            [
                r.study,
                r.protocol,
                GROUP_LABEL.get(r.group, r.group),
                "\n".join(textwrap.wrap(variant, 14)),
                str(r.n),
                "\n".join(textwrap.wrap(listed, 24)),
                "\n".join(textwrap.wrap(str(r.message), 50)),
            ]
        )
    return rows


def failures(ctx: Context) -> list[Page]:
    """Appendix C: every failed run, grouped, over as many pages as it needs; no page when none failed (the title
    page says so under its run counts)."""
    failed = failed_runs(ctx.inputs.runs)
    if failed.empty:
        return []  # the title page's run counts say that no run failed
    intro = text.render("failures.j2", n=int(failed["n"].sum()))
    title = "Appendix C: failed runs"
    figures = table_pages(title, FAILURE_COLUMNS, failures_table(failed), intro, FAILURE_WIDTHS)
    return [Page(title if k == 0 else "", "", fig) for k, fig in enumerate(figures)]
