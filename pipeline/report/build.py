"""The document: the report as a short list of named pages, written all or nothing; the command line.

:data:`PAGES` is the whole report after its title page, in order; each entry builds its page(s) from the
:class:`~pipeline.report.context.Context`. The title page comes last, once the contents are known, and goes first.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import pandas as pd
from matplotlib.backends.backend_pdf import PdfPages

from bogie.results import DynamicResult
from pipeline.atomic import atomic_outputs, run_stage, stage_inputs
from pipeline.report.context import Context, Page
from pipeline.report.inputs import ReportInputs, read_inputs
from pipeline.report.layout import contents, freeze_layout, number_pages
from pipeline.report.pages import (
    appendix,
    calibration,
    design,
    front,
    guidance,
    observed,
    reference,
    road,
    sensitivity,
    survey,
)  # fmt: skip
from pipeline.report.style import STYLE
from pipeline.report.tables import plot_series

__all__ = ["PAGES", "PNG_DPI", "build_pages", "main", "make_report", "report_series", "write_report"]

#: resolution of the PNG copies of the pages [dot/inch]
PNG_DPI = 110
#: the report after its title page: (what it is, the builder of its pages)
PAGES: tuple[tuple[str, Callable[[Context], list[Page]]], ...] = (
    ("summary", front.summary),
    ("sensitivity", sensitivity.page),
    ("survey: load share", survey.load_share),
    ("survey: tilt, static against WIM", survey.tilt),
    ("observed against simulated", observed.page),
    ("calibration", calibration.page),
    ("reference: Figure 2", reference.figure2_pages),
    ("reference: linear runs", reference.linear_pages),
    ("reference: step runs", reference.step_runs),
    ("design guidance", guidance.pages),
    ("fleet correlations by design", design.page),
    ("what unequal sharing costs the road", road.page),
    ("appendix A: parameters", appendix.parameters),
    ("appendix B: definitions", appendix.definitions),
    ("appendix C: failed runs", appendix.failures),
)


def build_pages(
    inputs: ReportInputs, runs: Mapping[str, DynamicResult], progress: Callable[[str], None] | None = None
) -> tuple[list[Page], dict[str, Any]]:
    """Every page of the report, in order (the title page first), and the summary's numbers.

    Parameters
    ----------
    inputs
        What the pipeline wrote (:func:`pipeline.report.inputs.read_inputs`).
    runs
        The reference cases' results (:func:`pipeline.report.pages.reference.reference_runs`).
    progress
        Told each part of the report as it is drawn (None: nothing).

    Returns
    -------
    pages : list of Page
        (section, PNG name or "" for a page without charts, Figure).
    numbers : dict
        The numbers the summary's sentences are made from, as read from metrics/*.json.
    """
    ctx = Context.of(inputs, runs)
    pages = []
    for k, (name, build) in enumerate(PAGES, start=1):
        if progress is not None:
            progress(f"report: drawing {name} ({k}/{len(PAGES)})")
        pages.extend(build(ctx))
    title = front.title(ctx, contents([p.section for p in pages], first=2))
    return [title, *pages], ctx.numbers


def report_series(inputs: ReportInputs) -> dict[str, pd.DataFrame]:
    """The DVC plot series of the report (:func:`pipeline.report.tables.plot_series`) from its inputs."""
    ablation, tilt = inputs.sensitivity["ablation.csv"], inputs.survey["tilt.csv"]
    return plot_series(inputs.sensitivity_metrics, ablation, inputs.ok, tilt)


def write_report(
    pages: Sequence[Page],
    series: Mapping[str, pd.DataFrame],
    pdf_path: str | Path,
    png_dir: str | Path,
    plots_dir: str | Path,
    code: str,
    own: Sequence[str | Path] = (),
) -> None:
    """Number the pages and write the PDF, the PNG pages and the plot series, all or nothing (pipeline.atomic).

    The footer names the code by the first 12 hex digits of ``code`` (its sha256). The PDF has no creation date, so
    the same pages give the same bytes.
    """
    number_pages([p.figure for p in pages], f"{front.TITLE} · code {code[:12]}")
    for page in pages:
        freeze_layout(page.figure)
    with atomic_outputs(files=[pdf_path], dirs=[png_dir, plots_dir], stage="report", own=own) as (
        (tmp_pdf,),
        (tmp_png, tmp_plots),
    ):
        metadata = {"Title": front.TITLE, "Subject": front.SUBTITLE, "Creator": "bogie pipeline.report"}
        with PdfPages(tmp_pdf, metadata={**metadata, "CreationDate": None}) as pdf:
            for page in pages:
                pdf.savefig(page.figure)
        for page in pages:
            if page.name:
                page.figure.savefig(tmp_png / f"{page.name}.png", format="png", dpi=PNG_DPI)
        for name, frame in series.items():
            frame.to_csv(tmp_plots / name, index=False, float_format="%.6g")


def make_report(
    inputs: ReportInputs, pdf: str | Path, png_dir: str | Path, plots_dir: str | Path,
    progress: Callable[[str], None] | None = None, own: Sequence[str | Path] = (),
) -> dict[str, Any]:  # fmt: skip
    """Build and write the whole report; returns the summary's numbers and the page count (key ``pages``).
    ``progress`` is told each step (the reference cases, each part, the writing; None: nothing)."""
    say = progress or (lambda text: None)
    say("report: running the reference's named cases")
    runs = reference.reference_runs()
    with matplotlib.rc_context(STYLE):
        pages, numbers = build_pages(inputs, runs, progress)
        say(f"report: writing {len(pages)} pages to the PDF and the PNG pages")
        write_report(pages, report_series(inputs), pdf, png_dir, plots_dir, inputs.facts["code_sha256"], own)
    return {**numbers, "pages": len(pages)}


def _to_stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    """Run the stage from the command line."""
    # the package's docstring is the command's description: the package is loaded before any module of it, so it is
    # read from there, not imported back (no circle of imports)
    package = sys.modules[__name__.rpartition(".")[0]]
    parser = argparse.ArgumentParser(prog="python -m pipeline.report", description=package.__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--samples", default="data/samples", help="sample tables (default: data/samples)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--survey", default="data/survey", help="survey tables (default: data/survey)")
    parser.add_argument("--sensitivity", default="data/sensitivity", help="default: data/sensitivity")
    parser.add_argument("--observed", default="data/observed", help="observed survey tables (default: data/observed)")
    parser.add_argument("--calibration", default="data/calibration", help="default: data/calibration")
    parser.add_argument("--design", default="data/design", help="design study tables (default: data/design)")
    parser.add_argument("--metrics", default="metrics", help="directory of the metrics JSON files")
    parser.add_argument("--pdf", default="reports/sensitivity_report.pdf", help="the report")
    parser.add_argument("--png", default="reports/figures/report", help="directory of the PNG pages")
    parser.add_argument("--plots", default="reports/plots", help="directory of the DVC plot series")
    args = parser.parse_args(argv)
    return run_stage("report", parser, args, lambda own: _stage(args, own), files=["pdf"], dirs=["png", "plots"])


def _stage(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """The stage's work while it owns its outputs: read, compute, write; the exit code."""
    with stage_inputs("report", KeyError):
        dirs = (args.survey, args.sensitivity, args.metrics, args.observed, args.calibration, args.design)
        inputs = read_inputs(args.params, args.samples, args.runs, *dirs)
    numbers = make_report(
        inputs, args.pdf, args.png, args.plots, lambda text: print(text, file=sys.stderr, flush=True), own
    )
    failed = int(inputs.runs["status"].ne("ok").sum())
    print(f"report: wrote {args.pdf} ({numbers['pages']} pages; {failed} failed runs listed), {args.png}, {args.plots}")
    return 0
