"""Air-sprung groups: one side of an n-axle group on rolling-lobe air springs with connected bags.

Per axle a bag (effective area changing linearly with height, volume with dV/de = A_e, a barotropic polytropic
gas whose mass is the state), the bags of the side connected to one line through equal linear restrictions, a
levelling valve with a dead band, a viscous damper per axle, the steel model's tyres and radius rods, chassis pitch
about the king pin, payload and tilt as in :mod:`bogie.steel.nonlinear`. The derivation is ``docs/air-suspension.md``.

This module holds the parameters (:class:`AirBogie`, validated), the bag's and the gas's relations, the
closed-form equalisation time constants and the presets; :mod:`bogie.air.static` the state at rest and
:mod:`bogie.air.dynamics` the time simulation.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.params import GRAVITY, AxleGroup
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.ranges import FieldRange, check_scalar, check_vector
from bogie.settings import refusal

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
class AirBogie(AxleGroup):
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
            object.__setattr__(self, name, check_vector(name, getattr(self, name), n, "axle", *r))
        if any(b <= a for a, b in zip(self.axle_x, self.axle_x[1:])):
            raise ValueError(f"axle_x = {self.axle_x!r} must increase front to rear (m)")
        for name, r in AIR_SCALAR_RANGES.items():
            object.__setattr__(self, name, check_scalar(name, getattr(self, name), *r))
        p0 = self.design_gauge_pressure
        if p0 >= self.supply_pressure:
            note = (
                "the design gauge pressure: the design bag load over bag_effective_area; at or below it the valve "
                "could not fill the bags"
            )
            raise ValueError(refusal("supply_pressure", self.supply_pressure, "Pa", low=p0, low_open=True, note=note))
        for i, w in enumerate(self.tyre_wear):
            if w >= self.tyre_radius:
                raise ValueError(f"tyre_wear[{i}] = {w!r} must be less than tyre_radius = {self.tyre_radius!r} m")

    def replace(self, **changes: Any) -> AirBogie:
        """A validated copy with some fields changed."""
        return dataclasses.replace(self, **changes)

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
        return p_abs / self.design_density**self.polytropic_index  # numerics-ok: floats, not arrays (libm pow)

    @property
    def design_tyre_compression(self) -> float:
        """c_0 = (W_d + m_a g) / k_t [m]."""
        return (self.design_bag_load + self.axle_mass * GRAVITY) / self.tyre_stiffness


# ---- the bag and its gas -----------------------------------------------------------------------------------------
def bag_extension(bogie: AirBogie, theta: float, z: NDArray[np.float64], rise: float) -> NDArray[np.float64]:
    """Each bag's extension e_i = Delta_h - x_i sin(theta_c) - z_i from its design height [m].

    ``theta`` the chassis pitch [rad], ``z`` the axle displacements [m], ``rise`` the king pin's total rise [m].
    """
    return rise - np.asarray(bogie.axle_x) * math.sin(theta) - z


def bag_area(bogie: AirBogie, extension: ArrayLike) -> NDArray[np.float64]:
    """Effective area A_e = A_0 + A' e at extension ``e`` from the design height [m^2]."""
    return bogie.bag_effective_area + bogie.bag_area_rate * np.asarray(extension, dtype=float)


def bag_volume(bogie: AirBogie, extension: ArrayLike) -> NDArray[np.float64]:
    """V = V_0 + A_0 e + A' e^2 / 2, so that dV/de = A_e (the bag is conservative) [m^3]."""
    e = np.asarray(extension, dtype=float)
    return bogie.bag_volume + bogie.bag_effective_area * e + 0.5 * bogie.bag_area_rate * e * e


def absolute_pressure(bogie: AirBogie, gas_mass: ArrayLike, volume: ArrayLike) -> NDArray[np.float64]:
    """p = K (m / V)^n [Pa]."""
    return bogie.gas_constant * numerics.power(
        np.asarray(gas_mass, dtype=float) / np.asarray(volume, dtype=float), bogie.polytropic_index
    )


def specific_enthalpy(bogie: AirBogie, pressure: ArrayLike) -> NDArray[np.float64]:
    """eta(p) = n p / ((n - 1) rho) of the barotropic gas, K (ln rho + 1) for n = 1 [J/kg]."""
    n, k = bogie.polytropic_index, bogie.gas_constant
    rho = numerics.power(np.asarray(pressure, dtype=float) / k, 1.0 / n)
    if n == 1.0:
        return k * (numerics.log(rho) + 1.0)
    return n * k * numerics.power(rho, n - 1.0) / (n - 1.0)


def gas_internal_energy(bogie: AirBogie, gas_mass: NDArray[np.float64], volume: NDArray[np.float64]) -> float:
    """Internal energy of the bags' air, sum m epsilon(m / V) [J]."""
    n, k = bogie.polytropic_index, bogie.gas_constant
    rho = gas_mass / volume
    eps = k * numerics.log(rho) if n == 1.0 else k * numerics.power(rho, n - 1.0) / (n - 1.0)
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


#: the presets' bag volume of each group size, by number of axles [m^3]
PRESET_BAG_VOLUMES: dict[int, float] = {2: 0.012, 3: 0.015}


def from_steel(steel, **changes: Any) -> AirBogie:
    """The air-sprung group that replaces the steel group ``steel`` (a :class:`bogie.params.Bogie`) on its trailer.

    It keeps the steel group's axle layout, tyres, axle masses, payload, centre of gravity and pitch inertia, and
    takes the presets' bags (:data:`PRESET_BAG_VOLUMES` by number of axles, the design pressure, area rate, pipe,
    valve and dampers of :func:`air_tandem`), so a steel and an air group of the fleet carry the same load.
    ``changes`` replace fields of the result (tilt, tyre wear, ...).
    """
    if steel.n_axles not in PRESET_BAG_VOLUMES:
        raise ValueError(
            f"n_axles = {steel.n_axles}: air bags are preset for groups of {sorted(PRESET_BAG_VOLUMES)} axles"
        )
    return _from_steel(steel, PRESET_BAG_VOLUMES[steel.n_axles], **changes)


def air_tandem(**changes: Any) -> AirBogie:
    """An air-sprung tandem on the layout, tyres and payload of :func:`bogie.presets.tandem_trrl`, 12 l bags."""
    return _from_steel(tandem_trrl(), PRESET_BAG_VOLUMES[2], **changes)


def air_triaxle(**changes: Any) -> AirBogie:
    """An air-sprung tri-axle on the layout, tyres and payload of :func:`bogie.presets.triaxle_stage1`, 15 l bags."""
    return _from_steel(triaxle_stage1(), PRESET_BAG_VOLUMES[3], **changes)
