"""Compiled phases of a weighing (numba): the static equilibrium to start from and a sequence of phases, each
stepped with fixed or adaptive time steps, in one call (:mod:`bogie.steel.phases` is the Python layer).

A phase's drive is computed at any time inside the kernel instead of being read from a table of rows: the payload
load factor follows a cosine ramp in closed form, the king pin height is constant, and the road height under each
axle is read from a uniform table of road heights (linear between its points, so its rate is exactly the table's
slope times the speed). A phase is stepped by the same Newmark / generalised-alpha residual and Newton iteration as
:mod:`bogie.steel.newmark.kernels` (its inlined helpers are reused), either with a fixed step, or with steps chosen by
the local error estimate of Zienkiewicz and Xie [1]_ and a PI step-size controller [2]_, rounded down to a geometric
ladder of steps. The iteration matrices are kept as inverses, one for each step they were formed for, and dropped
when the tangent is formed anew: a step that stays on its rung (most do, where the controller's steps change by a
few percent at every step) reuses its matrix, and a Newton solve is a matrix-vector product. Only what the
weighings read is kept: the state at the end, the time-mean tyre loads over a window, the tyre loads a WIM sensor
reads as the tyres pass over it, and whether an equaliser bore on its bump stop in the window. Equations:
``docs/phases.md``.

The kernel is split by its parts (issue 29): :mod:`bogie.steel.phases._layout` the layout of a phase row
(``phases[p]``, floats; :data:`PHASE_COLUMNS` names them, the ``P_*`` constants index them), of the statistics and
of the records, :mod:`bogie.steel.phases._step` the drive and one step's Newton iteration,
:mod:`bogie.steel.phases._readings` the readings, :mod:`bogie.steel.phases._adaptive` the adaptive step control,
:mod:`bogie.steel.force.equilibrium` the equilibrium to start from; this module the loop over a phase's steps (fixed
steps here) and the run. The kernel's functions pass their arrays grouped in records, tuples unpacked by name (the
model, the phase's course, the state, the trial state, the saved state, Newton's work space and the phase's outputs):
see the comment block "the records a phase is stepped with" in :mod:`bogie.steel.phases._layout`, and its ``J_*`` and
``C_*`` constants for the solver's memory and counts. Every name of the layout and the controller's constants are
importable from here as before.

References
----------
.. [1] O. C. Zienkiewicz, Y. M. Xie, "A simple error estimator and adaptive time stepping procedure for dynamic
   analysis", Earthquake Engineering and Structural Dynamics, 20(9), 871-887, 1991.
.. [2] K. Gustafsson, "Control theoretic techniques for stepsize selection in explicit Runge-Kutta methods", ACM
   Transactions on Mathematical Software, 17(4), 533-554, 1991; E. Hairer, G. Wanner, Solving Ordinary Differential
   Equations II, 2nd ed., Springer, 1996, Section IV.8.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from bogie.steel.force import core as nlc
from bogie.steel.force.equilibrium import relaxed_equilibrium
from bogie.steel.newmark.kernels import (  # noqa: F401 - the statuses run_phases returns, importable from here as before
    STATUS_NO_CONVERGENCE,
    STATUS_NOT_FINITE,
    STATUS_OK,
    STATUS_OUT_OF_RANGE,
    STATUS_SINGULAR,
)
from bogie.steel.phases._adaptive import (  # noqa: F401 - the controller's constants, importable from here as before
    _LOG2_MAX_GROWTH,
    _LOG2_MIN_SHRINK,
    _LOG2_MIN_STEP,
    _LOG2_SAFETY,
    ERR_FLOOR,
    K_I,
    K_P,
    MAX_GROWTH,
    MIN_SHRINK,
    MIN_STEP,
    RUNGS,
    SAFETY,
    _adaptive_steps,
)
from bogie.steel.phases._layout import *  # noqa: F403 - the layout, importable from here as before
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
    JST_SIZE,
    MAX_HALVINGS,
    P_ADAPTIVE,
    P_DT,
    P_DURATION,
    RUNG_MATRICES,
    S_END,
    S_EVALS,
    S_FACTORS,
    S_REJECTED,
    S_TANGENTS,
    S_UNCHECKED,
    STATUS_NO_EQUILIBRIUM,
)
from bogie.steel.phases._readings import _accepted, _trace
from bogie.steel.phases._step import _commit, _drive, _keep_correction, _solve_step


# ---- a phase ---------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _phase_loop(model, course, state, trial, saved, newton, out, t_offset):
    """Step one phase (``course``) from ``state``; returns (status, time reached [s], |r|, on_stop). The records:
    see "the records a phase is stepped with" in :mod:`bogie.steel.phases._layout`; ``t_offset`` [s] is the phase's
    start in the trace.

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
    """The fixed steps of a phase (:func:`_phase_loop`): those of a table of rows at t = k dt (bogie.steel.nonlinear's
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


# ---- the whole run ---------------------------------------------------------------------------------------------
@njit(cache=True)
def _work_records(n, n_axles, n_hist, n_record, work_size, check_every):
    """The records a run's steps work in (see "the records a phase is stepped with" in
    :mod:`bogie.steel.phases._layout`), zeros but for
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

    ``mass`` is the mass matrix, diagonal (:func:`bogie.steel.force.pack.pack` makes it so). ``readings`` (n_phases,
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
