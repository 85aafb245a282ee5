"""Compiled internal force of the Stage 4 non-linear model (see ``docs/models.md`` for the equations).

Freedoms u (2n for n axles): [chassis pitch, equaliser 0..n-2 absolute rotation, axle 0..n-1 vertical
displacement from the design position]. Rotations lower the rear when positive; displacements are upward.

The routine returns f = -Q, Q the generalised forces of springs, tyres, friction, bushes and gravity, so the
equations of motion are M a + f = 0. Its tangent K_T = df/du is formed by forward differences of this same
algorithmic force (the friction return map included), which is the consistent tangent of the discrete problem;
C_T = df/dv is exact.

Packed parameters (built by :func:`bogie.steel.force.pack.pack`); :mod:`bogie.steel.force.layout` is the one
definition of their layout (every name of it importable from here, as when it was part of this module):

* ``data_i = [n, pad_body_0 .. pad_body_{2n-1}]``: the body carrying contact e (-1 chassis, j equaliser j);
  contact 2i is spring i's front end, 2i + 1 its rear end.
* ``data_f``: the scalars of :data:`SCALARS` then the arrays of :data:`ARRAYS`, in that order; array k starts at
  :func:`array_start` (k, n) and has :func:`array_length` (k, n) entries.
* drive row: ``[road height 0..n-1, road rate 0..n-1, load factor, king pin rise]``.
* history: the entries of :data:`HISTORY`: the plastic slip s_e of each contact (2n), then each spring's deflection
  (n) and the hysteretic part of its force (n) at the last converged step.
* record: the entries of :data:`RECORD`, each a multiple of n long, in that order: ``[tyre load (n), spring load
  (n), friction force (2n), stick flag (2n), contact shift (2n), plastic slip (2n), axle position (n), stop
  moment (n - 1), spring deflection (n), spring hysteresis (n)]``.

Each axle's x is not a freedom: it follows from the axle's radius rod, pinned at a chassis anchor
(:func:`_radius_rod`), and the rod turns the spring ends' friction into generalised forces on the chassis pitch
and the axle's vertical freedom.

The force is split by physics into small compiled helpers (body points, radius rods, rolling contact points, in
:mod:`bogie.steel.force.geometry`; the springs with their end friction's return map, pad moments, tyre loads, bushes,
bump stops, the record, here); when they were split from a former single routine they kept its arithmetic in the same
order, so results were bit-identical to it (the radius rods and the equaliser stops, added later, changed the physics).
The helpers are inlined into :func:`_internal` at numba IR level (``inline="always"``): as separate calls they doubled
the cost of a force evaluation. The helpers used inside loops take and return scalars, and the short loops over pivots,
contacts and tyres stay in :func:`_internal`. Its scratch arrays are offsets into one ``work`` buffer (:data:`WORK`),
not views, and it is compiled without reference counting (``_nrt=False``), so an evaluation creates no array object and
touches no reference count (issue 15: 0.40 -> 0.36 us for the tri-axle, ``bench/README.md``).

Library sin, cos and atan2 calls were most of an evaluation's cost, so the same quantities are computed another
way. The springs never form the leaf end angles (:func:`_rolled_contacts`): their sines and cosines come from the
chord's unit vector turned back by the design chord angle (packed as its cosine and sine) and the angle-sum
formulas with the sine and cosine of the flattening angle. That angle, the chassis pitch and the equaliser
rotations are mostly small, and short Taylor series give their sines and cosines there (:func:`_sin_cos`). The
tri-axle's evaluation calls the library only for the hysteresis' exponential while the angles are within the
series' bound (0.43 -> 0.30 us, the tandem's 0.31 -> 0.24 us: ``bench.profile_protocol``'s sample bogies, old
and new timed alternately in one process). The same physics to round-off: ``tests/test_force_formulation.py``
keeps the former formulas and compares force, record and history over random states.
"""

from __future__ import annotations

import math

from numba import njit

from bogie.steel.force.geometry import (  # noqa: F401 - what the force uses, and the geometry's names as before
    SIN_COS_SERIES_BOUND,
    _body_point,
    _chassis_point,
    _radius_rod,
    _rolled_contacts,
    _sin_cos,
)
from bogie.steel.force.layout import (  # noqa: F401 - what the force uses, and the layout's names as before
    _BAND,
    _BETA,
    _C0,
    _CB,
    _CB0,
    _CT,
    _H0,
    _HIST_DEFLECTION,
    _HIST_HYSTERESIS,
    _KAPPA,
    _KB,
    _KR,
    _KSTOP,
    _KT,
    _KTAN,
    _LF,
    _LR,
    _MU,
    _MX0,
    _PX,
    _PZ,
    _RAX,
    _RAZ,
    _REC_AXLE_X,
    _REC_DEFLECTION,
    _REC_FRICTION,
    _REC_HYSTERESIS,
    _REC_SHIFT,
    _REC_SLIP,
    _REC_SPRING,
    _REC_STICK,
    _REC_STOP,
    _RHO,
    _RL,
    _SB0,
    _STOP,
    _VX,
    _VZ,
    _W_AXLE_X,
    _W_AXLE_X_PITCH,
    _W_AXLE_X_RISE,
    _W_CONTACT_X,
    _W_CONTACT_Z,
    _W_EQ_COS,
    _W_EQ_SIN,
    _W_FRICTION,
    _W_MAT_X,
    _W_MAT_Z,
    _W_NORMAL,
    _W_PAD_COS,
    _W_PAD_SIN,
    _W_PIVOT_X,
    _W_PIVOT_Z,
    _W_SPRING,
    _W_STICK,
    _WAXLE,
    _WD,
    _WEAR,
    _WPAY,
    _XA,
    _XCG,
    ARRAYS,
    HISTORY,
    NS,
    RECORD,
    RECORD_PER_AXLE,
    SCALARS,
    WORK,
    _work_start,
    array_length,
    array_offsets,
    array_start,
    data_length,
    history_length,
    history_slices,
    history_start,
    record_length,
    record_slices,
    record_start,
    scratch_size,
    work_size,
)

#: [rad] width of a stop's onset: its contact stiffness grows linearly from 0 to the full stiffness over this much
#: rotation beyond the stop angle (a crowned rubber face whose contact area grows over its first 0.75 mm at
#: 0.15 m), so that the moment has a continuous slope and the forward-difference tangent no kink
STOP_ONSET = 0.005

FD_STEP = 1e-7  # [m] or [rad]: forward-difference step of the tangent


# ---- springs and friction --------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _return_map(g, slip_old, limit, k_tan):
    """Elastic-plastic return map of a leaf end's slip g over its pad [m]: (friction force [N], new slip, stick)."""
    trial = k_tan * (g - slip_old)
    if abs(trial) <= limit:
        return trial, slip_old, 1.0
    t = limit if trial > 0.0 else -limit
    return t, g - t / k_tan, 0.0


@njit(cache=True, inline="always")
def _hysteresis(delta, delta_old, h_old, band, decay):
    """Hysteretic part h of a leaf spring's force [N] at deflection delta [m], from its last converged state.

    The Fancher form in the elastic line's frame: h moves towards +band while the spring compresses and -band while
    it extends, h = h_env + (h_old - h_env) exp(-|delta - delta_old| / decay); the loading and unloading envelopes
    are the elastic line +- band. Exact composition (two steps give the same h as one), so the loop does not depend
    on the time step (``docs/models.md``, "Leaf-spring hysteresis"). band = 0 switches it off.
    """
    if band <= 0.0:
        return 0.0
    step = delta - delta_old
    if step == 0.0:
        return h_old
    target = band if step > 0.0 else -band
    return target + (h_old - target) * math.exp(-abs(step) / decay)


@njit(cache=True, inline="always")
def _springs(u, data_f, n, hist_old, hist_new, work):
    """Every spring: contact points (rolling), deflection, interleaf hysteresis, end friction, seat and end loads.

    Reads the material points, pad rotations and axle x (each axle's, the seat's, on its radius rod; its leaf ends
    move with it) from the scratch arrays of ``work`` and writes the contact points, friction forces, stick flags,
    end loads and spring loads there. Each spring's deflection and hysteretic force go to the new history (and
    from there to the record).
    """
    # longer than 60 lines: one pass over the springs whose stages (contact points, deflection, hysteresis, each
    # end's return map, the loads) share the spring's scalars; split, they would pass a dozen scalars each way per
    # spring. The offsets into data_f and work are taken once, before the loop
    o_xa, o_h0, o_wd = array_start(_XA, n), array_start(_H0, n), array_start(_WD, n)
    o_cb0, o_sb0 = array_start(_CB0, n), array_start(_SB0, n)
    o_lf, o_lr, o_mx0 = array_start(_LF, n), array_start(_LR, n), array_start(_MX0, n)
    k_r, mu, k_tan = data_f[_KR], data_f[_MU], data_f[_KTAN]
    band, decay = data_f[_BAND], data_f[_BETA]
    o_hd, o_hh = history_start(_HIST_DEFLECTION, n), history_start(_HIST_HYSTERESIS, n)
    w_mx, w_mz = _work_start(_W_MAT_X, n), _work_start(_W_MAT_Z, n)
    w_ps, w_pc = _work_start(_W_PAD_SIN, n), _work_start(_W_PAD_COS, n)
    w_px, w_pz = _work_start(_W_CONTACT_X, n), _work_start(_W_CONTACT_Z, n)
    w_t, w_st, w_nl = _work_start(_W_FRICTION, n), _work_start(_W_STICK, n), _work_start(_W_NORMAL, n)
    w_fs, w_ax = _work_start(_W_SPRING, n), _work_start(_W_AXLE_X, n)
    for i in range(n):
        ef = 2 * i
        er = 2 * i + 1
        xa = work[w_ax + i]
        moved = xa - data_f[o_xa + i]  # the seat's fore-aft motion on its rod, carried by both leaf ends
        za = u[n + i]
        h0 = data_f[o_h0 + i]
        mxf = work[w_mx + ef]
        mxr = work[w_mx + er]
        pxf, pzf, pxr, pzr = _rolled_contacts(
            mxf, work[w_mz + ef], mxr, work[w_mz + er], work[w_ps + ef], work[w_pc + ef], work[w_ps + er],
            work[w_pc + er], xa, za, h0, data_f[o_cb0 + i], data_f[o_sb0 + i], data_f[_KAPPA], data_f[_RHO],
        )  # fmt: skip
        work[w_px + ef] = pxf
        work[w_pz + ef] = pzf
        work[w_px + er] = pxr
        work[w_pz + er] = pzr
        span = pxr - pxf
        wf = (pxr - xa) / span
        wr = 1.0 - wf
        delta = za - (wf * pzf + wr * pzr - h0)
        # interleaf friction: the leaf pack's force is the elastic line plus its hysteretic part
        h = _hysteresis(delta, hist_old[o_hd + i], hist_old[o_hh + i], band, decay)
        hist_new[o_hd + i] = delta
        hist_new[o_hh + i] = h
        f_elastic = data_f[o_wd + i] + k_r * delta + h
        n_el = max(f_elastic, 0.0)
        # friction: elastic-plastic return map on the slip of each leaf end over its pad
        lam_f = data_f[o_lf + i]
        lam_r = data_f[o_lr + i]
        g = moved - lam_f * delta - (mxf - data_f[o_mx0 + ef])
        t_f, hist_new[ef], work[w_st + ef] = _return_map(g, hist_old[ef], mu * wf * n_el, k_tan)
        g = moved + lam_r * delta - (mxr - data_f[o_mx0 + er])
        t_r, hist_new[er], work[w_st + er] = _return_map(g, hist_old[er], mu * wr * n_el, k_tan)
        work[w_t + ef] = t_f
        work[w_t + er] = t_r
        # friction resists the ends' sliding, so it stiffens the spring (arch thrust)
        fs = f_elastic - lam_f * t_f + lam_r * t_r
        if fs < 0.0:
            fs = 0.0
        work[w_fs + i] = fs
        work[w_nl + ef] = wf * fs
        work[w_nl + er] = wr * fs


# ---- forces on the bodies --------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _pad_moments(data_i, n, dh, work, f):
    """Contact forces (T, N) at P_e on the pads: moments about each body's centre of rotation (f = -Q)."""
    w_vx, w_vz = _work_start(_W_PIVOT_X, n), _work_start(_W_PIVOT_Z, n)
    w_px, w_pz = _work_start(_W_CONTACT_X, n), _work_start(_W_CONTACT_Z, n)
    w_t, w_nl = _work_start(_W_FRICTION, n), _work_start(_W_NORMAL, n)
    for e in range(2 * n):
        body = data_i[1 + e]
        t = work[w_t + e]
        nn = work[w_nl + e]
        if body < 0:
            f[0] -= t * (work[w_pz + e] - dh) - nn * work[w_px + e]
        else:
            pvx = work[w_vx + body]
            pvz = work[w_vz + body]
            f[1 + body] -= t * (work[w_pz + e] - pvz) - nn * (work[w_px + e] - pvx)
            f[0] -= t * (pvz - dh) - nn * pvx


@njit(cache=True, inline="always")
def _tyre_load(c_0, road, wear, z, k_t, c_t, road_rate, axle_rate):
    """Compression of a tyre [m] and its spring and damper force [N], before the unilateral cut-off.

    The compression is the design compression ``c_0`` plus the road height less the wear and the axle's rise.
    """
    comp = c_0 + road - wear - z
    return comp, k_t * comp + c_t * (road_rate - axle_rate)


@njit(cache=True, inline="always")
def _tyre_force(c_0, road, wear, z, k_t, c_t, road_rate, axle_rate):
    """A tyre's load on the road [N]: :func:`_tyre_load`'s force while the tyre is compressed and pushing, else 0
    (it leaves the road at zero force)."""
    comp, push = _tyre_load(c_0, road, wear, z, k_t, c_t, road_rate, axle_rate)
    if comp > 0.0:
        return 0.0 if push < 0.0 else push  # (a NaN passes, for the residual's check to see)
    return 0.0


@njit(cache=True, inline="always")
def readings(u, v, drv, data_f, n, rec):
    """What a weighing reads of the record at (u, v) for the drive row ``drv``: each tyre's load (the record's
    first n entries) and each equaliser's stop moment (its ``stop_moment`` entries), the same values as
    :func:`_internal` records, without its other outputs."""
    o_c0, o_wear, k_t, c_t = array_start(_C0, n), array_start(_WEAR, n), data_f[_KT], data_f[_CT]
    for i in range(n):
        rec[i] = _tyre_force(data_f[o_c0 + i], drv[i], data_f[o_wear + i], u[n + i], k_t, c_t, drv[n + i], v[n + i])
    stop, k_stop = data_f[_STOP], data_f[_KSTOP]
    o_stop = record_start(_REC_STOP, n)
    for j in range(n - 1):
        rec[o_stop + j] = _stop_moment(u[1 + j] - u[0], stop, k_stop)


@njit(cache=True, inline="always")
def _bushes(u, v, data_f, n, f):
    """Bush moments between each equaliser and the chassis."""
    k_b = data_f[_KB]
    c_b = data_f[_CB]
    th_c = u[0]
    for j in range(n - 1):
        m_b = k_b * (u[1 + j] - th_c) + c_b * (v[1 + j] - v[0])
        f[1 + j] += m_b
        f[0] -= m_b


@njit(cache=True, inline="always")
def _stop_moment(phi, stop, k_stop):
    """Moment of an equaliser's bump stop for the relative rotation phi = theta_e - theta_c [N m] (f = -Q).

    Zero within +-stop; beyond, the excess e = |phi| - stop gives k e^2 / (2 e_0) over the onset e_0
    (:data:`STOP_ONSET`) and k (e - e_0 / 2) past it, with the sign of phi: unilateral on each side, C1, and the
    derivative of the potential k e^3 / (6 e_0), k (e - e_0 / 2)^2 / 2 + k e_0^2 / 24 (``docs/models.md``).
    """
    excess = abs(phi) - stop
    if excess <= 0.0:
        return 0.0
    if excess < STOP_ONSET:
        m = 0.5 * k_stop * excess * excess / STOP_ONSET
    else:
        m = k_stop * (excess - 0.5 * STOP_ONSET)
    return m if phi > 0.0 else -m


@njit(cache=True, inline="always")
def _record_contacts(n, work, hist_new, rec):
    """Spring loads, friction forces, stick flags, contact shifts, plastic slips, axle positions, spring deflections
    and hysteretic forces into the record."""
    o_spring = record_start(_REC_SPRING, n)
    o_fric = record_start(_REC_FRICTION, n)
    o_stick = record_start(_REC_STICK, n)
    o_shift = record_start(_REC_SHIFT, n)
    o_slip = record_start(_REC_SLIP, n)
    o_axle = record_start(_REC_AXLE_X, n)
    o_def = record_start(_REC_DEFLECTION, n)
    o_hys = record_start(_REC_HYSTERESIS, n)
    h_def = history_start(_HIST_DEFLECTION, n)
    h_hys = history_start(_HIST_HYSTERESIS, n)
    w_mx, w_px = _work_start(_W_MAT_X, n), _work_start(_W_CONTACT_X, n)
    w_t, w_st = _work_start(_W_FRICTION, n), _work_start(_W_STICK, n)
    w_fs, w_ax = _work_start(_W_SPRING, n), _work_start(_W_AXLE_X, n)
    for i in range(n):
        rec[o_spring + i] = work[w_fs + i]
        rec[o_axle + i] = work[w_ax + i]
        rec[o_def + i] = hist_new[h_def + i]
        rec[o_hys + i] = hist_new[h_hys + i]
    for e in range(2 * n):
        rec[o_fric + e] = work[w_t + e]
        rec[o_stick + e] = work[w_st + e]
        rec[o_shift + e] = work[w_px + e] - work[w_mx + e]
        rec[o_slip + e] = hist_new[e]


#: floating-point licences of :func:`_internal`: fused multiply-adds ("contract"), a division by a reciprocal
#: ("arcp") and no distinction of -0.0 from +0.0 ("nsz"). They change results at rounding level only and make an
#: evaluation about 7 % cheaper; the licences that let LLVM reorder sums or approximate the library functions are
#: not given (they moved forces by far more than rounding)
FASTMATH = {"contract", "arcp", "nsz"}


@njit(cache=True, _nrt=False, fastmath=FASTMATH)
def _internal(u, v, drv, data_f, data_i, hist_old, hist_new, f, rec, record, work):
    """Internal force f = -Q at (u, v) for the drive row ``drv``; writes the new slips and, if asked, the record.

    Compiled without numba's reference counting (``_nrt=False``): it makes and keeps no array, and its caller
    holds every argument, so the atomic increment and decrement of each of its 10 arrays at every call (40 atomic
    operations in a step's two evaluations) are not needed. It stays a call: inlined as well, the kernel took
    minutes to compile and ran slower.
    """
    # longer than 60 lines: the short loops over pivots, contacts, axles, tyres and stops stay here and the helpers
    # they call take and return scalars (as calls of their own they doubled an evaluation's cost, the module text);
    # it reads as the force's terms in the order of docs/models.md
    n = data_i[0]
    load_factor = drv[2 * n]
    dh = drv[2 * n + 1]
    sc, cc = _sin_cos(u[0])
    for k in range(2 * n):
        f[k] = 0.0
    w_vx, w_vz = _work_start(_W_PIVOT_X, n), _work_start(_W_PIVOT_Z, n)
    w_mx, w_mz = _work_start(_W_MAT_X, n), _work_start(_W_MAT_Z, n)
    w_ps, w_pc = _work_start(_W_PAD_SIN, n), _work_start(_W_PAD_COS, n)
    w_ec, w_es = _work_start(_W_EQ_COS, n), _work_start(_W_EQ_SIN, n)
    w_t, w_fs = _work_start(_W_FRICTION, n), _work_start(_W_SPRING, n)
    w_ax, w_adth, w_adz = _work_start(_W_AXLE_X, n), _work_start(_W_AXLE_X_PITCH, n), _work_start(_W_AXLE_X_RISE, n)
    o_vx, o_vz, o_px, o_pz = array_start(_VX, n), array_start(_VZ, n), array_start(_PX, n), array_start(_PZ, n)
    # pivots (chassis points) in the world, and each equaliser's rotation
    for j in range(n - 1):
        work[w_es + j], work[w_ec + j] = _sin_cos(u[1 + j])
        work[w_vx + j], work[w_vz + j] = _chassis_point(data_f[o_vx + j], data_f[o_vz + j], dh, cc, sc)
    # material design contact points M_e carried with their bodies, and each pad's rotation
    for e in range(2 * n):
        body = data_i[1 + e]
        if body < 0:
            ox, oz, c, s = 0.0, dh, cc, sc
        else:
            ox, oz, c, s = work[w_vx + body], work[w_vz + body], work[w_ec + body], work[w_es + body]
        work[w_mx + e], work[w_mz + e] = _body_point(ox, oz, c, s, data_f[o_px + e], data_f[o_pz + e])
        work[w_ps + e] = s
        work[w_pc + e] = c
    # each axle's x on its radius rod from its chassis anchor
    o_rax, o_raz, o_rl = array_start(_RAX, n), array_start(_RAZ, n), array_start(_RL, n)
    for i in range(n):
        work[w_ax + i], work[w_adth + i], work[w_adz + i] = _radius_rod(
            data_f[o_rax + i], data_f[o_raz + i], data_f[o_rl + i], u[n + i], dh, cc, sc
        )
    _springs(u, data_f, n, hist_old, hist_new, work)
    for i in range(n):
        # the spring pushes its axle down: f = -Q
        f[n + i] += work[w_fs + i]
        # the seat pushes the axle by -(T_F + T_R) along x; the rod turns that into Q_k = -(T_F + T_R) dx_i/du_k
        h = work[w_t + 2 * i] + work[w_t + 2 * i + 1]
        f[0] += h * work[w_adth + i]
        f[n + i] += h * work[w_adz + i]
    _pad_moments(data_i, n, dh, work, f)
    # tyres: unilateral, with wear lowering the wheel's reach; the axle weights
    o_c0, o_wear, k_t, c_t = array_start(_C0, n), array_start(_WEAR, n), data_f[_KT], data_f[_CT]
    for i in range(n):
        ft = _tyre_force(data_f[o_c0 + i], drv[i], data_f[o_wear + i], u[n + i], k_t, c_t, drv[n + i], v[n + i])
        f[n + i] -= ft
        f[n + i] += data_f[_WAXLE]
        if record:
            rec[i] = ft
    _bushes(u, v, data_f, n, f)
    # bump stops between each equaliser and the chassis: equal and opposite, like the bush
    stop, k_stop = data_f[_STOP], data_f[_KSTOP]
    o_stop = record_start(_REC_STOP, n)
    for j in range(n - 1):
        m_s = _stop_moment(u[1 + j] - u[0], stop, k_stop)
        f[1 + j] += m_s
        f[0] -= m_s
        if record:
            rec[o_stop + j] = m_s
    # payload weight on the chassis
    f[0] -= load_factor * data_f[_WPAY] * data_f[_XCG] * cc
    if record:
        _record_contacts(n, work, hist_new, rec)


@njit(cache=True, inline="always")
def _damping_tangent(u, v, drv, data_f, n, ct):
    """The exact C_T = df/dv: bush dampers, and tyre dampers while the tyre is in contact and pushing."""
    ndof = 2 * n
    for i in range(ndof):
        for j in range(ndof):
            ct[i, j] = 0.0
    c_b = data_f[_CB]
    for j in range(n - 1):
        ct[1 + j, 1 + j] += c_b
        ct[1 + j, 0] -= c_b
        ct[0, 1 + j] -= c_b
        ct[0, 0] += c_b
    o_c0 = array_start(_C0, n)
    o_wear = array_start(_WEAR, n)
    c_t = data_f[_CT]
    for i in range(n):
        comp, push = _tyre_load(
            data_f[o_c0 + i], drv[i], data_f[o_wear + i], u[n + i], data_f[_KT], c_t, drv[n + i], v[n + i]
        )
        if comp > 0.0 and push > 0.0:
            ct[n + i, n + i] += c_t


@njit(cache=True, inline="always")
def force(u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work):
    """Internal force f(u, v) and, if ``want_tangent``, K_T by forward differences and the exact C_T.

    ``work`` is a scratch buffer of :func:`work_size` (n) entries: :func:`scratch_size` plus 4n.
    """
    n = data_i[0]
    ndof = 2 * n
    base = scratch_size(n)
    if want_tangent:
        fp = work[base : base + ndof]
        up = work[base + ndof : base + 2 * ndof]
        for j in range(ndof):
            up[j] = u[j]
        for j in range(ndof):
            up[j] = u[j] + FD_STEP
            _internal(up, v, drv, data_f, data_i, hist_old, hist_new, fp, rec, False, work)
            for i in range(ndof):
                kt[i, j] = fp[i]
            up[j] = u[j]
    _internal(u, v, drv, data_f, data_i, hist_old, hist_new, f, rec, record, work)
    if want_tangent:
        for j in range(ndof):
            for i in range(ndof):
                kt[i, j] = (kt[i, j] - f[i]) / FD_STEP
        _damping_tangent(u, v, drv, data_f, n, ct)
