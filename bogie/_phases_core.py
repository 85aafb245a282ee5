"""Compiled phases of a weighing (numba): the static equilibrium to start from and a sequence of phases, each
stepped with fixed or adaptive time steps, in one call (:mod:`bogie.phases` is the Python layer).

A phase's drive is computed at any time inside the kernel instead of being read from a table of rows: the payload
load factor follows a cosine ramp in closed form, the king pin height is constant, and the road height under each
axle is read from a uniform table of road heights (linear between its points, so its rate is exactly the table's
slope times the speed). A phase is stepped by the same Newmark / generalised-alpha residual and Newton iteration as
:mod:`bogie._newmark_core` (its inlined helpers are reused), either with a fixed step, or with steps chosen by the
local error estimate of Zienkiewicz and Xie [1]_ and a PI step-size controller [2]_, rounded down to a geometric
ladder of steps. The iteration matrices are kept as inverses, one for each step they were formed for, and dropped
when the tangent is formed anew: a step that stays on its rung (most do, where the controller's steps change by a
few percent at every step) reuses its matrix, and a Newton solve is a matrix-vector product. Only what the
weighings read is kept: the state at the end, the time-mean tyre loads over a window, the tyre loads a WIM sensor
reads as the tyres pass over it, and whether an equaliser bore on its bump stop in the window. Equations:
``docs/phases.md``.

Layout of a phase row (``phases[p]``, floats; :data:`PHASE_COLUMNS` names them): see the ``P_*`` constants.
The kernel's functions pass their arrays grouped in records, tuples unpacked by name (the model, the phase's course,
the state, the trial state, the saved state, Newton's work space and the phase's outputs): see the comment block "the
records a phase is stepped with" below, and the ``J_*`` and ``C_*`` constants for the solver's memory and counts.

References
----------
.. [1] O. C. Zienkiewicz, Y. M. Xie, "A simple error estimator and adaptive time stepping procedure for dynamic
   analysis", Earthquake Engineering and Structural Dynamics, 20(9), 871-887, 1991.
.. [2] K. Gustafsson, "Control theoretic techniques for stepsize selection in explicit Runge-Kutta methods", ACM
   Transactions on Mathematical Software, 17(4), 533-554, 1991; E. Hairer, G. Wanner, Solving Ordinary Differential
   Equations II, 2nd ed., Springer, 1996, Section IV.8.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bogie import _nonlinear_core as nlc
from bogie._equilibrium_core import relaxed_equilibrium
from bogie._lu import invert
from bogie._newmark_core import (
    STATUS_NO_CONVERGENCE,
    STATUS_NOT_FINITE,
    STATUS_OK,
    STATUS_OUT_OF_RANGE,
    STATUS_SINGULAR,
    _halve,
    _kinematics,
    _pull_inside,
)

#: a step that could not be made smaller than the smallest step allowed (adaptive stepping)
STATUS_STEP_TOO_SMALL = 5
#: the static equilibrium to start from did not converge, or left the freedoms' limits
STATUS_NO_EQUILIBRIUM = 6

#: columns of a phase row, in order
PHASE_COLUMNS = (
    "duration",  # [s]
    "load_factor_start",  # [-]
    "load_factor_end",  # [-]: a cosine ramp from start to end over the duration
    "kingpin",  # king pin height offset plus rise [m], constant
    "speed",  # [m/s]
    "front_axle_start",  # road distance of the front axle at the phase's start [m]
    "road_start",  # first index of the phase's road table in the concatenated tables; -1: level road
    "road_length",  # points of the table
    "road_x0",  # road distance of the table's first point [m]
    "road_dx",  # spacing of its points [m]
    "adaptive",  # 0: fixed steps of dt; 1: adaptive steps starting at dt
    "dt",  # [s]
    "tolerance",  # local error tolerance of adaptive steps, a displacement at a wheel [m]
    "max_step",  # largest adaptive step [s]
    "reading",  # 0 none, 1 time-mean of the tyre loads over the window, 2 WIM sensor passages
    "window_start",  # [s] from the phase's start
    "window_end",  # [s]
    "sensor_centre",  # time the front tyre's patch centre is over the sensor [s] from the phase's start
    "sensor_half",  # half the time a patch takes to cross the sensor, (S + L) / 2v [s]
    "sensor_flat",  # half the time of full overlap, |S - L| / 2v [s]
)
(
    P_DURATION,
    P_LF0,
    P_LF1,
    P_KINGPIN,
    P_SPEED,
    P_X0,
    P_ROAD_START,
    P_ROAD_LENGTH,
    P_ROAD_X0,
    P_ROAD_DX,
    P_ADAPTIVE,
    P_DT,
    P_TOL,
    P_MAX_STEP,
    P_READING,
    P_WINDOW_START,
    P_WINDOW_END,
    P_SENSOR_CENTRE,
    P_SENSOR_HALF,
    P_SENSOR_FLAT,
) = range(len(PHASE_COLUMNS))
READING_NONE, READING_MEAN, READING_SENSOR = 0, 1, 2

#: columns of the per-phase statistics
STAT_COLUMNS = ("steps", "rejected", "force_evaluations", "tangents", "factorisations", "end_time", "unchecked")
S_STEPS, S_REJECTED, S_EVALS, S_TANGENTS, S_FACTORS, S_END, S_UNCHECKED = range(len(STAT_COLUMNS))

#: PI step-size controller [2]: h_new = h * SAFETY * err^-(K_I + K_P) * err_prev^K_P, for a local error of order 3
SAFETY = 0.9
K_I = 0.3 / 3.0
K_P = 0.4 / 3.0
#: the factor one accepted step may grow or shrink the next by, and the least it shrinks a rejected one by
MAX_GROWTH = 4.0
MIN_SHRINK = 0.2
#: adaptive steps are the controller's step rounded down to a rung 2^(k / RUNGS) s: a step that stays on a rung
#: keeps its iteration matrix, where a step that changes a little at every step would form it anew at every step.
#: The controller keeps its own step and moves it by the errors of the rungs' steps, so these average its error
#: target (as many steps as without the ladder), and no step is longer than the controller asks for
RUNGS = 8
#: iteration matrices kept for the rungs, rung k's in matrix k mod RUNG_MATRICES (a phase's steps span fewer rungs),
#: and one more, the last, for a step off the ladder (one that ends on a boundary); fixed steps of dt / 2^j use
#: matrix j mod RUNG_MATRICES
RUNG_MATRICES = 16
# the controller in base-2 logarithms (one logarithm a step, and the rung at once)
_LOG2_SAFETY = math.log2(SAFETY)
_LOG2_MAX_GROWTH = math.log2(MAX_GROWTH)
_LOG2_MIN_SHRINK = math.log2(MIN_SHRINK)
#: a relative error below this counts as this (the controller's growth is bounded anyway)
ERR_FLOOR = 1e-4
#: a step's first correction is accepted without evaluating its residual when the contraction measured at the last
#: checked step, times the predictor's residual, is at most this (the tolerance being 1)
SKIP_LIMIT = 0.25
#: every this many steps the first correction is checked anyway, to measure its contraction afresh
CHECK_EVERY = 16
#: the smallest adaptive step [s], and how many times a fixed step is halved when Newton fails in it
MIN_STEP = 1e-7
MAX_HALVINGS = 5
_LOG2_MIN_STEP = math.log2(MIN_STEP)


# ---- the records a phase is stepped with -----------------------------------------------------------------------
# run_phases makes every array the steps use once and passes them on grouped in tuples, the records below (numba
# passes a tuple's members as it passes arguments: the same arrays, the same arithmetic as when _phase_loop took them
# as 46 arguments). Each function unpacks the members it uses by name, in this order:
#   model  = (mass, data_f, data_i, r_tol, u_limit, scheme, max_iter): the bogie and the solver, read only. mass is
#            the diagonal of the mass matrix (n), data_f / data_i the model's pack (bogie._nonlinear_core), r_tol the
#            residual's tolerance of each freedom and u_limit its range (n each), scheme (beta, gamma, alpha_m,
#            alpha_f), max_iter the Newton iterations a step may take
#   course = (phase, road_h, offsets, levers): the phase's row (P_*), the concatenated road tables [m], each axle's
#            distance behind the front one [m] and each freedom's lever to a wheel [m] (the adaptive error's), read
#            only
#   state  = (u, v, a, f, hist): the accepted state, the model force at it and the model's history, in place
#   trial  = (u_new, v_new, a_new, f_new, hist_new): the state a step tries, the same layout
#   saved  = (u_s, v_s, a_s, f_s, hist_s): a fixed step's starting state while it is retried in halves, the same
#   newton = (drv, kt, ct, jac, keys, piv, res, rec, work, jst, du, corr, counts, err_scale): a step's work space and
#            what steps keep for the next: the drive row (2 n_axles + 2), K_T and C_T (n, n), the kept inverses of
#            the iteration matrices (RUNG_MATRICES + 1, n, n) and the step each was formed for, the pivots, residual,
#            record (the tyre loads first) and work space of the force and the solve, the solver's memory jst (J_*),
#            the Newton update du (n), corr = [the step's plain predictor, the last accepted step's correction] (2n),
#            the work counts (C_*) and the adaptive error's scale of each freedom (n)
#   out    = (loads0, acc, stats, trace, trace_count): the tyre loads at the step's start (n_axles), the phase's reading
#            being summed (2 n_axles), its statistics (S_*), the trace rows (:func:`_trace`) and the rows used

#: members of ``jst``, the solver's memory from step to step (floats)
J_TANGENT = 0  # 1: K_T and C_T are a tangent of this phase; 0: form one at the next evaluation
J_CONTRACTION = 1  # the contraction of the first correction measured at the last checked step
J_SINCE_CHECK = 2  # steps since that one
J_CHECK_EVERY = 3  # a first correction is checked at least every this many steps
J_CHECKED_STEP = 4  # the length of the last checked step [s] (0: none)
J_LAST_STEP = 5  # the length of the last accepted step [s], whose correction corr[n:] holds (0: none)
JST_SIZE = 6
#: members of ``counts``: force evaluations, tangents, factorisations, first corrections accepted unchecked
C_EVALS, C_TANGENTS, C_FACTORS, C_UNCHECKED = range(4)


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
    """The model force (:func:`bogie._nonlinear_core.force`), inlined where a step evaluates it: its body is a call
    of the compiled :func:`bogie._nonlinear_core._internal` and, for a tangent, a loop of them. As a call of its own
    (it was one, to keep the step loop small) every evaluation passed its 12 arrays twice, to it and on to
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
    ``u_limit`` (30 times at most); False if never (:func:`bogie._newmark_core._update`)."""
    n = du.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += inv[k, i, j] * res[j]
        du[i] = s
        u_new[i] += s
    return _pull_inside(du, u_new, u_limit)


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
    (status, |r|). The records: see "the records a phase is stepped with" above.

    The iteration of :func:`bogie._newmark_core._attempt`: predictor of constant acceleration, the full residual,
    modified Newton with the iteration matrix kept while the residual falls at least fourfold, backtracking when
    it grows. K_T and C_T are kept from their last formation, and so are the iteration matrices formed from them
    for several steps (:data:`RUNG_MATRICES`): ``jac[k]`` for the step ``keys[k]`` (0: none); this step's is
    ``jac[slot]``, formed only when it is missing or for another step, a formation being far cheaper than a
    tangent's 2n + 1 force evaluations. A new tangent drops them all. ``jac`` holds the matrices' inverses
    (:func:`bogie._lu.invert`): one is solved with at every iteration of many steps and formed rarely, and a solve
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
        _kinematics(u, v, a, u_new, h, beta, gamma, c_a, v_new, a_new, False)
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
            _halve(du, u_new)
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
            _kinematics(u, v, a, u_new, h, beta, gamma, c_a, v_new, a_new, False)
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


# ---- readings --------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _sensor_weight(tau, half, flat):
    """The share of a tyre's force on the sensor [-], its patch centre ``tau`` [s] from the sensor's centre, over its
    largest value (:func:`bogie.road.wim._weight` in time): 1 within ``flat``, falling linearly to 0 at ``half``."""
    x = abs(tau)
    if half - flat <= 1e-9 * half:  # patch or strip of no length: the box of the longer one
        return 1.0 if x <= half * (1.0 + 1e-9) else 0.0
    w = (half - x) / (half - flat)
    if w <= 0.0:
        return 0.0
    return 1.0 if w >= 1.0 else w


@njit(cache=True, inline="always")
def _sensor_pass(t0, t1, f0, f1, centre, half, flat, acc, i):
    """Add int F o dt and int o dt over the step [t0, t1] to ``acc[i]`` and ``acc[n + i]``: F linear from f0 to f1,
    o the sensor's weight about ``centre``; Simpson's rule between the weight's knots is exact (products of two
    linear functions), as in :func:`bogie.road.wim.sensor_reading`."""
    lo = centre - half
    hi = centre + half
    if t1 <= lo or t0 >= hi:
        return
    n_half = acc.shape[0] // 2
    knots = (centre - half, centre - flat, centre + flat, centre + half)
    p = t0 if t0 > lo else lo
    end = t1 if t1 < hi else hi
    slope = (f1 - f0) / (t1 - t0)
    while p < end:
        q = end
        for k in knots:
            if p < k < q:
                q = k
        m = 0.5 * (p + q)
        wp = _sensor_weight(p - centre, half, flat)
        wm = _sensor_weight(m - centre, half, flat)
        wq = _sensor_weight(q - centre, half, flat)
        fp = f0 + slope * (p - t0)
        fm = f0 + slope * (m - t0)
        fq = f0 + slope * (q - t0)
        width = q - p
        acc[i] += width * (fp * wp + 4.0 * fm * wm + fq * wq) / 6.0
        acc[n_half + i] += width * (wp + 4.0 * wm + wq) / 6.0
        p = q


@njit(cache=True, inline="always")
def _read_step(phase, n, offsets, t0, t1, loads0, rec, acc):
    """Add one accepted step [t0, t1] (tyre loads ``loads0`` at t0, ``rec`` at t1) to the phase's reading."""
    kind = int(phase[P_READING])
    if kind == READING_MEAN:
        # the trapezoidal rule on the step's part inside the window (adaptive steps end on the window's edges)
        lo = max(t0, phase[P_WINDOW_START])
        hi = min(t1, phase[P_WINDOW_END])
        if hi > lo:
            for i in range(n):
                slope = (rec[i] - loads0[i]) / (t1 - t0)
                acc[i] += (hi - lo) * (loads0[i] + slope * (0.5 * (lo + hi) - t0))
    elif kind == READING_SENSOR:
        speed = phase[P_SPEED]
        half = phase[P_SENSOR_HALF]
        flat = phase[P_SENSOR_FLAT]
        for i in range(n):
            centre = phase[P_SENSOR_CENTRE] + offsets[i] / speed
            if half > 0.0:
                _sensor_pass(t0, t1, loads0[i], rec[i], centre, half, flat, acc, i)
            elif t0 <= centre <= t1:  # a point sensor reads the force at the centre's time
                acc[i] = loads0[i] + (rec[i] - loads0[i]) * (centre - t0) / (t1 - t0)
                acc[n + i] = 1.0


@njit(cache=True, inline="always")
def _stop_in_window(phase, n, t, h, rec):
    """Whether an equaliser bears on its bump stop at the state at ``t`` (reached by a step ``h``) in the window,
    widened by half a step each side (the samples a reading of a record at that step would take)."""
    if int(phase[P_READING]) == READING_NONE:
        return False
    if t < phase[P_WINDOW_START] - 0.5 * h or t > phase[P_WINDOW_END] + 0.5 * h:
        return False
    o_stop = nlc.record_start(nlc._REC_STOP, n)
    for j in range(n - 1):
        if rec[o_stop + j] != 0.0:
            return True
    return False


@njit(cache=True, inline="always")
def _reads_at(phase, t1, margin, tracing):
    """Whether the accepted step ending at ``t1`` [s] must take the readings (tyre loads and stop moments): while a
    trace is kept, and from ``margin`` [s] (at least the next step's length) before the reading's window to a step
    past its end. Elsewhere nothing reads them: a step's reading needs the loads at its start and end only where
    it overlaps the window (:func:`_read_step`), the stop flag only near it (:func:`_stop_in_window`), and each
    phase takes its first loads from the force at its start (:func:`run_phases`). Skipping them outside is the same
    result, bit for bit, at a twentieth less per step (issue 15)."""
    if tracing:
        return True
    if int(phase[P_READING]) == READING_NONE:
        return False
    return phase[P_WINDOW_START] - margin <= t1 <= phase[P_WINDOW_END] + margin


@njit(cache=True, inline="always")
def _trace(trace, count, t, n_axles, rec, u):
    """Row ``count[0]`` of ``trace`` = [time [s], tyre loads [N], chassis pitch [rad]] while it has room."""
    k = int(count[0])
    if k < trace.shape[0]:
        trace[k, 0] = t
        for i in range(n_axles):
            trace[k, 1 + i] = rec[i]
        trace[k, 1 + n_axles] = u[0]
    count[0] += 1.0


# ---- a phase ---------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _next_boundary(phase, t):
    """The next time after ``t`` a step must end at: the window's start or end (mean readings), else the phase's end."""
    duration = phase[P_DURATION]
    if int(phase[P_READING]) == READING_MEAN:
        eps = 1e-12 * duration
        w0 = phase[P_WINDOW_START]
        if t < w0 - eps:
            return w0
        w1 = phase[P_WINDOW_END]
        if t < w1 - eps:
            return w1
    return duration


@njit(cache=True, inline="always")
def _accepted(model, course, state, newton, out, t0, t1, h, margin, t_offset, on_stop):
    """After a step [t0, t1] of ``h`` [s] is accepted (``state`` is its end): its readings where :func:`_reads_at`
    asks for them (``margin`` [s]: at least the next step's length), its count and its trace row. Returns
    ``on_stop`` or whether an equaliser bears on its stop at t1 in the window."""
    _, data_f, data_i, _, _, _, _ = model
    phase, _, offsets, _ = course
    u, v, _, _, _ = state
    drv, _, _, _, _, _, _, rec, _, _, _, _, _, _ = newton
    loads0, acc, stats, trace, trace_count = out
    n_axles = data_i[0]
    if _reads_at(phase, t1, margin, trace.shape[0] > 0):
        nlc.readings(u, v, drv, data_f, n_axles, rec)
        _read_step(phase, n_axles, offsets, t0, t1, loads0, rec, acc)
        on_stop = on_stop or _stop_in_window(phase, n_axles, t1, h, rec)
        for i in range(n_axles):
            loads0[i] = rec[i]
    stats[S_STEPS] += 1.0
    _trace(trace, trace_count, t_offset + t1, n_axles, rec, u)
    return on_stop


@njit(cache=True, inline="always")
def _phase_loop(model, course, state, trial, saved, newton, out, t_offset):
    """Step one phase (``course``) from ``state``; returns (status, time reached [s], |r|, on_stop). The records:
    see "the records a phase is stepped with" above; ``t_offset`` [s] is the phase's start in the trace.

    Fixed steps (:func:`_fixed_steps`): round(duration / dt) steps of equal length; a step whose Newton iteration
    fails is retried as 2, 4, ... sub-steps (:data:`MAX_HALVINGS`). Adaptive steps (:func:`_adaptive_steps`): the
    local error of each step, e_i = |beta - 1/6| h^2 |a_(n+1) - a_n| for freedom i, at its lever (``levers``: a
    displacement at a wheel), over the tolerance must be at most 1, else the step is rejected and retried shorter;
    the PI controller picks the next step from its own last step (at most the phase's largest step), which is taken
    rounded down to a rung of the ladder 2^(k / :data:`RUNGS`) s: it stays on a rung, and keeps its iteration
    matrix, while the controller's step moves inside the rung. Steps end exactly at the phase's end and at a mean
    reading's window. Inlined into :func:`run_phases`: compiled on its own it only passed its records on, and took a
    twentieth of the kernel's compile time (3 s).
    """
    _, _, data_i, _, _, _, _ = model
    phase, _, _, _ = course
    _, _, _, _, _, _, _, rec, _, _, _, _, _, _ = newton
    loads0, acc, _, _, _ = out
    for i in range(acc.shape[0]):
        acc[i] = 0.0
    for i in range(data_i[0]):
        loads0[i] = rec[i]
    if phase[P_ADAPTIVE] != 0.0:
        return _adaptive_steps(model, course, state, trial, newton, out, t_offset)
    return _fixed_steps(model, course, state, trial, saved, newton, out, t_offset)


@njit(cache=True, _nrt=False)
def _fixed_steps(model, course, state, trial, saved, newton, out, t_offset):
    """The fixed steps of a phase (:func:`_phase_loop`): those of a table of rows at t = k dt (bogie.nonlinear's
    inputs), round(duration / dt) of them. A step whose Newton iteration fails is taken again from its start (kept in
    ``saved``) as 2, 4, ... sub-steps (2^:data:`MAX_HALVINGS` at most), the sub-steps of 2^j with matrix j: a step is
    2^level sub-steps, level 0 the step itself, all solved at one place (a second call of the inlined
    :func:`_solve_step` for the retries compiled 9 s longer, of 65)."""
    _, _, data_i, _, _, _, _ = model
    phase, road_h, offsets, _ = course
    u_new, _, _, _, _ = trial
    drv, _, _, _, _, _, _, _, _, jst, _, corr, _, _ = newton
    _, _, stats, _, _ = out
    n_axles = data_i[0]
    on_stop = False
    rnorm = 0.0
    h = phase[P_DT]
    n_steps = max(1, int(round(phase[P_DURATION] / h)))
    for step in range(n_steps):
        t0 = step * h
        t1 = (step + 1) * h
        level = 0
        sub = 0
        while True:
            hs = h / (1 << level)
            _drive(phase, road_h, offsets, n_axles, t1 if level == 0 else t0 + (sub + 1) * hs, drv)
            status, rnorm = _solve_step(model, state, trial, newton, hs, level % RUNG_MATRICES)
            if status == STATUS_OK:
                _keep_correction(corr, u_new, jst, hs)
                _commit(state, trial)
                sub += 1
                if sub == 1 << level:
                    break
                continue
            if level == 0:
                stats[S_REJECTED] += 1.0
                _commit(saved, state)  # a failed step leaves the state as it was at the step's start
            jst[J_TANGENT] = 0.0
            if level == MAX_HALVINGS:
                stats[S_END] = t0
                return status, t0, rnorm, on_stop
            level += 1
            sub = 0
            _commit(state, saved)
        on_stop = _accepted(model, course, state, newton, out, t0, t1, h, 2.0 * h, t_offset, on_stop)
    stats[S_END] = n_steps * h
    return STATUS_OK, n_steps * h, rnorm, on_stop


@njit(cache=True, inline="always")
def _local_error(err_scale, a_new, a, h):
    """The largest local error of a step of ``h`` [s] over the tolerance, err_scale_i h^2 |a_(n+1) - a_n|."""
    err = 0.0
    for i in range(a.shape[0]):
        e = err_scale[i] * abs(a_new[i] - a[i])
        if e > err:
            err = e
    return err * (h * h)


@njit(cache=True, inline="always")
def _next_log_step(l_err, le_prev, grow, cut_short, l_want, l_h):
    """The PI controller's next step as log2(h / 1 s) after an accepted step of log2 ``l_h`` whose error's log2 is
    ``l_err`` (``le_prev`` the last one's), from the controller's own step ``l_want``; ``grow``: the step may grow
    (no rejection since the last accepted step); ``cut_short``: the step was cut short to meet a boundary."""
    factor = _LOG2_SAFETY - (K_I + K_P) * l_err + K_P * le_prev
    if factor > _LOG2_MAX_GROWTH:
        factor = _LOG2_MAX_GROWTH
    if not grow and factor > 0.0:
        factor = 0.0
    if cut_short:
        # with room to spare: its error does not shorten the next
        return max(l_want, l_h + factor) if factor >= 0.0 else l_h + factor
    # from the controller's own step, not the rung below it: fed the rung, the controller would settle where its
    # step stops growing past the next rung, up to a rung short of the step the tolerance allows
    return l_want + factor


@njit(cache=True, _nrt=False)
def _adaptive_steps(model, course, state, trial, newton, out, t_offset):
    """The adaptive steps of a phase (:func:`_phase_loop`), each ending at the next boundary at the latest
    (:func:`_next_boundary`)."""
    # longer than 60 lines: the controller's state (its step, the last error, the rung and the rung's step, whether
    # the step may grow) lives across the loop's iterations and each outcome of a step (failed, rejected, accepted)
    # updates part of it; split into functions, those scalars would be passed in and returned at every step
    _, _, data_i, _, _, scheme, _ = model
    phase, road_h, offsets, levers = course
    _, _, a, _, _ = state
    u_new, _, a_new, _, _ = trial
    drv, _, _, _, _, _, _, _, _, jst, _, corr, _, err_scale = newton
    _, _, stats, _, _ = out
    beta, _, _, _ = scheme
    n_axles = data_i[0]
    duration = phase[P_DURATION]
    max_step = phase[P_MAX_STEP]
    # e_i / h^2 / |a_(n+1) - a_n|, the same for every step of the phase
    for i in range(a.shape[0]):
        err_scale[i] = abs(beta - 1.0 / 6.0) * levers[i] / phase[P_TOL]
    on_stop = False
    t = 0.0
    rnorm = 0.0
    # the controller's next step as lh = log2(h / 1 s), the error of the last accepted step as its log2
    lh = math.log2(phase[P_DT])
    l_max = math.log2(max_step)
    le_prev = 0.0
    grow = True
    rung = -(1 << 30)
    natural = 0.0
    l_natural = 0.0
    while True:
        target = _next_boundary(phase, t)
        remaining = target - t
        if remaining <= 1e-12 * duration:
            if target >= duration:
                break
            t = target
            continue
        l_want = lh if lh < l_max else l_max
        k = int(math.floor(l_want * RUNGS))
        if k != rung:
            rung = k
            l_natural = k / RUNGS
            natural = min(2.0**l_natural, max_step)
        hh = natural
        last = False
        if hh >= remaining * (1.0 - 1e-9):
            hh = remaining
            last = True
        elif hh > 0.5 * remaining:
            hh = 0.5 * remaining  # two equal steps instead of a long one and a sliver
        t1 = target if last else t + hh
        _drive(phase, road_h, offsets, n_axles, t1, drv)
        slot = rung % RUNG_MATRICES if hh == natural else RUNG_MATRICES
        status, rnorm = _solve_step(model, state, trial, newton, hh, slot)
        l_hh = l_natural if hh == natural else math.log2(hh)
        if status != STATUS_OK:
            stats[S_REJECTED] += 1.0
            jst[J_TANGENT] = 0.0
            lh = l_hh - 2.0
            grow = False
            if lh < _LOG2_MIN_STEP:
                stats[S_END] = t
                return status, t, rnorm, on_stop
            continue
        err = _local_error(err_scale, a_new, a, hh)
        l_err = math.log2(err if err > ERR_FLOOR else ERR_FLOOR)
        if err > 1.0:
            stats[S_REJECTED] += 1.0
            shrink = _LOG2_SAFETY - l_err / 3.0
            lh = l_hh + (shrink if shrink > _LOG2_MIN_SHRINK else _LOG2_MIN_SHRINK)
            grow = False
            if lh < _LOG2_MIN_STEP:
                stats[S_END] = t
                return STATUS_STEP_TOO_SMALL, t, err, on_stop
            continue
        _keep_correction(corr, u_new, jst, hh)
        _commit(state, trial)
        # the next step is at most max_step long (and ends on the window's start where it reaches it)
        on_stop = _accepted(model, course, state, newton, out, t, t1, hh, max(2.0 * hh, max_step), t_offset, on_stop)
        t = t1
        lh = _next_log_step(l_err, le_prev, grow, hh < natural * (1.0 - 1e-9), l_want, l_hh)
        le_prev = l_err
        grow = True
    stats[S_END] = duration
    return STATUS_OK, duration, rnorm, on_stop


# ---- the whole run ---------------------------------------------------------------------------------------------
@njit(cache=True)
def _work_records(n, n_axles, n_hist, n_record, work_size, check_every):
    """The records a run's steps work in (see "the records a phase is stepped with" above), zeros but for
    jst[:data:`J_CHECK_EVERY`]: (trial, saved, newton, loads0, acc, trace_count)."""
    trial = (np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n_hist))
    saved = (np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n_hist))
    jst = np.zeros(JST_SIZE)
    jst[J_CHECK_EVERY] = check_every
    newton = (
        np.zeros(2 * n_axles + 2), np.zeros((n, n)), np.zeros((n, n)), np.zeros((RUNG_MATRICES + 1, n, n)),
        np.zeros(RUNG_MATRICES + 1), np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros(n_record),
        np.zeros(work_size), jst, np.zeros(n), np.zeros(2 * n), np.zeros(4), np.zeros(n),
    )  # fmt: skip
    return trial, saved, newton, np.zeros(n_axles), np.zeros(2 * n_axles), np.zeros(1)


@njit(cache=True, inline="always")
def _fresh_phase(jst, keys, counts):
    """Each phase starts afresh (a new tangent, no kept matrices, no measured contraction, no correction to
    extrapolate, nothing counted), so that a phase is a function of its starting state alone: phases run in one call
    or one by one from each other's final state agree exactly. jst[:data:`J_CHECK_EVERY`] stays."""
    jst[J_TANGENT] = 0.0
    jst[J_CONTRACTION] = 0.0
    jst[J_SINCE_CHECK] = 0.0
    jst[J_CHECKED_STEP] = 0.0
    jst[J_LAST_STEP] = 0.0
    for k in range(keys.shape[0]):
        keys[k] = 0.0
    for k in range(counts.shape[0]):
        counts[k] = 0.0


@njit(cache=True)
def run_phases(
    mass, data_f, data_i, offsets, levers, phases, road_h, u, v, a, hist, at_rest, relaxed_slots, bogie_centre_x,
    r_tol, u_limit, max_iter, scheme, n_record, work_size, check_every, readings, on_stop, stats, trace,
):  # fmt: skip
    """Run ``phases`` in order from (u, v, a, hist), or with ``at_rest`` from the static equilibrium at the first
    phase's start with the friction relaxed (written into u, hist; v = a = 0 there, then a from M a = -f).

    ``mass`` is the mass matrix, diagonal (:func:`bogie.nonlinear.pack` makes it so). ``readings`` (n_phases,
    2 n_axles) receives each phase's reading (mean tyre loads, or the sensor's integrals of
    F o and o), ``on_stop`` whether an equaliser bore on its stop in the phase's window, ``stats`` the phase's
    :data:`STAT_COLUMNS`, ``trace`` the rows of :func:`_trace` at the start and after every accepted step while
    it has room (give it no rows for none). (u, v, a, hist) end as the state after the last phase run. Returns
    (status, phase index it stopped in, time in that phase [s], |r|, rows the trace needed); status 0 if every
    phase ran.
    """
    # longer than 60 lines with its docstring: the start (the equilibrium, the force, the accelerations) and the loop
    # over the phases share the records it makes; the steps are in _phase_loop
    n = u.shape[0]
    n_axles = data_i[0]
    trial, saved, newton, loads0, acc, trace_count = _work_records(
        n, n_axles, hist.shape[0], n_record, work_size, check_every
    )
    drv, kt, ct, _, keys, _, _, rec, work, jst, _, _, counts, _ = newton
    _, _, _, _, hist_new = trial
    f_old = np.zeros(n)
    m_diag = np.zeros(n)
    for i in range(n):
        m_diag[i] = mass[i, i]
    model = (m_diag, data_f, data_i, r_tol, u_limit, scheme, max_iter)
    state = (u, v, a, f_old, hist)
    _drive(phases[0], road_h, offsets, n_axles, 0.0, drv)
    if at_rest:
        if not relaxed_equilibrium(data_f, data_i, drv, u, hist, r_tol, u_limit, relaxed_slots, bogie_centre_x, rec,
                                   work):  # fmt: skip
            return STATUS_NO_EQUILIBRIUM, 0, 0.0, 0.0, 0
        for i in range(n):
            v[i] = 0.0
    for i in range(hist.shape[0]):
        hist_new[i] = hist[i]
    nlc.force(u, v, drv, data_f, data_i, hist, hist_new, f_old, kt, ct, rec, True, False, work)
    if at_rest:
        # consistent accelerations: M a = -f (a massless freedom gets 0)
        for i in range(n):
            a[i] = -f_old[i] / m_diag[i] if m_diag[i] > 0.0 else 0.0
    t_offset = 0.0
    _trace(trace, trace_count, 0.0, n_axles, rec, u)
    for p in range(phases.shape[0]):
        course = (phases[p], road_h, offsets, levers)
        if p > 0:
            # the drive may jump between phases (a new road, a new load): the force at the start of this one
            _drive(phases[p], road_h, offsets, n_axles, 0.0, drv)
            nlc.force(u, v, drv, data_f, data_i, hist, hist_new, f_old, kt, ct, rec, True, False, work)
        _fresh_phase(jst, keys, counts)
        out = (loads0, acc, stats[p], trace, trace_count)
        status, t_end, rnorm, stop = _phase_loop(model, course, state, trial, saved, newton, out, t_offset)
        t_offset += t_end
        stats[p, S_EVALS] = counts[C_EVALS]
        stats[p, S_TANGENTS] = counts[C_TANGENTS]
        stats[p, S_FACTORS] = counts[C_FACTORS]
        stats[p, S_UNCHECKED] = counts[C_UNCHECKED]
        for i in range(2 * n_axles):
            readings[p, i] = acc[i]
        on_stop[p] = stop
        if status != STATUS_OK:
            return status, p, t_end, rnorm, int(trace_count[0])
    return STATUS_OK, phases.shape[0], 0.0, 0.0, int(trace_count[0])
