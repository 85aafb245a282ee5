"""The rules between keys of params.yaml, and the bounds on what the settings cost, checked before any work.

Each rule reads the values it needs through a :class:`View` of the mapping as written. :class:`pipeline.config.schema.
Params` runs every rule once its fields are valid; when some field is bad, :func:`rule_errors` still runs each rule
whose keys are all valid (a bad key it needs makes it :class:`Unavailable`), so a rule between keys is reported with
the field errors, not only once they are fixed.

The costs are bounded on the numbers the settings imply, computed without building anything: runs of each study at
most :data:`MAX_RUNS`, and the pipeline's peak memory, :data:`BYTES_PER_RUN` a row, at most
:data:`pipeline.resources.MEMORY_BUDGET` (a constant: the same verdict on every machine).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel, TypeAdapter, ValidationError

from bogie.fleet.distributions import ParameterError
from bogie.params import INHIBITORS
from pipeline.config.distributions import NumericSpec
from pipeline.config.errors import locate
from pipeline.resources import MEMORY_BUDGET

__all__ = [
    "BYTES_PER_RUN",
    "MAX_RUNS",
    "RULES",
    "RuleError",
    "Unavailable",
    "View",
    "calibration_tilt_count",
    "design_tilt_count",
    "fleet_bounded",
    "rule_errors",
]

#: the most runs (sample rows) one study may have [-]: fleet.n_bogies' own bound; a larger study is a typo or a
#: step far finer than any result needs
MAX_RUNS = 10_000_000

#: memory one sample row or run costs at a stage's peak: its sample row (about 0.6 KiB with pandas' overheads) and its
#: runs' results with their derived columns (about 1 KiB each under each protocol) [bytes]; the same as
#: pipeline.sample.BYTES_PER_BOGIE
BYTES_PER_RUN = 3 * 1024

#: runs of each ablation bogie: the baseline, each inhibitor off, all off
ABLATION_VARIANTS = len(INHIBITORS) + 2


class Unavailable(Exception):
    """A value a rule needs is missing or itself bad: the rule is not evaluated (the bad key is reported)."""


@dataclass(frozen=True)
class RuleError:
    """A broken rule: the key path it names, the value as written there and what was expected."""

    key: str
    value: Any
    expected: str


def _touches(bad: str, path: str) -> bool:
    """Whether an error at key path ``bad`` makes the value at ``path`` unusable (the same key, above or below it)."""
    if bad in ("", path):
        return True
    return any(a.startswith(b + sep) for a, b in ((path, bad), (bad, path)) for sep in (".", "["))


class View:
    """The values of params.yaml as written, by dotted key path, with the schema's defaults for keys left out.

    Parameters
    ----------
    schema
        The model of the whole file (:class:`pipeline.config.schema.Params`).
    raw
        The mapping read from params.yaml.
    bad
        Key paths of the errors found in it: a value at, above or below one of them is :class:`Unavailable`.
    """

    def __init__(self, schema: type[BaseModel], raw: Mapping[str, Any], bad: Sequence[str] = ()) -> None:
        self.schema, self.raw, self.bad = schema, raw, tuple(bad)
        #: what the rules derive from the file more than once (the tilt distribution's bounds), by name
        self.derived: dict[str, Any] = {}

    def get(self, path: str) -> Any:
        """The value at ``path``; raises :class:`Unavailable` if it is bad, or missing without a default."""
        if any(_touches(bad, path) for bad in self.bad):
            raise Unavailable(path)
        parts = path.split(".")
        node: Any = self.raw
        for i, part in enumerate(parts):
            if not isinstance(node, Mapping):
                raise Unavailable(path)
            if part in node:
                node = node[part]
                continue
            field = locate(self.schema, parts[: i + 1]).field
            if field is None or field.is_required():
                raise Unavailable(path)
            node = field.get_default(call_default_factory=True)
            node = node.model_dump() if isinstance(node, BaseModel) else node
        return node

    def section(self, name: str) -> None:
        """Raise :class:`Unavailable` if the optional section ``name`` is not given (null: no such study)."""
        if self.get(name) is None:
            raise Unavailable(name)


Rule = Callable[[View], Iterator[RuleError]]

_SPEC = TypeAdapter(NumericSpec)


def _tilt_support(view: View) -> tuple[float, float]:
    """The bounds of distributions.chassis_tilt_deg [degree]."""
    if "tilt_support" not in view.derived:
        try:
            spec = _SPEC.validate_python(view.get("distributions.chassis_tilt_deg"))
            view.derived["tilt_support"] = spec.build().support
        except (ValidationError, ParameterError):
            raise Unavailable("distributions.chassis_tilt_deg") from None
    return view.derived["tilt_support"]


def calibration_tilt_count(low: float, high: float, step: float) -> int:
    """Tilts of the calibration table's grid: evenly spaced over [low, high] at most ``step`` apart, both ends [-]."""
    return max(2, math.ceil((high - low) / step - 1e-9) + 1)


def design_tilt_count(low: float, high: float, step: float) -> int:
    """At most the tilts of the design's tolerance grid: level, outward by ``step`` to ``low`` and ``high`` [-]."""
    return math.floor(max(high, 0.0) / step) + math.floor(max(-low, 0.0) / step) + 3


def _calibrates(view: View) -> None:
    """Raise :class:`Unavailable` (the rule does not apply) when no calibration will run: no ``calibrate`` section,
    or no observed survey to calibrate to (``observed.path`` null: the stage skips, docs/calibration.md), so that a
    small fleet (``dvc exp run -S fleet.n_bogies=40``) is not refused for a calibration that will not run."""
    view.section("calibrate")
    if view.get("observed.path") is None:
        raise Unavailable("observed.path")


# ---- rules between sections ---------------------------------------------------------------------------------
def _protocols_run(view: View) -> Iterator[RuleError]:
    run = view.get("protocol.run")
    protocol = view.get("sensitivity.protocol")
    if protocol not in run:
        yield RuleError("sensitivity.protocol", protocol, f"is not run: protocol.run lists only {', '.join(run)}")
    export = view.get("survey.export_format") if view.get("survey") is not None else None
    if export is not None and "wim" not in run:
        expected = f"needs WIM readings to export: protocol.run lists only {', '.join(run)} (add wim, or null)"
        yield RuleError("survey.export_format", export, expected)


def fleet_bounded(view: View, key: str) -> int:
    """A study size that reuses fleet bogies (``ablation.n_bogies``, ``calibrate.n_bogies``): at most the fleet's,
    so that one switch (``-S fleet.n_bogies=100``) makes a small study (issue 31; the params.yaml comments say so)."""
    return min(view.get(key), view.get("fleet.n_bogies"))


def _calibration_tilt(view: View) -> Iterator[RuleError]:
    _calibrates(view)
    fit = view.get("calibrate.fit")
    if not {"chassis_tilt_mean_deg", "chassis_tilt_sd_deg"} & set(fit):
        return
    tilt = view.get("distributions.chassis_tilt_deg")
    if tilt.get("kind") != "truncnormal":
        expected = (
            "must be of kind truncnormal: calibrate.fit has chassis tilt quantities, and the fleet's tilt has a centre "
            "and a spread to fit only as a truncated normal"
        )
        yield RuleError("distributions.chassis_tilt_deg.kind", tilt.get("kind"), expected)
        return
    low, high = _tilt_support(view)
    bounds = fit.get("chassis_tilt_mean_deg")
    if bounds and (bounds[0] < low or bounds[1] > high):
        expected = f"must lie within the tilt distribution's bounds, [{low:g}, {high:g}] degree"
        yield RuleError("calibrate.fit.chassis_tilt_mean_deg", bounds, expected)


def _calibration_site(view: View) -> Iterator[RuleError]:
    _calibrates(view)
    fit = view.get("calibrate.fit")
    if "site_iri_m_km" in fit:
        site = view.get("protocol.wim.site_length_before_m") + view.get("protocol.wim.site_length_after_m")
        if site <= 0.0:
            expected = (
                "the WIM protocol has no site (protocol.wim.site_length_before_m and site_length_after_m are 0), so "
                "no site roughness to fit"
            )
            yield RuleError("calibrate.fit.site_iri_m_km", fit["site_iri_m_km"], expected)


def _design_level(view: View) -> Iterator[RuleError]:
    view.section("design")
    low, high = _tilt_support(view)
    if not low <= 0.0 <= high:
        expected = (
            f"its range [{low:g}, {high:g}] degree must include level (0 degree): a design study measures the tilt "
            "tolerance outward from level"
        )
        yield RuleError("distributions.chassis_tilt_deg", view.get("distributions.chassis_tilt_deg"), expected)


# ---- what the settings cost ---------------------------------------------------------------------------------
def calibration_runs(view: View) -> tuple[int, str]:
    """Weighings of the calibration table, and how they are counted (bogies x 2 x tilts x roughnesses)."""
    _calibrates(view)
    low, high = _tilt_support(view)
    tilts = calibration_tilt_count(low, high, view.get("calibrate.tilt_step_deg"))
    levels = len(view.get("calibrate.site_iri_levels_m_km")) if view.get("calibrate.protocol") == "wim" else 1
    n = fleet_bounded(view, "calibrate.n_bogies")
    return n * 2 * tilts * levels, f"{n:,} bogies x 2 suspensions x {tilts:,} tilts x {levels} site roughnesses"


def design_runs(view: View) -> tuple[int, str]:
    """Static runs of the design study, and how they are counted (designs x conditions x tilts)."""
    view.section("design")
    low, high = _tilt_support(view)
    tilts = design_tilt_count(low, high, view.get("design.tilt_step_deg")) + 1  # and each condition's own tilt
    grid = math.prod(len(levels) for levels in view.get("design.grid").values())
    groups = len(view.get("design.groups"))
    designs = groups * (grid + view.get("design.n_space_filling") + 2)  # and the typical design and the air reference
    conditions = view.get("design.n_conditions")
    how = f"{designs:,} designs ({grid:,} grid combinations) x {conditions:,} conditions x {tilts:,} tilts"
    return designs * conditions * tilts, how


def study_rows(view: View) -> int:
    """Sample rows of the fleet, sensitivity and ablation studies (the survey holds all their runs at once)."""
    fleet = view.get("fleet.n_bogies")
    sensitivity = view.get("sensitivity.base_size") * (len(view.get("sensitivity.factors")) + 2)
    return fleet + sensitivity + ABLATION_VARIANTS * fleet_bounded(view, "ablation.n_bogies")


def _cost(key_of: str, counted: Callable[[View], tuple[int, str]], cause: str) -> Rule:
    def rule(view: View) -> Iterator[RuleError]:
        runs, how = counted(view)
        if runs > MAX_RUNS:
            expected = f"makes {how} = {runs:,} runs, more than {MAX_RUNS:,} (pipeline.config.rules.MAX_RUNS): {cause}"
            yield RuleError(key_of, view.get(key_of), expected)

    return rule


def _memory(view: View) -> Iterator[RuleError]:
    rows = {"the fleet, sensitivity and ablation studies": study_rows(view)}
    for name, counted in (("the calibration table and its fleet", calibration_runs), ("the design study", design_runs)):
        try:
            runs, _ = counted(view)
        except Unavailable:
            continue
        rows[name] = runs + (view.get("fleet.n_bogies") if counted is calibration_runs else 0)
    peak = max(rows, key=rows.get)
    need = rows[peak] * BYTES_PER_RUN
    if need > MEMORY_BUDGET:
        expected = (
            f"{peak} need about {need / 2**30:,.1f} GiB ({rows[peak]:,} rows at {BYTES_PER_RUN // 1024} KiB), "
            "more than "
            f"the memory budget of {MEMORY_BUDGET / 2**30:g} GiB (pipeline.resources.MEMORY_BUDGET, the same on every "
            "machine): make the study smaller"
        )
        # the key of the largest term: the fleet's, or the calibration's or the design's own runs
        runs = rows[peak] - (view.get("fleet.n_bogies") if "calibration" in peak else 0)
        where = (
            "fleet.n_bogies"
            if peak.startswith("the fleet") or runs <= view.get("fleet.n_bogies")
            else ("calibrate.n_bogies" if "calibration" in peak else "design.n_conditions")
        )
        yield RuleError(where, view.get(where), expected)


#: every rule between keys, in the order of the file's sections
RULES: tuple[Rule, ...] = (
    _calibration_tilt,
    _design_level,
    _protocols_run,
    _calibration_site,
    _cost("calibrate.tilt_step_deg", calibration_runs, "raise calibrate.tilt_step_deg or lower calibrate.n_bogies"),
    _cost("design.tilt_step_deg", design_runs, "raise design.tilt_step_deg, or use fewer grid levels or conditions"),
    _memory,
)


def rule_errors(schema: type[BaseModel], raw: Mapping[str, Any], bad: Sequence[str] = ()) -> list[RuleError]:
    """Every broken rule of :data:`RULES` whose keys are all valid (none at, above or below a key path of ``bad``)."""
    view = View(schema, raw, bad)
    found: list[RuleError] = []
    for rule in RULES:
        try:
            found.extend(rule(view))
        except Unavailable:
            continue
    return found
