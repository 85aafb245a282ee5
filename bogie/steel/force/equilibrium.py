"""The compiled static equilibrium of the non-linear model (numba): bogie's one Newton iteration on the force
without inertia (issue 29: it was written twice, in Python for :func:`bogie.steel.nonlinear.equilibrium` and compiled
for the start of :func:`bogie.steel.phases._core.run_phases`).

:func:`newton` solves f(u) = 0 for the force of :func:`bogie.steel.force.core.force` at one drive row from a given
start: a tangent at every iterate, each step limited to :data:`STEP_LIMIT` rad or m, backtracking (halving, at most
:data:`BACKTRACKS` times) while the tolerance-scaled residual norm does not fall, and half of the last step taken
back where the tangent is singular. Its callers choose the start, the history the friction starts from and whether
the friction is relaxed: :func:`relaxed_equilibrium` (the phases' start: the friction relaxed, from the design
position pitched to the king pin, :func:`design_start`) and :func:`bogie.steel.nonlinear._equilibrium` (any history, any
start, and the errors' messages). The residual norm is summed freedom by freedom in order, as the compiled one always
was: numpy's pairwise sum (the former Python iteration's) is the same sum below 8 freedoms, and from 8 on it differs
in the last bits, which moves a result only where a trial's norm ties the last one's to those bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bogie.lu import lu_factor, lu_solve
from bogie.steel.force import core as nlc

#: what :func:`newton` returns: converged inside the freedoms' limits; converged outside them; no convergence in
#: :data:`MAX_ITERATIONS`; a singular tangent with no step to take back
CONVERGED, OUTSIDE_LIMITS, NO_CONVERGENCE, SINGULAR = range(4)
#: Newton iterations at most
MAX_ITERATIONS = 100
#: the largest rotation [rad] of the chassis or an equaliser and the largest axle displacement [m] of one step
STEP_LIMIT = 0.05
#: halvings of a step that does not lower the residual norm, at most
BACKTRACKS = 12
#: a singular tangent after a step larger than this (any freedom) takes half of the step back [rad or m]
RETREAT_FLOOR = 1e-9


@njit(cache=True, inline="always")
def design_start(drv, n_axles, bogie_centre_x, u):
    """u = the design position with the chassis pitched so that its bogie end sits at its design height for the king
    pin height ``drv[2 n_axles + 1]`` [m], ``bogie_centre_x`` [m] behind it: no spring starts slack."""
    for i in range(u.shape[0]):
        u[i] = 0.0
    u[0] = math.atan2(drv[2 * n_axles + 1], bogie_centre_x)


@njit(cache=True)
def newton(data_f, data_i, drv, u, hist, hist_new, f, r_tol, u_limit, rec, work):
    """Static equilibrium at the drive row ``drv`` from ``u`` (in place), the friction starting from the history
    ``hist`` (read only); returns :data:`CONVERGED` or the reason it stopped. ``f`` ends as the force at the last
    iterate evaluated, ``hist_new`` as its history (each contact's slip, each spring's deflection and hysteresis);
    ``u`` as the last iterate. Converged: every |f_i| <= r_tol_i; then each |u_i| <= u_limit_i is checked.
    ``data_f`` is the pack the force is evaluated with (the caller relaxes the friction in a copy if it wants)."""
    # longer than 60 lines: one Newton iteration with its singular-tangent retreat, step limit and backtracking, which
    # share the step and the last step taken; split, those arrays and scalars would pass in and out at every iteration
    n = u.shape[0]
    n_axles = data_i[0]
    v = np.zeros(n)
    f_try = np.zeros(n)
    kt = np.zeros((n, n))
    ct = np.zeros((n, n))
    piv = np.zeros(n, dtype=np.int64)
    step = np.zeros(n)
    last = np.zeros(n)
    trial = np.zeros(n)
    converged = False
    for _ in range(MAX_ITERATIONS):
        nlc.force(u, v, drv, data_f, data_i, hist, hist_new, f, kt, ct, rec, False, True, work)
        inside = True
        for i in range(n):
            if not abs(f[i]) <= r_tol[i]:
                inside = False
        if inside:
            converged = True
            break
        if not lu_factor(kt, piv):
            big = 0.0
            for i in range(n):
                big = max(big, abs(last[i]))
            if big > RETREAT_FLOOR:
                # the last step lifted an axle off both its spring and its tyre (a stiff stop's onset can throw one
                # there): take back half of it and go on from there
                for i in range(n):
                    last[i] *= 0.5
                    u[i] -= last[i]
                continue
            return SINGULAR
        for i in range(n):
            step[i] = -f[i]
        lu_solve(kt, piv, step)
        # limit the rotation and displacement of one iteration to keep Newton inside the physical range
        big_rot = 0.0
        big_disp = 0.0
        for i in range(n_axles):
            big_rot = max(big_rot, abs(step[i]))
            big_disp = max(big_disp, abs(step[n_axles + i]))
        scale = max(1.0, big_rot / STEP_LIMIT, big_disp / STEP_LIMIT)
        norm = 0.0
        for i in range(n):
            step[i] /= scale
            norm += (f[i] / r_tol[i]) ** 2
        norm = math.sqrt(norm)
        # backtrack while the step raises the residual: a free equaliser is unstable inside its stops and stiff on
        # them, where the full Newton step can cycle across a stop's onset
        for _ in range(BACKTRACKS):
            for i in range(n):
                trial[i] = u[i] + step[i]
            nlc.force(trial, v, drv, data_f, data_i, hist, hist_new, f_try, kt, ct, rec, False, False, work)
            norm_try = 0.0
            for i in range(n):
                norm_try += (f_try[i] / r_tol[i]) ** 2
            if math.sqrt(norm_try) < norm:
                break
            for i in range(n):
                step[i] *= 0.5
        for i in range(n):
            u[i] += step[i]
            last[i] = step[i]
    if not converged:
        return NO_CONVERGENCE
    for i in range(n):
        if not abs(u[i]) <= u_limit[i]:
            return OUTSIDE_LIMITS
    return CONVERGED


@njit(cache=True)
def relaxed_equilibrium(data_f, data_i, drv, u, hist_new, r_tol, u_limit, relaxed_slots, bogie_centre_x, rec, work):
    """The equilibrium a run starts from at rest (:func:`bogie.steel.phases._core.run_phases`): :func:`newton` with the
    friction relaxed (the slots ``relaxed_slots`` of a copy of ``data_f`` zeroed, the history zero) from
    :func:`design_start`. Writes the solution to ``u`` and its history (each contact's slip where it carries no
    friction, each spring on its elastic line) to ``hist_new``; returns whether it converged inside the limits."""
    relaxed = data_f.copy()
    for k in relaxed_slots:
        relaxed[k] = 0.0
    design_start(drv, data_i[0], bogie_centre_x, u)
    hist = np.zeros(hist_new.shape[0])
    f = np.zeros(u.shape[0])
    return newton(relaxed, data_i, drv, u, hist, hist_new, f, r_tol, u_limit, rec, work) == CONVERGED
