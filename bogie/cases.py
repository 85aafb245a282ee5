"""The reference's named runs, reproducible by name: ``bogie.cases.run("L01")``.

Linear runs L01-L07 (Table 1) use the Stage 3 model on :func:`~bogie.params.tandem_trrl` with Table 1's bush
stiffness, bush damping, axle mass, number of steps, time step and speed, over the ramped step of Figure 4.
Every assumption beyond the table is stated in :data:`CASES` and in ``docs/validation.md``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from bogie import linear
from bogie.params import Bogie, tandem_trrl
from bogie.results import DynamicResult
from bogie.road import RampedStep

#: the front axle starts this far before the step [m], so every run begins with a settled static state
STEP_LEAD = 0.5


@dataclass(frozen=True)
class Case:
    """One named run of the reference.

    Attributes
    ----------
    name
        The reference's run number ("L01", ...).
    description
        What the run is and every assumption we made for it.
    model
        "linear" (Stage 3) or "nonlinear" (Stage 4).
    bogie
        Factory of the bogie of the run.
    speed
        Vehicle speed [m/s].
    dt
        Time step [s].
    n_steps
        Number of steps.
    reference
        What the reference reports for the run (peak p, peak P1, ... as printed).
    """

    name: str
    description: str
    model: str
    bogie: Callable[[], Bogie]
    speed: float
    dt: float
    n_steps: int
    reference: dict[str, Any] = field(default_factory=dict)

    def road(self) -> RampedStep:
        """The road of the run: the ramped step of Figure 4 (see :class:`bogie.road.RampedStep`)."""
        return RampedStep()


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
        speed=speed,
        dt=dt,
        n_steps=n_steps,
        reference={"peak_p": p, "peak_p1": p1},
    )


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
    if case.model == "linear":
        return linear.simulate(bogie, case.road(), case.speed, case.dt, case.n_steps, front_axle_start=-STEP_LEAD)
    raise ValueError(f"case {name!r} has unknown model {case.model!r}")
