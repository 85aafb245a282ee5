"""The readings of a phase of :mod:`bogie.steel.phases._core`, integrated as its steps are accepted: the time-mean of
the tyre loads over a window, a WIM sensor's average of each tyre's force over its passage (:mod:`bogie.road.wim` in
time), whether an equaliser bore on its stop in the window, and the trace.
"""

from __future__ import annotations

from numba import njit

from bogie.steel.force import core as nlc
from bogie.steel.phases._layout import (
    P_READING,
    P_SENSOR_CENTRE,
    P_SENSOR_FLAT,
    P_SENSOR_HALF,
    P_SPEED,
    P_WINDOW_END,
    P_WINDOW_START,
    READING_MEAN,
    READING_NONE,
    READING_SENSOR,
    S_STEPS,
)


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


# ---- an accepted step ------------------------------------------------------------------------------------------
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
