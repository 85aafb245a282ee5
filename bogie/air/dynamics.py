"""Air-sprung groups in motion: the time simulation, its energy terms and its result.

The state is the chassis pitch, the axle displacements, their rates, the air in each bag and the running
integrals of the dissipations and works; a compiled RK4 (:mod:`bogie.air._core`, the default) or scipy's LSODA
(the reference) integrates it over :class:`bogie.steel.nonlinear.Inputs` (``docs/air-suspension.md``, "Numerics").
The result is a :class:`~bogie.results.DynamicResult`, as the steel model's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import air
from bogie.air import _core as _air_core
from bogie.air import static as air_static
from bogie.params import GRAVITY
from bogie.results import DynamicResult
from bogie.steel.nonlinear import Inputs


@dataclass(frozen=True, repr=False)
class AirResult(DynamicResult):
    """A :class:`~bogie.results.DynamicResult` with the state at its end, to continue from."""

    final_state: air_static.AirState | None = None


#: the running integrals the simulation carries after the mechanical and gas states, in this order [J]
WORK_TERMS = (
    "damper_dissipation",
    "tyre_dissipation",
    "pipe_dissipation",
    "valve_dissipation",
    "road_work",
    "supply_energy",
    "vent_energy",
)


class _Drive:
    """The inputs as piecewise-linear functions of time, with their slopes as the rates."""

    def __init__(self, inputs: Inputs, bogie: air.AirBogie) -> None:
        if inputs.road_height.shape[1] != bogie.n_axles:
            raise ValueError(f"inputs are for {inputs.road_height.shape[1]} axles but the group has {bogie.n_axles}")
        self.dt, self.n = inputs.dt, inputs.n_steps
        self.road = inputs.road_height
        self.load = inputs.load_factor
        self.rise = bogie.kingpin_height_offset + inputs.kingpin_rise

    def __call__(self, t: float):
        # t / dt of a row's time can fall a rounding error short of the row: snap so that the row uses its own segment
        k = min(max(int(math.floor(t / self.dt + 1e-9)), 0), self.n - 1)
        s = t / self.dt - k
        road_rate = (self.road[k + 1] - self.road[k]) / self.dt
        rise_rate = (self.rise[k + 1] - self.rise[k]) / self.dt
        load = self.load[k] + s * (self.load[k + 1] - self.load[k])
        return (
            self.road[k] + s * road_rate * self.dt,
            road_rate,
            load,
            self.rise[k] + s * rise_rate * self.dt,
            rise_rate,
        )


def _forces(bogie: air.AirBogie, y: NDArray[np.float64], drive_row, valve: bool) -> dict:
    """Every force, flow and power of the state ``y`` (``docs/air-suspension.md``, "Equations of motion")."""
    n = bogie.n_axles
    road, road_rate, load, rise, rise_rate = drive_row
    theta, z, theta_d, z_d, m = y[0], y[1 : n + 1], y[n + 1], y[n + 2 : 2 * n + 2], y[2 * n + 2 : 3 * n + 2]
    x = np.asarray(bogie.axle_x)
    cos_t = math.cos(theta)
    e = rise - x * math.sin(theta) - z
    e_d = rise_rate - x * cos_t * theta_d - z_d
    area, volume = air.bag_area(bogie, e), air.bag_volume(bogie, e)
    if np.any(volume <= 0.0) or np.any(m <= 0.0):
        raise FloatingPointError(f"a bag emptied or closed: volumes {volume} m^3, air {m} kg")
    p = air.absolute_pressure(bogie, m, volume)
    p_a = bogie.atmospheric_pressure
    bag = (p - p_a) * area
    damper = bogie.damper_damping * e_d
    comp = bogie.design_tyre_compression + road - np.asarray(bogie.tyre_wear) - z
    push = bogie.tyre_stiffness * comp + bogie.tyre_damping * (road_rate - z_d)
    tyre = np.where(comp > 0.0, np.maximum(push, 0.0), 0.0)
    eta = air.specific_enthalpy(bogie, p)
    pipe = bogie.pipe_conductance * (np.mean(p) - p)
    fill = np.zeros(n)
    vent = np.zeros(n)
    if valve:
        e_mean = float(np.mean(e))
        error = math.copysign(max(abs(e_mean) - bogie.valve_dead_band, 0.0), e_mean)
        flow = -(m / volume) * area * error / bogie.valve_time_constant
        p_supply = bogie.supply_pressure + p_a
        fill = np.where((flow > 0.0) & (p < p_supply), flow, 0.0)
        vent = np.where(flow < 0.0, -flow, 0.0)
    eta_s = float(air.specific_enthalpy(bogie, bogie.supply_pressure + p_a))
    eta_a = float(air.specific_enthalpy(bogie, p_a))
    return {
        "extension": e, "extension_rate": e_d, "pressure": p - p_a, "bag": bag, "damper": damper, "tyre": tyre,
        "comp": comp, "cos": cos_t, "load": load, "road_rate": road_rate, "gas_flow": pipe + fill - vent,
        "powers": np.array([
            float(np.sum(damper * e_d)),
            float(np.sum((tyre - bogie.tyre_stiffness * np.maximum(comp, 0.0)) * (road_rate - z_d))),
            float(bogie.pipe_conductance * np.sum((p - np.mean(p)) * (eta - air.specific_enthalpy(bogie, np.mean(p))))),
            float(np.sum(fill * (eta_s - eta)) + np.sum(vent * (eta - eta_a))),
            float(np.sum(tyre * road_rate)),
            float(np.sum(fill) * eta_s),
            float(np.sum(vent) * eta_a),
        ]),
    }  # fmt: skip


def _rates(t: float, y: NDArray[np.float64], bogie: air.AirBogie, drive: _Drive, valve: bool) -> NDArray[np.float64]:
    n = bogie.n_axles
    f = _forces(bogie, y, drive(t), valve)
    x = np.asarray(bogie.axle_x)
    sprung = f["load"] * bogie.payload_mass * GRAVITY * bogie.payload_cg_x
    theta_dd = (sprung - np.sum(x * (f["bag"] - f["damper"]))) * f["cos"] / bogie.chassis_pitch_inertia
    z_dd = (f["tyre"] - f["bag"] + f["damper"]) / bogie.axle_mass - GRAVITY
    return np.concatenate([y[n + 1 : 2 * n + 2], [theta_dd], z_dd, f["gas_flow"], f["powers"]])


#: the integrators :func:`simulate` offers
METHODS = ("rk4", "lsoda")
#: the largest RK4 step [s]: rows longer than this are split into equal substeps (``docs/air-suspension.md``)
RK4_MAX_STEP = 1e-3
_FAILURES = {
    _air_core.EMPTIED: "a bag emptied or closed (volume or air mass <= 0)",
    _air_core.NOT_FINITE: "the state became non-finite",
}


def rk4_substeps(dt: float) -> int:
    """Equal RK4 steps per input row of ``dt`` [s]: the fewest that keep each step within :data:`RK4_MAX_STEP`."""
    return max(1, math.ceil(dt / RK4_MAX_STEP - 1e-9))


def _pack(bogie: air.AirBogie) -> NDArray[np.float64]:
    """The scalars of :data:`bogie.air._core.SCALARS`, in that order."""
    values = {
        "gas_constant": bogie.gas_constant,
        "design_tyre_compression": bogie.design_tyre_compression,
        "payload_moment": bogie.payload_mass * GRAVITY * bogie.payload_cg_x,
        "gravity": GRAVITY,
    }
    return np.array([values[name] if name in values else getattr(bogie, name) for name in _air_core.SCALARS])


def _simulate_rk4(bogie: air.AirBogie, inputs: Inputs, drive: _Drive, y0: NDArray[np.float64], valve: bool):
    n = bogie.n_axles
    ys, recs, rows, status = _air_core.integrate(
        _pack(bogie), np.asarray(bogie.axle_x, dtype=float), np.asarray(bogie.tyre_wear, dtype=float), y0,
        np.ascontiguousarray(drive.road, dtype=float), np.ascontiguousarray(drive.load, dtype=float),
        np.ascontiguousarray(drive.rise, dtype=float), inputs.dt, rk4_substeps(inputs.dt), bool(valve),
    )  # fmt: skip
    ok = status == _air_core.OK
    if rows == 0:  # the initial state itself is invalid: report it alone, as the lsoda path does
        ys, recs, rows = y0[None, :], np.full((1, recs.shape[1]), np.nan), 1
    ys, recs = ys[:rows], recs[:rows]
    t = inputs.t[:rows]
    works = ys[:, 3 * n + 2 :]
    extras = {
        "chassis_pitch": ys[:, 0],
        "axle_displacement": ys[:, 1 : n + 1],
        "bag_extension": recs[:, n : 2 * n],
        "bag_pressure": recs[:, 2 * n : 3 * n],
        "bag_force": recs[:, 3 * n : 4 * n],
        "gas_mass": ys[:, 2 * n + 2 : 3 * n + 2],
        **{name: works[:, k] for k, name in enumerate(WORK_TERMS)},
        "dissipation_rate": recs[:, 4 * n : 4 * n + 4],
        "road_height": inputs.road_height[:rows],
        "load_factor": inputs.load_factor[:rows],
    }
    last = ys[-1]
    final = air_static.AirState(
        u=last[: n + 1].copy(), v=last[n + 1 : 2 * n + 2].copy(), gas_mass=last[2 * n + 2 : 3 * n + 2].copy()
    )
    return AirResult(
        t=t,
        wheel_loads=recs[:, :n],
        reference_load=bogie.design_bag_load + bogie.axle_mass * GRAVITY,
        status="ok" if ok else "failed",
        message="ok" if ok else f"failed at t = {inputs.t[min(rows, inputs.n_steps)]:g} s: {_FAILURES[status]}",
        extras=extras,
        final_state=final if ok else None,
    )


def stored_energy(
    bogie: air.AirBogie,
    state: air_static.AirState,
    load_factor: float = 1.0,
    rise: float | None = None,
    road: ArrayLike | None = None,
) -> float:
    """E of ``docs/air-suspension.md``, "Energy": kinetic, gas, atmosphere, tyres, payload and axle weights [J].

    ``rise`` is the total king pin rise above the design height [m] (by default the bogie's tilt), ``road`` the
    road height under each axle [m] (level by default).
    """
    r = np.zeros(bogie.n_axles) if road is None else np.asarray(road, dtype=float)
    rise = bogie.kingpin_height_offset if rise is None else rise
    theta, z = state.u[0], state.u[1:]
    e = air.bag_extension(bogie, theta, z, rise)
    volume = air.bag_volume(bogie, e)
    comp = np.maximum(bogie.design_tyre_compression + r - np.asarray(bogie.tyre_wear) - z, 0.0)
    kinetic = 0.5 * bogie.chassis_pitch_inertia * state.v[0] ** 2 + 0.5 * bogie.axle_mass * np.sum(state.v[1:] ** 2)
    return float(
        kinetic
        + air.gas_internal_energy(bogie, state.gas_mass, volume)
        + bogie.atmospheric_pressure * np.sum(volume)
        + 0.5 * bogie.tyre_stiffness * np.sum(comp**2)
        + load_factor * bogie.payload_mass * GRAVITY * (rise - bogie.payload_cg_x * math.sin(theta))
        + bogie.axle_mass * GRAVITY * np.sum(z)
    )


def simulate(
    bogie: air.AirBogie,
    inputs: Inputs,
    initial: air_static.AirState | None = None,
    valve: bool = True,
    rtol: float = 1e-8,
    method: str = "rk4",
) -> AirResult:
    """Integrate the air-sprung group over ``inputs`` (:func:`bogie.steel.nonlinear.road_inputs`, ``hold``, ...).

    Parameters
    ----------
    bogie
        The group.
    inputs
        Road, load and king pin histories, one row per time step. Between rows each is linear in time and the
        road's rate is that line's slope (``inputs.road_rate`` is not used), so that the tyre's damper and the
        road's work see the same road as the tyre's spring.
    initial
        State to start from; by default the levelled equilibrium at the first input row.
    valve
        Whether the levelling valve works (False: shut, the side's air only moves between its bags).
    rtol
        Relative tolerance of the integrator [-]; used by ``method="lsoda"`` only.
    method
        "rk4" (default): the compiled fixed-step classical Runge-Kutta of :mod:`bogie.air._core`, with
        :func:`rk4_substeps` equal steps per input row; "lsoda": scipy's LSODA on the same equations, the
        reference (about a thousand times slower).

    Returns
    -------
    AirResult
        Wheel loads [N] at the input rows and the histories (chassis pitch, axle displacements, bag extensions,
        gauge pressures and forces, air masses, the running dissipations and works of :data:`WORK_TERMS` [J],
        ``dissipation_rate`` of the damper, tyre, pipe and valve at each row [W]);
        ``status`` "failed" with the solver's message and the history up to there if the solve stopped.
    """
    if method not in METHODS:
        raise ValueError(f"method = {method!r} is not one of the allowed values {', '.join(map(repr, METHODS))}")
    drive = _Drive(inputs, bogie)
    if initial is None:
        initial = air_static.equilibrium(
            bogie, inputs.load_factor[0], float(inputs.kingpin_rise[0]), inputs.road_height[0]
        )
    y0 = np.concatenate([initial.u, initial.v, initial.gas_mass, np.zeros(len(WORK_TERMS))])
    if method == "rk4":
        return _simulate_rk4(bogie, inputs, drive, y0, valve)
    return _simulate_lsoda(bogie, inputs, drive, y0, valve, rtol)


def _simulate_lsoda(
    bogie: air.AirBogie, inputs: Inputs, drive: _Drive, y0: NDArray[np.float64], valve: bool, rtol: float
):
    """:func:`simulate` by scipy's LSODA (the reference), its history read back through :func:`_forces`."""
    n = bogie.n_axles
    w_d = bogie.design_bag_load
    atol = np.concatenate([
        [1e-9], np.full(n, 1e-9), [1e-8], np.full(n, 1e-8), np.full(n, 1e-10 * bogie.design_gas_mass),
        np.full(len(WORK_TERMS), 1e-9 * w_d),
    ])  # fmt: skip
    from scipy.integrate import solve_ivp  # here: the default RK4 does not need it, and it takes 0.2 s to import

    t = inputs.t
    try:
        sol = solve_ivp(
            _rates, (t[0], t[-1]), y0, method="LSODA", t_eval=t, args=(bogie, drive, valve), rtol=rtol, atol=atol,
            max_step=inputs.dt,
        )  # fmt: skip
        ok, message, ys, ts = sol.success, sol.message, sol.y.T, sol.t
    except FloatingPointError as err:
        ok, message, ys, ts = False, str(err), y0[None, :], t[:1]
    if not ok and len(ts) == 0:
        ys, ts = y0[None, :], t[:1]
    rows = [_forces(bogie, y, drive(tk), valve) for tk, y in zip(ts, ys)]
    stack = {k: np.array([r[k] for r in rows]) for k in ("extension", "pressure", "bag", "tyre", "powers")}
    works = ys[:, 3 * n + 2 :]
    extras = {
        "chassis_pitch": ys[:, 0],
        "axle_displacement": ys[:, 1 : n + 1],
        "bag_extension": stack["extension"],
        "bag_pressure": stack["pressure"],
        "bag_force": stack["bag"],
        "gas_mass": ys[:, 2 * n + 2 : 3 * n + 2],
        **{name: works[:, k] for k, name in enumerate(WORK_TERMS)},
        "dissipation_rate": stack["powers"][:, :4],
        "road_height": inputs.road_height[: len(ts)],
        "load_factor": inputs.load_factor[: len(ts)],
    }
    last = ys[-1]
    final = air_static.AirState(
        u=last[: n + 1].copy(), v=last[n + 1 : 2 * n + 2].copy(), gas_mass=last[2 * n + 2 : 3 * n + 2]
    )
    return AirResult(
        t=ts,
        wheel_loads=stack["tyre"],
        reference_load=w_d + bogie.axle_mass * GRAVITY,
        status="ok" if ok else "failed",
        message="ok" if ok else f"failed at t = {ts[-1]:g} s: {message}",
        extras=extras,
        final_state=final if ok else None,
    )
