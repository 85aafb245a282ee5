"""Stage 2: the algebraic linear static model of a mechanically equalised bogie.

Two forms, both derived in ``docs/static-model.md``:

* :func:`nondimensional_loads`, the reference's Equation 1 generalised to n axles,
  (I + q L) W = 1 + d (c - l), with L the tridiagonal "path" matrix, c = (n - 1) / 2 and l the axle index;
* :func:`wheel_loads`, the same equilibrium written with the real geometry of a :class:`~bogie.params.Bogie`
  (unequal arms and spring halves, any axle count, per-axle tyre wear), small angles, linear springs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.params import GRAVITY, Bogie
from bogie.settings import check_value, refusal


@lru_cache(maxsize=16)
def _path_laplacian_eig(n_axles: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Eigenvalues (ascending) and orthonormal eigenvectors (columns) of the path graph's Laplacian L, in closed form:
    lambda_k = 2 - 2 cos(k pi / n), v_k(l) = c_k cos(k pi (l + 1/2) / n), c_0 = sqrt(1 / n), c_k = sqrt(2 / n) (the
    DCT-II basis, Strang 1999). LAPACK's eigensolver would give the same to rounding, in bits that depend on the BLAS
    kernel OpenBLAS picks for the CPU (``bogie/numerics.py``)."""
    k = np.arange(n_axles, dtype=float)
    lam = 2.0 - 2.0 * numerics.cos(k * math.pi / n_axles)
    lam[0] = 0.0
    vec = numerics.cos(np.outer(np.arange(n_axles) + 0.5, k) * (math.pi / n_axles)) * math.sqrt(2.0 / n_axles)
    vec[:, 0] = math.sqrt(1.0 / n_axles)
    lam.setflags(write=False)
    vec.setflags(write=False)
    return lam, vec


def nondimensional_loads(q: ArrayLike, d: ArrayLike, n_axles: int = 3) -> NDArray[np.float64]:
    """Non-dimensional wheel loads W_l / (alpha K_S) of the reference's Equation 1, for any n >= 2.

    Solves (I + q L) W = r with L the n x n matrix with 1, 2, ..., 2, 1 on its diagonal and -1 beside it, and
    r_l = 1 + d ((n - 1) / 2 - l). For n = 3 this is Equation 1 exactly: r = (1 + d, 1, 1 - d).

    Parameters
    ----------
    q
        Stiffness ratio q = b^2 K_S / (4 K_B) [-], >= 0; ``inf`` is a free bush. Broadcasts against ``d``.
    d
        Generalised chassis rotation d = -psi s / alpha [-] (psi nose-up positive, s the axle spacing); the
        reference writes d = (psi / alpha)(2a + 3b/2) with its own sign. d > 0 loads the front axle.
    n_axles
        Number of axles n [-], >= 2.

    Returns
    -------
    ndarray of shape ``broadcast(q, d).shape + (n_axles,)``; the loads sum to n for every q and d.

    References
    ----------
    ETA Engineering Consultants for TRRL, Axle load equalisation in mechanical trailer suspensions, Equation 1.
    """
    if int(n_axles) != n_axles or n_axles < 2:
        raise ValueError(f"n_axles = {n_axles!r} must be an integer >= 2 (axles in the group)")
    q_arr = np.asarray(q, dtype=float)
    d_arr = np.asarray(d, dtype=float)
    bad_q = q_arr[np.isnan(q_arr) | (q_arr < 0.0)]
    if bad_q.size:
        note = "stiffness ratio b^2 K_S / 4 K_B; inf: a free bush"
        raise ValueError(refusal("q", float(bad_q.flat[0]), "-", low=0.0, note=note))
    bad_d = d_arr[~np.isfinite(d_arr)]
    if bad_d.size:
        raise ValueError(f"d = {float(bad_d.flat[0])!r} must be finite (generalised chassis rotation, dimensionless)")
    q_arr, d_arr = np.broadcast_arrays(q_arr, d_arr)
    lam, vec = _path_laplacian_eig(int(n_axles))
    offsets = 0.5 * (n_axles - 1) - np.arange(n_axles)
    rhs = 1.0 + d_arr[..., None] * offsets
    modal = numerics.matmul(rhs, vec)
    with np.errstate(invalid="ignore"):
        gain = 1.0 / (1.0 + q_arr[..., None] * lam)
    gain = np.where(lam == 0.0, 1.0, gain)
    return numerics.matmul(modal * gain, vec.T)


@dataclass(frozen=True)
class StaticSolution:
    """Result of :func:`solve_static`.

    Attributes
    ----------
    wheel_loads
        Load on each axle's tyres [N], front to rear.
    equaliser_rotation
        Rotation of each equaliser relative to the chassis, rear tip down positive [rad].
    """

    wheel_loads: NDArray[np.float64]
    equaliser_rotation: NDArray[np.float64]


def _end_shares(bogie: Bogie) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    a_f = np.asarray(bogie.spring_front_half_length)
    a_r = np.asarray(bogie.spring_rear_half_length)
    return a_r / (a_f + a_r), a_f / (a_f + a_r)


def coupling_matrix(bogie: Bogie) -> NDArray[np.float64]:
    """Matrix B [m] with (B phi)_l the change of spring l's mean end deflection from equaliser rotations phi.

    B[j, j] = -b_f,j c_r,j (spring j's rear end on equaliser j's front tip, which rises as phi_j > 0) and
    B[j + 1, j] = b_r,j c_f,j+1 (spring j + 1's front end on the rear tip). Its transpose maps spring loads to
    the moments they put on the equalisers: M_j = -(B^T W)_j.
    """
    n = bogie.n_axles
    c_f, c_r = _end_shares(bogie)
    coupling = np.zeros((n, n - 1))
    for j in range(n - 1):
        coupling[j, j] = -bogie.equaliser_front_arm[j] * c_r[j]
        coupling[j + 1, j] = bogie.equaliser_rear_arm[j] * c_f[j + 1]
    return coupling


def solve_static(
    bogie: Bogie,
    chassis_deflection: float,
    chassis_rotation: float,
    tyre_wear: ArrayLike | None = None,
) -> StaticSolution:
    """Wheel loads of the linear static model with the bogie's real geometry.

    Each spring-and-tyre pair is a linear spring K_S (1/K_S = 1/K_T + 1/K_R) loaded by the mean of its end
    deflections, weighted by the lever rule, less the tyre wear; each equaliser balances the moments of its two
    spring-end loads against its bush: b_f c_r W_j - b_r c_f W_{j+1} = K_B phi_j. Small angles throughout.

    Parameters
    ----------
    bogie
        The bogie; its geometry, ``road_spring_stiffness``, ``tyre_stiffness`` and ``bush_stiffness`` are used.
    chassis_deflection
        Downward displacement alpha of the chassis at the bogie centre from the unloaded position [m].
    chassis_rotation
        Chassis pitch psi, nose up positive (rear of the bogie lower) [rad].
    tyre_wear
        Loss of tyre radius per axle [m]; defaults to ``bogie.tyre_wear``.

    Returns
    -------
    StaticSolution
        ``wheel_loads`` [N] and ``equaliser_rotation`` [rad]. Loads may come out negative where the linear model
        is pushed beyond lift-off; no unilateral contact is modelled here.
    """
    wear = np.asarray(bogie.tyre_wear if tyre_wear is None else tyre_wear, dtype=float)
    n = bogie.n_axles
    if wear.shape != (n,):
        raise ValueError(f"tyre_wear has shape {wear.shape} but the bogie has {n} axles: give one value per axle in m")
    for name, value in (("chassis_deflection", chassis_deflection), ("chassis_rotation", chassis_rotation)):
        if not np.isfinite(value):
            raise ValueError(f"{name} = {value!r} must be finite ({'m' if name == 'chassis_deflection' else 'rad'})")
    c_f, c_r = _end_shares(bogie)
    x = np.asarray(bogie.axle_x)
    x_front = x - np.asarray(bogie.spring_front_half_length)
    x_rear = x + np.asarray(bogie.spring_rear_half_length)
    x_c = bogie.bogie_centre_x

    def chassis(xx: NDArray[np.float64]) -> NDArray[np.float64]:
        return chassis_deflection + chassis_rotation * (xx - x_c)

    g = c_f * chassis(x_front) + c_r * chassis(x_rear) - wear
    coupling = coupling_matrix(bogie)
    k_s = bogie.combined_stiffness
    lhs = bogie.bush_stiffness * np.eye(n - 1) + k_s * numerics.matmul(coupling.T, coupling)
    phi = numerics.solve(lhs, -k_s * numerics.matmul(coupling.T, g))
    loads = k_s * (g + numerics.matmul(coupling, phi))
    return StaticSolution(wheel_loads=loads, equaliser_rotation=phi)


def wheel_loads(
    bogie: Bogie, chassis_deflection: float, chassis_rotation: float, tyre_wear: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Wheel loads [N] of :func:`solve_static`, front to rear."""
    return solve_static(bogie, chassis_deflection, chassis_rotation, tyre_wear).wheel_loads


def equation1_mapping(bogie: Bogie, chassis_deflection: float, chassis_rotation: float) -> tuple[float, float]:
    """The (q, d) of Equation 1 for a bogie with equal arms, symmetric springs and equal axle spacing [-].

    q = b^2 K_S / (4 K_B) and d = -psi s / alpha, s the axle spacing; then
    ``wheel_loads(bogie, alpha, psi) / (alpha K_S) == nondimensional_loads(q, d, n)``.
    """
    spacing = np.diff(bogie.axle_x)
    arms = np.concatenate([bogie.equaliser_front_arm, bogie.equaliser_rear_arm])
    halves = np.concatenate([bogie.spring_front_half_length, bogie.spring_rear_half_length])
    if np.ptp(spacing) > 1e-9 or np.ptp(arms) > 1e-9 or np.ptp(halves) > 1e-9:
        raise ValueError(
            "equation1_mapping needs equal axle spacing, equal equaliser arms and symmetric springs; this bogie "
            "has unequal ones: use wheel_loads for its real geometry"
        )
    if chassis_deflection == 0.0:
        raise ValueError("chassis_deflection = 0.0 m: Equation 1 is scaled by alpha, which must be non-zero")
    return bogie.q(0), -chassis_rotation * float(spacing[0]) / chassis_deflection


def tilted_axle_loads(bogie: Bogie, chassis_tilt: float | None = None) -> NDArray[np.float64]:
    """Static tyre loads [N] of each axle of one side, front to rear, with the chassis tilted by ``chassis_tilt``.

    The linear static model (:func:`solve_static`, the bogie's real geometry and wear, small angles) with the chassis
    pitched by the tilt about the bogie centre and lowered until the springs carry the sprung weight's share that
    the moments about the king pin give, ``sum_i W_i x_i = m g x_cg`` (as :func:`bogie.params.design_spring_loads`
    does for the level design position); each tyre carries its spring's load and the axle's weight. The springs'
    loads are linear in the chassis deflection, so two solves give it exactly. Friction, bump stops and the
    non-linear geometry are left out (:func:`bogie.steel.nonlinear.equilibrium` has them); level, unworn and with a
    moment-free bush these are the design loads (:func:`bogie.steel.force.pack.design_wheel_loads`).

    Parameters
    ----------
    bogie
        The bogie: its geometry, stiffnesses, tyre wear, payload and axle masses.
    chassis_tilt
        Pitch of the chassis, nose up positive (king pin raised) [rad]; ``bogie.chassis_tilt`` if None.

    Returns
    -------
    numpy.ndarray
        One load per axle [N]; they sum to the sprung weight on the bogie plus the axles' weight.
    """
    tilt = bogie.chassis_tilt if chassis_tilt is None else float(chassis_tilt)
    check_value("chassis_tilt", tilt, "rad", low=-math.pi / 2, high=math.pi / 2, low_open=True, high_open=True)
    x = np.asarray(bogie.axle_x)
    per_deflection = wheel_loads(bogie, 1.0, 0.0, np.zeros(bogie.n_axles))  # [N/m]
    tilted = wheel_loads(bogie, 0.0, tilt)  # the tilt and the wear at zero deflection [N]
    moment = bogie.payload_mass * GRAVITY * bogie.payload_cg_x  # about the king pin [N m]
    deflection = (moment - math.fsum(tilted * x)) / math.fsum(per_deflection * x)  # sums without BLAS
    return tilted + deflection * per_deflection + bogie.axle_mass * GRAVITY
