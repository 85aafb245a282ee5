"""Compiled internal force of the Stage 4 non-linear model (see ``docs/models.md`` for the equations).

Freedoms u (2n for n axles): [chassis pitch, equaliser 0..n-2 absolute rotation, axle 0..n-1 vertical
displacement from the design position]. Rotations lower the rear when positive; displacements are upward.

The routine returns f = -Q, Q the generalised forces of springs, tyres, friction, bushes and gravity, so the
equations of motion are M a + f = 0. Its tangent K_T = df/du is formed by forward differences of this same
algorithmic force (the friction return map included), which is the consistent tangent of the discrete problem;
C_T = df/dv is exact.

Packed parameters (built by :func:`bogie.nonlinear.pack`):

* ``data_i = [n, pad_body_0 .. pad_body_{2n-1}]``: the body carrying contact e (-1 chassis, j equaliser j);
  contact 2i is spring i's front end, 2i + 1 its rear end.
* ``data_f``: the scalars of :data:`SCALARS` then the arrays of :data:`ARRAYS`, in that order.
* drive row: ``[road height 0..n-1, road rate 0..n-1, load factor, king pin rise]``.
* history: the plastic slip s_e of each contact (2n).
* record: ``[tyre load (n), spring load (n), friction force (2n), stick flag (2n), contact shift (2n),
  plastic slip (2n)]``.
"""

from __future__ import annotations

import math

from numba import njit

SCALARS = (
    "road_spring_stiffness",
    "tyre_stiffness",
    "tyre_damping",
    "bush_stiffness",
    "bush_damping",
    "contact_roll_radius",
    "friction_coefficient",
    "contact_tangential_stiffness",
    "spring_end_slope_rate",
    "payload_weight",
    "payload_cg_x",
    "axle_weight",
)
(
    _KR,
    _KT,
    _CT,
    _KB,
    _CB,
    _RHO,
    _MU,
    _KTAN,
    _KAPPA,
    _WPAY,
    _XCG,
    _WAXLE,
) = range(len(SCALARS))
NS = len(SCALARS)

#: packed arrays: name -> length as a multiple of n (axles), 2n (contacts) or n - 1 (equalisers)
ARRAYS = (
    ("axle_x", "n"),
    ("elongation_front", "n"),
    ("elongation_rear", "n"),
    ("design_spring_load", "n"),
    ("design_tyre_compression", "n"),
    ("tyre_wear", "n"),
    ("design_chord_height", "n"),
    ("design_chord_angle", "n"),
    ("pad_x", "2n"),
    ("pad_z", "2n"),
    ("design_contact_x", "2n"),
    ("pivot_x", "n-1"),
    ("pivot_z", "n-1"),
)

FD_STEP = 1e-7  # [m] or [rad]: forward-difference step of the tangent


def array_offsets(n: int) -> dict[str, tuple[int, int]]:
    """Start and length of each packed array in ``data_f`` for n axles."""
    out = {}
    pos = NS
    for name, size in ARRAYS:
        length = {"n": n, "2n": 2 * n, "n-1": n - 1}[size]
        out[name] = (pos, length)
        pos += length
    return out


#: record entries per axle
RECORD_PER_AXLE = 10


@njit(cache=True)
def scratch_size(n):
    """Length of the work array :func:`force` needs for n axles."""
    return 4 * (n - 1) + 9 * 2 * n + n


@njit(cache=True)
def _internal(u, v, drv, data_f, data_i, hist_old, hist_new, f, rec, record, work):
    n = data_i[0]
    ne = n - 1
    # offsets, in the order of ARRAYS
    o_xa = NS
    o_lf = o_xa + n
    o_lr = o_lf + n
    o_wd = o_lr + n
    o_c0 = o_wd + n
    o_wear = o_c0 + n
    o_h0 = o_wear + n
    o_b0 = o_h0 + n
    o_px = o_b0 + n
    o_pz = o_px + 2 * n
    o_mx0 = o_pz + 2 * n
    o_vx = o_mx0 + 2 * n
    o_vz = o_vx + ne

    k_r = data_f[_KR]
    k_t = data_f[_KT]
    c_t = data_f[_CT]
    k_b = data_f[_KB]
    c_b = data_f[_CB]
    rho = data_f[_RHO]
    mu = data_f[_MU]
    k_tan = data_f[_KTAN]
    kappa = data_f[_KAPPA]

    load_factor = drv[2 * n]
    dh = drv[2 * n + 1]
    th_c = u[0]
    cc = math.cos(th_c)
    sc = math.sin(th_c)

    for k in range(2 * n):
        f[k] = 0.0

    # work arrays are views into one buffer: no allocation in the stepping loop
    m2 = 2 * n
    piv_x = work[0:ne]
    piv_z = work[ne : 2 * ne]
    w0 = 2 * ne
    m_x = work[w0 : w0 + m2]
    m_z = work[w0 + m2 : w0 + 2 * m2]
    pad_s = work[w0 + 2 * m2 : w0 + 3 * m2]
    pad_c = work[w0 + 3 * m2 : w0 + 4 * m2]
    p_x = work[w0 + 4 * m2 : w0 + 5 * m2]
    p_z = work[w0 + 5 * m2 : w0 + 6 * m2]
    t_fric = work[w0 + 6 * m2 : w0 + 7 * m2]
    stick = work[w0 + 7 * m2 : w0 + 8 * m2]
    n_load = work[w0 + 8 * m2 : w0 + 9 * m2]
    f_spring = work[w0 + 9 * m2 : w0 + 9 * m2 + n]
    eq_c = work[w0 + 9 * m2 + n : w0 + 9 * m2 + n + ne]
    eq_s = work[w0 + 9 * m2 + n + ne : w0 + 9 * m2 + n + 2 * ne]

    # pivots (chassis points) in the world, and each equaliser's rotation
    for j in range(ne):
        eq_c[j] = math.cos(u[1 + j])
        eq_s[j] = math.sin(u[1 + j])
        bx = data_f[o_vx + j]
        bz = data_f[o_vz + j]
        piv_x[j] = bx * cc + bz * sc
        piv_z[j] = dh - bx * sc + bz * cc

    # material design contact points M_e and the pad rotation
    for e in range(2 * n):
        body = data_i[1 + e]
        dx = data_f[o_px + e]
        dz = data_f[o_pz + e]
        if body < 0:
            ox = 0.0
            oz = dh
            c = cc
            s = sc
        else:
            ox = piv_x[body]
            oz = piv_z[body]
            c = eq_c[body]
            s = eq_s[body]
        m_x[e] = ox + dx * c + dz * s
        m_z[e] = oz - dx * s + dz * c
        pad_s[e] = s
        pad_c[e] = c

    # springs: contact points (rolling), deflection, friction, loads
    for i in range(n):
        ef = 2 * i
        er = 2 * i + 1
        xa = data_f[o_xa + i]
        za = u[n + i]
        h0 = data_f[o_h0 + i]
        # chord angle and a first deflection from the material points fix the leaf end angles
        span = m_x[er] - m_x[ef]
        wf = (m_x[er] - xa) / span
        d_tilde = za - (wf * m_z[ef] + (1.0 - wf) * m_z[er] - h0)
        beta = math.atan2(-(m_z[er] - m_z[ef]), span) - data_f[o_b0 + i]
        g_front = beta - kappa * d_tilde
        g_rear = beta + kappa * d_tilde
        # a leaf end on a convex pad of radius rho touches it where their tangents agree: the contact point
        # moves along the pad by rho x (pad rotation - leaf end rotation)
        if rho > 0.0:
            p_x[ef] = m_x[ef] + rho * (pad_s[ef] - math.sin(g_front))
            p_z[ef] = m_z[ef] + rho * (pad_c[ef] - math.cos(g_front))
            p_x[er] = m_x[er] + rho * (pad_s[er] - math.sin(g_rear))
            p_z[er] = m_z[er] + rho * (pad_c[er] - math.cos(g_rear))
        else:
            p_x[ef] = m_x[ef]
            p_z[ef] = m_z[ef]
            p_x[er] = m_x[er]
            p_z[er] = m_z[er]
        span = p_x[er] - p_x[ef]
        wf = (p_x[er] - xa) / span
        wr = 1.0 - wf
        delta = za - (wf * p_z[ef] + wr * p_z[er] - h0)
        f_elastic = data_f[o_wd + i] + k_r * delta
        n_el = max(f_elastic, 0.0)
        # friction: elastic-plastic return map on the slip of each leaf end over its pad
        for side in range(2):
            e = ef + side
            if side == 0:
                g = -data_f[o_lf + i] * delta - (m_x[e] - data_f[o_mx0 + e])
                limit = mu * wf * n_el
            else:
                g = data_f[o_lr + i] * delta - (m_x[e] - data_f[o_mx0 + e])
                limit = mu * wr * n_el
            trial = k_tan * (g - hist_old[e])
            if abs(trial) <= limit:
                t_fric[e] = trial
                hist_new[e] = hist_old[e]
                stick[e] = 1.0
            else:
                t = limit if trial > 0.0 else -limit
                t_fric[e] = t
                hist_new[e] = g - t / k_tan
                stick[e] = 0.0
        # friction resists the ends' sliding, so it stiffens the spring (arch thrust)
        fs = f_elastic - data_f[o_lf + i] * t_fric[ef] + data_f[o_lr + i] * t_fric[er]
        if fs < 0.0:
            fs = 0.0
        f_spring[i] = fs
        n_load[ef] = wf * fs
        n_load[er] = wr * fs
        # the spring pushes its axle down: f = -Q
        f[n + i] += fs

    # contact forces on the pads: (T, N) at P_e; moments about each body's centre of rotation
    for e in range(2 * n):
        body = data_i[1 + e]
        t = t_fric[e]
        nn = n_load[e]
        if body < 0:
            f[0] -= t * (p_z[e] - dh) - nn * p_x[e]
        else:
            f[1 + body] -= t * (p_z[e] - piv_z[body]) - nn * (p_x[e] - piv_x[body])
            f[0] -= t * (piv_z[body] - dh) - nn * piv_x[body]

    # tyres: unilateral, with wear lowering the wheel's reach
    for i in range(n):
        comp = data_f[o_c0 + i] + drv[i] - data_f[o_wear + i] - u[n + i]
        ft = 0.0
        if comp > 0.0:
            ft = k_t * comp + c_t * (drv[n + i] - v[n + i])
            if ft < 0.0:
                ft = 0.0
        f[n + i] -= ft
        f[n + i] += data_f[_WAXLE]
        if record:
            rec[i] = ft

    # bushes between each equaliser and the chassis
    for j in range(ne):
        m_b = k_b * (u[1 + j] - th_c) + c_b * (v[1 + j] - v[0])
        f[1 + j] += m_b
        f[0] -= m_b

    # payload weight on the chassis
    f[0] -= load_factor * data_f[_WPAY] * data_f[_XCG] * cc

    if record:
        for i in range(n):
            rec[n + i] = f_spring[i]
        for e in range(2 * n):
            rec[2 * n + e] = t_fric[e]
            rec[4 * n + e] = stick[e]
            rec[6 * n + e] = p_x[e] - m_x[e]
            rec[8 * n + e] = hist_new[e]


@njit(cache=True)
def force(u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, record, want_tangent, work):
    """Internal force f(u, v) and, if ``want_tangent``, K_T by forward differences and the exact C_T.

    ``work`` is a scratch buffer of :func:`scratch_size` plus 4n entries.
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
        for i in range(ndof):
            for j in range(ndof):
                ct[i, j] = 0.0
        c_b = data_f[_CB]
        for j in range(n - 1):
            ct[1 + j, 1 + j] += c_b
            ct[1 + j, 0] -= c_b
            ct[0, 1 + j] -= c_b
            ct[0, 0] += c_b
    _internal(u, v, drv, data_f, data_i, hist_old, hist_new, f, rec, record, work)
    if want_tangent:
        for j in range(ndof):
            for i in range(ndof):
                kt[i, j] = (kt[i, j] - f[i]) / FD_STEP
        # tyre damping acts only while the tyre is in contact and pushing
        o_c0 = NS + 4 * n
        o_wear = o_c0 + n
        c_t = data_f[_CT]
        k_t = data_f[_KT]
        for i in range(n):
            comp = data_f[o_c0 + i] + drv[i] - data_f[o_wear + i] - u[n + i]
            if comp > 0.0 and k_t * comp + c_t * (drv[n + i] - v[n + i]) > 0.0:
                ct[n + i, n + i] += c_t
