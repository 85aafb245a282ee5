"""Compiled kernels of the time integrator :mod:`bogie.steel.newmark` (numba): the general Newton stepping loop
:func:`_integrate` for every model, and the one-correction loop :func:`_integrate_linear_kernel` for constant
matrices.

:func:`_integrate` solves M a + f(u, v, t, history) = 0 step by step with Newmark's (beta, gamma) rule [1]_ or
the generalised-alpha method [2]_: each step by Newton-Raphson on the full residual (:func:`_attempt`), a step that
fails retried as 2, 4, ... sub-steps (:func:`_substeps`). :func:`_integrate` allocates, :func:`_step_loop` steps;
the step's helpers and the model force are inlined into it, and the loop and the functions it calls are compiled
without numba's reference counting (``_nrt=False``; they make no array): the calls and the atomic reference counts
of their array arguments had cost as much as the arithmetic (issue 15, ``bench/README.md``). The model is named
by an integer id (:data:`MODEL_LINEAR`, :data:`MODEL_NONLINEAR`): numba cannot cache a compiled function that
takes another compiled function (or a closure) as an argument, and a fresh worker process must start in well under
a second.
Derivation and verification: ``docs/dynamics.md``.

References
----------
.. [1] N. M. Newmark, "A method of computation for structural dynamics", Journal of the Engineering Mechanics
   Division, ASCE, 85(EM3), 1959.
.. [2] J. Chung, G. M. Hulbert, "A time integration algorithm for structural dynamics with improved numerical
   dissipation: the generalized-alpha method", Journal of Applied Mechanics, 60, 1993.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bogie.lu import lu_factor, lu_solve
from bogie.steel.force import core as nlc

MODEL_LINEAR = 0
MODEL_NONLINEAR = 1

STATUS_OK = 0
STATUS_NO_CONVERGENCE = 1
STATUS_NOT_FINITE = 2
STATUS_SINGULAR = 3
STATUS_OUT_OF_RANGE = 4


# ---- model forces ----------------------------------------------------------------------------------------------
@njit(cache=True, _nrt=False)
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


@njit(cache=True, inline="always")
def _force(model, u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work):
    if model == MODEL_LINEAR:
        _linear_force(u, v, drv, data_f, data_i, f, kt, ct, want_tangent)
    else:
        nlc.force(u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work)


# ---- the stepping kernel ---------------------------------------------------------------------------------------
# The helpers of _attempt run once per Newton iteration; they are inlined (numba IR) so that splitting the
# iteration into named parts costs no calls and no reference counting of the arrays they share.
@njit(cache=True, inline="always")
def _predict(drive, row, frac1, u, v, a, dt, drv, u_new, quasi_static):
    """Drive at fraction ``frac1`` of the step from drive row ``row`` to the next, and the predictor of u: constant
    acceleration.

    A quasi-static path has no rates and starts from the last equilibrium.
    """
    for k in range(drv.shape[0]):
        d0 = drive[row, k]
        drv[k] = d0 + frac1 * (drive[row + 1, k] - d0)
    for i in range(u.shape[0]):
        u_new[i] = u[i] if quasi_static else u[i] + dt * v[i] + 0.5 * dt * dt * a[i]


@njit(cache=True, inline="always")
def kinematics(u, v, a, u_new, dt, beta, gamma, c_a, v_new, a_new, quasi_static):
    """Newmark: the accelerations and velocities that go with the displacements ``u_new`` at the step's end."""
    for i in range(u.shape[0]):
        if quasi_static:
            a_new[i] = 0.0
            v_new[i] = 0.0
        else:
            a_new[i] = c_a * (u_new[i] - u[i] - dt * v[i]) - (0.5 / beta - 1.0) * a[i]
            v_new[i] = v[i] + dt * ((1.0 - gamma) * a[i] + gamma * a_new[i])


@njit(cache=True, inline="always")
def _residual(mass, a, a_new, f_old, f_new, alpha_m, alpha_f, r_tol, res):
    """res = -(M a_(1-alpha_m) + f_(1-alpha_f)); returns (largest |residual| / tolerance, all finite)."""
    n = a.shape[0]
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
    return rnorm, finite


@njit(cache=True, inline="always")
def _factor_iteration_matrix(mass, kt, ct, c_a, c_v, alpha_m, alpha_f, dt, jac, piv, jac_state):
    """Form and factor (1 - alpha_m) c_a M + (1 - alpha_f)(K_T + c_v C_T); False if it is singular.

    ``jac_state`` = [valid, dt it was formed for] records a good factorisation for the next steps.
    """
    n = mass.shape[0]
    for i in range(n):
        for j in range(n):
            jac[i, j] = (1.0 - alpha_m) * c_a * mass[i, j] + (1.0 - alpha_f) * (kt[i, j] + c_v * ct[i, j])
    jac_state[0] = 0.0
    if not lu_factor(jac, piv):
        return False
    jac_state[0] = 1.0
    jac_state[1] = dt
    return True


@njit(cache=True, inline="always")
def halve(du, u_new):
    """Go back half of the last update."""
    for i in range(du.shape[0]):
        du[i] *= 0.5
        u_new[i] -= du[i]


@njit(cache=True, inline="always")
def pull_inside(du, u_new, u_limit):
    """After an update ``du`` to ``u_new``: halve it back until |u_new| is inside ``u_limit`` (30 times at most);
    False if never."""
    n = du.shape[0]
    for _ in range(30):
        inside = True
        for i in range(n):
            if abs(u_new[i]) > u_limit[i]:
                inside = False
        if inside:
            return True
        halve(du, u_new)
    return False


@njit(cache=True, inline="always")
def _update(jac, piv, res, du, u_new, u_limit):
    """Newton update u_new += J^-1 res, halved until inside ``u_limit`` (30 times at most); False if never."""
    lu_solve(jac, piv, res)
    n = du.shape[0]
    for i in range(n):
        du[i] = res[i]
        u_new[i] += res[i]
    return pull_inside(du, u_new, u_limit)


@njit(cache=True, inline="always")
def _attempt(
    model, mass, data_f, data_i, drive, row, frac1, u, v, a, f_old, hist, dt, scheme, r_tol, max_iter,
    trial, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_limit, quasi_static,
):  # fmt: skip
    """One step of size dt from (u, v, a) to fraction frac1 of the drive from row ``row`` to the next (the step
    starts where the last one ended). Returns (status, |r|, iters); ``trial`` = (u_new, v_new, a_new, f_new,
    hist_new) receives the state at its end, ``scheme`` = (beta, gamma, alpha_m, alpha_f).

    Inlined into its two callers (numba IR): as a call, its arrays' reference counting cost more than the step's
    own stepping arithmetic. The grouping into tuples keeps the call under 31 arguments, beyond which Python
    passes them as ``*args``, which numba cannot inline.

    Newton-Raphson on the full residual. The factored iteration matrix is kept from step to step
    (``jac_state`` = [valid, dt it was formed for]) while the residual falls at least fourfold per iteration; when
    it does not, or dt changed, the tangent is formed anew at the current iterate. Convergence is always judged
    on the full residual, so keeping the matrix changes the cost, never the answer's accuracy. Friction makes the
    residual piecewise smooth, and Newton can then cycle between stick and slip: when an update makes the residual
    grow, or leaves the freedoms' limits ``u_limit`` (beyond which the model has spurious equilibria, e.g. a
    chassis pitched 90 degrees on slack springs), it is halved (backtracking) before a new direction is taken.
    """
    # longer than 60 lines with its docstring (the code is 45): the iteration's branches (backtracking, a new
    # tangent, a kept matrix) share its scalars; split, they would be passed in and returned at every iteration
    beta, gamma, alpha_m, alpha_f = scheme
    u_new, v_new, a_new, f_new, hist_new = trial
    c_a = 1.0 / (beta * dt * dt)
    c_v = gamma / (beta * dt)
    _predict(drive, row, frac1, u, v, a, dt, drv, u_new, quasi_static)
    rnorm = 0.0
    r_prev = 0.0
    want = not (jac_state[0] == 1.0 and jac_state[1] == dt)
    fresh = want
    backtracks = 0
    for it in range(max_iter + 1):
        kinematics(u, v, a, u_new, dt, beta, gamma, c_a, v_new, a_new, quasi_static)
        _force(model, u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, True, want, work)
        rnorm, finite = _residual(mass, a, a_new, f_old, f_new, alpha_m, alpha_f, r_tol, res)
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
            halve(du, u_new)
            continue
        backtracks = 0
        if it > 0 and not fresh and rnorm > 0.25 * r_prev:
            # slow contraction with a stale matrix: form the tangent at this iterate and solve again
            _force(model, u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, False, True, work)
            want = True
        if want:
            if not _factor_iteration_matrix(mass, kt, ct, c_a, c_v, alpha_m, alpha_f, dt, jac, piv, jac_state):
                return STATUS_SINGULAR, rnorm, it
            want = False
            fresh = True
        r_prev = rnorm
        if not _update(jac, piv, res, du, u_new, u_limit):
            return STATUS_OUT_OF_RANGE, rnorm, it
        # the matrix now belongs to an earlier iterate: if the next residual falls slowly, form it anew there (a
        # tangent formed at a kink, e.g. a leaf spring's reversal, can be wrong by a factor of two, and modified
        # Newton with it stalls)
        fresh = False
    return STATUS_NO_CONVERGENCE, rnorm, max_iter


@njit(cache=True, inline="always")
def _copy_state(u, v, a, f, hist, u_from, v_from, a_from, f_from, hist_from):
    """(u, v, a, f, hist) = (u_from, v_from, a_from, f_from, hist_from), in place (loops: a slice copy makes views)."""
    for i in range(u.shape[0]):
        u[i] = u_from[i]
        v[i] = v_from[i]
        a[i] = a_from[i]
        f[i] = f_from[i]
    for i in range(hist.shape[0]):
        hist[i] = hist_from[i]


@njit(cache=True, inline="always")
def _record(uu, vv, aa, rr, row, u, v, a, rec):
    """Store the state and the model's record in row ``row`` of the histories (loops: ``uu[row] = u`` makes views)."""
    for i in range(u.shape[0]):
        uu[row, i] = u[i]
        vv[row, i] = v[i]
        aa[row, i] = a[i]
    for i in range(rec.shape[0]):
        rr[row, i] = rec[i]


@njit(cache=True, _nrt=False)
def _substeps(
    model, mass, data_f, data_i, drive, row, u, v, a, f_old, hist, dt,
    beta, gamma, alpha_m, alpha_f, r_tol, max_iter, max_halvings,
    u_new, v_new, a_new, f_new, hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_limit,
    quasi_static, u_s, v_s, a_s, f_s, h_s, status, rnorm,
):  # fmt: skip
    """Retry a failed step (from drive row ``row``) as 2, 4, ... 2^max_halvings sub-steps from its starting state
    (saved in the *_s arrays).

    ``status`` and ``rnorm`` are those of the failed full step, returned as they are if max_halvings is 0.
    Returns (status, |r|, iterations); on success (u, v, a, f_old, hist) hold the state at the step's end.
    """
    jac_state[0] = 0.0
    scheme = (beta, gamma, alpha_m, alpha_f)
    trial = (u_new, v_new, a_new, f_new, hist_new)
    _copy_state(u_s, v_s, a_s, f_s, h_s, u, v, a, f_old, hist)
    total = 0
    for level in range(1, max_halvings + 1):
        n_sub = 1 << level
        h = dt / n_sub
        _copy_state(u, v, a, f_old, hist, u_s, v_s, a_s, f_s, h_s)
        for sub in range(n_sub):
            status, rnorm, iters = _attempt(
                model, mass, data_f, data_i, drive, row, (sub + 1) / n_sub, u, v, a, f_old, hist, h, scheme,
                r_tol, max_iter, trial, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_limit, quasi_static,
            )  # fmt: skip
            total += iters
            if status != STATUS_OK:
                jac_state[0] = 0.0
                break
            _copy_state(u, v, a, f_old, hist, u_new, v_new, a_new, f_new, hist_new)
        if status == STATUS_OK:
            break
    return status, rnorm, total


@njit(cache=True, _nrt=False)
def _step_loop(
    model, mass, drive, data_f, data_i, dt, n_steps, beta, gamma, alpha_m, alpha_f, r_tol, max_iter, max_halvings,
    u_limit, quasi_static, uu, vv, aa, rr, u, v, a, f_old, hist, u_new, v_new, a_new, f_new, hist_new, drv, kt, ct,
    jac, piv, res, rec, work, jac_state, du, u_s, v_s, a_s, f_s, h_s,
):  # fmt: skip
    """The steps of :func:`_integrate` in the arrays it allocated; returns (status, last step, |r|, iterations).

    Compiled without numba's reference counting (``_nrt=False``): it makes no array (the views of the tangent's
    forward differences borrow ``work``), so the arrays that the step's inlined helpers share need no atomic
    increments and decrements.
    """
    total_iter = 0
    scheme = (beta, gamma, alpha_m, alpha_f)
    trial = (u_new, v_new, a_new, f_new, hist_new)
    for step in range(n_steps):
        status, rnorm, iters = _attempt(
            model, mass, data_f, data_i, drive, step, 1.0, u, v, a, f_old, hist, dt, scheme, r_tol, max_iter,
            trial, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_limit, quasi_static,
        )  # fmt: skip
        total_iter += iters
        if status == STATUS_OK:
            _copy_state(u, v, a, f_old, hist, u_new, v_new, a_new, f_new, hist_new)
        else:
            status, rnorm, iters = _substeps(
                model, mass, data_f, data_i, drive, step, u, v, a, f_old, hist, dt,
                beta, gamma, alpha_m, alpha_f, r_tol, max_iter, max_halvings,
                u_new, v_new, a_new, f_new, hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du,
                u_limit, quasi_static, u_s, v_s, a_s, f_s, h_s, status, rnorm,
            )  # fmt: skip
            total_iter += iters
            if status != STATUS_OK:
                return status, step, rnorm, total_iter
        # commit: the last residual evaluation recorded the model's outputs at the converged state
        _record(uu, vv, aa, rr, step + 1, u, v, a, rec)
    return STATUS_OK, n_steps, 0.0, total_iter


@njit(cache=True)
def _integrate(
    model, mass, drive, data_f, data_i, u0, v0, a0, hist0, dt, n_steps,
    beta, gamma, alpha_m, alpha_f, r_tol, max_iter, max_halvings, n_rec, work_size, u_limit, quasi_static,
):  # fmt: skip
    """Step the model ``n_steps`` times; returns the histories, the final history variables and the status.

    The arrays are allocated once here and reused by every step (:func:`_step_loop`): (u, v, a, f, hist) at the
    step's start, the *_new arrays of an attempt (so that a failed try leaves the starting state untouched), the
    tangents, the iteration matrix and its factors, and the state saved for sub-stepping (*_s).
    """
    n = u0.shape[0]
    # not zeroed: rows are written as steps converge, and the caller keeps only those (``newmark.integrate``)
    uu = np.empty((n_steps + 1, n))
    vv = np.empty((n_steps + 1, n))
    aa = np.empty((n_steps + 1, n))
    rr = np.empty((n_steps + 1, n_rec))
    u, v, a, hist, hist_new = u0.copy(), v0.copy(), a0.copy(), hist0.copy(), hist0.copy()
    f_old, res, du = np.zeros(n), np.zeros(n), np.zeros(n)
    kt, ct, jac = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    piv = np.zeros(n, dtype=np.int64)
    rec, work, jac_state, drv = np.zeros(n_rec), np.zeros(work_size), np.zeros(2), drive[0].copy()
    _force(model, u, v, drv, data_f, data_i, hist, hist_new, f_old, kt, ct, rec, True, False, work)
    _record(uu, vv, aa, rr, 0, u, v, a, rec)
    u_new, v_new, a_new, f_new = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    u_s, v_s, a_s, f_s, h_s = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(hist0.shape[0])
    status, last, rnorm, total_iter = _step_loop(
        model, mass, drive, data_f, data_i, dt, n_steps, beta, gamma, alpha_m, alpha_f, r_tol, max_iter,
        max_halvings, u_limit, quasi_static, uu, vv, aa, rr, u, v, a, f_old, hist, u_new, v_new, a_new, f_new,
        hist_new, drv, kt, ct, jac, piv, res, rec, work, jac_state, du, u_s, v_s, a_s, f_s, h_s,
    )  # fmt: skip
    return uu, vv, aa, rr, hist, status, last, rnorm, total_iter


@njit(cache=True)
def _integrate_linear_kernel(mass, damping, stiffness, loads, u0, v0, a0, dt, n_steps, beta, gamma, alpha_m, alpha_f):
    """Newmark / generalised-alpha for M a + C v + K u = R with constant matrices.

    The same scheme and residual as :func:`_integrate`, but a linear residual is solved exactly by one correction
    from the predictor with the iteration matrix factored once, so no Newton loop, convergence test or state
    saving is needed. Returns (u, v, a, status): status is STATUS_SINGULAR if the iteration matrix is singular.
    """
    # longer than 60 lines: the set-up (the matrix factored once) and the loop over the steps share the scheme's
    # constants and the factors; the loop body is one predictor, one solve and the update
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
    # the sums in index order (numba's @ is BLAS's dgemv, whose kernel OpenBLAS picks by the CPU)
    f_old = np.zeros(n)
    for i in range(n):
        ku = 0.0
        cv = 0.0
        for j in range(n):
            ku += stiffness[i, j] * u[j]
            cv += damping[i, j] * v[j]
        f_old[i] = ku + cv - loads[0, i]
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
