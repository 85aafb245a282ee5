"""The reference's named runs, reproducible by name: ``bogie.cases.run("L01")``, ``bogie.cases.run("N10")``.

* L01-L07 (Table 1): the Stage 3 linear model on :func:`~bogie.params.tandem_trrl` with Table 1's bush
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

from bogie import linear, metrics, nonlinear
from bogie.params import TARE_FRACTION, Bogie, design_spring_loads, tandem_trrl, with_equaliser_arms
from bogie.results import DynamicResult
from bogie.road import ISO8608Profile, RampedStep

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
_SINE = np.concatenate([np.linspace(TARE_FRACTION, 1.0, 41), 0.8 + 0.2 * np.cos(np.linspace(0.0, 4.0 * np.pi, 81))[1:]])


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
    spacing = 1.31
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


# ---- the cases -------------------------------------------------------------------------------------------------
def _linear_case(
    name: str, k_b: float, d_b: float, m_a: float, n_steps: int, dt: float, speed: float, p: float, p1: float
) -> Case:
    regime = "low speed" if speed < 1.0 else "high speed"
    return Case(
        name=name,
        description=(
            f"Table 1 run {name} ({regime}): bush stiffness {k_b:g} N m/rad, bush damping {d_b:g} N m s/rad, axle mass "
            f"{m_a:g} kg, {n_steps} steps of {dt:g} s at {speed:g} m/s over the 25 mm ramped step; tandem_trrl() "
            "(its tyre damping of 2 kN s/m stands in for the damping the reference's plots show), average-acceleration "
            "Newmark"
        ),
        model="linear",
        bogie=lambda: tandem_trrl(bush_stiffness=k_b, bush_damping=d_b, axle_mass=m_a),
        runner=_linear_step(n_steps, dt, speed),
        summarise=_linear_summary,
        reference={"peak_p": p, "peak_p1": p1},
    )


def _level(friction: str) -> float:
    return {"High": HIGH_FRICTION, "Zero": 0.0}[friction]


def _bush(stiffness: str) -> float:
    return {"High": HIGH_BUSH, "Zero": 0.0}[stiffness]


def _nl_bogie(friction: float, bush: float, **changes: Any) -> Callable[[], Bogie]:
    long_arm = changes.pop("long_arm", False)

    def make() -> Bogie:
        b = tandem_trrl(friction_coefficient=friction, bush_stiffness=bush, **changes)
        return with_equaliser_arms(b, LONG_ARM) if long_arm else b

    return make


def _nl_case(name: str, block: str, friction: str, bush: str, what: str, reference: dict[str, Any], **kw: Any) -> Case:
    speed = kw.pop("speed", None)
    kind = kw.pop("kind")
    fr = kw.pop("friction_value", _level(friction))
    if kind == "step":
        runner = _nonlinear_step(speed)
        summarise = _step_summary_low if speed < 1.0 else _step_summary_high
        timing = "25 s at 10 ms steps" if speed < 1.0 else "1 s at 0.5 ms steps"
        setting = f"the 25 mm ramped step at {speed:g} m/s ({timing}), 0.5 m lead"
    elif kind == "static":
        runner, summarise = _static_history(_APPLY), _static_summary
        setting = (
            f"quasi-static load application from the empty trailer ({TARE_FRACTION:g} of the payload) to full load "
            "and back, on a trailer whose king pin height makes it level when empty"
        )
    elif kind == "sine":
        runner, summarise = _static_history(_SINE), _sine_summary
        setting = "quasi-static load application, then two cycles of load between 0.6 and 1.0 of the payload"
    else:
        runner, summarise = _road_run(speed), _rms_summary
        setting = (
            "100 m of ISO 8608 class B road (seed 1987, standing in for the lost TRRL Track 1 profile) "
            f"at {speed:g} m/s"
        )
    description = (
        f"Table 2 block {block} run {name}: {what}; spring-end friction {friction} ({fr:g}), bush stiffness {bush} "
        f"({_bush(bush):g} N m/rad); {setting}; tandem_trrl() otherwise"
    )
    return Case(
        name=name,
        description=description,
        model="nonlinear",
        bogie=_nl_bogie(fr, _bush(bush), **kw),
        runner=runner,
        summarise=summarise,
        reference=reference,
    )


_TRRL_CONTACT = {"long_arm": True, "contact_roll_radius": 0.04}


def _table2() -> list[Case]:
    low, high = LOW_SPEED, HIGH_SPEED
    c: list[Case] = []
    for name, fr, bu, ref in (
        ("N01", "High", "High", 800),
        ("N02", "High", "Zero", 720),
        ("N03", "Zero", "High", 790),
        ("N04", "Zero", "Zero", 680),
    ):
        c.append(
            _nl_case(name, "1", fr, bu, "static load application and removal", {"p1_full_load": ref}, kind="static")
        )
    for name, fr, bu, ref in (("N05", "High", "High", (1060, 380)), ("N06", "Zero", "Zero", (1200, 220))):
        what = "static load application and sinusoidal variation"
        ref_d = {"p1_max_load": ref[0], "p1_min_load": ref[1]}
        c.append(_nl_case(name, "2", fr, bu, what, ref_d, kind="sine"))
    for name, fr, bu, speed, ref in (
        ("N07", "High", "High", low, (2800, 3500)),
        ("N08", "High", "Zero", low, (2500, 3100)),
        ("N09", "Zero", "High", low, (3100, 3600)),
        ("N10", "Zero", "Zero", low, (2700, 3200)),
        ("N11", "High", "High", high, (5700, 7400)),
        ("N12", "High", "Zero", high, (5700, 7400)),
        ("N13", "Zero", "High", high, (6000, 7400)),
        ("N14", "Zero", "Zero", high, (6000, 7400)),
    ):
        what = "short step in the road profile (payload 6500 kg, ramp 0.025 m)"
        ref_d = (
            {"p1_front_on_step": ref[0], "p1_rear_on_step": ref[1]}
            if speed < 1.0
            else {"peak_p1 (two peaks)": f"{ref[0]}/{ref[1]}"}
        )
        c.append(_nl_case(name, "3", fr, bu, what, ref_d, kind="step", speed=speed))
    for name, fr, bu, speed, ref in (
        ("N15", "High", "High", 1.0, 0.00389),
        ("N16", "Zero", "Zero", 1.0, 0.00321),
        ("N17", "High", "High", 20.0, 0.00350),
        ("N18", "Zero", "Zero", 20.0, 0.00342),
    ):
        what = "true road profile, long equaliser arm (low speed taken as 1 m/s, high as 20 m/s)"
        c.append(_nl_case(name, "4", fr, bu, what, {"rms": ref}, kind="road", speed=speed, long_arm=True))
    block5 = (
        ("N19", "Zero", "Zero", {"contact_roll_radius": 0.0, "equaliser_front_tip_drop": 0.0,
                                 "equaliser_rear_tip_drop": 0.0},
         "linear constraints: contact points fixed (contact_roll_radius = 0) and level arms", (200, 200)),
        ("N20", "Zero", "Zero", {}, "non-linear constraints (the preset's rolling contact; as N10)", (1500, 1800)),
        ("N21", "Zero", "Zero", {"long_arm": True}, f"long equaliser arm ({LONG_ARM:g} m)", (700, 950)),
        ("N22", "High", "High", {"long_arm": True}, f"long equaliser arm ({LONG_ARM:g} m)", (700, 900)),
        ("N23", "Zero", "Zero", dict(_TRRL_CONTACT), "contact points as the TRRL vehicle (stand-in: long arm, "
         "contact_roll_radius 0.04 m)", None),
        ("N24", "High", "High", dict(_TRRL_CONTACT), "contact points as the TRRL vehicle (stand-in)", None),
        ("N25", "Zero", "Zero", {"equaliser_front_tip_drop": 0.55 * 0.155}, "front arm angled, xi = 0.55 "
         "(read as the slope of the front arm: tip 0.55 x arm below the pivot)", None),
        ("N26", "High", "High", {"equaliser_rear_tip_drop": 0.55 * 0.155}, "rear arm angled, eta = 0.55", None),
        ("N27", "Zero", "Zero", {"equaliser_front_tip_drop": 0.55 * 0.155, "equaliser_rear_tip_drop": 0.55 * 0.155},
         "both arms angled, zeta = 0.55", None),
        ("N28", "High", "High", {"equaliser_rear_tip_drop": -0.55 * 0.155}, "rear arm angled up, eta = -0.55", None),
        ("N29", "High", "High", {**_TRRL_CONTACT, "friction_value": 0.6},
         "friction coefficient 0.6, contact points as the TRRL vehicle (stand-in)", None),
    )  # fmt: skip
    for name, fr, bu, changes, what, ref in block5:
        ref_d = {"p1_front_on_step": ref[0], "p1_rear_on_step": ref[1]} if ref else {}
        c.append(_nl_case(name, "5", fr, bu, what, ref_d, kind="step", speed=low, **changes))
    return c


CASES: dict[str, Case] = {
    c.name: c
    for c in (
        _linear_case("L01", 1000.0, 0.0, 0.0, 400, 0.0625, 0.2, 0.2, 0.11),
        _linear_case("L02", 1000.0, 0.0, 0.0, 400, 0.0025, 10.0, 0.95, 0.46),
        _linear_case("L03", 10.0, 0.0, 0.0, 200, 0.125, 0.2, 0.14, 0.08),
        _linear_case("L04", 10.0, 0.0, 0.0, 200, 0.005, 10.0, 1.05, 0.50),
        _linear_case("L05", 1000.0, 2000.0, 0.0, 400, 0.0025, 10.0, 1.55, 0.75),
        _linear_case("L06", 1000.0, 2000.0, 0.0, 400, 0.0625, 0.2, 1.8, 0.89),
        _linear_case("L07", 1000.0, 2000.0, 200.0, 400, 0.0625, 0.2, 1.7, 0.85),
        *_table2(),
    )
}


def get(name: str) -> Case:
    """The case called ``name`` (case-insensitive)."""
    try:
        return CASES[name.upper()]
    except KeyError:
        raise ValueError(f"unknown case {name!r}: must be one of {', '.join(CASES)}") from None


def run(name: str, **bogie_changes: Any) -> DynamicResult:
    """Run the reference's case ``name``; ``bogie_changes`` override fields of its bogie (for what-if runs)."""
    case = get(name)
    bogie = case.bogie()
    if bogie_changes:
        bogie = bogie.replace(**bogie_changes)
    return case.runner(bogie)


def summary(name: str, result: DynamicResult | None = None) -> dict[str, float]:
    """The run's figures in the form of the reference's table (runs the case if no result is given)."""
    case = get(name)
    return case.summarise(run(name) if result is None else result)
