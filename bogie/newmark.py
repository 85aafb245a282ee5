"""Time integration: Newmark (beta, gamma) and generalised-alpha with Newton-Raphson iterations.

One compiled kernel, :func:`_integrate`, steps every model of the project. It solves

    M a + f(u, v, t, history) = 0

where ``f`` holds the internal (elastic, damping, contact, friction) forces less the external ones, and is given
by the model named by an integer id (:data:`MODEL_LINEAR`, :data:`MODEL_NONLINEAR`) together with its tangents
K_T = df/du and C_T = df/dv. Each step is solved by Newton-Raphson on the full residual with the consistent
tangent; a step that does not converge is retried as 2, 4, ... sub-steps; a step that still fails stops the run
with a status, the time and the residual, never with NaN. History variables (friction slips) are committed only
after a step has converged. Derivation and verification: ``docs/dynamics.md``.

Why a model id and not a function argument: numba cannot cache a compiled function that takes another compiled
function (or a closure) as an argument, and a fresh worker process must start in well under a second.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from bogie import _nonlinear_core as nlc

MODEL_LINEAR = 0
MODEL_NONLINEAR = 1

STATUS_OK = 0
STATUS_NO_CONVERGENCE = 1
STATUS_NOT_FINITE = 2
STATUS_SINGULAR = 3
STATUS_OUT_OF_RANGE = 4

_STATUS_TEXT = {
    STATUS_OK: "ok",
    STATUS_NO_CONVERGENCE: "Newton iterations did not converge",
    STATUS_NOT_FINITE: "non-finite state",
    STATUS_SINGULAR: "singular iteration matrix",
    STATUS_OUT_OF_RANGE: "the solution left the model's range of validity (see the freedoms' limits)",
}


# ---- small dense linear algebra (numba) ------------------------------------------------------------------------
@njit(cache=True)
def lu_factor(a, piv):
    """LU factorisation with partial pivoting, in place. Returns False if a pivot is zero."""
    n = a.shape[0]
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        piv[k] = p
        if big == 0.0 or not math.isfinite(big):
            return False
        if p != k:
            for j in range(n):
                tmp = a[k, j]
                a[k, j] = a[p, j]
                a[p, j] = tmp
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            a[i, k] *= inv
            lik = a[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= lik * a[k, j]
    return True


@njit(cache=True)
def lu_solve(lu, piv, b):
    """Solve with the factors of :func:`lu_factor`; ``b`` is overwritten with the solution."""
    n = lu.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= lu[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= lu[i, j] * b[j]
        b[i] = s / lu[i, i]


# ---- model forces ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _linear_force(u, v, drv, data_f, data_i, f, kt, ct, want_tangent):
    """f = C v + K u - R(t); data_f = [K.ravel(), C.ravel()], the drive row is R(t). The tangents are K and C."""
    n = u.shape[0]
    for i in range(n):
        s = -drv[i]
        for j in range(n):
            s += data_f[i * n + j] * u[j] + data_f[n * n + i * n + j] * v[j]
        f[i] = s
    if want_tangent:
        for i in range(n):
            for j in range(n):
                kt[i, j] = data_f[i * n + j]
                ct[i, j] = data_f[n * n + i * n + j]


@njit(cache=True)
def _force(model, u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work):
    if model == MODEL_LINEAR:
        _linear_force(u, v, drv, data_f, data_i, f, kt, ct, want_tangent)
    else:
        nlc.force(u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work)


# ---- the stepping kernel ---------------------------------------------------------------------------------------
@njit(cache=True)
def _attempt(
    model, mass, data_f, data_i, drv0, drv1, frac0, frac1, u, v, a, f_old, hist, dt,
    beta, gamma, alpha_m, alpha_f, r_tol, max_iter,
    u_new, v_new, a_new, f_new, hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_limit,
    quasi_static,
):  # fmt: skip
    """One step of size dt from (u, v, a) between drive fractions frac0 -> frac1. Returns (status, |r|, iters).

    Newton-Raphson on the full residual. The factored iteration matrix is kept from step to step
    (``jac_state`` = [valid, dt it was formed for]) while the residual falls at least fourfold per iteration; when
    it does not, or dt changed, the tangent is formed anew at the current iterate. Convergence is always judged
    on the full residual, so keeping the matrix changes the cost, never the answer's accuracy. Friction makes the
    residual piecewise smooth, and Newton can then cycle between stick and slip: when an update makes the residual
    grow, or leaves the freedoms' limits ``u_limit`` (beyond which the model has spurious equilibria, e.g. a
    chassis pitched 90 degrees on slack springs), it is halved (backtracking) before a new direction is taken.
    """
    n = u.shape[0]
    for k in range(drv.shape[0]):
        drv[k] = drv0[k] + frac1 * (drv1[k] - drv0[k])
    c_a = 1.0 / (beta * dt * dt)
    c_v = gamma / (beta * dt)
    # predictor: constant acceleration; a quasi-static path has no rates and starts from the last equilibrium
    for i in range(n):
        u_new[i] = u[i] if quasi_static else u[i] + dt * v[i] + 0.5 * dt * dt * a[i]
    rnorm = 0.0
    r_prev = 0.0
    want = not (jac_state[0] == 1.0 and jac_state[1] == dt)
    fresh = want
    backtracks = 0
    for it in range(max_iter + 1):
        for i in range(n):
            if quasi_static:
                a_new[i] = 0.0
                v_new[i] = 0.0
            else:
                a_new[i] = c_a * (u_new[i] - u[i] - dt * v[i]) - (0.5 / beta - 1.0) * a[i]
                v_new[i] = v[i] + dt * ((1.0 - gamma) * a[i] + gamma * a_new[i])
        _force(model, u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, True, want, work)
        rnorm = 0.0
        finite = True
        for i in range(n):
            s = (1.0 - alpha_f) * f_new[i] + alpha_f * f_old[i]
            for j in range(n):
                s += mass[i, j] * ((1.0 - alpha_m) * a_new[j] + alpha_m * a[j])
            res[i] = -s
            if not math.isfinite(s):
                finite = False
            r = abs(s) / r_tol[i]
            if r > rnorm:
                rnorm = r
        if not finite:
            return STATUS_NOT_FINITE, rnorm, it
        if rnorm <= 1.0 and it > 0:
            if it > 2:
                jac_state[0] = 0.0
            return STATUS_OK, rnorm, it
        if it == max_iter:
            break
        if it > 0 and rnorm > r_prev and backtracks < 6:
            # the last update overshot: go back half of it and look again
            backtracks += 1
            for i in range(n):
                du[i] *= 0.5
                u_new[i] -= du[i]
            continue
        backtracks = 0
        if it > 0 and not fresh and rnorm > 0.25 * r_prev:
            # slow contraction with a stale matrix: form the tangent at this iterate and solve again
            _force(model, u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, False, True, work)
            want = True
        if want:
            for i in range(n):
                for j in range(n):
                    jac[i, j] = (1.0 - alpha_m) * c_a * mass[i, j] + (1.0 - alpha_f) * (kt[i, j] + c_v * ct[i, j])
            jac_state[0] = 0.0
            if not lu_factor(jac, piv):
                return STATUS_SINGULAR, rnorm, it
            jac_state[0] = 1.0
            jac_state[1] = dt
            want = False
            fresh = True
        r_prev = rnorm
        lu_solve(jac, piv, res)
        for i in range(n):
            du[i] = res[i]
            u_new[i] += res[i]
        for _ in range(30):
            inside = True
            for i in range(n):
                if abs(u_new[i]) > u_limit[i]:
                    inside = False
            if inside:
                break
            for i in range(n):
                du[i] *= 0.5
                u_new[i] -= du[i]
        else:
            return STATUS_OUT_OF_RANGE, rnorm, it
    return STATUS_NO_CONVERGENCE, rnorm, max_iter


@njit(cache=True)
def _integrate(
    model, mass, drive, data_f, data_i, u0, v0, a0, hist0, dt, n_steps,
    beta, gamma, alpha_m, alpha_f, r_tol, max_iter, max_halvings, n_rec, work_size, u_limit, quasi_static,
):  # fmt: skip
    n = u0.shape[0]
    n_hist = hist0.shape[0]
    uu = np.zeros((n_steps + 1, n))
    vv = np.zeros((n_steps + 1, n))
    aa = np.zeros((n_steps + 1, n))
    rr = np.zeros((n_steps + 1, n_rec))
    u = u0.copy()
    v = v0.copy()
    a = a0.copy()
    hist = hist0.copy()
    f_old = np.zeros(n)
    kt = np.zeros((n, n))
    ct = np.zeros((n, n))
    jac = np.zeros((n, n))
    piv = np.zeros(n, dtype=np.int64)
    res = np.zeros(n)
    rec = np.zeros(n_rec)
    hist_new = hist0.copy()
    drv = drive[0].copy()
    work = np.zeros(work_size)
    jac_state = np.zeros(2)
    du = np.zeros(n)
    _force(model, u, v, drv, data_f, data_i, hist, hist_new, f_old, kt, ct, rec, True, False, work)
    uu[0] = u
    vv[0] = v
    aa[0] = a
    rr[0] = rec
    u_new = np.zeros(n)
    v_new = np.zeros(n)
    a_new = np.zeros(n)
    f_new = np.zeros(n)
    # state saved at the start of a step, to retry it in sub-steps
    u_s = np.zeros(n)
    v_s = np.zeros(n)
    a_s = np.zeros(n)
    f_s = np.zeros(n)
    h_s = np.zeros(n_hist)
    total_iter = 0
    for step in range(n_steps):
        d0 = drive[step]
        d1 = drive[step + 1]
        # _attempt writes only the *_new arrays, so a failed try leaves the step's starting state untouched
        status, rnorm, iters = _attempt(
            model, mass, data_f, data_i, d0, d1, 0.0, 1.0, u, v, a, f_old, hist, dt,
            beta, gamma, alpha_m, alpha_f, r_tol, max_iter,
            u_new, v_new, a_new, f_new, hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du,
            u_limit, quasi_static,
        )  # fmt: skip
        total_iter += iters
        if status == STATUS_OK:
            u[:] = u_new
            v[:] = v_new
            a[:] = a_new
            f_old[:] = f_new
            hist[:] = hist_new
        else:
            # retry as 2, 4, ... sub-steps from the saved starting state
            jac_state[0] = 0.0
            u_s[:] = u
            v_s[:] = v
            a_s[:] = a
            f_s[:] = f_old
            h_s[:] = hist
            for level in range(1, max_halvings + 1):
                n_sub = 1 << level
                h = dt / n_sub
                u[:] = u_s
                v[:] = v_s
                a[:] = a_s
                f_old[:] = f_s
                hist[:] = h_s
                for sub in range(n_sub):
                    status, rnorm, iters = _attempt(
                        model, mass, data_f, data_i, d0, d1, sub / n_sub, (sub + 1) / n_sub, u, v, a, f_old, hist,
                        h, beta, gamma, alpha_m, alpha_f, r_tol, max_iter,
                        u_new, v_new, a_new, f_new, hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du,
                        u_limit, quasi_static,
                    )  # fmt: skip
                    total_iter += iters
                    if status != STATUS_OK:
                        jac_state[0] = 0.0
                        break
                    u[:] = u_new
                    v[:] = v_new
                    a[:] = a_new
                    f_old[:] = f_new
                    hist[:] = hist_new
                if status == STATUS_OK:
                    break
            if status != STATUS_OK:
                return uu, vv, aa, rr, hist, status, step, rnorm, total_iter
        # commit: the last residual evaluation recorded the model's outputs at the converged state
        uu[step + 1] = u
        vv[step + 1] = v
        aa[step + 1] = a
        rr[step + 1] = rec
    return uu, vv, aa, rr, hist, STATUS_OK, n_steps, 0.0, total_iter


@njit(cache=True)
def _integrate_linear_kernel(mass, damping, stiffness, loads, u0, v0, a0, dt, n_steps, beta, gamma, alpha_m, alpha_f):
    """Newmark / generalised-alpha for M a + C v + K u = R with constant matrices.

    The same scheme and residual as :func:`_integrate`, but a linear residual is solved exactly by one correction
    from the predictor with the iteration matrix factored once, so no Newton loop, convergence test or state
    saving is needed. Returns (u, v, a, status): status is STATUS_SINGULAR if the iteration matrix is singular.
    """
    n = u0.shape[0]
    uu = np.zeros((n_steps + 1, n))
    vv = np.zeros((n_steps + 1, n))
    aa = np.zeros((n_steps + 1, n))
    uu[0] = u0
    vv[0] = v0
    aa[0] = a0
    c_a = 1.0 / (beta * dt * dt)
    c_v = gamma / (beta * dt)
    jac = (1.0 - alpha_m) * c_a * mass + (1.0 - alpha_f) * (stiffness + c_v * damping)
    piv = np.zeros(n, dtype=np.int64)
    if not lu_factor(jac, piv):
        return uu, vv, aa, STATUS_SINGULAR
    u = u0.copy()
    v = v0.copy()
    a = a0.copy()
    f_old = stiffness @ u + damping @ v - loads[0]
    u_new = np.zeros(n)
    v_new = np.zeros(n)
    a_new = np.zeros(n)
    res = np.zeros(n)
    for step in range(n_steps):
        r_new = loads[step + 1]
        for i in range(n):
            u_new[i] = u[i] + dt * v[i] + 0.5 * dt * dt * a[i]
        for i in range(n):
            a_new[i] = c_a * (u_new[i] - u[i] - dt * v[i]) - (0.5 / beta - 1.0) * a[i]
            v_new[i] = v[i] + dt * ((1.0 - gamma) * a[i] + gamma * a_new[i])
        for i in range(n):
            s = alpha_f * f_old[i] - (1.0 - alpha_f) * r_new[i]
            for j in range(n):
                s += (1.0 - alpha_f) * (stiffness[i, j] * u_new[j] + damping[i, j] * v_new[j])
                s += mass[i, j] * ((1.0 - alpha_m) * a_new[j] + alpha_m * a[j])
            res[i] = -s
        lu_solve(jac, piv, res)
        for i in range(n):
            u_new[i] += res[i]
            a_new[i] += c_a * res[i]
            v_new[i] += c_v * res[i]
        for i in range(n):
            s = -r_new[i]
            for j in range(n):
                s += stiffness[i, j] * u_new[j] + damping[i, j] * v_new[j]
            f_old[i] = s
        u[:] = u_new
        v[:] = v_new
        a[:] = a_new
        uu[step + 1] = u
        vv[step + 1] = v
        aa[step + 1] = a
    return uu, vv, aa, STATUS_OK


# ---- Python layer ----------------------------------------------------------------------------------------------
def generalized_alpha(rho_inf: float) -> tuple[float, float, float, float]:
    """Chung-Hulbert generalised-alpha parameters (alpha_m, alpha_f, beta, gamma) for spectral radius rho_inf.

    rho_inf = 1 gives average-acceleration Newmark (no numerical damping); smaller values damp the highest
    frequencies to rho_inf per step while keeping second-order accuracy.
    """
    if not 0.0 <= rho_inf <= 1.0:
        raise ValueError(f"rho_inf = {rho_inf!r} is out of range: must be in [0, 1] (spectral radius, dimensionless)")
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


def _check_positive(name: str, value: float, unit: str) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} = {value!r} is out of range: must be > 0 {unit}")


def newmark_parameters(beta: float, gamma: float, rho_inf: float | None) -> tuple[float, float, float, float]:
    """(alpha_m, alpha_f, beta, gamma) for plain Newmark, or generalised-alpha when ``rho_inf`` is given."""
    if rho_inf is not None:
        return generalized_alpha(rho_inf)
    if not (0.0 < beta <= 0.5):
        raise ValueError(f"beta = {beta!r} is out of range: must be in (0, 0.5] (Newmark parameter, dimensionless)")
    if not (0.5 <= gamma <= 1.0):
        raise ValueError(f"gamma = {gamma!r} is out of range: must be in [0.5, 1] (Newmark parameter, dimensionless)")
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
    _check_positive("dt", dt, "s")
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
    if status == STATUS_OK:
        message = "ok"
        keep = n_steps + 1
    else:
        keep = last + 1
        message = (
            f"{_STATUS_TEXT[status]} at t = {t[last]:.6g} s (step {last + 1} of {n_steps}, after {max_halvings} "
            f"halvings of dt = {dt:g} s); scaled residual {rnorm:.3g} (1 = tolerance)"
        )
    return IntegrationResult(
        t=t[:keep],
        u=uu[:keep],
        v=vv[:keep],
        a=aa[:keep],
        record=rr[:keep],
        history=hist,
        status=int(status),
        message=message,
        n_iterations=int(iters),
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
        a0[m] = np.linalg.solve(mass[np.ix_(m, m)], -force[m])
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
    dt
        Time step [s].
    n_steps
        Number of steps.
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
    """
    mass = _square("M", M, None)
    n = mass.shape[0]
    damping = _square("C", C, n)
    stiffness = _square("K", K, n)
    _check_positive("dt", dt, "s")
    t = np.arange(int(n_steps) + 1) * float(dt)
    loads = _load_history(R, t, n)
    u_init = np.array(u0, dtype=float).reshape(n)
    v_init = np.array(v0, dtype=float).reshape(n)
    f0 = stiffness @ u_init + damping @ v_init - loads[0]
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
            f"integrate_linear failed: {_STATUS_TEXT[status]} at t = 0 s (M / (beta dt^2) + C gamma / (beta dt) + K "
            "is singular)"
        )
    return uu, vv, aa
