"""One step of a phase of :mod:`bogie.steel.phases._core`: the drive at any time, the step's Newmark / generalised-alpha
residual and its Newton iteration (the iteration matrices kept as inverses, a first correction accepted unchecked
where its measured contraction allows), and the state's commit. The records the functions take: "the records a phase
is stepped with" in :mod:`bogie.steel.phases._layout`.
"""

from __future__ import annotations

import math

from numba import njit

from bogie.lu import invert
from bogie.steel.force import core as nlc
from bogie.steel.newmark.kernels import (
    STATUS_NO_CONVERGENCE,
    STATUS_NOT_FINITE,
    STATUS_OK,
    STATUS_OUT_OF_RANGE,
    STATUS_SINGULAR,
    halve,
    kinematics,
    pull_inside,
)
from bogie.steel.phases._layout import (
    C_EVALS,
    C_FACTORS,
    C_TANGENTS,
    C_UNCHECKED,
    J_CHECK_EVERY,
    J_CHECKED_STEP,
    J_CONTRACTION,
    J_LAST_STEP,
    J_SINCE_CHECK,
    J_TANGENT,
    P_DURATION,
    P_KINGPIN,
    P_LF0,
    P_LF1,
    P_ROAD_DX,
    P_ROAD_LENGTH,
    P_ROAD_START,
    P_ROAD_X0,
    P_SPEED,
    P_X0,
    SKIP_LIMIT,
)


# ---- drive -----------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _drive(phase, road_h, offsets, n, t, drv):
    """The drive row [road heights, road rates, load factor, king pin] at time ``t`` [s] of ``phase``."""
    duration = phase[P_DURATION]
    lf0 = phase[P_LF0]
    lf1 = phase[P_LF1]
    if lf1 == lf0:
        drv[2 * n] = lf0
    else:
        s = t / duration
        if s > 1.0:
            s = 1.0
        drv[2 * n] = lf0 + (lf1 - lf0) * 0.5 * (1.0 - math.cos(math.pi * s))
    drv[2 * n + 1] = phase[P_KINGPIN]
    start = int(phase[P_ROAD_START])
    if start < 0:
        for i in range(n):
            drv[i] = 0.0
            drv[n + i] = 0.0
        return
    speed = phase[P_SPEED]
    last = int(phase[P_ROAD_LENGTH]) - 2
    x0 = phase[P_ROAD_X0]
    dx = phase[P_ROAD_DX]
    front = phase[P_X0] + speed * t
    for i in range(n):
        s = (front - offsets[i] - x0) / dx
        k = int(math.floor(s))
        if k < 0:
            k = 0
        elif k > last:
            k = last
        h0 = road_h[start + k]
        rise = road_h[start + k + 1] - h0
        drv[i] = h0 + rise * (s - k)
        drv[n + i] = rise / dx * speed


# ---- one step --------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _force(u, v, drv, data_f, data_i, hist, hist_new, f, kt, ct, rec, record, want, work):
    """The model force (:func:`bogie.steel.force.core.force`), inlined where a step evaluates it: its body is a
    call of the compiled :func:`bogie.steel.force.core._internal` and, for a tangent, a loop of them. As a call of
    its own (it was one, to keep the step loop small) every evaluation passed its 12 arrays twice, to it and on to
    ``_internal``: inlined, the 20 s tri-axle run takes 9.3 ms instead of 10.1 (issue 15, ``bench.bench_single_run``),
    the same bits."""
    nlc.force(u, v, drv, data_f, data_i, hist, hist_new, f, kt, ct, rec, record, want, work)


@njit(cache=True, inline="always")
def _residual(mass, a, a_new, f_old, f_new, alpha_m, alpha_f, r_tol, res):
    """res = -(M a_(1-alpha_m) + f_(1-alpha_f)) for the diagonal ``mass``; returns (largest |residual| / tolerance,
    all finite)."""
    rnorm = 0.0
    finite = True
    for i in range(a.shape[0]):
        s = (1.0 - alpha_f) * f_new[i] + alpha_f * f_old[i] + mass[i] * ((1.0 - alpha_m) * a_new[i] + alpha_m * a[i])
        res[i] = -s
        if not math.isfinite(s):
            finite = False
        r = abs(s) / r_tol[i]
        if r > rnorm:
            rnorm = r
    return rnorm, finite


@njit(cache=True, inline="always")
def _update(inv, k, res, du, u_new, u_limit):
    """Newton update u_new += J^-1 res with the inverse ``inv[k]`` of the iteration matrix, halved until inside
    ``u_limit`` (30 times at most); False if never (:func:`bogie.steel.newmark.kernels._update`)."""
    n = du.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += inv[k, i, j] * res[j]
        du[i] = s
        u_new[i] += s
    return pull_inside(du, u_new, u_limit)


@njit(cache=True, inline="always")
def _form_matrix(jac, slot, kt, ct, mass, c_a, c_v, alpha_m, alpha_f):
    """jac[slot] = (1 - alpha_f) (K_T + c_v C_T) + (1 - alpha_m) c_a M, the iteration matrix of a step (not yet
    inverted); ``mass`` is the diagonal of M."""
    n = mass.shape[0]
    for i in range(n):
        for j in range(n):
            jac[slot, i, j] = (1.0 - alpha_f) * (kt[i, j] + c_v * ct[i, j])
        jac[slot, i, i] += (1.0 - alpha_m) * c_a * mass[i]


@njit(cache=True, inline="always")
def _solve_step(model, state, trial, newton, h, slot):
    """Newton-Raphson for one step of size ``h`` from ``state`` to the drive ``drv`` into ``trial``; returns
    (status, |r|). The records: see "the records a phase is stepped with" in
    :mod:`bogie.steel.phases._layout`.

    The iteration of :func:`bogie.steel.newmark.kernels._attempt`: predictor of constant acceleration, the full
    residual, modified Newton with the iteration matrix kept while the residual falls at least fourfold, backtracking
    when it grows. K_T and C_T are kept from their last formation, and so are the iteration matrices formed from them
    for several steps (:data:`RUNG_MATRICES`): ``jac[k]`` for the step ``keys[k]`` (0: none); this step's is
    ``jac[slot]``, formed only when it is missing or for another step, a formation being far cheaper than a
    tangent's 2n + 1 force evaluations. A new tangent drops them all. ``jac`` holds the matrices' inverses
    (:func:`bogie.lu.invert`): one is solved with at every iteration of many steps and formed rarely, and a solve
    with the inverse is a matrix-vector product. ``jst`` (:data:`J_TANGENT`...) is read and updated, ``corr`` =
    [this step's plain predictor, the last accepted step's correction], ``counts`` (:data:`C_EVALS`...) incremented.
    """
    # longer than 60 lines: the iteration's branches (backtracking, a new tangent, a new matrix, a correction
    # accepted unchecked) share its scalars (the last and the first residual, whether a tangent or a matrix is due,
    # the backtracks); split into functions they would be passed in and returned at every iteration
    mass, data_f, data_i, r_tol, u_limit, scheme, max_iter = model
    u, v, a, f_old, hist = state
    u_new, v_new, a_new, f_new, hist_new = trial
    drv, kt, ct, jac, keys, piv, res, rec, work, jst, du, corr, counts, _ = newton
    beta, gamma, alpha_m, alpha_f = scheme
    n = u.shape[0]
    c_a = 1.0 / (beta * h * h)
    c_v = gamma / (beta * h)
    # the predictor: constant acceleration, plus the last accepted step's Newton correction if that step was as
    # long as this one. The correction is about beta h^2 (a_(n+1) - a_n), which changes little from one step to the
    # next, so the iteration starts closer and more first corrections are accepted unchecked (a 20 s pass over a
    # class B road at 15 m/s: 1.15 force evaluations a step instead of 1.67). Scaled to a step of another length
    # it helped less than it cost: after a change of rung the plain predictor is used
    scale = 1.0 if jst[J_LAST_STEP] == h else 0.0
    for i in range(n):
        u_new[i] = u[i] + h * v[i] + 0.5 * h * h * a[i] + scale * corr[n + i]
        corr[i] = u[i] + h * v[i] + 0.5 * h * h * a[i]
    rnorm = 0.0
    r_prev = 0.0
    r_first = 0.0
    want = jst[J_TANGENT] == 0.0
    refactor = keys[slot] != h
    fresh = want
    backtracks = 0
    # the contraction of the first correction measured at the last checked step, scaled to this step (the iteration
    # matrix is about M / (beta h^2): its relative error grows as h^2)
    ratio = h / jst[J_CHECKED_STEP] if jst[J_CHECKED_STEP] > 0.0 else 1e30
    rho = jst[J_CONTRACTION] * ratio * ratio
    may_skip = (
        jst[J_CHECK_EVERY] > 0.0 and jst[J_SINCE_CHECK] + 1.0 < jst[J_CHECK_EVERY] and alpha_f == 0.0 and not want
    )
    for it in range(max_iter + 1):
        kinematics(u, v, a, u_new, h, beta, gamma, c_a, v_new, a_new, False)
        _force(u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, False, want, work)
        counts[C_EVALS] += 1.0
        if want:
            counts[C_EVALS] += n
            counts[C_TANGENTS] += 1.0
            jst[J_TANGENT] = 1.0
        rnorm, finite = _residual(mass, a, a_new, f_old, f_new, alpha_m, alpha_f, r_tol, res)
        if not finite:
            return STATUS_NOT_FINITE, rnorm
        if it == 0:
            r_first = rnorm
        elif it == 1 and r_first > 0.0:
            jst[J_CONTRACTION] = rnorm / r_first
            jst[J_SINCE_CHECK] = 0.0
            jst[J_CHECKED_STEP] = h
        if rnorm <= 1.0 and it > 0:
            if it > 2:
                jst[J_TANGENT] = 0.0
            return STATUS_OK, rnorm
        if it == max_iter:
            break
        if it > 0 and rnorm > r_prev and backtracks < 6:
            backtracks += 1
            halve(du, u_new)
            continue
        backtracks = 0
        if it > 0 and not fresh and rnorm > 0.25 * r_prev:
            _force(u_new, v_new, drv, data_f, data_i, hist, hist_new, f_new, kt, ct, rec, False, True, work)
            counts[C_EVALS] += n + 1
            counts[C_TANGENTS] += 1.0
            want = True
        if want or refactor:
            if want:
                # a new tangent: the matrices formed from the last one go
                for k in range(keys.shape[0]):
                    keys[k] = 0.0
            keys[slot] = 0.0
            _form_matrix(jac, slot, kt, ct, mass, c_a, c_v, alpha_m, alpha_f)
            counts[C_FACTORS] += 1.0
            if not invert(jac[slot], piv):
                return STATUS_SINGULAR, rnorm
            keys[slot] = h
            want = False
            refactor = False
            fresh = True
        r_prev = rnorm
        if not _update(jac, slot, res, du, u_new, u_limit):
            return STATUS_OUT_OF_RANGE, rnorm
        if it == 0 and may_skip and rho * r_first <= SKIP_LIMIT:
            # the correction's expected residual is far inside the tolerance: accept it unchecked, with the
            # history of the predictor's evaluation (it differs from the corrected state's by the correction, far
            # below the tolerance); the readings are taken at the accepted state by the caller
            kinematics(u, v, a, u_new, h, beta, gamma, c_a, v_new, a_new, False)
            jst[J_SINCE_CHECK] += 1.0
            counts[C_UNCHECKED] += 1.0
            return STATUS_OK, rho * r_first
        fresh = False
    return STATUS_NO_CONVERGENCE, rnorm


@njit(cache=True, inline="always")
def _keep_correction(corr, u_new, jst, h):
    """After an accepted step of ``h`` [s]: its Newton correction, the accepted displacements less the plain predictor
    (kept in ``corr[:n]`` by :func:`_solve_step`), to extrapolate the next step's predictor from."""
    n = u_new.shape[0]
    for i in range(n):
        corr[n + i] = u_new[i] - corr[i]
    jst[J_LAST_STEP] = h


@njit(cache=True, inline="always")
def _commit(state, source):
    """``state`` = ``source``, in place: two records (u, v, a, f, hist) (a state, a trial or a saved state)."""
    u, v, a, f, hist = state
    u_new, v_new, a_new, f_new, hist_new = source
    for i in range(u.shape[0]):
        u[i] = u_new[i]
        v[i] = v_new[i]
        a[i] = a_new[i]
        f[i] = f_new[i]
    for i in range(hist.shape[0]):
        hist[i] = hist_new[i]
