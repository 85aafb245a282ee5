"""Air-sprung groups at rest: the equilibrium, its loads, the effective-area closed form, the coupled time constants.

At rest the connected bags share one pressure, so their loads differ only through each bag's effective area;
``docs/air-suspension.md``, "Static equilibrium". The parameters are :class:`bogie.air.AirBogie`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import air
from bogie.params import GRAVITY
from bogie.ranges import check_scalar


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


def _static_residual(y, bogie, load_factor, rise, road, gas_mass):
    n = bogie.n_axles
    theta, z, m = y[0], y[1 : n + 1], y[n + 1 :] * bogie.design_gas_mass
    x = np.asarray(bogie.axle_x)
    e = air.bag_extension(bogie, theta, z, rise)
    p = air.absolute_pressure(bogie, m, air.bag_volume(bogie, e))
    force = (p - bogie.atmospheric_pressure) * air.bag_area(bogie, e)
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
    bogie: air.AirBogie,
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
    ValueError
        If the bags are not connected (``pipe_conductance`` 0) and ``gas_mass`` does not give each bag's air: then
        nothing makes their pressures equal, and the state at rest depends on how each bag was filled.
    RuntimeError
        If the solve does not converge.
    """
    check_scalar("load_factor", load_factor, 0.0, 2.0, "-", False)
    n = bogie.n_axles
    if bogie.pipe_conductance == 0.0 and (gas_mass is None or np.ndim(gas_mass) == 0):
        raise ValueError(
            "pipe_conductance = 0.0 kg/(s Pa): unconnected bags have no common pressure at rest; give gas_mass as "
            f"one value per bag ({n} values, kg)"
        )
    if gas_mass is not None and np.ndim(gas_mass) == 1 and len(gas_mass) != n:
        raise ValueError(f"gas_mass has {len(gas_mass)} values but the group has {n} bags: give one per bag in kg")
    r = np.zeros(n) if road is None else np.asarray(road, dtype=float).reshape(n)
    rise = bogie.kingpin_height_offset + float(kingpin_rise)
    y0 = np.concatenate([[rise / bogie.bogie_centre_x], r - np.asarray(bogie.tyre_wear), np.ones(n) * load_factor])
    from scipy.optimize import root  # here: 0.2 s to import, which a steel group's weighings need not pay

    sol = root(_static_residual, y0, args=(bogie, load_factor, rise, r, gas_mass), method="hybr", tol=1e-13)
    residual = np.max(np.abs(_static_residual(sol.x, bogie, load_factor, rise, r, gas_mass)))
    if residual > 1e-9:
        raise RuntimeError(f"air-suspension equilibrium did not converge: residual {residual:.3g} ({sol.message})")
    return AirState(u=sol.x[: n + 1].copy(), v=np.zeros(n + 1), gas_mass=sol.x[n + 1 :] * bogie.design_gas_mass)


def state_loads(bogie: air.AirBogie, state: AirState, kingpin_rise: float = 0.0, road: ArrayLike | None = None) -> dict:
    """Bag extensions [m], gauge pressures [Pa], bag forces [N] and static tyre loads [N] of a state at rest."""
    n = bogie.n_axles
    r = np.zeros(n) if road is None else np.asarray(road, dtype=float).reshape(n)
    z = state.u[1:]
    e = air.bag_extension(bogie, state.u[0], z, bogie.kingpin_height_offset + kingpin_rise)
    p = air.absolute_pressure(bogie, state.gas_mass, air.bag_volume(bogie, e)) - bogie.atmospheric_pressure
    comp = bogie.design_tyre_compression + r - np.asarray(bogie.tyre_wear) - z
    return {
        "bag_extension": e,
        "bag_pressure": p,
        "bag_force": p * air.bag_area(bogie, e),
        "wheel_loads": bogie.tyre_stiffness * np.maximum(comp, 0.0),
    }


def static_wheel_loads(bogie: air.AirBogie, **kwargs: Any) -> NDArray[np.float64]:
    """Tyre loads at rest [N], front to rear (arguments of :func:`equilibrium`)."""
    state = equilibrium(bogie, **kwargs)
    return state_loads(bogie, state, kwargs.get("kingpin_rise", 0.0), kwargs.get("road"))["wheel_loads"]


def area_load_spread(bogie: air.AirBogie, state: AirState, kingpin_rise: float = 0.0) -> NDArray[np.float64]:
    """The closed form F_i / mean(F) - 1 = A' (e_i - mean(e)) / (A_0 + A' mean(e)) at one pressure [-].

    ``docs/air-suspension.md``, "Static equilibrium": equal pressures leave only the effective area's change with
    each bag's height.
    """
    e = air.bag_extension(bogie, state.u[0], state.u[1:], bogie.kingpin_height_offset + kingpin_rise)
    return bogie.bag_area_rate * (e - e.mean()) / (bogie.bag_effective_area + bogie.bag_area_rate * e.mean())


def coupled_time_constants(bogie: air.AirBogie) -> NDArray[np.float64]:
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
    # numerics-ok: LAPACK's eigenvalues, a time scale for the docs and tests (to 3 digits), on no pipeline output
    rates = np.sort(np.abs(np.real(np.linalg.eigvals(bogie.pipe_conductance * proj @ jac))))
    return 1.0 / rates[1:]
