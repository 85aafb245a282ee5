"""Stage 4: the full non-linear suspension model of one side of an n-axle bogie.

Finite chassis pitch and equaliser rotation, spring-end contact points that roll along cylindrical pads
(``contact_roll_radius``), Coulomb friction with stick and slip at the spring ends (``friction_coefficient``,
elastic-plastic return map), interleaf friction of the leaf springs (``spring_friction_band``, Fancher's
hysteresis), bush stiffness and damping, unilateral tyres with per-axle wear, axle masses,
payload on the chassis and chassis tilt from a king pin rise. The equations are in ``docs/models.md``; the
compiled force is :mod:`bogie.steel.force.core`; time stepping is :mod:`bogie.steel.newmark`; the static
equilibrium's Newton iteration is compiled, :mod:`bogie.steel.force.equilibrium` (the one the phases start from).
The pack of a bogie's parameters, the cache of its constants and the freedoms' limits are
:mod:`bogie.steel.force.pack`, whose names are importable from here.

A simulation is driven by :class:`Inputs` (road height and rate under each axle, payload load factor, king pin
rise, each per time step) and starts from a :class:`State`; its result carries the final state, so runs chain:
load application, a crawl over a road, settling on a weighbridge, each starting where the last one stopped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.params import Bogie
from bogie.results import DynamicResult, Profile
from bogie.road import axle_heights
from bogie.settings import check_value, refusal
from bogie.steel.force import core
from bogie.steel.force import equilibrium as eq
from bogie.steel.force.pack import (  # noqa: F401 - the packing's public names, importable from here as before
    FRICTION_SLOTS,
    Constants,
    cached_pack,
    check_limits,
    checked_history,
    constants,
    design_wheel_loads,
    dof_names,
    limits,
    pack,
    residual_tolerance,
    work_size,
)
from bogie.steel.newmark import MODEL_NONLINEAR, consistent_acceleration, integrate


# ---- inputs and state ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Inputs:
    """Time histories that drive the model, one row per time step (n_steps + 1 rows).

    Attributes
    ----------
    dt
        Time step [s].
    road_height
        Road height under each axle [m], shape (n_t, n_axles).
    road_rate
        Its time derivative [m/s], shape (n_t, n_axles).
    load_factor
        Payload weight as a fraction of the design payload [-], shape (n_t,).
    kingpin_rise
        Rise of the king pin above the height that makes the bogie's ``chassis_tilt`` [m], shape (n_t,).
    """

    dt: float
    road_height: NDArray[np.float64]
    road_rate: NDArray[np.float64]
    load_factor: NDArray[np.float64]
    kingpin_rise: NDArray[np.float64]

    def __post_init__(self) -> None:
        check_value("dt", self.dt, "s", low=0.0, low_open=True)
        n_t = self.road_height.shape[0]
        if n_t < 2:
            raise ValueError(f"inputs have {n_t} rows: at least 2 (one step) are needed")
        for name in ("road_rate", "load_factor", "kingpin_rise"):
            if getattr(self, name).shape[0] != n_t:
                raise ValueError(f"{name} has {getattr(self, name).shape[0]} rows but road_height has {n_t}")
        for name in ("road_height", "road_rate", "load_factor", "kingpin_rise"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"{name} contains NaN or infinity: inputs must be finite")
        if np.any(self.load_factor <= 0.0) or np.any(self.load_factor > 2.0):
            bad = float(self.load_factor[(self.load_factor <= 0.0) | (self.load_factor > 2.0)][0])
            note = "fraction of the design payload; an empty trailer still has its chassis weight"
            raise ValueError(refusal("load_factor", bad, "-", low=0.0, low_open=True, high=2.0, note=note))

    @property
    def n_steps(self) -> int:
        """Number of time steps."""
        return self.road_height.shape[0] - 1

    @property
    def t(self) -> NDArray[np.float64]:
        """Times from the start of these inputs [s]."""
        return np.arange(self.n_steps + 1) * self.dt

    def then(self, other: Inputs) -> Inputs:
        """These inputs followed by ``other`` (its first row replaces this one's last)."""
        if other.dt != self.dt:
            raise ValueError(f"cannot join inputs with dt = {self.dt} s and dt = {other.dt} s")
        return Inputs(
            self.dt,
            np.concatenate([self.road_height, other.road_height[1:]]),
            np.concatenate([self.road_rate, other.road_rate[1:]]),
            np.concatenate([self.load_factor, other.load_factor[1:]]),
            np.concatenate([self.kingpin_rise, other.kingpin_rise[1:]]),
        )

    def drive(self, bogie: Bogie) -> NDArray[np.float64]:
        """The kernel's drive rows [road heights, road rates, load factor, king pin rise] for ``bogie``."""
        n = bogie.n_axles
        if self.road_height.shape[1] != n:
            raise ValueError(f"inputs are for {self.road_height.shape[1]} axles but the bogie has {n}")
        return np.ascontiguousarray(
            np.column_stack(
                [
                    self.road_height,
                    self.road_rate,
                    self.load_factor,
                    bogie.kingpin_height_offset + self.kingpin_rise,
                ]
            )
        )

    def drive_row(self, bogie: Bogie, row: int) -> NDArray[np.float64]:
        """Row ``row`` of :meth:`drive`, value for value, without forming the others."""
        n = bogie.n_axles
        if self.road_height.shape[1] != n:
            raise ValueError(f"inputs are for {self.road_height.shape[1]} axles but the bogie has {n}")
        rest = np.array([self.load_factor[row], bogie.kingpin_height_offset + self.kingpin_rise[row]])
        return np.concatenate([self.road_height[row], self.road_rate[row], rest])


def _steps(duration: float, dt: float) -> int:
    check_value("duration", duration, "s", low=0.0, low_open=True)
    # a time step longer than the phase would silently stretch it to one step of dt
    check_value("dt", dt, "s", low=0.0, low_open=True, high=duration, note="at most the duration")
    return max(1, int(round(duration / dt)))


def road_inputs(
    bogie: Bogie,
    profile: Profile,
    speed: float,
    duration: float,
    dt: float,
    front_axle_start: float = 0.0,
    load_factor: float = 1.0,
) -> Inputs:
    """Inputs for a pass over ``profile`` at constant ``speed`` [m/s] for ``duration`` [s].

    Each axle sees the profile at its own position (the wheel-path delay); road rates are the exact derivative
    of the linearly interpolated heights between steps.
    """
    n_steps = _steps(duration, dt)
    t = np.arange(n_steps + 1) * dt
    heights = axle_heights(profile, bogie.axle_x, speed, t, front_axle_start)
    rates = np.gradient(heights, t, axis=0)
    ones = np.ones(n_steps + 1)
    return Inputs(dt, heights, rates, load_factor * ones, 0.0 * ones)


def load_ramp(bogie: Bogie, start: float, end: float, duration: float, dt: float) -> Inputs:
    """Inputs that change the payload load factor from ``start`` to ``end`` [-] over ``duration`` [s], level road.

    The ramp is a smooth cosine so that the loading excites the bogie as little as a crane or a forklift would.
    """
    n_steps = _steps(duration, dt)
    s = np.linspace(0.0, 1.0, n_steps + 1)
    factor = start + (end - start) * 0.5 * (1.0 - numerics.cos(np.pi * s))
    zeros = np.zeros((n_steps + 1, bogie.n_axles))
    return Inputs(dt, zeros, zeros.copy(), factor, np.zeros(n_steps + 1))


def hold(bogie: Bogie, duration: float, dt: float, load_factor: float = 1.0, road: ArrayLike | None = None) -> Inputs:
    """Inputs that hold everything constant for ``duration`` [s]: a level (or given) road, a fixed load factor."""
    n_steps = _steps(duration, dt)
    heights = np.zeros((n_steps + 1, bogie.n_axles))
    if road is not None:
        heights[:] = np.asarray(road, dtype=float)
    return Inputs(dt, heights, np.zeros_like(heights), np.full(n_steps + 1, float(load_factor)), np.zeros(n_steps + 1))


@dataclass(frozen=True)
class State:
    """Configuration of the model: displacements, velocities, accelerations and the history variables.

    ``u`` = [chassis pitch [rad], equaliser rotations [rad], axle displacements [m]] from the design position.
    ``history`` holds the variables of :data:`bogie.steel.force.core.HISTORY` (4n): the spring ends' plastic
    slips [m], then each spring's deflection [m] and the hysteretic part of its force [N] at the last step.
    """

    u: NDArray[np.float64]
    v: NDArray[np.float64]
    a: NDArray[np.float64]
    history: NDArray[np.float64]

    @property
    def slip(self) -> NDArray[np.float64]:
        """The plastic slip of each spring end over its pad (2n) [m]."""
        return self.history[core.history_slices(len(self.u) // 2)["plastic_slip"]]


@dataclass(frozen=True, repr=False)
class NonlinearResult(DynamicResult):
    """A :class:`~bogie.results.DynamicResult` with the state at its end, to continue from."""

    final_state: State | None = None


# ---- static equilibrium ----------------------------------------------------------------------------------------
def equilibrium(
    bogie: Bogie, drive_row: ArrayLike, history: ArrayLike | None = None, u0: ArrayLike | None = None
) -> State:
    """Static equilibrium for one drive row (no inertia, no damping).

    With ``history`` None the friction is relaxed: the equilibrium is solved without end friction and without the
    springs' interleaf friction, each contact's slip is set so that it carries no friction force there and each
    spring sits on its elastic line (no locked-in forces, as after a long vibration). With ``history`` given
    (:attr:`State.history`), friction and hysteresis start from it and the equilibrium includes their forces.

    Newton starts from ``u0`` or, by default, from the design position with the chassis pitched to the king pin's
    height. When that fails (no convergence, or a solution outside the freedoms' limits: an equaliser that turned
    over onto a slack spring is an equilibrium of the equations but not of a bogie) and no ``u0`` was given, the
    equilibrium is followed from the design state (level road, full load, king pin at design height: ``u = 0``)
    to ``drive_row`` in small steps, each starting from the last: the state a bogie reaches when its load, tilt
    and road heights change slowly (:data:`CONTINUATION_STEPS`, halved where a step fails).

    Raises ``ValueError`` if the equilibrium lies outside the freedoms' limits (:func:`limits`) and the
    continuation cannot reach one inside them (a bogie without stops has none there, e.g. a free tri-axle with
    low pads at 2 degrees); ``RuntimeError`` if neither converges. An equaliser that meets its bump stop
    (``Bogie.equaliser_stop``) is a valid equilibrium.
    """
    try:
        return _equilibrium(bogie, drive_row, history, u0)
    except (RuntimeError, ValueError) as direct:
        if u0 is not None:
            raise
        failure = direct
    try:
        return _continued_equilibrium(bogie, np.asarray(drive_row, dtype=float), history)
    except (RuntimeError, ValueError) as followed:
        raise type(failure)(f"{failure}; following the equilibrium from the design state: {followed}") from None


#: equal steps of the continuation from the design state to the drive row (:func:`equilibrium`)
CONTINUATION_STEPS = 20
#: smallest fraction of the path a continuation step may shrink to before it gives up
CONTINUATION_MIN_STEP = 1.0 / 640.0


def _continued_equilibrium(bogie: Bogie, drive_row: NDArray[np.float64], history: ArrayLike | None) -> State:
    """Follow the static equilibrium from the design state (u = 0) to ``drive_row`` (see :func:`equilibrium`)."""
    n = bogie.n_axles
    design = np.r_[np.zeros(2 * n), 1.0, 0.0]
    u = np.zeros(2 * n)
    done, step = 0.0, 1.0 / CONTINUATION_STEPS
    state = None
    while done < 1.0:
        target = min(1.0, done + step)
        try:
            state = _equilibrium(bogie, design + target * (drive_row - design), history, u)
        except (RuntimeError, ValueError) as err:
            step *= 0.5
            if step < CONTINUATION_MIN_STEP:
                raise type(err)(f"stopped at {100.0 * done:.3g} % of the way: {err}") from None
            continue
        u, done = state.u, target
        step = min(2.0 * step, 1.0 / CONTINUATION_STEPS)
    assert state is not None
    return state


def _equilibrium(bogie: Bogie, drive_row: ArrayLike, history: ArrayLike | None, u0: ArrayLike | None) -> State:
    """Newton's static equilibrium from ``u0`` (see :func:`equilibrium`): the compiled
    :func:`bogie.steel.force.equilibrium.newton`, the one the phases start from, and its failures as errors."""
    n = bogie.n_axles
    ndof = 2 * n
    relaxed = history is None
    c = constants(bogie)
    # relaxed: the pack of bogie.replace(friction_coefficient=0.0, spring_friction_band=0.0), without a new bogie
    data_f = c.data_f.copy()
    if relaxed:
        data_f[FRICTION_SLOTS] = 0.0
    drv = np.ascontiguousarray(drive_row, dtype=float)
    hist = np.zeros(core.history_length(n)) if relaxed else checked_history(bogie, history, "history")
    hist_new = hist.copy()
    if u0 is None:
        # start with the bogie end of the chassis at its design height, so that no spring starts slack
        u = np.zeros(ndof)
        eq.design_start(drv, n, bogie.bogie_centre_x, u)
    else:
        u = np.array(u0, dtype=float)
    f = np.zeros(ndof)
    rec = np.zeros(core.record_length(n))
    work = np.zeros(work_size(bogie))
    status = eq.newton(data_f, c.data_i, drv, u, hist, hist_new, f, c.r_tol, c.u_limit, rec, work)
    if status == eq.SINGULAR:
        raise RuntimeError(
            f"static equilibrium: singular stiffness at u = {np.array2string(u, precision=4)} "
            "(a spring and its tyre both unloaded: is the load factor or king pin rise out of reach?)"
        )
    if status == eq.NO_CONVERGENCE:
        worst = int(np.argmax(np.abs(f) / c.r_tol))
        raise RuntimeError(
            f"static equilibrium did not converge: largest force residual {np.max(np.abs(f)):.3g} "
            f"(on {dof_names(n)[worst]}) at u = {np.array2string(u, precision=4)}"
        )
    check_limits(bogie, u)
    return State(u=u, v=np.zeros(ndof), a=np.zeros(ndof), history=hist_new.copy() if relaxed else hist.copy())


# ---- running ---------------------------------------------------------------------------------------------------
def _result(bogie: Bogie, run, inputs: Inputs, final: State | None) -> NonlinearResult:
    n = bogie.n_axles
    rec = run.record
    where = core.record_slices(n)
    keep = len(run.t)
    extras = {
        "chassis_pitch": run.u[:, 0],
        "equaliser_rotation": run.u[:, 1:n] - run.u[:, :1],
        "axle_displacement": run.u[:, n:],
        **{name: rec[:, where[name]] for name, *_ in core.RECORD if name != "tyre_load"},
        "road_height": inputs.road_height[:keep],
        "load_factor": inputs.load_factor[:keep],
    }
    return NonlinearResult(
        t=run.t,
        wheel_loads=rec[:, where["tyre_load"]],
        reference_load=float(np.mean(design_wheel_loads(bogie))),
        status="ok" if run.success else "failed",
        message=run.message,
        extras=extras,
        final_state=final,
    )


def simulate(
    bogie: Bogie,
    inputs: Inputs,
    initial: State | None = None,
    rho_inf: float | None = None,
    max_iter: int = 25,
    max_halvings: int = 5,
) -> NonlinearResult:
    """Integrate the non-linear model over ``inputs``.

    Parameters
    ----------
    bogie
        The bogie.
    inputs
        Road, load and king pin histories (:func:`road_inputs`, :func:`load_ramp`, :func:`hold`, ``then``).
    initial
        State to start from; by default the static equilibrium at the first input row with relaxed friction.
    rho_inf
        Generalised-alpha spectral radius; None for average-acceleration Newmark.
    max_iter, max_halvings
        Newton iterations per step, and how many times a step that fails is split in two before the run stops.

    Returns
    -------
    NonlinearResult
        Wheel loads [N] and the model's histories; ``status`` "failed" with the solver's message if a step could
        not be solved (the history up to there is kept), never NaN.

    References
    ----------
    N. M. Newmark, "A method of computation for structural dynamics", Journal of the Engineering Mechanics
    Division, ASCE, 85(EM3), 1959.
    J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
    dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
    """
    mass, data_f, data_i = cached_pack(bogie)
    drive = inputs.drive(bogie)
    state = equilibrium(bogie, drive[0]) if initial is None else initial
    checked_history(bogie, state.history, "initial.history")
    n_rec = core.record_length(bogie.n_axles)
    ndof = 2 * bogie.n_axles
    f0 = np.zeros(ndof)
    hist_new = state.history.copy()
    core.force(
        state.u, state.v, drive[0], data_f, data_i, state.history, hist_new, f0,
        np.zeros((ndof, ndof)), np.zeros((ndof, ndof)), np.zeros(n_rec), False, False, np.zeros(work_size(bogie)),
    )  # fmt: skip
    a0 = consistent_acceleration(mass, f0) if initial is None else state.a
    run = integrate(
        MODEL_NONLINEAR, mass, drive, data_f, data_i, state.u.copy(), state.v.copy(), a0, state.history.copy(),
        inputs.dt, inputs.n_steps, residual_tolerance(bogie), rho_inf=rho_inf, max_iter=max_iter,
        max_halvings=max_halvings, n_record=n_rec, work_size=work_size(bogie), limits=limits(bogie),
    )  # fmt: skip
    final = State(u=run.u[-1].copy(), v=run.v[-1].copy(), a=run.a[-1].copy(), history=run.history.copy())
    return _result(bogie, run, inputs, final if run.success else None)


def static_loads(bogie: Bogie, inputs: Inputs, initial: State | None = None) -> NonlinearResult:
    """Quasi-static path through ``inputs`` (no inertia, no damping): the weighbridge model.

    Each row is an equilibrium; friction slips carry from row to row, so the loads depend on the load history
    (apply and remove the payload, tilt the chassis, raise a wheel). Consistent with :func:`simulate` at very low
    speed. Without inertia the friction problem is only piecewise smooth and Newton may need many iterations
    near stick-slip transitions; rows are cheap, so the iteration budget is generous.
    """
    quiet = bogie.replace(tyre_damping=0.0, bush_damping=0.0)
    _, data_f, data_i = pack(quiet)
    drive = inputs.drive(quiet)
    state = equilibrium(quiet, drive[0]) if initial is None else initial
    checked_history(bogie, state.history, "initial.history")
    ndof = 2 * bogie.n_axles
    run = integrate(
        MODEL_NONLINEAR, np.zeros((ndof, ndof)), drive, data_f, data_i, state.u.copy(), np.zeros(ndof),
        np.zeros(ndof), state.history.copy(), inputs.dt, inputs.n_steps, residual_tolerance(bogie), max_iter=200,
        max_halvings=8, n_record=core.record_length(bogie.n_axles), work_size=work_size(bogie),
        limits=limits(bogie), quasi_static=True,
    )  # fmt: skip
    final = State(u=run.u[-1].copy(), v=np.zeros(ndof), a=np.zeros(ndof), history=run.history.copy())
    return _result(bogie, run, inputs, final if run.success else None)
