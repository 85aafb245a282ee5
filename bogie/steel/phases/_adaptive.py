"""Adaptive steps of a phase of :mod:`bogie.steel.phases._core`: the local error estimate of Zienkiewicz and Xie [1]_
and a PI step-size controller [2]_, its steps rounded down to a geometric ladder of steps (rungs) that keep their
iteration matrices, each step ending at the next boundary (a mean reading's window, the phase's end) at the latest.

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

from numba import njit

from bogie.steel.newmark.kernels import STATUS_OK
from bogie.steel.phases._layout import (
    J_TANGENT,
    P_DT,
    P_DURATION,
    P_MAX_STEP,
    P_READING,
    P_TOL,
    P_WINDOW_END,
    P_WINDOW_START,
    READING_MEAN,
    RUNG_MATRICES,
    S_END,
    S_REJECTED,
    STATUS_STEP_TOO_SMALL,
)
from bogie.steel.phases._readings import _accepted
from bogie.steel.phases._step import _commit, _drive, _keep_correction, _solve_step

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
# the controller in base-2 logarithms (one logarithm a step, and the rung at once)
_LOG2_SAFETY = math.log2(SAFETY)
_LOG2_MAX_GROWTH = math.log2(MAX_GROWTH)
_LOG2_MIN_SHRINK = math.log2(MIN_SHRINK)
#: a relative error below this counts as this (the controller's growth is bounded anyway)
ERR_FLOOR = 1e-4
#: the smallest adaptive step [s]
MIN_STEP = 1e-7
_LOG2_MIN_STEP = math.log2(MIN_STEP)


# ---- a phase's boundaries --------------------------------------------------------------------------------------
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


# ---- adaptive steps --------------------------------------------------------------------------------------------
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
