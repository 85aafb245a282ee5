"""The geometry of the Stage 4 model's force (:mod:`bogie.steel.force.core`), inlined into it: body points, the
short sine and cosine series of small angles, the spring ends' rolled contact points and the radius rods.
"""

from __future__ import annotations

import math

from numba import njit


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
