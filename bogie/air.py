"""Air-sprung groups: one side of an n-axle group on rolling-lobe air springs with connected bags.

Per axle a bag (effective area changing linearly with height, volume with dV/de = A_e, a barotropic polytropic
gas whose mass is the state), the bags of the side connected to one line through equal linear restrictions, a
levelling valve with a dead band, a viscous damper per axle, the steel model's tyres and radius rods, chassis pitch
about the king pin, payload and tilt as in :mod:`bogie.nonlinear`. The derivation is ``docs/air-suspension.md``.

:func:`equilibrium` solves the state at rest (one pressure in connected bags; the valve levelled or shut with a
given gas mass), :func:`simulate` integrates the model over :class:`bogie.nonlinear.Inputs` and returns a
:class:`~bogie.results.DynamicResult` like the steel model's, with the dissipations and works as extras.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp
from scipy.optimize import root

from bogie.nonlinear import Inputs
from bogie.params import GRAVITY, FieldRange, _check_scalar, _check_vector, tandem_trrl, triaxle_stage1
from bogie.results import DynamicResult

#: specific gas constant of dry air [J/(kg K)]
GAS_CONSTANT_AIR = 287.05
#: the standard atmosphere [Pa]
STANDARD_ATMOSPHERE = 101_325.0

#: allowed range and unit of every scalar field of :class:`AirBogie`, by field name
AIR_SCALAR_RANGES: dict[str, FieldRange] = {
    "bag_effective_area": FieldRange(0.0, 0.5, "m^2", False),
    "bag_area_rate": FieldRange(-1.0, 1.0, "m^2/m", True),
    "bag_volume": FieldRange(0.0, 0.5, "m^3", False),
    "polytropic_index": FieldRange(1.0, 1.67, "-", True),
    "gas_temperature": FieldRange(200.0, 400.0, "K", True),
    "atmospheric_pressure": FieldRange(5e4, 1.2e5, "Pa", True),
    "pipe_conductance": FieldRange(0.0, 1e-3, "kg/(s Pa)", True),
    "valve_dead_band": FieldRange(0.0, 0.1, "m", True),
    "valve_time_constant": FieldRange(0.1, 1000.0, "s", True),
    "supply_pressure": FieldRange(0.0, 2e6, "Pa", False),
    "damper_damping": FieldRange(0.0, 1e6, "N s/m", True),
    "tyre_stiffness": FieldRange(0.0, 1e10, "N/m", False),
    "tyre_damping": FieldRange(0.0, 1e7, "N s/m", True),
    "tyre_radius": FieldRange(0.05, 2.0, "m", True),
    "axle_mass": FieldRange(0.0, 5000.0, "kg", False),
    "payload_mass": FieldRange(0.0, 1e6, "kg", False),
    "payload_cg_x": FieldRange(0.0, 50.0, "m", False),
    "chassis_pitch_inertia": FieldRange(0.0, 1e9, "kg m^2", False),
    "chassis_tilt": FieldRange(-math.radians(10.0), math.radians(10.0), "rad", True),
}
#: allowed range and unit of each value of the per-axle fields of :class:`AirBogie`
AIR_AXLE_RANGES: dict[str, FieldRange] = {
    "axle_x": FieldRange(0.0, 50.0, "m", False),
    "tyre_wear": FieldRange(0.0, 0.05, "m", True),
}


@dataclass(frozen=True)
class AirBogie:
    """One side of an n-axle air-sprung group (n >= 2), its bags connected by one line.

    Parameters
    ----------
    axle_x
        Axle (and bag) positions rearward of the king pin, front to rear [m].
    bag_effective_area
        Effective area A_0 of each bag at its design height [m^2].
    bag_area_rate
        A' = dA_e/de, the change of the effective area with the bag's extension [m^2/m]; negative when the area
        grows as the bag is compressed.
    bag_volume
        Volume V_0 of each bag at its design height [m^3].
    polytropic_index
        n of p V^n = const at fixed mass [-]: 1 isothermal, 1.4 adiabatic.
    gas_temperature
        Reference temperature T_0 of the air at the design state [K].
    atmospheric_pressure
        p_a [Pa].
    pipe_conductance
        Linear conductance C of each bag's restriction to the line, mass flow per pressure difference
        [kg/(s Pa)]; 0 for unconnected bags.
    valve_dead_band
        Half-width b_v of the levelling valve's neutral zone in mean bag extension [m].
    valve_time_constant
        Time tau_v in which the valve's flow would restore the ride height at constant pressure [s].
    supply_pressure
        Gauge pressure of the air supply the valve fills from [Pa].
    damper_damping
        Viscous rate of each axle's shock absorber [N s/m].
    tyre_stiffness, tyre_damping, tyre_radius, axle_mass, payload_mass, payload_cg_x, chassis_pitch_inertia,
    chassis_tilt, tyre_wear
        As in :class:`bogie.params.Bogie` [N/m, N s/m, m, kg, kg, m, kg m^2, rad, m per axle].
    """

    axle_x: tuple[float, ...]
    bag_effective_area: float
    bag_area_rate: float
    bag_volume: float
    polytropic_index: float
    gas_temperature: float
    atmospheric_pressure: float
    pipe_conductance: float
    valve_dead_band: float
    valve_time_constant: float
    supply_pressure: float
    damper_damping: float
    tyre_stiffness: float
    tyre_damping: float
    tyre_radius: float
    axle_mass: float
    payload_mass: float
    payload_cg_x: float
    chassis_pitch_inertia: float
    chassis_tilt: float = 0.0
    tyre_wear: tuple[float, ...] = field(default=())

    def __post_init__(self) -> None:
        if isinstance(self.axle_x, str | bytes) or np.ndim(self.axle_x) != 1 or len(self.axle_x) < 2:
            raise ValueError(f"axle_x = {self.axle_x!r} must be a sequence of at least 2 axle positions in m")
        n = len(self.axle_x)
        if isinstance(self.tyre_wear, tuple) and not self.tyre_wear:
            object.__setattr__(self, "tyre_wear", (0.0,) * n)
        for name, r in AIR_AXLE_RANGES.items():
            object.__setattr__(self, name, _check_vector(name, getattr(self, name), n, "axle", *r))
        if any(b <= a for a, b in zip(self.axle_x, self.axle_x[1:])):
            raise ValueError(f"axle_x = {self.axle_x!r} must increase front to rear (m)")
        for name, r in AIR_SCALAR_RANGES.items():
            object.__setattr__(self, name, _check_scalar(name, getattr(self, name), *r))
        p0 = self.design_gauge_pressure
        if p0 >= self.supply_pressure:
            raise ValueError(
                f"supply_pressure = {self.supply_pressure!r} is out of range: must exceed the design gauge pressure "
                f"{p0:.6g} Pa (the design bag load over bag_effective_area), or the valve could not fill the bags"
            )
        for i, w in enumerate(self.tyre_wear):
            if w >= self.tyre_radius:
                raise ValueError(f"tyre_wear[{i}] = {w!r} must be less than tyre_radius = {self.tyre_radius!r} m")

    def replace(self, **changes: Any) -> AirBogie:
        """A validated copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    @property
    def n_axles(self) -> int:
        """Number of axles."""
        return len(self.axle_x)

    @property
    def bogie_centre_x(self) -> float:
        """Mean of the axle positions [m]."""
        return sum(self.axle_x) / self.n_axles

    @property
    def kingpin_height_offset(self) -> float:
        """Rise of the king pin above its design height that makes :attr:`chassis_tilt` [m]."""
        return self.bogie_centre_x * math.tan(self.chassis_tilt)

    @property
    def design_bag_load(self) -> float:
        """W_d = m g x_cg / sum x_i, every bag's load in the design position [N]."""
        return self.payload_mass * GRAVITY * self.payload_cg_x / sum(self.axle_x)

    @property
    def design_gauge_pressure(self) -> float:
        """p_0 = W_d / A_0 [Pa]."""
        return self.design_bag_load / self.bag_effective_area

    @property
    def design_density(self) -> float:
        """rho_0 = p_abs,0 / (R T_0) [kg/m^3]."""
        return (self.design_gauge_pressure + self.atmospheric_pressure) / (GAS_CONSTANT_AIR * self.gas_temperature)

    @property
    def design_gas_mass(self) -> float:
        """m_0 = rho_0 V_0, the air in each bag in the design position [kg]."""
        return self.design_density * self.bag_volume

    @property
    def gas_constant(self) -> float:
        """K of p_abs = K rho^n [Pa (m^3/kg)^n]."""
        p_abs = self.design_gauge_pressure + self.atmospheric_pressure
        return p_abs / self.design_density**self.polytropic_index

    @property
    def design_tyre_compression(self) -> float:
        """c_0 = (W_d + m_a g) / k_t [m]."""
        return (self.design_bag_load + self.axle_mass * GRAVITY) / self.tyre_stiffness


# ---- the bag and its gas -----------------------------------------------------------------------------------------
def bag_area(bogie: AirBogie, extension: ArrayLike) -> NDArray[np.float64]:
    """Effective area A_e = A_0 + A' e at extension ``e`` from the design height [m^2]."""
    return bogie.bag_effective_area + bogie.bag_area_rate * np.asarray(extension, dtype=float)


def bag_volume(bogie: AirBogie, extension: ArrayLike) -> NDArray[np.float64]:
    """V = V_0 + A_0 e + A' e^2 / 2, so that dV/de = A_e (the bag is conservative) [m^3]."""
    e = np.asarray(extension, dtype=float)
    return bogie.bag_volume + bogie.bag_effective_area * e + 0.5 * bogie.bag_area_rate * e * e


def absolute_pressure(bogie: AirBogie, gas_mass: ArrayLike, volume: ArrayLike) -> NDArray[np.float64]:
    """p = K (m / V)^n [Pa]."""
    return bogie.gas_constant * (np.asarray(gas_mass, dtype=float) / np.asarray(volume, dtype=float)) ** (
        bogie.polytropic_index
    )


def specific_enthalpy(bogie: AirBogie, pressure: ArrayLike) -> NDArray[np.float64]:
    """eta(p) = n p / ((n - 1) rho) of the barotropic gas, K (ln rho + 1) for n = 1 [J/kg]."""
    n, k = bogie.polytropic_index, bogie.gas_constant
    rho = (np.asarray(pressure, dtype=float) / k) ** (1.0 / n)
    if n == 1.0:
        return k * (np.log(rho) + 1.0)
    return n * k * rho ** (n - 1.0) / (n - 1.0)


def _internal_energy(bogie: AirBogie, gas_mass: NDArray[np.float64], volume: NDArray[np.float64]) -> float:
    n, k = bogie.polytropic_index, bogie.gas_constant
    rho = gas_mass / volume
    eps = k * np.log(rho) if n == 1.0 else k * rho ** (n - 1.0) / (n - 1.0)
    return float(np.sum(gas_mass * eps))


def bag_stiffness(bogie: AirBogie) -> float:
    """Rate of one bag at fixed gas mass in the design position, n p_abs A_0^2 / V_0 - p_0 A' [N/m]."""
    p0 = bogie.design_gauge_pressure
    p_abs = p0 + bogie.atmospheric_pressure
    return bogie.polytropic_index * p_abs * bogie.bag_effective_area**2 / bogie.bag_volume - p0 * bogie.bag_area_rate


def pipe_time_constant(bogie: AirBogie) -> float:
    """tau = V_0 / (n R T_0 C): the decay time of the bags' pressure differences with their volumes held [s].

    ``docs/air-suspension.md``, "The pipe"; infinite for unconnected bags.
    """
    if bogie.pipe_conductance == 0.0:
        return math.inf
    return bogie.bag_volume / (
        bogie.polytropic_index * GAS_CONSTANT_AIR * bogie.gas_temperature * bogie.pipe_conductance
    )


def equalisation_time_constant(bogie: AirBogie) -> float:
    """tau (1 + k_gas / (k_t + k_A)): the decay time with each bag's axle free on its tyre, chassis held [s].

    A pressure rise pushes the axle down on its tyre and enlarges the bag, so the bag holds more air per pascal:
    the tyre (with the area term k_A = -p_0 A') in series with the gas's n p_abs A_0^2 / V_0
    (``docs/air-suspension.md``).
    """
    p0 = bogie.design_gauge_pressure
    k_gas = bogie.polytropic_index * (p0 + bogie.atmospheric_pressure) * bogie.bag_effective_area**2 / bogie.bag_volume
    k_area = -p0 * bogie.bag_area_rate
    return pipe_time_constant(bogie) * (1.0 + k_gas / (bogie.tyre_stiffness + k_area))


# ---- state, equilibrium ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AirState:
    """Configuration of the air-sprung group.

    Attributes
    ----------
    u
        [chassis pitch [rad], axle displacements [m]] from the design position, n + 1 values.
    v
        Their rates [rad/s, m/s].
    gas_mass
        Air in each bag [kg], n values.
    """

    u: NDArray[np.float64]
    v: NDArray[np.float64]
    gas_mass: NDArray[np.float64]


@dataclass(frozen=True, repr=False)
class AirResult(DynamicResult):
    """A :class:`~bogie.results.DynamicResult` with the state at its end, to continue from."""

    final_state: AirState | None = None


def _extension(bogie: AirBogie, theta: float, z: NDArray[np.float64], rise: float) -> NDArray[np.float64]:
    """e_i = Delta_h - x_i sin(theta_c) - z_i [m]."""
    return rise - np.asarray(bogie.axle_x) * math.sin(theta) - z


def _static_residual(y, bogie, load_factor, rise, road, gas_mass):
    n = bogie.n_axles
    theta, z, m = y[0], y[1 : n + 1], y[n + 1 :] * bogie.design_gas_mass
    x = np.asarray(bogie.axle_x)
    e = _extension(bogie, theta, z, rise)
    p = absolute_pressure(bogie, m, bag_volume(bogie, e))
    force = (p - bogie.atmospheric_pressure) * bag_area(bogie, e)
    comp = bogie.design_tyre_compression + road - np.asarray(bogie.tyre_wear) - z
    tyre = bogie.tyre_stiffness * np.maximum(comp, 0.0)
    w_d = bogie.design_bag_load
    moment = load_factor * bogie.payload_mass * GRAVITY * bogie.payload_cg_x - np.sum(x * force)
    res = [moment * math.cos(theta) / (w_d * bogie.bogie_centre_x)]
    res += list((tyre - force - bogie.axle_mass * GRAVITY) / w_d)
    p0 = bogie.design_gauge_pressure
    if gas_mass is not None and np.ndim(gas_mass) == 1:
        res += list(m / bogie.design_gas_mass - np.asarray(gas_mass) / bogie.design_gas_mass)
        return np.asarray(res)
    res += list((p[:-1] - p[1:]) / p0)
    if gas_mass is None:
        res.append(np.mean(e) / 0.01)
    else:
        res.append((np.sum(m) - float(gas_mass)) / bogie.design_gas_mass)
    return np.asarray(res)


def equilibrium(
    bogie: AirBogie,
    load_factor: float = 1.0,
    kingpin_rise: float = 0.0,
    road: ArrayLike | None = None,
    gas_mass: float | ArrayLike | None = None,
) -> AirState:
    """The group at rest [rad, m, kg].

    Parameters
    ----------
    bogie
        The group.
    load_factor
        Payload as a fraction of the design payload [-].
    kingpin_rise
        King pin rise above the height that makes the bogie's ``chassis_tilt`` [m].
    road
        Road height under each axle [m]; level by default.
    gas_mass
        None: the valve has levelled the group (mean bag extension at its set point) and the pipe has equalised
        the pressures. A number: the valve shut, that total air in the side's bags [kg], pressures equal. A
        sequence: each bag's air held [kg] (no flow), the quasi-static response the coupled time constant uses.

    Raises
    ------
    RuntimeError
        If the solve does not converge.
    """
    _check_scalar("load_factor", load_factor, 0.0, 2.0, "-", False)
    n = bogie.n_axles
    r = np.zeros(n) if road is None else np.asarray(road, dtype=float).reshape(n)
    rise = bogie.kingpin_height_offset + float(kingpin_rise)
    y0 = np.concatenate([[rise / bogie.bogie_centre_x], r - np.asarray(bogie.tyre_wear), np.ones(n) * load_factor])
    sol = root(_static_residual, y0, args=(bogie, load_factor, rise, r, gas_mass), method="hybr", tol=1e-13)
    residual = np.max(np.abs(_static_residual(sol.x, bogie, load_factor, rise, r, gas_mass)))
    if residual > 1e-9:
        raise RuntimeError(f"air-suspension equilibrium did not converge: residual {residual:.3g} ({sol.message})")
    return AirState(u=sol.x[: n + 1].copy(), v=np.zeros(n + 1), gas_mass=sol.x[n + 1 :] * bogie.design_gas_mass)


def state_loads(bogie: AirBogie, state: AirState, kingpin_rise: float = 0.0, road: ArrayLike | None = None) -> dict:
    """Bag extensions [m], gauge pressures [Pa], bag forces [N] and static tyre loads [N] of a state at rest."""
    n = bogie.n_axles
    r = np.zeros(n) if road is None else np.asarray(road, dtype=float).reshape(n)
    z = state.u[1:]
    e = _extension(bogie, state.u[0], z, bogie.kingpin_height_offset + kingpin_rise)
    p = absolute_pressure(bogie, state.gas_mass, bag_volume(bogie, e)) - bogie.atmospheric_pressure
    comp = bogie.design_tyre_compression + r - np.asarray(bogie.tyre_wear) - z
    return {
        "bag_extension": e,
        "bag_pressure": p,
        "bag_force": p * bag_area(bogie, e),
        "wheel_loads": bogie.tyre_stiffness * np.maximum(comp, 0.0),
    }


def static_wheel_loads(bogie: AirBogie, **kwargs: Any) -> NDArray[np.float64]:
    """Tyre loads at rest [N], front to rear (arguments of :func:`equilibrium`)."""
    state = equilibrium(bogie, **kwargs)
    return state_loads(bogie, state, kwargs.get("kingpin_rise", 0.0), kwargs.get("road"))["wheel_loads"]


def area_load_spread(bogie: AirBogie, state: AirState, kingpin_rise: float = 0.0) -> NDArray[np.float64]:
    """The closed form F_i / mean(F) - 1 = A' (e_i - mean(e)) / (A_0 + A' mean(e)) at one pressure [-].

    ``docs/air-suspension.md``, "Static equilibrium": equal pressures leave only the effective area's change with
    each bag's height.
    """
    e = _extension(bogie, state.u[0], state.u[1:], bogie.kingpin_height_offset + kingpin_rise)
    return bogie.bag_area_rate * (e - e.mean()) / (bogie.bag_effective_area + bogie.bag_area_rate * e.mean())


def coupled_time_constants(bogie: AirBogie) -> NDArray[np.float64]:
    """Decay times of the bags' pressure differences with the mechanics quasi-static, slowest first [s].

    Linearising the pressures p(m) of :func:`equilibrium` with each bag's air held about the levelled state,
    the pipe's dm/dt = C (mean(p) - p) has the n - 1 non-zero rates of C P J (P removing the mean, J = dp/dm).
    """
    n = bogie.n_axles
    base = equilibrium(bogie)
    p_base = state_loads(bogie, base)["bag_pressure"]
    step = 1e-6 * bogie.design_gas_mass
    jac = np.empty((n, n))
    for j in range(n):
        m = base.gas_mass.copy()
        m[j] += step
        p = state_loads(bogie, equilibrium(bogie, gas_mass=m))["bag_pressure"]
        jac[:, j] = (p - p_base) / step
    proj = np.eye(n) - np.full((n, n), 1.0 / n)
    rates = np.sort(np.abs(np.real(np.linalg.eigvals(bogie.pipe_conductance * proj @ jac))))
    return 1.0 / rates[1:]


# ---- dynamics ----------------------------------------------------------------------------------------------------
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

    def __init__(self, inputs: Inputs, bogie: AirBogie) -> None:
        if inputs.road_height.shape[1] != bogie.n_axles:
            raise ValueError(f"inputs are for {inputs.road_height.shape[1]} axles but the group has {bogie.n_axles}")
        self.dt, self.n = inputs.dt, inputs.n_steps
        self.road = inputs.road_height
        self.load = inputs.load_factor
        self.rise = bogie.kingpin_height_offset + inputs.kingpin_rise

    def __call__(self, t: float):
        k = min(max(int(t / self.dt), 0), self.n - 1)
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


def _forces(bogie: AirBogie, y: NDArray[np.float64], drive_row, valve: bool) -> dict:
    """Every force, flow and power of the state ``y`` (``docs/air-suspension.md``, "Equations of motion")."""
    n = bogie.n_axles
    road, road_rate, load, rise, rise_rate = drive_row
    theta, z, theta_d, z_d, m = y[0], y[1 : n + 1], y[n + 1], y[n + 2 : 2 * n + 2], y[2 * n + 2 : 3 * n + 2]
    x = np.asarray(bogie.axle_x)
    cos_t = math.cos(theta)
    e = rise - x * math.sin(theta) - z
    e_d = rise_rate - x * cos_t * theta_d - z_d
    area, volume = bag_area(bogie, e), bag_volume(bogie, e)
    if np.any(volume <= 0.0) or np.any(m <= 0.0):
        raise FloatingPointError(f"a bag emptied or closed: volumes {volume} m^3, air {m} kg")
    p = absolute_pressure(bogie, m, volume)
    p_a = bogie.atmospheric_pressure
    bag = (p - p_a) * area
    damper = bogie.damper_damping * e_d
    comp = bogie.design_tyre_compression + road - np.asarray(bogie.tyre_wear) - z
    push = bogie.tyre_stiffness * comp + bogie.tyre_damping * (road_rate - z_d)
    tyre = np.where(comp > 0.0, np.maximum(push, 0.0), 0.0)
    eta = specific_enthalpy(bogie, p)
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
    eta_s = float(specific_enthalpy(bogie, bogie.supply_pressure + p_a))
    eta_a = float(specific_enthalpy(bogie, p_a))
    return {
        "extension": e, "extension_rate": e_d, "pressure": p - p_a, "bag": bag, "damper": damper, "tyre": tyre,
        "comp": comp, "cos": cos_t, "load": load, "road_rate": road_rate, "gas_flow": pipe + fill - vent,
        "powers": np.array([
            float(np.sum(damper * e_d)),
            float(np.sum((tyre - bogie.tyre_stiffness * np.maximum(comp, 0.0)) * (road_rate - z_d))),
            float(bogie.pipe_conductance * np.sum((p - np.mean(p)) * (eta - specific_enthalpy(bogie, np.mean(p))))),
            float(np.sum(fill * (eta_s - eta)) + np.sum(vent * (eta - eta_a))),
            float(np.sum(tyre * road_rate)),
            float(np.sum(fill) * eta_s),
            float(np.sum(vent) * eta_a),
        ]),
    }  # fmt: skip


def _rates(t: float, y: NDArray[np.float64], bogie: AirBogie, drive: _Drive, valve: bool) -> NDArray[np.float64]:
    n = bogie.n_axles
    f = _forces(bogie, y, drive(t), valve)
    x = np.asarray(bogie.axle_x)
    sprung = f["load"] * bogie.payload_mass * GRAVITY * bogie.payload_cg_x
    theta_dd = (sprung - np.sum(x * (f["bag"] - f["damper"]))) * f["cos"] / bogie.chassis_pitch_inertia
    z_dd = (f["tyre"] - f["bag"] + f["damper"]) / bogie.axle_mass - GRAVITY
    return np.concatenate([y[n + 1 : 2 * n + 2], [theta_dd], z_dd, f["gas_flow"], f["powers"]])


def stored_energy(
    bogie: AirBogie,
    state: AirState,
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
    e = _extension(bogie, theta, z, rise)
    volume = bag_volume(bogie, e)
    comp = np.maximum(bogie.design_tyre_compression + r - np.asarray(bogie.tyre_wear) - z, 0.0)
    kinetic = 0.5 * bogie.chassis_pitch_inertia * state.v[0] ** 2 + 0.5 * bogie.axle_mass * np.sum(state.v[1:] ** 2)
    return float(
        kinetic
        + _internal_energy(bogie, state.gas_mass, volume)
        + bogie.atmospheric_pressure * np.sum(volume)
        + 0.5 * bogie.tyre_stiffness * np.sum(comp**2)
        + load_factor * bogie.payload_mass * GRAVITY * (rise - bogie.payload_cg_x * math.sin(theta))
        + bogie.axle_mass * GRAVITY * np.sum(z)
    )


def simulate(
    bogie: AirBogie,
    inputs: Inputs,
    initial: AirState | None = None,
    valve: bool = True,
    rtol: float = 1e-8,
) -> AirResult:
    """Integrate the air-sprung group over ``inputs`` (:func:`bogie.nonlinear.road_inputs`, ``hold``, ...).

    Parameters
    ----------
    bogie
        The group.
    inputs
        Road, load and king pin histories, one row per time step.
    initial
        State to start from; by default the levelled equilibrium at the first input row.
    valve
        Whether the levelling valve works (False: shut, the side's air only moves between its bags).
    rtol
        Relative tolerance of the integrator [-].

    Returns
    -------
    AirResult
        Wheel loads [N] at the input rows and the histories (chassis pitch, axle displacements, bag extensions,
        gauge pressures and forces, air masses, the running dissipations and works of :data:`WORK_TERMS` [J],
        ``dissipation_rate`` of the damper, tyre, pipe and valve at each row [W]);
        ``status`` "failed" with the solver's message and the history up to there if the solve stopped.
    """
    n = bogie.n_axles
    drive = _Drive(inputs, bogie)
    if initial is None:
        initial = equilibrium(bogie, inputs.load_factor[0], float(inputs.kingpin_rise[0]), inputs.road_height[0])
    y0 = np.concatenate([initial.u, initial.v, initial.gas_mass, np.zeros(len(WORK_TERMS))])
    w_d = bogie.design_bag_load
    atol = np.concatenate([
        [1e-9], np.full(n, 1e-9), [1e-8], np.full(n, 1e-8), np.full(n, 1e-10 * bogie.design_gas_mass),
        np.full(len(WORK_TERMS), 1e-9 * w_d),
    ])  # fmt: skip
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
    final = AirState(u=last[: n + 1].copy(), v=last[n + 1 : 2 * n + 2].copy(), gas_mass=last[2 * n + 2 : 3 * n + 2])
    return AirResult(
        t=ts,
        wheel_loads=stack["tyre"],
        reference_load=w_d + bogie.axle_mass * GRAVITY,
        status="ok" if ok else "failed",
        message="ok" if ok else f"failed at t = {ts[-1]:g} s: {message}",
        extras=extras,
        final_state=final if ok else None,
    )


# ---- presets -----------------------------------------------------------------------------------------------------
#: the presets' design gauge pressure of a laden bag, in the 5-7 bar quoted for trailer bags (unverified) [Pa]
PRESET_DESIGN_PRESSURE = 5.5e5
#: the presets' A' / A_0: 5 % more effective area per 100 mm of compression (unverified choice) [1/m]
PRESET_RELATIVE_AREA_RATE = -0.5
#: the presets' pipe time constant with the bags' volumes held, tau = V_0 / (n R T_0 C) (unverified choice) [s]
PRESET_PIPE_TIME_CONSTANT = 1.5
#: the presets' damping ratio of each shock absorber on its bag's rate and load (a choice) [-]
PRESET_DAMPING_RATIO = 0.25


def _from_steel(steel, bag_volume_m3: float, **changes: Any) -> AirBogie:
    """An air group on the steel preset's layout, tyres, axle masses and payload (``docs/air-suspension.md``)."""
    n_index, temperature = 1.4, 293.15
    w_d = steel.payload_mass * GRAVITY * steel.payload_cg_x / sum(steel.axle_x)
    area = w_d / PRESET_DESIGN_PRESSURE
    base = AirBogie(
        axle_x=steel.axle_x,
        bag_effective_area=area,
        bag_area_rate=PRESET_RELATIVE_AREA_RATE * area,
        bag_volume=bag_volume_m3,
        polytropic_index=n_index,
        gas_temperature=temperature,
        atmospheric_pressure=STANDARD_ATMOSPHERE,
        pipe_conductance=bag_volume_m3 / (n_index * GAS_CONSTANT_AIR * temperature * PRESET_PIPE_TIME_CONSTANT),
        valve_dead_band=0.005,
        valve_time_constant=8.0,
        supply_pressure=8.0e5,
        damper_damping=1.0,
        tyre_stiffness=steel.tyre_stiffness,
        tyre_damping=steel.tyre_damping,
        tyre_radius=steel.tyre_radius,
        axle_mass=steel.axle_mass,
        payload_mass=steel.payload_mass,
        payload_cg_x=steel.payload_cg_x,
        chassis_pitch_inertia=steel.chassis_pitch_inertia,
    )
    damping = 2.0 * PRESET_DAMPING_RATIO * math.sqrt(bag_stiffness(base) * w_d / GRAVITY)
    return base.replace(damper_damping=damping, **changes)


def air_tandem(**changes: Any) -> AirBogie:
    """An air-sprung tandem on the layout, tyres and payload of :func:`bogie.params.tandem_trrl`, 12 l bags."""
    return _from_steel(tandem_trrl(), 0.012, **changes)


def air_triaxle(**changes: Any) -> AirBogie:
    """An air-sprung tri-axle on the layout, tyres and payload of :func:`bogie.params.triaxle_stage1`, 15 l bags."""
    return _from_steel(triaxle_stage1(), 0.015, **changes)
