"""A weighing as a sequence of phases of the Stage 4 model, run in one compiled call.

A weighbridge or a weigh-in-motion (WIM) reading needs a few numbers from a simulation, not its history: the
state at the end, the mean tyre loads over a window, the loads a WIM sensor reads as the tyres pass. :func:`run`
steps a list of :class:`Phase` (a load ramp, a pass over a road, a hold) from rest or from a given state in one
call of :func:`bogie.steel.phases._core.run_phases`, which computes each phase's drive at any time (the load ramp in
closed form, the road from a :class:`RoadTable`) and keeps only those readings. A phase is stepped with fixed steps
of ``dt`` (the scheme of :func:`bogie.steel.nonlinear.simulate`) or, given a ``tolerance``, with adaptive steps under
control of their local error: long where nothing changes fast, short where the road or a friction contact does.
Equations, the controller and the accuracy record: ``docs/phases.md``. :func:`bogie.steel.nonlinear.simulate` remains
the tool for time histories.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bogie.params import Bogie
from bogie.ranges import check_positive
from bogie.results import Profile
from bogie.settings import check_value
from bogie.steel import nonlinear as nl
from bogie.steel.force import core
from bogie.steel.newmark import STATUS_TEXT, consistent_acceleration
from bogie.steel.phases import _core as pc

__all__ = ["MeanReading", "Phase", "PhaseOutcome", "PhasesRun", "RoadTable", "SensorReading", "kernel_cached", "run"]


def kernel_cached() -> bool:
    """Whether numba's cache holds this version of the weighings' kernel (``run_phases``) for this clone
    (:func:`bogie.numba_cache.is_cached`): what a stage asks before it starts workers that would each compile it."""
    from bogie.numba_cache import is_cached

    return is_cached(pc.__file__, function="run_phases")


#: Newton iterations per step and the residual tolerance are those of :func:`bogie.steel.nonlinear.simulate`
MAX_ITER = 25
_STATUS_TEXT = {
    **STATUS_TEXT,
    pc.STATUS_STEP_TOO_SMALL: f"the adaptive step fell below {pc.MIN_STEP:g} s",
    pc.STATUS_NO_EQUILIBRIUM: "no static equilibrium to start from",
}


@dataclass(frozen=True, eq=False)
class RoadTable:
    """Road heights at the distances ``x0 + k dx``, k = 0 .. len(heights) - 1 [m], linear between them.

    The table a phase reads the road under each axle from: its rate is the table's slope times the speed, exactly.
    """

    x0: float
    dx: float
    heights: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "dx", check_positive("dx", self.dx, "m"))
        h = np.ascontiguousarray(self.heights, dtype=float)
        if h.ndim != 1 or h.size < 2:
            raise ValueError(f"heights has shape {h.shape}: a road table needs at least 2 heights [m] in a 1-D array")
        if not np.all(np.isfinite(h)):
            raise ValueError("heights contains NaN or infinity: road heights must be finite [m]")
        if not math.isfinite(self.x0):
            raise ValueError(f"x0 = {self.x0!r} is not finite: the table's first distance [m]")
        object.__setattr__(self, "heights", h)

    @property
    def x_end(self) -> float:
        """Road distance of the table's last point [m]."""
        return self.x0 + (len(self.heights) - 1) * self.dx

    @classmethod
    def from_profile(cls, profile: Profile, x_from: float, x_to: float, dx: float) -> RoadTable:
        """``profile`` at the multiples of ``dx`` [m] that cover [x_from, x_to] [m].

        With ``dx`` the spacing of a profile's own grid (:class:`bogie.road.ISO8608Profile`: length / points) the
        table holds that grid's heights and reproduces the profile's linear interpolation exactly.
        """
        dx = check_positive("dx", dx, "m")
        if not (math.isfinite(x_from) and math.isfinite(x_to) and x_to > x_from):
            raise ValueError(f"x_from = {x_from!r}, x_to = {x_to!r}: need finite distances [m] with x_to > x_from")
        k0 = math.floor(x_from / dx)
        k1 = math.ceil(x_to / dx)
        x = np.arange(k0, k1 + 1) * dx
        return cls(k0 * dx, dx, np.asarray(profile(x), dtype=float))


@dataclass(frozen=True)
class MeanReading:
    """A weighbridge's reading: each tyre's load averaged over [start, end] [s] from the phase's start."""

    start: float
    end: float


@dataclass(frozen=True)
class SensorReading:
    """A WIM sensor's reading of each tyre's passage (:func:`bogie.road.wim.sensor_reading`).

    ``front_centre`` [s] from the phase's start: the front tyre's patch centre is over the sensor's centre; each
    trailing axle passes its spacing / speed later. ``half`` = (S + L) / 2v and ``flat`` = |S - L| / 2v [s] for
    sensor length S, patch length L and speed v. The stop flag looks at the passage of all the tyres.
    """

    front_centre: float
    half: float
    flat: float


@dataclass(frozen=True)
class Phase:
    """One phase of a weighing.

    Attributes
    ----------
    duration
        [s].
    load_factor
        Payload load factor [-], constant, or (start, end) for a cosine ramp over the phase (as
        :func:`bogie.steel.nonlinear.load_ramp`).
    road
        Road under the axles (a :class:`RoadTable`), or None for a level road.
    speed
        Road speed [m/s] (0 for a standstill).
    front_axle_start
        Road distance of the front axle at the phase's start [m]; trailing axles are their spacing behind.
    kingpin_rise
        Rise of the king pin above the height that makes the bogie's chassis tilt [m].
    dt
        Fixed time step; with ``tolerance``, the first adaptive step [s].
    tolerance
        None: fixed steps of ``dt``. Else the local error allowed per step, a displacement at a wheel, spring end or
        king pin lever [m]: adaptive steps (``docs/phases.md``).
    max_step
        Largest adaptive step [s].
    reading
        :class:`MeanReading`, :class:`SensorReading` or None.
    name
        For messages.
    """

    duration: float
    load_factor: float | tuple[float, float] = 1.0
    road: RoadTable | None = None
    speed: float = 0.0
    front_axle_start: float = 0.0
    kingpin_rise: float = 0.0
    dt: float = 1e-3
    tolerance: float | None = None
    max_step: float = 0.05
    reading: MeanReading | SensorReading | None = None
    name: str = "phase"

    def __post_init__(self) -> None:
        check_positive("duration", self.duration, "s")
        check_value("dt", self.dt, "s", low=0.0, low_open=True, high=self.duration, note="at most the duration")
        if self.tolerance is not None:
            check_positive("tolerance", self.tolerance, "m")
            check_positive("max_step", self.max_step, "s")
        check_positive("speed", self.speed, "m/s", allow_zero=True)
        lf = self.load_factor if isinstance(self.load_factor, tuple) else (self.load_factor, self.load_factor)
        for value in lf:
            check_value(
                "load_factor", value, "-", low=0.0, low_open=True, high=2.0, note="fraction of the design payload"
            )
        if isinstance(self.reading, MeanReading):
            if not (0.0 <= self.reading.start < self.reading.end <= self.duration):
                raise ValueError(
                    f"reading window [{self.reading.start!r}, {self.reading.end!r}] s must lie in [0, duration = "
                    f"{self.duration:g}] s and have start < end"
                )
        elif isinstance(self.reading, SensorReading):
            if self.speed <= 0.0:
                raise ValueError(f"a sensor reading needs a speed > 0 m/s, got speed = {self.speed!r}")
            check_positive("reading.half", self.reading.half, "s", allow_zero=True)

    @property
    def load_factors(self) -> tuple[float, float]:
        """(start, end) of the load factor [-]."""
        if isinstance(self.load_factor, tuple):
            return float(self.load_factor[0]), float(self.load_factor[1])
        return float(self.load_factor), float(self.load_factor)


@dataclass(frozen=True)
class PhaseOutcome:
    """What one phase gave: its reading per axle (wheel loads [N]; None if it has none or did not finish), the stop
    flag, and the work: accepted and rejected steps, force evaluations (those of the tangents included), tangents,
    factorisations of the iteration matrix, and the time it reached [s]."""

    name: str
    reading: NDArray[np.float64] | None
    on_stop: bool
    steps: int
    rejected: int
    force_evaluations: int
    tangents: int
    factorisations: int
    end_time: float
    unchecked: int = 0


@dataclass(frozen=True)
class PhasesRun:
    """The result of :func:`run`: ``status`` "ok" or "failed" with the ``message``; the state after the last phase
    run (None if a phase failed) and each phase's outcome (the phases after a failure are left out).

    With ``history`` asked for, ``t`` [s] from the first phase's start, ``wheel_loads`` [N] (n_t, n_axles) and
    ``chassis_pitch`` [rad] at the start and after every accepted step (up to a failure); else None.
    """

    status: str
    message: str
    final_state: nl.State | None
    phases: tuple[PhaseOutcome, ...]
    t: NDArray[np.float64] | None = None
    wheel_loads: NDArray[np.float64] | None = None
    chassis_pitch: NDArray[np.float64] | None = None

    @property
    def success(self) -> bool:
        """True if every phase ran."""
        return self.status == "ok"


_RELAXED_SLOTS = np.asarray(nl.FRICTION_SLOTS, dtype=np.int64)
_SCHEME = (0.25, 0.5, 0.0, 0.0)  # Newmark's average acceleration: (beta, gamma, alpha_m, alpha_f)


def _rows(phases: list[Phase], c: nl.Constants) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The kernel's phase rows and the concatenated road tables."""
    rows = np.zeros((len(phases), len(pc.PHASE_COLUMNS)))
    tables = []
    start = 0
    for p, phase in enumerate(phases):
        r = rows[p]
        r[pc.P_DURATION] = phase.duration
        r[pc.P_LF0], r[pc.P_LF1] = phase.load_factors
        r[pc.P_KINGPIN] = c.kingpin + phase.kingpin_rise
        r[pc.P_SPEED] = phase.speed
        r[pc.P_X0] = phase.front_axle_start
        r[pc.P_ROAD_START] = -1.0
        if phase.road is not None:
            road = phase.road
            reach_lo = phase.front_axle_start - c.offsets[-1]
            reach_hi = phase.front_axle_start + phase.speed * phase.duration
            slack = 1e-9 * max(1.0, abs(reach_lo), abs(reach_hi))
            if reach_lo < road.x0 - slack or reach_hi > road.x_end + slack:
                raise ValueError(
                    f"phase {phase.name!r}: the axles cover road distances [{reach_lo:g}, {reach_hi:g}] m but its "
                    f"road table covers [{road.x0:g}, {road.x_end:g}] m"
                )
            r[pc.P_ROAD_START] = start
            r[pc.P_ROAD_LENGTH] = len(road.heights)
            r[pc.P_ROAD_X0] = road.x0
            r[pc.P_ROAD_DX] = road.dx
            tables.append(road.heights)
            start += len(road.heights)
        r[pc.P_ADAPTIVE] = 0.0 if phase.tolerance is None else 1.0
        r[pc.P_DT] = phase.dt
        r[pc.P_TOL] = 0.0 if phase.tolerance is None else phase.tolerance
        r[pc.P_MAX_STEP] = phase.max_step
        reading = phase.reading
        if isinstance(reading, MeanReading):
            r[pc.P_READING] = pc.READING_MEAN
            r[pc.P_WINDOW_START], r[pc.P_WINDOW_END] = reading.start, reading.end
        elif isinstance(reading, SensorReading):
            r[pc.P_READING] = pc.READING_SENSOR
            r[pc.P_SENSOR_CENTRE] = reading.front_centre
            r[pc.P_SENSOR_HALF] = reading.half
            r[pc.P_SENSOR_FLAT] = reading.flat
            r[pc.P_WINDOW_START] = reading.front_centre - reading.half
            r[pc.P_WINDOW_END] = reading.front_centre + c.offsets[-1] / phase.speed + reading.half
    road_h = np.concatenate(tables) if tables else np.zeros(1)
    return rows, road_h


def _first_drive_row(phase: Phase, c: nl.Constants, n: int) -> NDArray[np.float64]:
    """The drive row at a phase's start, as :func:`bogie.steel.phases._core._drive` computes it (for the Python
    equilibrium the kernel falls back on)."""
    drv = np.zeros(2 * n + 2)
    rows, road_h = _rows([phase], c)
    pc._drive(rows[0], road_h, c.offsets, n, 0.0, drv)
    return drv


def run(
    bogie: Bogie,
    phases: list[Phase] | tuple[Phase, ...],
    initial: nl.State | None = None,
    history: bool = False,
    check_every: int = pc.CHECK_EVERY,
) -> PhasesRun:
    """Run ``phases`` in order, each from where the last ended, in one compiled call.

    Parameters
    ----------
    bogie
        The steel bogie.
    phases
        The phases, at least one.
    initial
        The state to start from; None: at rest, in the static equilibrium at the first phase's start with the
        friction relaxed (:func:`bogie.steel.nonlinear.equilibrium`; its continuation from the design state if Newton
        alone does not reach one).
    history
        Also return the wheel loads and chassis pitch at every accepted step (for plots and checks; the weighings
        need only the readings).
    check_every
        A step's first Newton correction is accepted without evaluating its residual where the contraction measured
        at the last checked step puts it far inside the tolerance, and checked at least every ``check_every`` steps
        (``docs/phases.md``); 1 checks every step, as :func:`bogie.steel.nonlinear.simulate` does.

    Returns
    -------
    PhasesRun
        "failed" with the solver's message (the phase, its time and the residual) if a step could not be solved;
        never NaN. Raises what :func:`bogie.steel.nonlinear.equilibrium` raises if there is no equilibrium to
        start from.
    """
    phases = list(phases)
    if not phases:
        raise ValueError("phases is empty: give at least one Phase")
    check_every = check_value("check_every", check_every, "steps", low=1, whole=True)
    c = nl.constants(bogie)  # the bogie's pack, tolerances and limits, computed once per bogie
    n = bogie.n_axles
    u, v, a, hist = _start(bogie, initial)
    out = _Outputs(len(phases), n)
    status, stopped, t_stop, rnorm, traced, trace = _run_kernel(
        bogie, phases, c, (u, v, a, hist), initial is None, history, check_every, out
    )
    if status == pc.STATUS_NO_EQUILIBRIUM:
        # Newton alone did not reach an equilibrium inside the limits: the Python one follows it from the design
        # state (and raises, naming why, if there is none)
        return run(bogie, phases, _continued_start(bogie, phases[0], c), history, check_every)
    outcomes = _outcomes(phases, stopped, out, n)
    traces = (trace[:traced, 0], trace[:traced, 1 : n + 1], trace[:traced, n + 1]) if history else (None,) * 3
    if status != pc.STATUS_OK:
        phase = phases[stopped]
        message = (
            f"{_STATUS_TEXT[int(status)]} at t = {t_stop:.6g} s of phase {phase.name!r} ({stopped + 1} of "
            f"{len(phases)}); scaled residual {rnorm:.3g} (1 = tolerance)"
        )
        return PhasesRun("failed", message, None, tuple(outcomes), *traces)
    return PhasesRun("ok", "ok", nl.State(u=u, v=v, a=a, history=hist), tuple(outcomes), *traces)


def _start(bogie: Bogie, initial: nl.State | None) -> tuple[np.ndarray, ...]:
    """The state arrays the kernel starts from and updates in place: ``u``, ``v``, ``a`` and the friction history
    (zeros at rest: the kernel then finds the equilibrium itself)."""
    n = bogie.n_axles
    if initial is None:
        return np.zeros(2 * n), np.zeros(2 * n), np.zeros(2 * n), np.zeros(core.history_length(n))
    hist = nl.checked_history(bogie, initial.history, "initial.history")
    u, v, a = (np.array(x, dtype=float) for x in (initial.u, initial.v, initial.a))
    return u, v, a, hist


class _Outputs:
    """What the kernel writes per phase: the readings' sums (and sensor weights), on-stop flags and statistics."""

    def __init__(self, n_phases: int, n_axles: int) -> None:
        self.readings = np.zeros((n_phases, 2 * n_axles))
        self.on_stop = np.zeros(n_phases, dtype=np.bool_)
        self.stats = np.zeros((n_phases, len(pc.STAT_COLUMNS)))


def _run_kernel(
    bogie: Bogie, phases: list[Phase], c: nl.Constants, state: tuple, at_rest: bool, history: bool, check_every: int,
    out: _Outputs,
) -> tuple:  # fmt: skip
    """One compiled call of every phase (again, with room, if the trace outgrew its first guess); the state arrays
    and ``out`` are updated in place. Returns the kernel's status, the phase it stopped in, its time and residual,
    the trace's rows and the trace."""
    n = bogie.n_axles
    rows, road_h = _rows(phases, c)
    u, v, a, hist = state
    # room for the trace: twice the fixed steps of dt (adaptive steps are mostly longer), more if it needs more
    rows_needed = int(2 * sum(p.duration / p.dt for p in phases)) + 16 if history else 0
    start = tuple(x.copy() for x in state)
    while True:
        trace = np.zeros((rows_needed, n + 2))
        args = (
            c.mass, c.data_f, c.data_i, c.offsets, c.levers, rows, road_h, u, v, a, hist, at_rest, _RELAXED_SLOTS,
            float(bogie.bogie_centre_x), c.r_tol, c.u_limit, MAX_ITER, _SCHEME, core.record_length(n),
            core.work_size(n), float(check_every), out.readings, out.on_stop, out.stats, trace,
        )  # fmt: skip
        status, stopped, t_stop, rnorm, traced = pc.run_phases(*args)
        if traced <= rows_needed or not history:
            return status, stopped, t_stop, rnorm, traced, trace
        rows_needed = traced  # a run is a pure function of its inputs: the same again, with room for its trace
        for x, x0 in zip((u, v, a, hist), start):
            x[:] = x0


def _continued_start(bogie: Bogie, first: Phase, c: nl.Constants) -> nl.State:
    """The state at rest at the first phase's start by :func:`bogie.steel.nonlinear.equilibrium` (its continuation from
    the design state), with the acceleration consistent with its forces."""
    n = bogie.n_axles
    ndof = 2 * n
    drive = _first_drive_row(first, c, n)
    state = nl.equilibrium(bogie, drive)
    f0 = np.zeros(ndof)
    core.force(
        state.u, state.v, drive, c.data_f, c.data_i, state.history, state.history.copy(), f0,
        np.zeros((ndof, ndof)), np.zeros((ndof, ndof)), np.zeros(core.record_length(n)), False, False,
        np.zeros(core.work_size(n)),
    )  # fmt: skip
    return nl.State(state.u, state.v, consistent_acceleration(c.mass, f0), state.history)


def _outcomes(phases: list[Phase], stopped: int, out: _Outputs, n: int) -> list[PhaseOutcome]:
    """Each phase run (up to the one the run stopped in): its reading, whether it ended on a stop, its counts."""
    outcomes = []
    for p in range(min(stopped + 1, len(phases))):
        phase = phases[p]
        reading = None
        if p < stopped and phase.reading is not None:
            if isinstance(phase.reading, MeanReading):
                reading = out.readings[p, :n] / (phase.reading.end - phase.reading.start)
            else:
                weight = out.readings[p, n:]
                reading = np.where(weight > 0.0, out.readings[p, :n] / np.where(weight > 0.0, weight, 1.0), np.nan)
        s = out.stats[p]
        outcomes.append(
            PhaseOutcome(
                name=phase.name, reading=reading, on_stop=bool(out.on_stop[p]), steps=int(s[pc.S_STEPS]),
                rejected=int(s[pc.S_REJECTED]), force_evaluations=int(s[pc.S_EVALS]), tangents=int(s[pc.S_TANGENTS]),
                factorisations=int(s[pc.S_FACTORS]), end_time=float(s[pc.S_END]), unchecked=int(s[pc.S_UNCHECKED]),
            )
        )  # fmt: skip
    return outcomes
