"""Compiled internal force of the Stage 4 non-linear model (see ``docs/models.md`` for the equations).

Freedoms u (2n for n axles): [chassis pitch, equaliser 0..n-2 absolute rotation, axle 0..n-1 vertical
displacement from the design position]. Rotations lower the rear when positive; displacements are upward.

The routine returns f = -Q, Q the generalised forces of springs, tyres, friction, bushes and gravity, so the
equations of motion are M a + f = 0. Its tangent K_T = df/du is formed by forward differences of this same
algorithmic force (the friction return map included), which is the consistent tangent of the discrete problem;
C_T = df/dv is exact.

Packed parameters (built by :func:`bogie.nonlinear.pack`); this module is the one definition of their layout:

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

The force is split by physics into small compiled helpers (body points, radius rods, rolling contact points, the
springs with their end friction's return map, pad moments, tyre loads, bushes, bump stops, the record); when they
were split from a former single routine they kept its arithmetic in the same order, so results were bit-identical
to it (the radius rods and the equaliser stops, added later, changed the physics). The helpers are inlined into
:func:`_internal` at numba IR level (``inline="always"``): as separate calls they doubled the cost of a force
evaluation. The helpers used inside loops take and return scalars, and the short loops over pivots, contacts and
tyres stay in :func:`_internal`. Its scratch arrays are offsets into one ``work`` buffer (:data:`WORK`), not views,
and it is compiled without reference counting (``_nrt=False``), so an evaluation creates no array object and
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
    "equaliser_stop",
    "equaliser_stop_stiffness",
    "spring_friction_band",
    "spring_friction_decay",
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
    _STOP,
    _KSTOP,
    _BAND,
    _BETA,
) = range(len(SCALARS))
NS = len(SCALARS)

#: packed arrays after the scalars: (name, length per axle, extra length); length = per_axle * n + extra, so
#: (1, 0) is one per axle, (2, 0) one per contact and (1, -1) one per equaliser
ARRAYS = (
    ("axle_x", 1, 0),
    ("elongation_front", 1, 0),
    ("elongation_rear", 1, 0),
    ("design_spring_load", 1, 0),
    ("design_tyre_compression", 1, 0),
    ("tyre_wear", 1, 0),
    ("design_chord_height", 1, 0),
    ("design_chord_cos", 1, 0),
    ("design_chord_sin", 1, 0),
    ("pad_x", 2, 0),
    ("pad_z", 2, 0),
    ("design_contact_x", 2, 0),
    ("pivot_x", 1, -1),
    ("pivot_z", 1, -1),
    ("rod_anchor_x", 1, 0),
    ("rod_anchor_z", 1, 0),
    ("rod_length", 1, 0),
)
(
    _XA,
    _LF,
    _LR,
    _WD,
    _C0,
    _WEAR,
    _H0,
    _CB0,
    _SB0,
    _PX,
    _PZ,
    _MX0,
    _VX,
    _VZ,
    _RAX,
    _RAZ,
    _RL,
) = range(len(ARRAYS))
_ARRAY_PER_AXLE = tuple(a[1] for a in ARRAYS)
_ARRAY_EXTRA = tuple(a[2] for a in ARRAYS)
# start of array k = NS + _START_PER_AXLE[k] n + _START_EXTRA[k]: prefix sums of the table, so that the compiled
# code finds an offset without a loop (k is a compile-time constant there)
_START_PER_AXLE = tuple(sum(_ARRAY_PER_AXLE[:k]) for k in range(len(ARRAYS) + 1))
_START_EXTRA = tuple(sum(_ARRAY_EXTRA[:k]) for k in range(len(ARRAYS) + 1))

#: recorded outputs: (name, entries per axle, extra entries), in record order; length = per_axle * n + extra, as
#: in :data:`ARRAYS`. New outputs go at the end, so that the earlier ones keep their slices.
RECORD = (
    ("tyre_load", 1, 0),
    ("spring_load", 1, 0),
    ("friction_force", 2, 0),
    ("stick", 2, 0),
    ("contact_shift", 2, 0),
    ("plastic_slip", 2, 0),
    ("axle_position", 1, 0),
    ("stop_moment", 1, -1),
    ("spring_deflection", 1, 0),
    ("spring_hysteresis", 1, 0),
)
(
    _REC_TYRE,
    _REC_SPRING,
    _REC_FRICTION,
    _REC_STICK,
    _REC_SHIFT,
    _REC_SLIP,
    _REC_AXLE_X,
    _REC_STOP,
    _REC_DEFLECTION,
    _REC_HYSTERESIS,
) = range(len(RECORD))
_RECORD_START_PER_AXLE = tuple(sum(r[1] for r in RECORD[:k]) for k in range(len(RECORD) + 1))
_RECORD_START_EXTRA = tuple(sum(r[2] for r in RECORD[:k]) for k in range(len(RECORD) + 1))
#: record entries per axle: ``RECORD_PER_AXLE * n`` is at least the record's length, :func:`record_length` (n)
#: exactly (the per-equaliser outputs are one short of n)
RECORD_PER_AXLE = _RECORD_START_PER_AXLE[-1]

#: history variables, committed at converged steps: (name, entries per axle, extra entries), in order
HISTORY = (
    ("plastic_slip", 2, 0),
    ("spring_deflection", 1, 0),
    ("spring_hysteresis", 1, 0),
)
_HIST_SLIP, _HIST_DEFLECTION, _HIST_HYSTERESIS = range(len(HISTORY))
_HISTORY_START = tuple(sum(h[1] for h in HISTORY[:k]) for k in range(len(HISTORY) + 1))


@njit(cache=True, inline="always")
def history_start(k, n):
    """Index in the history of the first entry of variable k (an index into :data:`HISTORY`) for n axles.

    k = len(HISTORY) gives the history's length.
    """
    return _HISTORY_START[k] * n


def history_length(n: int) -> int:
    """Length of the history of n axles: the plastic slips, then each spring's deflection and hysteretic force."""
    return int(history_start(len(HISTORY), n))


def history_slices(n: int) -> dict[str, slice]:
    """Where each history variable sits in the history of n axles, by name."""
    return {
        name: slice(int(history_start(k, n)), int(history_start(k + 1, n))) for k, (name, _, _) in enumerate(HISTORY)
    }


#: [rad] width of a stop's onset: its contact stiffness grows linearly from 0 to the full stiffness over this much
#: rotation beyond the stop angle (a crowned rubber face whose contact area grows over its first 0.75 mm at
#: 0.15 m), so that the moment has a continuous slope and the forward-difference tangent no kink
STOP_ONSET = 0.005

FD_STEP = 1e-7  # [m] or [rad]: forward-difference step of the tangent


# ---- layout ----------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def array_length(k, n):
    """Number of entries of packed array k (an index into :data:`ARRAYS`) for n axles."""
    return _ARRAY_PER_AXLE[k] * n + _ARRAY_EXTRA[k]


@njit(cache=True, inline="always")
def array_start(k, n):
    """Index in ``data_f`` of the first entry of packed array k (an index into :data:`ARRAYS`) for n axles.

    k = len(ARRAYS) gives the length of ``data_f``.
    """
    return NS + _START_PER_AXLE[k] * n + _START_EXTRA[k]


def array_offsets(n: int) -> dict[str, tuple[int, int]]:
    """Start and length of each packed array in ``data_f`` for n axles, by name."""
    return {name: (int(array_start(k, n)), int(array_length(k, n))) for k, (name, _, _) in enumerate(ARRAYS)}


def data_length(n: int) -> int:
    """Length of ``data_f`` for n axles."""
    return int(array_start(len(ARRAYS), n))


@njit(cache=True, inline="always")
def record_start(k, n):
    """Index in the record of the first entry of output k (an index into :data:`RECORD`) for n axles.

    k = len(RECORD) gives the record's length.
    """
    return _RECORD_START_PER_AXLE[k] * n + _RECORD_START_EXTRA[k]


def record_length(n: int) -> int:
    """Length of the record of n axles."""
    return int(record_start(len(RECORD), n))


def record_slices(n: int) -> dict[str, slice]:
    """Where each recorded output sits in the record of n axles, by name."""
    return {name: slice(int(record_start(k, n)), int(record_start(k + 1, n))) for k, (name, _, _) in enumerate(RECORD)}


#: scratch arrays of :func:`_internal` in the work buffer, in order: (name, length per axle, extra length)
WORK = (
    ("pivot_x", 1, -1),
    ("pivot_z", 1, -1),
    ("material_x", 2, 0),
    ("material_z", 2, 0),
    ("pad_sin", 2, 0),
    ("pad_cos", 2, 0),
    ("contact_x", 2, 0),
    ("contact_z", 2, 0),
    ("friction_force", 2, 0),
    ("stick", 2, 0),
    ("normal_load", 2, 0),
    ("spring_load", 1, 0),
    ("equaliser_cos", 1, -1),
    ("equaliser_sin", 1, -1),
    ("axle_x", 1, 0),
    ("axle_x_pitch", 1, 0),
    ("axle_x_rise", 1, 0),
)
_WORK_START_PER_AXLE = tuple(sum(w[1] for w in WORK[:k]) for k in range(len(WORK) + 1))
_WORK_START_EXTRA = tuple(sum(w[2] for w in WORK[:k]) for k in range(len(WORK) + 1))


@njit(cache=True, inline="always")
def _work_start(k, n):
    """Index in the work buffer of scratch array k (an index into :data:`WORK`); k = len(WORK) gives the total."""
    return _WORK_START_PER_AXLE[k] * n + _WORK_START_EXTRA[k]


@njit(cache=True, inline="always")
def scratch_size(n):
    """Length of the work array :func:`_internal` needs for n axles (:data:`WORK`)."""
    return _work_start(len(WORK), n)


def work_size(n: int) -> int:
    """Length of the work array :func:`force` needs for n axles: :func:`scratch_size` plus 4n for the tangent."""
    return int(scratch_size(n)) + 4 * n


(
    _W_PIVOT_X,
    _W_PIVOT_Z,
    _W_MAT_X,
    _W_MAT_Z,
    _W_PAD_SIN,
    _W_PAD_COS,
    _W_CONTACT_X,
    _W_CONTACT_Z,
    _W_FRICTION,
    _W_STICK,
    _W_NORMAL,
    _W_SPRING,
    _W_EQ_COS,
    _W_EQ_SIN,
    _W_AXLE_X,
    _W_AXLE_X_PITCH,
    _W_AXLE_X_RISE,
) = range(len(WORK))
# The scratch arrays are read and written as work[_work_start(k, n) + i], not through views: each view of a
# buffer is a new array object, and its reference counting at every use cost more than the arithmetic it served.


# ---- geometry --------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _chassis_point(bx, bz, dh, cc, sc):
    """World position (x, z) [m] of the chassis point at (bx, bz) from the king pin, raised by dh, pitched (cc, sc).

    The same as :func:`_body_point` with origin (0, dh) but without adding the 0 to x, which could turn a -0.0 into
    +0.0 and so differ in the last bit from the single routine this was split from.
    """
    return bx * cc + bz * sc, dh - bx * sc + bz * cc


@njit(cache=True, inline="always")
def _body_point(ox, oz, c, s, dx, dz):
    """World position (x, z) [m] of the point at (dx, dz) in a body's frame, origin (ox, oz), rotation (c, s)."""
    return ox + dx * c + dz * s, oz - dx * s + dz * c


#: [rad] bound of |x| up to which :func:`_sin_cos` sums Taylor series instead of calling the library. It covers the
#: chassis pitch's limit (20 degrees, 0.35 rad) and what the protocols' runs of the sample bogies of
#: ``bench/profile_protocol.py`` reach: equaliser rotations up to 0.25 rad, flattening angles kappa d up to 0.1 rad.
#: There the first omitted terms, x^15/15! of sin and x^14/14! of cos, are below 1e-17 relative, and the series are
#: within an ulp of the exact values (0.55 and 0.82 ulp at most; ``tests/test_force_formulation.py``)
SIN_COS_SERIES_BOUND = 0.4
# the series' coefficients: (-1)^k / (2k + 1)! for sin, (-1)^k / (2k)! for cos, k = 1 .. 6
_S1, _S2, _S3, _S4, _S5, _S6 = (-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0,
                                1.0 / 6227020800.0)  # fmt: skip
_C1, _C2, _C3, _C4, _C5, _C6 = (-0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0, -1.0 / 3628800.0, 1.0 / 479001600.0)


@njit(cache=True, inline="always")
def _sin_cos(x):
    """(sin x, cos x) to double precision: Taylor series for |x| up to :data:`SIN_COS_SERIES_BOUND`, else the library.

    The angles of the model are mostly small, and two inlined series in x^2 (12 multiply-adds that overlap with the
    rest of the evaluation) cost less than the two library calls. Each series adds a small correction to its first
    term (x, 1), so its own round-off stays below an ulp.
    """
    if abs(x) > SIN_COS_SERIES_BOUND:
        return math.sin(x), math.cos(x)
    x2 = x * x
    s = x + x * x2 * (_S1 + x2 * (_S2 + x2 * (_S3 + x2 * (_S4 + x2 * (_S5 + x2 * _S6)))))
    c = 1.0 + x2 * (_C1 + x2 * (_C2 + x2 * (_C3 + x2 * (_C4 + x2 * (_C5 + x2 * _C6)))))
    return s, c


@njit(cache=True, inline="always")
def _rolled_contacts(xf, zf, xr, zr, pad_sf, pad_cf, pad_sr, pad_cr, xa, za, h0, cos_b0, sin_b0, kappa, rho):
    """Contact points P (x, z) of a spring's front and rear ends, from their material points M (x, z) [m].

    The chord's rotation beta from its design angle beta0 (cos_b0, sin_b0) and a first deflection d from the
    material points fix the leaf end angles g = beta -+ kappa d; a leaf end on a convex pad of radius rho touches it
    where their tangents agree, so the contact point moves along the pad by rho x (pad rotation - leaf end
    rotation). Returns (x_front, z_front, x_rear, z_rear).

    The angles are never formed: (cos, sin) of beta is the chord's unit vector turned back by beta0, and those of
    g follow by the angle-sum formulas with (sin, cos) of kappa d (:func:`_sin_cos`). The same values as
    atan2, a subtraction and four sin/cos calls to round-off, for a square root, a division and a short series.
    """
    if rho > 0.0:
        span = xr - xf
        rise = zf - zr
        wf = (xr - xa) / span
        d_tilde = za - (wf * zf + (1.0 - wf) * zr - h0)
        inv_chord = 1.0 / math.sqrt(span * span + rise * rise)
        cos_chord = span * inv_chord
        sin_chord = rise * inv_chord
        cos_beta = cos_chord * cos_b0 + sin_chord * sin_b0
        sin_beta = sin_chord * cos_b0 - cos_chord * sin_b0
        sin_k, cos_k = _sin_cos(kappa * d_tilde)
        sc = sin_beta * cos_k
        cs = cos_beta * sin_k
        cc = cos_beta * cos_k
        ss = sin_beta * sin_k
        # sin and cos of g_front = beta - kappa d and g_rear = beta + kappa d
        return (
            xf + rho * (pad_sf - (sc - cs)),
            zf + rho * (pad_cf - (cc + ss)),
            xr + rho * (pad_sr - (sc + cs)),
            zr + rho * (pad_cr - (cc - ss)),
        )
    return xf, zf, xr, zr


@njit(cache=True, inline="always")
def _radius_rod(xi_a, zeta_a, length, z, dh, cc, sc):
    """Axle x on its radius rod and its derivatives: (x_i [m], dx_i/dtheta_c [m/rad], dx_i/dz_i [-]).

    The rod of ``length`` runs from the chassis anchor (xi_a, zeta_a) (king pin coordinates, pitched (cc, sc) and
    raised by dh) back to the axle's eye, which is at zeta_a + z: level in the design position. The axle's
    vertical displacement z is the freedom, its x follows (``docs/models.md``, "Axle location").
    """
    x_anchor = xi_a * cc + zeta_a * sc
    dz = zeta_a + z - (dh - xi_a * sc + zeta_a * cc)
    s2 = length * length - dz * dz
    floor = 0.01 * length * length  # a rod beyond 84 degrees: far outside the freedoms' limits
    if s2 < floor:
        s2 = floor
    span = math.sqrt(s2)
    ratio = dz / span
    return x_anchor + span, (-xi_a * sc + zeta_a * cc) + ratio * (-xi_a * cc - zeta_a * sc), -ratio


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
