"""The rules between keys of params.yaml, and the bounds on what the settings cost, checked before any work.

Each rule reads the values it needs through a :class:`View` of the mapping as written, and yields every broken case
it finds (each fit quantity, design factor, axle group on its own), not the first. :class:`pipeline.config.schema.
Params` runs every rule once its fields are valid; when some field is bad, :func:`rule_errors` still runs each rule
whose keys are all valid (a bad key it needs makes it :class:`Unavailable`), so a rule is reported with the field
errors, not only once they are fixed. The rules within one section (a group's payload, a phase's steps, the
calibration's bounds, the design grid's levels) are rules here too, not the sections' model validators: pydantic runs
a model's validator only once every field of that model is valid, so one bad key in a section hid them.

A rule whose value is already reported bad does not run: a key that a field check, or an earlier rule, found bad is
:class:`Unavailable` to the rules after it, so one mistake gives one line, not a line for each check that reads it.

The costs are bounded on the numbers the settings imply, computed without building anything: runs of each study at
most :data:`MAX_RUNS`, and the pipeline's peak memory, :data:`BYTES_PER_RUN` a row, at most
:data:`pipeline.resources.MEMORY_BUDGET` (a constant: the same verdict on every machine).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

from pydantic import BaseModel

from bogie.bogie_file import base_bogie
from bogie.fleet.constants import (
    CALIBRATION_QUANTITIES,
    GROUP_AXLES,
    MAX_PHASE_STEPS,
    ROUTE_MARGIN,
    WIM_QUANTITIES,
)
from pipeline.config.quantities import QUANTITIES
from pipeline.config.view import (
    ABLATION_VARIANTS,
    BYTES_PER_RUN,
    MAX_RUNS,
    Rule,
    RuleError,
    Unavailable,
    View,
    _calibrates,
    _tilt_support,
    calibration_protocol,
    calibration_tilt_count,
    design_tilt_count,
    survey_protocol,
    why_static,
)
from pipeline.resources import MEMORY_BUDGET

__all__ = [
    "BYTES_PER_RUN",
    "MAX_RUNS",
    "RULES",
    "RuleError",
    "Unavailable",
    "View",
    "DESIGN_FACTORS",
    "calibration_protocol",
    "calibration_tilt_count",
    "design_tilt_count",
    "fleet_bounded",
    "rule_errors",
    "survey_protocol",
    "why_static",
]


# ---- rules within a section -------------------------------------------------------------------------------------
def _payloads(view: View) -> Iterator[RuleError]:
    # the design bogie needs a positive payload: the legal load must exceed the group's own unsprung mass
    for group, n_axles in GROUP_AXLES.items():
        try:
            name, tonnes = view.get(f"fleet.presets.{group}"), view.get(f"fleet.legal_group_load_t.{group}")
        except Unavailable:
            continue
        unsprung = 2 * n_axles * base_bogie(name).axle_mass / 1000.0
        if tonnes <= unsprung:
            expected = f"must exceed the unsprung mass of the {name} axles, {unsprung:g} t"
            yield RuleError(f"fleet.legal_group_load_t.{group}", tonnes, expected)


def _too_many_steps(key: str, value: float, duration: float, dt: float) -> RuleError | None:
    """A protocol phase of more than MAX_PHASE_STEPS time steps (its histories would not fit in memory), or None."""
    steps = duration / dt
    if steps <= MAX_PHASE_STEPS:
        return None
    expected = (
        f"makes a phase of {duration:.4g} s, {steps:,.0f} steps of {dt:g} s, more than {MAX_PHASE_STEPS:,} "
        "(about 250 bytes a step per worker): shorten it or raise dt_s"
    )
    return RuleError(key, value, expected)


def _static_phases(view: View) -> Iterator[RuleError]:
    static = "protocol.static."
    dt, value = view.get(static + "dt_s"), lambda name: view.get(static + name)
    durations: dict[str, Callable[[], float]] = {
        "load_time_s": lambda: value("load_time_s"),
        "crawl_speed_m_s": lambda: (value("approach_length_m") + ROUTE_MARGIN) / value("crawl_speed_m_s"),
        "settle_time_s": lambda: value("settle_time_s"),
    }
    for name, duration in durations.items():
        try:
            error = _too_many_steps(static + name, view.get(static + name), duration(), dt)
        except Unavailable:
            continue
        if error is not None:
            # the phases share dt_s: a line for each further phase would repeat the one cause, a step too small
            yield error
            return


def _wim_steps(view: View) -> Iterator[RuleError]:
    approach = view.get("protocol.wim.approach_length_m")
    route = (approach + ROUTE_MARGIN) / view.get("protocol.wim.speed_m_s")
    error = _too_many_steps("protocol.wim.approach_length_m", approach, route, view.get("protocol.wim.dt_s"))
    if error is not None:
        yield error


def _wim_site(view: View) -> Iterator[RuleError]:
    approach, before = view.get("protocol.wim.approach_length_m"), view.get("protocol.wim.site_length_before_m")
    if before > approach:
        expected = (
            f"must not exceed approach_length_m = {approach:g} m: the site lies on the approach road ahead of the "
            "sensor"
        )
        yield RuleError("protocol.wim.site_length_before_m", before, expected)


#: an address of a dask scheduler, in words (execution.dask_scheduler)
DASK_ADDRESS = 'an address such as "tcp://127.0.0.1:8786" or a scheduler file such as "scheduler.json"'
#: dask's own environment variable of the scheduler's address (dask.config's ``scheduler-address``): used when
#: execution.dask_scheduler is null
DASK_ENV = "DASK_SCHEDULER_ADDRESS"
#: what backend dask lacks when neither is given (validate's rule and the stages' client say it alike)
DASK_MISSING = f"backend dask needs the scheduler: {DASK_ADDRESS}, or {DASK_ENV} set"


def _dask_scheduler(view: View) -> Iterator[RuleError]:
    if view.get("execution.backend") == "dask" and view.get("execution.dask_scheduler") is None:
        if not os.environ.get(DASK_ENV, "").strip():
            yield RuleError("execution.dask_scheduler", None, DASK_MISSING)


def _calibration_levels(view: View) -> Iterator[RuleError]:
    view.section("calibrate")
    levels = view.get("calibrate.site_iri_levels_m_km")
    if any(b <= a for a, b in zip(levels, levels[1:])) or levels[0] <= 0.0:
        yield RuleError("calibrate.site_iri_levels_m_km", levels, "must be positive and increasing [m/km]")


def _fit_bounds(name: str, bounds: Any) -> str | None:
    """What is wrong with one quantity of calibrate.fit on its own, the first thing found (a later check of a quantity
    calibrate does not know, or of bounds of another form, would only repeat it), or None."""
    if name not in CALIBRATION_QUANTITIES:
        return f"is not a fleet quantity calibrate can fit; allowed: {', '.join(CALIBRATION_QUANTITIES)}"
    low, high, unit = CALIBRATION_QUANTITIES[name]
    if len(bounds) != 2 or not all(isinstance(b, int | float) and math.isfinite(b) for b in bounds):
        return f"must be [low, high], two numbers in {unit}"
    if not bounds[0] < bounds[1]:
        return f"bounds inverted or equal: low must be below high [{unit}]"
    if bounds[0] < low or bounds[1] > high:
        return f"must lie within [{low:g}, {high:g}] {unit}"
    return None


def _calibration_fit(view: View) -> Iterator[RuleError]:
    view.section("calibrate")
    for name, bounds in view.entries("calibrate.fit").items():
        key = f"calibrate.fit.{name}"
        wrong = _fit_bounds(name, bounds)
        if wrong is not None:
            yield RuleError(key, bounds, wrong)
            continue
        if name != "site_iri_m_km":
            continue
        try:
            # a static calibration drops the WIM quantities (pipeline.config.settings); the levels, once refused
            # themselves (_calibration_levels, an earlier rule), are no range to hold the bounds against
            if calibration_protocol(view) != "wim":
                continue
            levels = view.get("calibrate.site_iri_levels_m_km")
        except Unavailable:
            continue
        if bounds[0] < levels[0] or bounds[1] > levels[-1]:
            expected = f"must lie within site_iri_levels_m_km, [{levels[0]:g}, {levels[-1]:g}] m/km"
            yield RuleError(key, bounds, expected)


def _static_calibration_fits(view: View) -> Iterator[RuleError]:
    view.section("calibrate")
    names = view.names("calibrate.fit")
    if names and calibration_protocol(view) == "static" and all(name in WIM_QUANTITIES for name in names):
        why = why_static(view.get("calibrate.protocol"))
        others = ", ".join(q for q in CALIBRATION_QUANTITIES if q not in WIM_QUANTITIES)
        expected = (
            f"names only WIM quantities, which a static calibration ({why}) does not fit: a weighbridge has no WIM "
            f"site or sensor; name one of {others}"
        )
        yield RuleError("calibrate.fit", dict(view.entries("calibrate.fit")), expected)


#: the design factors a ``design:`` study controls, by params.yaml key (keys of ``distributions:``): bush, arm, pad
#: radius (contact movement), spring-end friction and the springs' interleaf band (``docs/design.md``)
DESIGN_FACTORS: tuple[str, ...] = (
    "bush_stiffness",
    "equaliser_arm_mm",
    "contact_roll_radius_mm",
    "friction_coefficient",
    "spring_friction_band_kn",
)


def _design_grid(view: View) -> Iterator[RuleError]:
    view.section("design")
    for name, levels in view.entries("design.grid").items():
        key = f"design.grid.{name}"
        if name not in DESIGN_FACTORS:
            yield RuleError(key, levels, f"is not a design factor; allowed: {', '.join(DESIGN_FACTORS)}")
            continue
        q = QUANTITIES[name]
        if not levels or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in levels):
            yield RuleError(key, levels, f"must be a list of one or more numbers in {q.yaml_unit}")
            continue
        if len(set(levels)) != len(levels):
            yield RuleError(key, levels, "lists a level twice")
        for i, v in enumerate(levels):
            if not (math.isfinite(v) and q.range.contains(q.to_si(float(v)))):
                yield RuleError(f"{key}[{i}]", v, f"is outside the allowed range {q.range_text} of {q.name}")


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
    if not {"chassis_tilt_mean_deg", "chassis_tilt_sd_deg"} & set(view.names("calibrate.fit")):
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
    bounds = view.entries("calibrate.fit").get("chassis_tilt_mean_deg")
    if bounds and (bounds[0] < low or bounds[1] > high):
        expected = f"must lie within the tilt distribution's bounds, [{low:g}, {high:g}] degree"
        yield RuleError("calibrate.fit.chassis_tilt_mean_deg", bounds, expected)


def _calibration_site(view: View) -> Iterator[RuleError]:
    _calibrates(view)
    fit = view.entries("calibrate.fit")
    if "site_iri_m_km" in fit and calibration_protocol(view) == "wim":
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
    levels = len(view.get("calibrate.site_iri_levels_m_km")) if calibration_protocol(view) == "wim" else 1
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


#: every rule between keys: those within a section, then those between sections, each in the order of the file's
#: sections (an earlier rule's bad key is unavailable to the later ones)
RULES: tuple[Rule, ...] = (
    _payloads,
    _static_phases,
    _wim_steps,
    _wim_site,
    _dask_scheduler,
    _calibration_levels,
    _calibration_fit,
    _static_calibration_fits,
    _design_grid,
    _calibration_tilt,
    _design_level,
    _protocols_run,
    _calibration_site,
    _cost("calibrate.tilt_step_deg", calibration_runs, "raise calibrate.tilt_step_deg or lower calibrate.n_bogies"),
    _cost("design.tilt_step_deg", design_runs, "raise design.tilt_step_deg, or use fewer grid levels or conditions"),
    _memory,
)


def rule_errors(schema: type[BaseModel], raw: Mapping[str, Any], bad: Sequence[str] = ()) -> list[RuleError]:
    """Every broken rule of :data:`RULES` whose keys are all valid (none at, above or below a key path of ``bad``, nor
    of a broken rule before it)."""
    view = View(schema, raw, bad)
    found: list[RuleError] = []
    for rule in RULES:
        broken: list[RuleError] = []
        try:
            for error in rule(view):
                broken.append(error)
        except Unavailable:
            pass  # a rule that stops at a bad key keeps what it found before it
        found += broken
        view.bad += [error.key for error in broken]
    return found
