"""The reference's named runs, reproducible by name: ``bogie.steel.cases.run("L01")``, ``bogie.steel.cases.run("N10")``.

* L01-L07 (Table 1): the Stage 3 linear model on :func:`~bogie.presets.tandem_trrl` with Table 1's bush
  stiffness, bush damping, axle mass, number of steps, time step and speed, over the ramped step of Figure 4.
* N01-N29 (Table 2): the Stage 4 non-linear model. "High" friction is 0.3 and "high" bush stiffness
  1000 N m/rad, as the reference states; "zero" is 0. Everything else the reference left open is stated in each
  case's ``description`` and in ``docs/validation.md``.

:func:`summary` gives each run's figures in the form of the reference's tables (peak p and P1 for Table 1; P1 in
newtons with the front and then the rear wheel on the step, at full and reduced load, or the RMS of Equation 5
for Table 2).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bogie import metrics, numerics
from bogie.params import TARE_FRACTION, Bogie, design_spring_loads, with_equaliser_arms
from bogie.presets import tandem_trrl
from bogie.results import DynamicResult
from bogie.road import ISO8608Profile, RampedStep
from bogie.steel import linear, nonlinear

#: the front axle starts this far before the step [m], so every run begins with a settled static state
STEP_LEAD = 0.5
#: speeds of the step runs [m/s]: Table 1's 0.2 and 10 m/s
LOW_SPEED, HIGH_SPEED = 0.2, 10.0
#: "high" spring-end friction and "high" bush stiffness of Table 2 [-], [N m/rad]
HIGH_FRICTION, HIGH_BUSH = 0.3, 1000.0
#: the long equaliser arm of Table 2's blocks 4 and 5 [m] (the preset's is 0.155 m)
LONG_ARM = 0.25


@dataclass(frozen=True)
class Case:
    """One named run of the reference.

    Attributes
    ----------
    name
        The reference's run number ("L01", "N10", ...).
    description
        What the run is and every assumption we made for it.
    model
        "linear" (Stage 3) or "nonlinear" (Stage 4).
    bogie
        Factory of the bogie of the run.
    runner
        Runs the model on a bogie and returns the result.
    summarise
        The run's figures in the form of the reference's table.
    reference
        What the reference reports for the run, as printed.
    """

    name: str
    description: str
    model: str
    bogie: Callable[[], Bogie]
    runner: Callable[[Bogie], DynamicResult]
    summarise: Callable[[DynamicResult], dict[str, float]]
    reference: dict[str, Any] = field(default_factory=dict)

    def unit(self, key: str) -> str:
        """The unit of figure ``key`` of the summary and the reference: Table 1's peaks of p and P1 are
        non-dimensional (the loads over their mean), Table 2's P1 is in newtons and its RMS (Equation 5)
        non-dimensional."""
        return "N" if self.model == "nonlinear" and key != "rms" else "[-]"


# ---- runners ---------------------------------------------------------------------------------------------------
def _linear_step(n_steps: int, dt: float, speed: float) -> Callable[[Bogie], DynamicResult]:
    def run(bogie: Bogie) -> DynamicResult:
        return linear.simulate(bogie, RampedStep(), speed, dt, n_steps, front_axle_start=-STEP_LEAD)

    return run


def _step_timing(speed: float) -> tuple[float, float]:
    """Duration and time step of a non-linear step run: 25 s at 10 ms (low speed), 1 s at 0.5 ms (high)."""
    return (25.0, 0.01) if speed < 1.0 else (1.0, 0.0005)


def _nonlinear_step(speed: float) -> Callable[[Bogie], DynamicResult]:
    def run(bogie: Bogie) -> DynamicResult:
        duration, dt = _step_timing(speed)
        inputs = nonlinear.road_inputs(bogie, RampedStep(), speed, duration, dt, front_axle_start=-STEP_LEAD)
        return nonlinear.simulate(bogie, inputs)

    return run


def _level_when_empty(bogie: Bogie) -> float:
    """King pin rise that makes the chassis level with the empty trailer [m] (the bogie drops as it is loaded)."""
    return (1.0 - TARE_FRACTION) * float(np.mean(design_spring_loads(bogie))) / bogie.combined_stiffness


def _static_history(load_factors: np.ndarray) -> Callable[[Bogie], DynamicResult]:
    def run(bogie: Bogie) -> DynamicResult:
        n_t = len(load_factors)
        zeros = np.zeros((n_t, bogie.n_axles))
        inputs = nonlinear.Inputs(1.0, zeros, zeros.copy(), load_factors, np.full(n_t, _level_when_empty(bogie)))
        return nonlinear.static_loads(bogie, inputs)

    return run


_APPLY = np.concatenate([np.linspace(TARE_FRACTION, 1.0, 41), np.linspace(1.0, TARE_FRACTION, 41)[1:]])
_SINE = np.concatenate(
    [np.linspace(TARE_FRACTION, 1.0, 41), 0.8 + 0.2 * numerics.cos(np.linspace(0.0, 4.0 * np.pi, 81))[1:]]
)


def _road_run(speed: float) -> Callable[[Bogie], DynamicResult]:
    def run(bogie: Bogie) -> DynamicResult:
        dt = 0.005 if speed < 5.0 else 0.0005
        profile = ISO8608Profile("B", length=100.0, seed=1987)
        inputs = nonlinear.road_inputs(bogie, profile, speed, 100.0 / speed, dt)
        return nonlinear.simulate(bogie, inputs)

    return run


# ---- summaries -------------------------------------------------------------------------------------------------
def _linear_summary(r: DynamicResult) -> dict[str, float]:
    return {"peak_p": r.peak_p, "peak_p1": r.peak_p1}


def _phase_windows(speed: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """Middle 60 % of the front-alone and rear-alone phases on the step of a tandem_trrl() run [s].

    Front alone: the front axle on the plateau while the rear has not reached the step. Rear alone: the front
    axle has left the step while the rear is still on the plateau. Positions are the front axle's along the road.
    """
    step = RampedStep()
    axle_x = tandem_trrl().axle_x
    spacing = axle_x[1] - axle_x[0]
    plateau_end = step.start + step.ramp_length + step.plateau_length
    front = (step.start + step.ramp_length, step.start + spacing)
    rear = (step.end, plateau_end + spacing)

    def window(lo: float, hi: float) -> tuple[float, float]:
        mid, half = 0.5 * (lo + hi), 0.3 * (hi - lo)
        return ((mid - half + STEP_LEAD) / speed, (mid + half + STEP_LEAD) / speed)

    return window(*front), window(*rear)


def _p1_newtons(r: DynamicResult) -> np.ndarray:
    return metrics.p1(r.wheel_loads)


def _step_summary_low(r: DynamicResult) -> dict[str, float]:
    (f0, f1), (r0, r1) = _phase_windows(LOW_SPEED)
    p1 = _p1_newtons(r)
    return {
        "p1_front_on_step": float(np.mean(p1[(r.t >= f0) & (r.t <= f1)])),
        "p1_rear_on_step": float(np.mean(p1[(r.t >= r0) & (r.t <= r1)])),
        "p1_after_step": float(p1[-1]),
    }


def _step_summary_high(r: DynamicResult) -> dict[str, float]:
    return {"peak_p1": float(np.max(_p1_newtons(r)))}


def _static_summary(r: DynamicResult) -> dict[str, float]:
    p1 = _p1_newtons(r)
    full = int(np.argmax(r.extras["load_factor"]))
    return {"p1_full_load": float(p1[full]), "p1_after_removal": float(p1[-1])}


def _sine_summary(r: DynamicResult) -> dict[str, float]:
    p1 = _p1_newtons(r)
    lf = np.asarray(r.extras["load_factor"])
    cycle = slice(len(lf) - 41, len(lf))  # the last load cycle
    return {
        "p1_max_load": float(p1[cycle][np.argmax(lf[cycle])]),
        "p1_min_load": float(p1[cycle][np.argmin(lf[cycle])]),
    }


def _rms_summary(r: DynamicResult) -> dict[str, float]:
    return {"rms": float(metrics.rms(r.wheel_loads[r.t >= 1.0]))}


# ---- the reference's tables ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Table1Row:
    """One run of the reference's Table 1 (Stage 3, linear model, on the ramped step) and what it reports."""

    name: str
    bush_stiffness: float  # [N m/rad]
    bush_damping: float  # [N m s/rad]
    axle_mass: float  # [kg]
    n_steps: int
    dt: float  # time step [s]
    speed: float  # [m/s]
    peak_p: float  # the reference's peak p (Equation 2) [-]
    peak_p1: float  # the reference's peak P1 (Equation 4) [-]


#: the reference's Table 1, row by row
TABLE1 = (
    Table1Row("L01", bush_stiffness=1000.0, bush_damping=0.0, axle_mass=0.0, n_steps=400, dt=0.0625, speed=0.2,
              peak_p=0.2, peak_p1=0.11),
    Table1Row("L02", bush_stiffness=1000.0, bush_damping=0.0, axle_mass=0.0, n_steps=400, dt=0.0025, speed=10.0,
              peak_p=0.95, peak_p1=0.46),
    Table1Row("L03", bush_stiffness=10.0, bush_damping=0.0, axle_mass=0.0, n_steps=200, dt=0.125, speed=0.2,
              peak_p=0.14, peak_p1=0.08),
    Table1Row("L04", bush_stiffness=10.0, bush_damping=0.0, axle_mass=0.0, n_steps=200, dt=0.005, speed=10.0,
              peak_p=1.05, peak_p1=0.50),
    Table1Row("L05", bush_stiffness=1000.0, bush_damping=2000.0, axle_mass=0.0, n_steps=400, dt=0.0025, speed=10.0,
              peak_p=1.55, peak_p1=0.75),
    Table1Row("L06", bush_stiffness=1000.0, bush_damping=2000.0, axle_mass=0.0, n_steps=400, dt=0.0625, speed=0.2,
              peak_p=1.8, peak_p1=0.89),
    Table1Row("L07", bush_stiffness=1000.0, bush_damping=2000.0, axle_mass=200.0, n_steps=400, dt=0.0625, speed=0.2,
              peak_p=1.7, peak_p1=0.85),
)  # fmt: skip


@dataclass(frozen=True)
class Table2Row:
    """One run of the reference's Table 2 (Stage 4, non-linear model) and what it reports.

    ``friction`` and ``bush`` are the table's "High" or "Zero" (:data:`HIGH_FRICTION`, :data:`HIGH_BUSH`, 0);
    ``kind`` is the loading: "static" (load application and removal), "sine" (then sinusoidal load), "step" (the
    ramped step at ``speed`` [m/s]) or "road" (a random road at ``speed``). ``reference`` holds the reported
    figures under the keys of the run's summary (P1 in newtons, or the RMS of Equation 5). ``long_arm`` fits the
    :data:`LONG_ARM` equaliser arms, ``friction_value`` overrides the friction coefficient [-] and ``changes``
    are further :class:`~bogie.params.Bogie` fields.
    """

    name: str
    block: str
    friction: str
    bush: str
    kind: str
    what: str
    reference: dict[str, Any]
    speed: float | None = None
    long_arm: bool = False
    friction_value: float | None = None
    changes: dict[str, Any] = field(default_factory=dict)


_WHAT_STATIC = "static load application and removal"
_WHAT_SINE = "static load application and sinusoidal variation"
_WHAT_STEP = "short step in the road profile (payload 6500 kg, ramp 0.025 m)"
_WHAT_ROAD = "true road profile, long equaliser arm (low speed taken as 1 m/s, high as 20 m/s)"
_ANGLED = 0.55 * 0.155  # tip drop of an arm angled at 0.55 of the preset's 0.155 m arm [m]


def _on_step(front: float, rear: float) -> dict[str, Any]:
    """The reference's P1 [N] with the front and with the rear wheel on the step (low speed)."""
    return {"p1_front_on_step": front, "p1_rear_on_step": rear}


def _two_peaks(first: float, second: float) -> dict[str, Any]:
    """The reference's two peaks of P1 [N] over the step at high speed, as printed."""
    return {"peak_p1 (two peaks)": f"{first}/{second}"}


#: the reference's Table 2, block by block
TABLE2 = (
    # block 1: load application and removal
    Table2Row("N01", block="1", friction="High", bush="High", kind="static",
              what=_WHAT_STATIC, reference={"p1_full_load": 800}),
    Table2Row("N02", block="1", friction="High", bush="Zero", kind="static",
              what=_WHAT_STATIC, reference={"p1_full_load": 720}),
    Table2Row("N03", block="1", friction="Zero", bush="High", kind="static",
              what=_WHAT_STATIC, reference={"p1_full_load": 790}),
    Table2Row("N04", block="1", friction="Zero", bush="Zero", kind="static",
              what=_WHAT_STATIC, reference={"p1_full_load": 680}),
    # block 2: load application and sinusoidal variation
    Table2Row("N05", block="2", friction="High", bush="High", kind="sine",
              what=_WHAT_SINE, reference={"p1_max_load": 1060, "p1_min_load": 380}),
    Table2Row("N06", block="2", friction="Zero", bush="Zero", kind="sine",
              what=_WHAT_SINE, reference={"p1_max_load": 1200, "p1_min_load": 220}),
    # block 3: the short step at low and high speed
    Table2Row("N07", block="3", friction="High", bush="High", kind="step",
              what=_WHAT_STEP, reference=_on_step(2800, 3500), speed=LOW_SPEED),
    Table2Row("N08", block="3", friction="High", bush="Zero", kind="step",
              what=_WHAT_STEP, reference=_on_step(2500, 3100), speed=LOW_SPEED),
    Table2Row("N09", block="3", friction="Zero", bush="High", kind="step",
              what=_WHAT_STEP, reference=_on_step(3100, 3600), speed=LOW_SPEED),
    Table2Row("N10", block="3", friction="Zero", bush="Zero", kind="step",
              what=_WHAT_STEP, reference=_on_step(2700, 3200), speed=LOW_SPEED),
    Table2Row("N11", block="3", friction="High", bush="High", kind="step",
              what=_WHAT_STEP, reference=_two_peaks(5700, 7400), speed=HIGH_SPEED),
    Table2Row("N12", block="3", friction="High", bush="Zero", kind="step",
              what=_WHAT_STEP, reference=_two_peaks(5700, 7400), speed=HIGH_SPEED),
    Table2Row("N13", block="3", friction="Zero", bush="High", kind="step",
              what=_WHAT_STEP, reference=_two_peaks(6000, 7400), speed=HIGH_SPEED),
    Table2Row("N14", block="3", friction="Zero", bush="Zero", kind="step",
              what=_WHAT_STEP, reference=_two_peaks(6000, 7400), speed=HIGH_SPEED),
    # block 4: a road profile, long equaliser arm
    Table2Row("N15", block="4", friction="High", bush="High", kind="road",
              what=_WHAT_ROAD, reference={"rms": 0.00389}, speed=1.0, long_arm=True),
    Table2Row("N16", block="4", friction="Zero", bush="Zero", kind="road",
              what=_WHAT_ROAD, reference={"rms": 0.00321}, speed=1.0, long_arm=True),
    Table2Row("N17", block="4", friction="High", bush="High", kind="road",
              what=_WHAT_ROAD, reference={"rms": 0.00350}, speed=20.0, long_arm=True),
    Table2Row("N18", block="4", friction="Zero", bush="Zero", kind="road",
              what=_WHAT_ROAD, reference={"rms": 0.00342}, speed=20.0, long_arm=True),
    # block 5: constraints and geometry, on the step at low speed
    Table2Row("N19", block="5", friction="Zero", bush="Zero", kind="step",
              what="linear constraints: contact points fixed (contact_roll_radius = 0) and level arms",
              reference=_on_step(200, 200),
              speed=LOW_SPEED,
              changes={"contact_roll_radius": 0.0, "equaliser_front_tip_drop": 0.0, "equaliser_rear_tip_drop": 0.0}),
    Table2Row("N20", block="5", friction="Zero", bush="Zero", kind="step",
              what="non-linear constraints (the preset's rolling contact; as N10)",
              reference=_on_step(1500, 1800), speed=LOW_SPEED),
    Table2Row("N21", block="5", friction="Zero", bush="Zero", kind="step",
              what=f"long equaliser arm ({LONG_ARM:g} m)",
              reference=_on_step(700, 950),
              speed=LOW_SPEED, long_arm=True),
    Table2Row("N22", block="5", friction="High", bush="High", kind="step",
              what=f"long equaliser arm ({LONG_ARM:g} m)",
              reference=_on_step(700, 900),
              speed=LOW_SPEED, long_arm=True),
    Table2Row("N23", block="5", friction="Zero", bush="Zero", kind="step",
              what="contact points as the TRRL vehicle (stand-in: long arm, contact_roll_radius 0.04 m)",
              reference={},
              speed=LOW_SPEED, long_arm=True, changes={"contact_roll_radius": 0.04}),
    Table2Row("N24", block="5", friction="High", bush="High", kind="step",
              what="contact points as the TRRL vehicle (stand-in)",
              reference={},
              speed=LOW_SPEED, long_arm=True, changes={"contact_roll_radius": 0.04}),
    Table2Row("N25", block="5", friction="Zero", bush="Zero", kind="step",
              what="front arm angled, xi = 0.55 (read as the slope of the front arm: tip 0.55 x arm below the pivot)",
              reference={},
              speed=LOW_SPEED, changes={"equaliser_front_tip_drop": _ANGLED}),
    Table2Row("N26", block="5", friction="High", bush="High", kind="step",
              what="rear arm angled, eta = 0.55",
              reference={},
              speed=LOW_SPEED, changes={"equaliser_rear_tip_drop": _ANGLED}),
    Table2Row("N27", block="5", friction="Zero", bush="Zero", kind="step",
              what="both arms angled, zeta = 0.55",
              reference={},
              speed=LOW_SPEED, changes={"equaliser_front_tip_drop": _ANGLED, "equaliser_rear_tip_drop": _ANGLED}),
    Table2Row("N28", block="5", friction="High", bush="High", kind="step",
              what="rear arm angled up, eta = -0.55",
              reference={},
              speed=LOW_SPEED, changes={"equaliser_rear_tip_drop": -_ANGLED}),
    Table2Row("N29", block="5", friction="High", bush="High", kind="step",
              what="friction coefficient 0.6, contact points as the TRRL vehicle (stand-in)",
              reference={},
              speed=LOW_SPEED, long_arm=True, friction_value=0.6, changes={"contact_roll_radius": 0.04}),
)  # fmt: skip


# ---- the cases -------------------------------------------------------------------------------------------------
def _linear_case(row: Table1Row) -> Case:
    regime = "low speed" if row.speed < 1.0 else "high speed"
    k_b, d_b, m_a = row.bush_stiffness, row.bush_damping, row.axle_mass
    return Case(
        name=row.name,
        description=(
            f"Table 1 run {row.name} ({regime}): bush stiffness {k_b:g} N m/rad, bush damping {d_b:g} N m s/rad, "
            f"axle mass {m_a:g} kg, {row.n_steps} steps of {row.dt:g} s at {row.speed:g} m/s over the 25 mm ramped "
            "step; tandem_trrl() (its tyre damping of 2 kN s/m stands in for the damping the reference's plots "
            "show), average-acceleration Newmark"
        ),
        model="linear",
        bogie=lambda: tandem_trrl(bush_stiffness=k_b, bush_damping=d_b, axle_mass=m_a),
        runner=_linear_step(row.n_steps, row.dt, row.speed),
        summarise=_linear_summary,
        reference={"peak_p": row.peak_p, "peak_p1": row.peak_p1},
    )


def _level(friction: str) -> float:
    return {"High": HIGH_FRICTION, "Zero": 0.0}[friction]


def _bush(stiffness: str) -> float:
    return {"High": HIGH_BUSH, "Zero": 0.0}[stiffness]


def _nl_bogie(friction: float, bush: float, long_arm: bool, changes: dict[str, Any]) -> Callable[[], Bogie]:
    def make() -> Bogie:
        # the reference's Stage 4 model has no interleaf friction in its springs: its runs keep it off
        b = tandem_trrl(friction_coefficient=friction, bush_stiffness=bush, spring_friction_band=0.0, **changes)
        return with_equaliser_arms(b, LONG_ARM) if long_arm else b

    return make


def _nl_loading(row: Table2Row) -> tuple[Callable[[Bogie], DynamicResult], Callable[[DynamicResult], dict], str]:
    """Runner, summary and a description of the loading of a Table 2 run."""
    speed = row.speed
    if row.kind == "step":
        timing = "25 s at 10 ms steps" if speed < 1.0 else "1 s at 0.5 ms steps"
        summarise = _step_summary_low if speed < 1.0 else _step_summary_high
        return _nonlinear_step(speed), summarise, f"the 25 mm ramped step at {speed:g} m/s ({timing}), 0.5 m lead"
    if row.kind == "static":
        setting = (
            f"quasi-static load application from the empty trailer ({TARE_FRACTION:g} of the payload) to full load "
            "and back, on a trailer whose king pin height makes it level when empty"
        )
        return _static_history(_APPLY), _static_summary, setting
    if row.kind == "sine":
        setting = "quasi-static load application, then two cycles of load between 0.6 and 1.0 of the payload"
        return _static_history(_SINE), _sine_summary, setting
    setting = (
        f"100 m of ISO 8608 class B road (seed 1987, standing in for the lost TRRL Track 1 profile) at {speed:g} m/s"
    )
    return _road_run(speed), _rms_summary, setting


def _nl_case(row: Table2Row) -> Case:
    runner, summarise, setting = _nl_loading(row)
    fr = _level(row.friction) if row.friction_value is None else row.friction_value
    description = (
        f"Table 2 block {row.block} run {row.name}: {row.what}; spring-end friction {row.friction} ({fr:g}), bush "
        f"stiffness {row.bush} ({_bush(row.bush):g} N m/rad); {setting}; no leaf-spring hysteresis (the "
        "reference's springs have none); tandem_trrl() otherwise"
    )
    return Case(
        name=row.name,
        description=description,
        model="nonlinear",
        bogie=_nl_bogie(fr, _bush(row.bush), row.long_arm, row.changes),
        runner=runner,
        summarise=summarise,
        reference=dict(row.reference),
    )


CASES: dict[str, Case] = {c.name: c for c in (*map(_linear_case, TABLE1), *map(_nl_case, TABLE2))}


def names() -> list[str]:
    """The names of every run, Table 1 then Table 2: ``["L01", ..., "L07", "N01", ..., "N29"]``."""
    return list(CASES)


def get(name: str) -> Case:
    """The case called ``name`` (case-insensitive).

    Raises
    ------
    ValueError
        If ``name`` is not a text or no run has that name; the message lists the names.
    """
    if not isinstance(name, str) or name.upper() not in CASES:
        raise ValueError(f"unknown case {name!r}: must be one of {', '.join(CASES)}")
    return CASES[name.upper()]


def run(name: str, **bogie_changes: Any) -> DynamicResult:
    """Run the reference's case ``name``; ``bogie_changes`` override fields of its bogie (for what-if runs)."""
    case = get(name)
    bogie = case.bogie()
    if bogie_changes:
        bogie = bogie.replace(**bogie_changes)
    return case.runner(bogie)


def summary(name: str, result: DynamicResult | None = None) -> dict[str, float]:
    """The run's figures in the form of the reference's table (runs the case if no result is given).

    Raises
    ------
    ValueError
        If the run failed: the figures of a history cut short (a NaN here, the last load difference of a
        half-finished run there) would read as results, e.g. as perfect equalisation.
    """
    case = get(name)
    result = run(name) if result is None else result
    if not result.success:
        raise ValueError(f"run {case.name} failed ({result.message}): it has no figures to compare")
    return case.summarise(result)
