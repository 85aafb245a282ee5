"""What every page builder gets (:class:`Context`) and gives back (:class:`Page`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from matplotlib.figure import Figure

from bogie.results import DynamicResult
from pipeline.report.inputs import ReportInputs
from pipeline.report.style import GROUPS
from pipeline.report.tables import summary_numbers

__all__ = ["Context", "Page"]


class Page(NamedTuple):
    """One page of the report."""

    #: its entry in the contents; "" continues the section of the page before
    section: str
    #: the name of its PNG copy (reports/figures/report/<name>.png); "" for a page without charts
    name: str
    figure: Figure


@dataclass(frozen=True)
class Context:
    """The inputs, the reference runs and what several pages share.

    Attributes
    ----------
    inputs
        What the pipeline wrote (:func:`pipeline.report.inputs.read_inputs`).
    runs
        The reference cases' results by name (:func:`pipeline.report.pages.reference.reference_runs`).
    numbers
        The summary's numbers (:func:`pipeline.report.tables.summary_numbers`).
    groups, protocols
        The axle groups and protocols the fleet's succeeded runs have, in order.
    main
        The protocol of the single-protocol charts: the sensitivity protocol if it ran, else the first.
    """

    inputs: ReportInputs
    runs: Mapping[str, DynamicResult]
    numbers: dict[str, Any]
    groups: list[str]
    protocols: list[str]
    main: str

    @classmethod
    def of(cls, inputs: ReportInputs, runs: Mapping[str, DynamicResult]) -> Context:
        """The context of ``inputs`` and the reference ``runs``."""
        ok, cfg = inputs.ok, inputs.config
        groups = [g for g in GROUPS if g in set(ok["group"])]
        protocols = [p for p in cfg.protocol.run if p in set(ok["protocol"])]
        main = cfg.sensitivity.protocol if cfg.sensitivity.protocol in protocols else protocols[0]
        numbers = summary_numbers(inputs.survey_metrics, inputs.sensitivity_metrics)
        return cls(inputs, runs, numbers, groups, protocols, main)
