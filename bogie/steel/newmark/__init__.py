"""Time integration: Newmark (beta, gamma) and generalised-alpha with Newton-Raphson iterations.

One compiled kernel (:func:`bogie.steel.newmark.kernels._integrate`, called by :func:`integrate`) steps every model of
the project. It solves

    M a + f(u, v, t, history) = 0

where ``f`` holds the internal (elastic, damping, contact, friction) forces less the external ones, and is given
by the model named by an integer id (:data:`MODEL_LINEAR`, :data:`MODEL_NONLINEAR`) together with its tangents
K_T = df/du and C_T = df/dv. Each step is solved by Newton-Raphson on the full residual with the consistent
tangent; a step that does not converge is retried as 2, 4, ... sub-steps; a step that still fails stops the run
with a status, the time and the residual, never with NaN. History variables (friction slips) are committed only
after a step has converged. Linear systems with constant matrices (:func:`integrate_linear`,
:func:`linear_steps`) use a loop that needs one correction per step. This module is the Python layer (checks,
parameters, results); the compiled loops are in :mod:`bogie.steel.newmark.kernels`, the LU factors in :mod:`bogie.lu`.
Derivation and verification: ``docs/dynamics.md``.

References
----------
.. [1] N. M. Newmark, "A method of computation for structural dynamics", Journal of the Engineering Mechanics
   Division, ASCE, 85(EM3), 1959.
.. [2] J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
   dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.lu import lu_factor, lu_solve
from bogie.ranges import check_positive
from bogie.settings import check_value
from bogie.steel.newmark.kernels import (
    MODEL_LINEAR,
    MODEL_NONLINEAR,
    STATUS_NO_CONVERGENCE,
    STATUS_NOT_FINITE,
    STATUS_OK,
    STATUS_OUT_OF_RANGE,
    STATUS_SINGULAR,
    _integrate,
    _integrate_linear_kernel,
)

#: re-exported: the compiled LU factors (now in :mod:`bogie.lu`) and the model ids and statuses of the kernel
__all__ = [
    "MODEL_LINEAR",
    "MODEL_NONLINEAR",
    "STATUS_NO_CONVERGENCE",
    "STATUS_NOT_FINITE",
    "STATUS_OK",
    "STATUS_OUT_OF_RANGE",
    "STATUS_SINGULAR",
    "IntegrationResult",
    "consistent_acceleration",
    "generalized_alpha",
    "integrate",
    "integrate_linear",
    "linear_steps",
    "lu_factor",
    "lu_solve",
    "massless_dofs",
    "newmark_parameters",
]

STATUS_TEXT = {
    STATUS_OK: "ok",
    STATUS_NO_CONVERGENCE: "Newton iterations did not converge",
    STATUS_NOT_FINITE: "non-finite state",
    STATUS_SINGULAR: "singular iteration matrix",
    STATUS_OUT_OF_RANGE: "the solution left the model's range of validity (see the freedoms' limits)",
}


# ---- Python layer ----------------------------------------------------------------------------------------------
def generalized_alpha(rho_inf: float) -> tuple[float, float, float, float]:
    """Chung-Hulbert generalised-alpha parameters (alpha_m, alpha_f, beta, gamma) for spectral radius rho_inf.

    rho_inf = 1 gives average-acceleration Newmark (no numerical damping); smaller values damp the highest
    frequencies to rho_inf per step while keeping second-order accuracy.

    References
    ----------
    J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
    dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
    """
    check_value("rho_inf", rho_inf, "-", low=0.0, high=1.0, note="spectral radius")
    alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    alpha_f = rho_inf / (rho_inf + 1.0)
    gamma = 0.5 - alpha_m + alpha_f
    beta = 0.25 * (1.0 - alpha_m + alpha_f) ** 2
    return alpha_m, alpha_f, beta, gamma


@dataclass(frozen=True)
class IntegrationResult:
    """Time histories of one integration.

    Attributes
    ----------
    t
        Times [s], shape (n_t,).
    u, v, a
        Displacements, velocities and accelerations, shape (n_t, n_dof), in the units of the model's freedoms.
    record
        Model outputs recorded after each converged step, shape (n_t, n_record).
    history
        History variables after the last converged step.
    status
        0 if every step converged; otherwise the run stopped at ``t[-1]`` (see ``message``).
    message
        "ok", or why and where the run stopped, with the residual.
    n_iterations
        Newton iterations over the whole run.
    """

    t: NDArray[np.float64]
    u: NDArray[np.float64]
    v: NDArray[np.float64]
    a: NDArray[np.float64]
    record: NDArray[np.float64]
    history: NDArray[np.float64]
    status: int
    message: str
    n_iterations: int

    @property
    def success(self) -> bool:
        """True if every step converged."""
        return self.status == STATUS_OK


def newmark_parameters(beta: float, gamma: float, rho_inf: float | None) -> tuple[float, float, float, float]:
    """(alpha_m, alpha_f, beta, gamma) for plain Newmark, or generalised-alpha when ``rho_inf`` is given."""
    if rho_inf is not None:
        return generalized_alpha(rho_inf)
    check_value("beta", beta, "-", low=0.0, low_open=True, high=0.5, note="Newmark parameter")
    check_value("gamma", gamma, "-", low=0.5, high=1.0, note="Newmark parameter")
    return 0.0, 0.0, beta, gamma


def integrate(
    model: int,
    mass: NDArray[np.float64],
    drive: NDArray[np.float64],
    data_f: NDArray[np.float64],
    data_i: NDArray[np.int64],
    u0: NDArray[np.float64],
    v0: NDArray[np.float64],
    a0: NDArray[np.float64],
    history0: NDArray[np.float64],
    dt: float,
    n_steps: int,
    residual_tolerance: NDArray[np.float64],
    beta: float = 0.25,
    gamma: float = 0.5,
    rho_inf: float | None = None,
    max_iter: int = 20,
    max_halvings: int = 4,
    n_record: int = 0,
    work_size: int = 0,
    limits: NDArray[np.float64] | None = None,
    quasi_static: bool = False,
) -> IntegrationResult:
    """Run the compiled kernel for a model; see the module docstring. Arrays must already be float64/int64.

    ``limits`` bounds each freedom's magnitude; a step whose solution would leave them fails with its own status.
    ``quasi_static`` solves each row as an equilibrium (no inertia or damping; pass a zero mass matrix): rates
    are zero and each step starts from the last equilibrium.
    """
    u_limit = np.full(u0.shape[0], np.inf) if limits is None else np.asarray(limits, dtype=float)
    check_positive("dt", dt, "s")
    if int(n_steps) != n_steps or n_steps < 1:
        raise ValueError(f"n_steps = {n_steps!r} must be an integer >= 1")
    if drive.shape[0] != n_steps + 1:
        raise ValueError(f"drive has {drive.shape[0]} rows but n_steps + 1 = {n_steps + 1} are needed")
    alpha_m, alpha_f, beta, gamma = newmark_parameters(beta, gamma, rho_inf)
    uu, vv, aa, rr, hist, status, last, rnorm, iters = _integrate(
        model, mass, drive, data_f, data_i, u0, v0, a0, history0, float(dt), int(n_steps),
        beta, gamma, alpha_m, alpha_f, residual_tolerance, int(max_iter), int(max_halvings), int(n_record),
        int(work_size), u_limit, bool(quasi_static),
    )  # fmt: skip
    t = np.arange(n_steps + 1) * dt
    keep = n_steps + 1 if status == STATUS_OK else last + 1
    return IntegrationResult(
        t=t[:keep],
        u=uu[:keep],
        v=vv[:keep],
        a=aa[:keep],
        record=rr[:keep],
        history=hist,
        status=int(status),
        message=_stop_message(status, t, last, n_steps, max_halvings, dt, rnorm),
        n_iterations=int(iters),
    )


def _stop_message(status: int, t: NDArray[np.float64], last: int, n_steps: int, max_halvings: int, dt: float,
                  rnorm: float) -> str:  # fmt: skip
    """ "ok", or why and where a run stopped, with the residual."""
    if status == STATUS_OK:
        return "ok"
    return (
        f"{STATUS_TEXT[status]} at t = {t[last]:.6g} s (step {last + 1} of {n_steps}, after {max_halvings} "
        f"halvings of dt = {dt:g} s); scaled residual {rnorm:.3g} (1 = tolerance)"
    )


def _load_history(
    r: ArrayLike | Callable[[float], ArrayLike], t: NDArray[np.float64], n_dof: int
) -> NDArray[np.float64]:
    if callable(r):
        out = np.array([np.asarray(r(ti), dtype=float) for ti in t], dtype=float)
    else:
        out = np.array(r, dtype=float)
    if out.ndim == 1 and n_dof == 1 and out.shape[0] == t.shape[0]:
        out = out[:, None]
    if out.shape != (t.shape[0], n_dof):
        raise ValueError(f"R has shape {out.shape} but (n_steps + 1, n_dof) = {(t.shape[0], n_dof)} is needed (N)")
    if not np.all(np.isfinite(out)):
        raise ValueError("R contains NaN or infinity: loads must be finite (N)")
    return out


def _square(name: str, m: ArrayLike, n: int | None) -> NDArray[np.float64]:
    arr = np.array(m, dtype=float)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or (n is not None and arr.shape[0] != n):
        raise ValueError(f"{name} has shape {arr.shape}: must be a square n_dof x n_dof matrix")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinity")
    return arr


def _system(M: ArrayLike, C: ArrayLike, K: ArrayLike) -> tuple[NDArray[np.float64], ...]:
    """Mass, damping and stiffness as checked float64 matrices of one order."""
    mass = _square("M", M, None)
    n = mass.shape[0]
    return mass, _square("C", C, n), _square("K", K, n)


def massless_dofs(mass: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Freedoms whose row and column of the mass matrix are zero."""
    return np.all(mass == 0.0, axis=0) & np.all(mass == 0.0, axis=1)


def consistent_acceleration(
    mass: NDArray[np.float64], force: NDArray[np.float64], massless: NDArray[np.bool_] | None = None
) -> NDArray[np.float64]:
    """Initial accelerations from M a = -f on the massive freedoms; zero on massless ones."""
    massless = massless_dofs(mass) if massless is None else massless
    a0 = np.zeros(mass.shape[0])
    m = ~massless
    if np.any(m):
        a0[m] = numerics.solve(mass[np.ix_(m, m)], -force[m])
    return a0


def integrate_linear(
    M: ArrayLike,
    C: ArrayLike,
    K: ArrayLike,
    R: ArrayLike | Callable[[float], ArrayLike],
    u0: ArrayLike,
    v0: ArrayLike,
    dt: float,
    n_steps: int,
    beta: float = 0.25,
    gamma: float = 0.5,
    rho_inf: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Integrate M a + C v + K u = R(t) with Newmark (or generalised-alpha when ``rho_inf`` is given).

    Parameters
    ----------
    M, C, K
        Mass, damping and stiffness matrices, n_dof x n_dof. M may be singular (massless freedoms): their
        equations are then algebraic (or first order, if damped) and are still solved at every step.
    R
        Loads, an array (n_steps + 1, n_dof) at t = k dt, or a callable of t [s] returning n_dof loads.
    u0, v0
        Initial displacements and velocities.
    dt, n_steps
        Time step [s] and number of steps.
    beta, gamma
        Newmark parameters; the default (1/4, 1/2) is the unconditionally stable average-acceleration rule.
    rho_inf
        If given, use Chung-Hulbert generalised-alpha with this high-frequency spectral radius in [0, 1]
        (beta and gamma are then derived from it).

    Returns
    -------
    u, v, a
        Arrays of shape (n_steps + 1, n_dof).

    Raises
    ------
    RuntimeError
        If a step cannot be solved (a singular iteration matrix: K + C/dt + M/dt^2 is singular).

    References
    ----------
    N. M. Newmark, "A method of computation for structural dynamics", Journal of the Engineering Mechanics
    Division, ASCE, 85(EM3), 1959.
    J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
    dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
    """
    mass, damping, stiffness = _system(M, C, K)
    n = mass.shape[0]
    check_positive("dt", dt, "s")
    t = np.arange(int(n_steps) + 1) * float(dt)
    loads = _load_history(R, t, n)
    u_init = np.array(u0, dtype=float).reshape(n)
    v_init = np.array(v0, dtype=float).reshape(n)
    f0 = numerics.matmul(stiffness, u_init) + numerics.matmul(damping, v_init) - loads[0]
    a_init = consistent_acceleration(mass, f0)
    return linear_steps(mass, damping, stiffness, loads, u_init, v_init, a_init, dt, n_steps, beta, gamma, rho_inf)


def linear_steps(
    mass: NDArray[np.float64],
    damping: NDArray[np.float64],
    stiffness: NDArray[np.float64],
    loads: NDArray[np.float64],
    u0: NDArray[np.float64],
    v0: NDArray[np.float64],
    a0: NDArray[np.float64],
    dt: float,
    n_steps: int,
    beta: float = 0.25,
    gamma: float = 0.5,
    rho_inf: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The compiled linear stepping loop on checked float64 arrays (loads of shape (n_steps + 1, n_dof)).

    Same scheme as the general kernel; a linear residual needs one correction per step, with the iteration matrix
    factored once (``tests/test_newmark.py`` checks that both give the same histories).
    """
    alpha_m, alpha_f, beta, gamma = newmark_parameters(beta, gamma, rho_inf)
    uu, vv, aa, status = _integrate_linear_kernel(
        mass, damping, stiffness, loads, u0, v0, a0, float(dt), int(n_steps), beta, gamma, alpha_m, alpha_f
    )
    if status != STATUS_OK:
        raise RuntimeError(
            f"integrate_linear failed: {STATUS_TEXT[status]} at t = 0 s (M / (beta dt^2) + C gamma / (beta dt) + K "
            "is singular)"
        )
    return uu, vv, aa
