"""Stage 3: the linear dynamic model of one side of an n-axle bogie (the reference's Figure 3).

Freedoms (3n for n axles; six for the reference's two-axle model), all measured from the **design position**
(laden with ``payload_mass``, chassis and equalisers level, every spring and tyre at its design load; see
:func:`bogie.params.design_spring_loads`), vertical displacements upward, rotations positive when they lower the
rear (nose up for the chassis):

====================  =====================================================================
``chassis_pitch``      rotation of the rigid trailer about the king pin [rad]
``equaliser_j``        absolute rotation of equaliser j, rear tip down positive [rad]
``axle_i``             vertical displacement of axle i [m]
``tyre_i``             vertical displacement of tyre i's road-contact node (massless) [m]
====================  =====================================================================

Elements: a leaf spring per axle between its two ends (hanger or equaliser arm tip) and its seat (lever rule), a
tyre spring between axle and contact node, a very stiff spring from each contact node to the road (through which
the road enters, as in the reference; purely computational), a torsional spring and damper between each
equaliser and the chassis (the bush), optional tyre dampers between axle and road. Derivation:
``docs/dynamics.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bogie import numerics
from bogie.params import GRAVITY, Bogie, design_spring_loads
from bogie.results import DynamicResult, Profile
from bogie.road import axle_heights
from bogie.settings import check_value
from bogie.steel.newmark import consistent_acceleration, linear_steps

#: ground springs are this many times stiffer than the tyres
GROUND_STIFFNESS_FACTOR = 1000.0


@dataclass(frozen=True)
class LinearMatrices:
    """Assembled matrices of the linear model.

    Attributes
    ----------
    M, C, K
        Mass [kg, kg m^2], damping and stiffness matrices in the freedoms of ``dofs``.
    dofs
        Names of the freedoms, in order.
    design_wheel_loads
        Tyre loads in the design position [N]; the weights are in equilibrium with them there, so they do not
        appear in the load vector.
    road_stiffness
        (n_dof, n_axles): load per metre of road height under each axle, R = road_stiffness @ h.
    road_damping
        (n_dof, n_axles): load per m/s of road height rate (tyre dampers), R = road_damping @ dh/dt.
    kingpin
        Load per metre of king pin rise (chassis tilt).
    """

    M: NDArray[np.float64]
    C: NDArray[np.float64]
    K: NDArray[np.float64]
    dofs: tuple[str, ...]
    design_wheel_loads: NDArray[np.float64]
    road_stiffness: NDArray[np.float64]
    road_damping: NDArray[np.float64]
    kingpin: NDArray[np.float64]


def dof_names(n_axles: int) -> tuple[str, ...]:
    """Names of the 3n freedoms of the linear model."""
    return (
        ("chassis_pitch",)
        + tuple(f"equaliser_{j}" for j in range(n_axles - 1))
        + tuple(f"axle_{i}" for i in range(n_axles))
        + tuple(f"tyre_{i}" for i in range(n_axles))
    )


def _spring_vectors(bogie: Bogie) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Compression of each leaf spring as B q + kingpin_rise * b [m]; returns (B (n x n_dof), b (n,))."""
    n = bogie.n_axles
    n_dof = 3 * n
    i_eq, i_ax = 1, n
    pivots = bogie.equaliser_pivot_x
    comp = np.zeros((n, n_dof))
    kp = np.zeros(n)
    for i in range(n):
        a_f, a_r = bogie.spring_front_half_length[i], bogie.spring_rear_half_length[i]
        c_f, c_r = a_r / (a_f + a_r), a_f / (a_f + a_r)
        comp[i, i_ax + i] += 1.0  # the seat rises: compression grows
        # each end moves up with the chassis (king pin rise minus x * pitch) plus its equaliser's rotation
        if i == 0:
            comp[i, 0] -= c_f * (-bogie.front_hanger_x)
        else:
            comp[i, 0] -= c_f * (-pivots[i - 1])
            comp[i, i_eq + i - 1] -= c_f * (-bogie.equaliser_rear_arm[i - 1])
        if i == n - 1:
            comp[i, 0] -= c_r * (-bogie.rear_hanger_x)
        else:
            comp[i, 0] -= c_r * (-pivots[i])
            comp[i, i_eq + i] -= c_r * bogie.equaliser_front_arm[i]
        kp[i] = -(c_f + c_r)
    return comp, kp


def matrices(bogie: Bogie, ground_stiffness_factor: float = GROUND_STIFFNESS_FACTOR) -> LinearMatrices:
    """Assemble M, C, K and the load vectors of the linear model for ``bogie``.

    The leaf-spring, tyre and ground springs each contribute k B^T B for their compression B q; the bush
    contributes K_B and C_B on (equaliser - chassis) rotation. Small angles; spring ends stay at their design x.
    """
    check_value("ground_stiffness_factor", ground_stiffness_factor, "-", low=1.0, low_open=True)
    n = bogie.n_axles
    n_dof = 3 * n
    i_eq, i_ax, i_ty = 1, n, 2 * n
    k_g = ground_stiffness_factor * bogie.tyre_stiffness
    M = np.zeros((n_dof, n_dof))
    C = np.zeros((n_dof, n_dof))
    K = np.zeros((n_dof, n_dof))
    road_k = np.zeros((n_dof, n))
    road_c = np.zeros((n_dof, n))
    kingpin = np.zeros(n_dof)

    M[0, 0] = bogie.chassis_pitch_inertia
    for j in range(n - 1):
        M[i_eq + j, i_eq + j] = bogie.equaliser_inertia
        bush = np.zeros(n_dof)
        bush[i_eq + j], bush[0] = 1.0, -1.0
        K += bogie.bush_stiffness * np.outer(bush, bush)
        C += bogie.bush_damping * np.outer(bush, bush)
    for i in range(n):
        M[i_ax + i, i_ax + i] = bogie.axle_mass

    springs, springs_kp = _spring_vectors(bogie)
    for i in range(n):
        K += bogie.road_spring_stiffness * np.outer(springs[i], springs[i])
        kingpin -= bogie.road_spring_stiffness * springs[i] * springs_kp[i]
        tyre = np.zeros(n_dof)
        tyre[i_ty + i], tyre[i_ax + i] = 1.0, -1.0  # compression = contact node - axle
        K += bogie.tyre_stiffness * np.outer(tyre, tyre)
        # ground spring: compression = road - node
        K[i_ty + i, i_ty + i] += k_g
        road_k[i_ty + i, i] = k_g
        # tyre damper between axle and road: compression rate = road rate - axle rate
        C[i_ax + i, i_ax + i] += bogie.tyre_damping
        road_c[i_ax + i, i] = bogie.tyre_damping
    design = np.asarray(design_spring_loads(bogie)) + bogie.axle_mass * GRAVITY
    return LinearMatrices(M, C, K, dof_names(n), design, road_k, road_c, kingpin)


def wheel_loads_from_state(
    bogie: Bogie,
    mats: LinearMatrices,
    u: NDArray[np.float64],
    v: NDArray[np.float64],
    road_rate: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Tyre forces on the road [N] (compression positive), shape (..., n_axles)."""
    n = bogie.n_axles
    axle, tyre = u[..., n : 2 * n], u[..., 2 * n : 3 * n]
    axle_rate = v[..., n : 2 * n]
    return mats.design_wheel_loads + bogie.tyre_stiffness * (tyre - axle) + bogie.tyre_damping * (road_rate - axle_rate)


def static_state(bogie: Bogie, mats: LinearMatrices | None = None) -> NDArray[np.float64]:
    """Static equilibrium on a level road with the chassis tilt, from the design position [m, rad]."""
    mats = matrices(bogie) if mats is None else mats
    return numerics.solve(mats.K, mats.kingpin * bogie.kingpin_height_offset)


def design_deflection(bogie: Bogie, mats: LinearMatrices | None = None) -> float:
    """Mean drop of the spring ends from the unloaded to the design position [m]: spring plus tyre deflection."""
    mats = matrices(bogie) if mats is None else mats
    springs = np.asarray(design_spring_loads(bogie)) / bogie.road_spring_stiffness
    tyres = mats.design_wheel_loads / bogie.tyre_stiffness
    return float(np.mean(springs + tyres))


def simulate(
    bogie: Bogie,
    profile: Profile,
    speed: float,
    dt: float,
    n_steps: int,
    front_axle_start: float = 0.0,
    beta: float = 0.25,
    gamma: float = 0.5,
    rho_inf: float | None = None,
    ground_stiffness_factor: float = GROUND_STIFFNESS_FACTOR,
) -> DynamicResult:
    """Run the linear model over a road profile at constant speed, starting from static equilibrium.

    Parameters
    ----------
    bogie
        The bogie (``bush_stiffness``, ``bush_damping`` and the linear properties are used; the non-linear
        inhibitors ``contact_roll_radius`` and ``friction_coefficient`` have no place in this model).
    profile
        Road height as a function of distance [m] (see :mod:`bogie.road`).
    speed
        Vehicle speed [m/s].
    dt, n_steps
        Time step [s] and number of steps.
    front_axle_start
        Road distance of the front axle at t = 0 [m].
    beta, gamma, rho_inf
        Integration parameters (see :func:`bogie.steel.newmark.integrate_linear`).
    ground_stiffness_factor
        Ground springs' stiffness over the tyre stiffness [-].

    References
    ----------
    N. M. Newmark, "A method of computation for structural dynamics", Journal of the Engineering Mechanics
    Division, ASCE, 85(EM3), 1959.
    J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
    dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
    """
    mats = matrices(bogie, ground_stiffness_factor)
    t = np.arange(int(n_steps) + 1) * float(dt)
    heights = axle_heights(profile, bogie.axle_x, speed, t, front_axle_start)
    rates = np.gradient(heights, t, axis=0) if len(t) > 1 else np.zeros_like(heights)
    loads = _loads(bogie, mats, heights, rates)
    # start at rest in equilibrium with the road under the wheels at t = 0
    u0 = numerics.solve(mats.K, loads[0])  # at rest: no damping force
    v0 = np.zeros_like(u0)
    a0 = consistent_acceleration(mats.M, numerics.matmul(mats.K, u0) - loads[0])
    u, v, _ = linear_steps(mats.M, mats.C, mats.K, loads, u0, v0, a0, dt, n_steps, beta, gamma, rho_inf)
    wheel = wheel_loads_from_state(bogie, mats, u, v, rates)
    return DynamicResult(
        t=t,
        wheel_loads=wheel,
        reference_load=float(np.mean(wheel[0])),
        status="ok",
        message="ok",
        extras=_histories(bogie, mats, u, heights),
    )


def _loads(
    bogie: Bogie, mats: LinearMatrices, heights: NDArray[np.float64], rates: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Load history R(t) [N, N m] of the king pin rise and the road heights [m] and rates [m/s] under the axles."""
    return (
        (mats.kingpin * bogie.kingpin_height_offset)[None, :]
        + numerics.matmul(heights, mats.road_stiffness.T)
        + numerics.matmul(rates, mats.road_damping.T)
    )


def _histories(
    bogie: Bogie, mats: LinearMatrices, u: NDArray[np.float64], heights: NDArray[np.float64]
) -> dict[str, NDArray[np.float64]]:
    """The named histories of a linear run, for :attr:`~bogie.results.DynamicResult.extras`.

    Chassis pitch [rad], bogie centre displacement from the unloaded position [m], each equaliser's rotation
    relative to the chassis [rad] and the road height under each axle [m].
    """
    n = bogie.n_axles
    centre = bogie.equaliser_pivot_x[(n - 2) // 2]
    return {
        "chassis_pitch": u[:, 0],
        # from the unloaded position, as the reference's Figure 5
        "centre_displacement": bogie.kingpin_height_offset - centre * u[:, 0] - design_deflection(bogie, mats),
        **{f"equaliser_rotation_{j}": u[:, 1 + j] - u[:, 0] for j in range(n - 1)},
        **{f"road_height_{i}": heights[:, i] for i in range(n)},
    }
