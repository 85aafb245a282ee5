"""The layout of :mod:`bogie.steel.phases._core`'s kernel: the columns of a phase row and of a phase's statistics, the
statuses it adds to :mod:`bogie.steel.newmark.kernels`'s, the solver's memory and counts (``J_*``, ``C_*``) and the
records its functions pass their arrays in (the comment block "the records a phase is stepped with" below).

Layout of a phase row (``phases[p]``, floats; :data:`PHASE_COLUMNS` names them): see the ``P_*`` constants.
"""

from __future__ import annotations

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

#: iteration matrices kept for the rungs, rung k's in matrix k mod RUNG_MATRICES (a phase's steps span fewer rungs),
#: and one more, the last, for a step off the ladder (one that ends on a boundary); fixed steps of dt / 2^j use
#: matrix j mod RUNG_MATRICES
RUNG_MATRICES = 16
#: a step's first correction is accepted without evaluating its residual when the contraction measured at the last
#: checked step, times the predictor's residual, is at most this (the tolerance being 1)
SKIP_LIMIT = 0.25
#: every this many steps the first correction is checked anyway, to measure its contraction afresh
CHECK_EVERY = 16
#: how many times a fixed step is halved when Newton fails in it
MAX_HALVINGS = 5


# ---- the records a phase is stepped with -----------------------------------------------------------------------
# run_phases makes every array the steps use once and passes them on grouped in tuples, the records below (numba
# passes a tuple's members as it passes arguments: the same arrays, the same arithmetic as when _phase_loop took them
# as 46 arguments). Each function unpacks the members it uses by name, in this order:
#   model  = (mass, data_f, data_i, r_tol, u_limit, scheme, max_iter): the bogie and the solver, read only. mass is
#            the diagonal of the mass matrix (n), data_f / data_i the model's pack (bogie.steel.force.core), r_tol
#            the residual's tolerance of each freedom and u_limit its range (n each), scheme (beta, gamma, alpha_m,
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
