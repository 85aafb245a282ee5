"""DVC stage ``report``: the PDF sensitivity report -> reports/sensitivity_report.pdf, its figures, plot series.

``python -m pipeline.report`` reads what the earlier stages wrote (the fleet samples, the runs of every study, the
survey, sensitivity, observed and calibration tables and their metrics JSON), reruns the reference's named cases it
reproduces (about a second with a warm numba cache) and writes:

- ``reports/sensitivity_report.pdf``: A4 pages, vector figures, numbered (contents: ``docs/report.md``);
- ``reports/figures/report/<page>.png``: every page that holds charts, as PNG;
- ``reports/plots/*.csv``: small series declared as DVC plots (``dvc plots show``).

The words of the summary and of the captions are generated from the numbers (``metrics/*.json``, the tables and the
runs) by the Jinja2 templates of ``templates/``, never fixed text, except for what the reference reported. Failed
runs are listed, never a reason to stop. Every output is written under a temporary name and renamed into place
(:func:`pipeline.atomic.atomic_outputs`), so a reader sees the old report or the new.

Modules: :mod:`~pipeline.report.inputs` (reading), :mod:`~pipeline.report.tables` (derived tables),
:mod:`~pipeline.report.text` (templates and number filters), :mod:`~pipeline.report.layout` (A4 pages, text
blocks, tables, page numbers, contents), :mod:`~pipeline.report.style`, the pages by subject in
:mod:`pipeline.report.pages`, and :mod:`~pipeline.report.build` (the document as a list of named pages, writing,
the command line).
"""

from pipeline.report.build import PAGES, PNG_DPI, build_pages, main, make_report, report_series, write_report
from pipeline.report.context import Context, Page
from pipeline.report.inputs import ReportInputs, build_date, code_digest, read_inputs
from pipeline.report.pages.front import SUBTITLE, TITLE
from pipeline.report.pages.reference import REFERENCE_RUNS, reference_runs
from pipeline.report.tables import failed_runs, plot_series, run_counts, summary_numbers

__all__ = [
    "PAGES",
    "PNG_DPI",
    "REFERENCE_RUNS",
    "SUBTITLE",
    "TITLE",
    "Context",
    "Page",
    "ReportInputs",
    "build_date",
    "code_digest",
    "build_pages",
    "failed_runs",
    "main",
    "make_report",
    "plot_series",
    "read_inputs",
    "reference_runs",
    "report_series",
    "run_counts",
    "summary_numbers",
    "write_report",
]
