"""The compiled internal force against a plain copy of its former formulas: the same physics to round-off.

The force was made cheaper by computing the same quantities another way (``bogie.steel.force.core``'s module text):
the leaf end angles' sines and cosines from the chord's unit vector and angle sums instead of atan2 and four
library calls per spring, and short Taylor series for small angles. :func:`reference_internal` keeps the former
arithmetic (atan2, library sin and cos, every helper as it was) in plain Python, so these tests fail if a
reformulation changes the physics rather than the last bits: for random states of the presets and of modified
bogies (fixed and rolling contacts, with and without interleaf friction, leaf end angles beyond the series' bound,
pitched chassis and equalisers turned up to their limits) the force, the record and the new history must agree
within 1e-12 of their scale (:func:`largest_differences`).
"""

import math
from decimal import Decimal, getcontext

import numpy as np
import pytest

from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.steel import nonlinear as nl
from bogie.steel.force import core

#: the largest difference allowed, relative to the scale of each compared quantity
RELATIVE = 1e-12
N_STATES = 200


# ---- the former formulas, in plain Python ----------------------------------------------------------------------
def _rolled_contacts(xf, zf, xr, zr, pad_sf, pad_cf, pad_sr, pad_cr, xa, za, h0, beta0, kappa, rho):
    span = xr - xf
    wf = (xr - xa) / span
    d_tilde = za - (wf * zf + (1.0 - wf) * zr - h0)
    beta = math.atan2(-(zr - zf), span) - beta0
    g_front = beta - kappa * d_tilde
    g_rear = beta + kappa * d_tilde
    if rho > 0.0:
        return (
            xf + rho * (pad_sf - math.sin(g_front)),
            zf + rho * (pad_cf - math.cos(g_front)),
            xr + rho * (pad_sr - math.sin(g_rear)),
            zr + rho * (pad_cr - math.cos(g_rear)),
        )
    return xf, zf, xr, zr


def _radius_rod(xi_a, zeta_a, length, z, dh, cc, sc):
    x_anchor = xi_a * cc + zeta_a * sc
    dz = zeta_a + z - (dh - xi_a * sc + zeta_a * cc)
    s2 = length * length - dz * dz
    floor = 0.01 * length * length
    if s2 < floor:
        s2 = floor
    span = math.sqrt(s2)
    ratio = dz / span
    return x_anchor + span, (-xi_a * sc + zeta_a * cc) + ratio * (-xi_a * cc - zeta_a * sc), -ratio


def _return_map(g, slip_old, limit, k_tan):
    trial = k_tan * (g - slip_old)
    if abs(trial) <= limit:
        return trial, slip_old, 1.0
    t = limit if trial > 0.0 else -limit
    return t, g - t / k_tan, 0.0


def _hysteresis(delta, delta_old, h_old, band, decay):
    if band <= 0.0:
        return 0.0
    step = delta - delta_old
    if step == 0.0:
        return h_old
    target = band if step > 0.0 else -band
    return target + (h_old - target) * math.exp(-abs(step) / decay)


def _stop_moment(phi, stop, k_stop):
    excess = abs(phi) - stop
    if excess <= 0.0:
        return 0.0
    if excess < core.STOP_ONSET:
        m = 0.5 * k_stop * excess * excess / core.STOP_ONSET
    else:
        m = k_stop * (excess - 0.5 * core.STOP_ONSET)
    return m if phi > 0.0 else -m


def reference_internal(u, v, drv, data_f, data_i, hist_old):
    """The internal force f = -Q, the new history and the record by the former formulas (one evaluation)."""
    n = int(data_i[0])
    a = {name: data_f[start : start + length] for name, (start, length) in core.array_offsets(n).items()}
    s = {name: data_f[k] for k, name in enumerate(core.SCALARS)}
    hs = core.history_slices(n)
    h_slip, h_def = hist_old[hs["plastic_slip"]], hist_old[hs["spring_deflection"]]
    h_hys = hist_old[hs["spring_hysteresis"]]
    hist_new = hist_old.copy()
    f = np.zeros(2 * n)
    load_factor, dh = drv[2 * n], drv[2 * n + 1]
    cc, sc = math.cos(u[0]), math.sin(u[0])
    eq_c = [math.cos(u[1 + j]) for j in range(n - 1)]
    eq_s = [math.sin(u[1 + j]) for j in range(n - 1)]
    pvx = [a["pivot_x"][j] * cc + a["pivot_z"][j] * sc for j in range(n - 1)]
    pvz = [dh - a["pivot_x"][j] * sc + a["pivot_z"][j] * cc for j in range(n - 1)]
    mx, mz, ps, pc = [], [], [], []
    for e in range(2 * n):
        body = data_i[1 + e]
        if body < 0:
            ox, oz, c, si = 0.0, dh, cc, sc
        else:
            ox, oz, c, si = pvx[body], pvz[body], eq_c[body], eq_s[body]
        dx, dz = a["pad_x"][e], a["pad_z"][e]
        mx.append(ox + dx * c + dz * si)
        mz.append(oz - dx * si + dz * c)
        ps.append(si)
        pc.append(c)
    rods = [_radius_rod(a["rod_anchor_x"][i], a["rod_anchor_z"][i], a["rod_length"][i], u[n + i], dh, cc, sc)
            for i in range(n)]  # fmt: skip
    px, pz, t, stick, nl_e = ([0.0] * (2 * n) for _ in range(5))
    fs_i = []
    # the former pack stored the design chord angle itself
    beta0 = np.arctan2(a["design_chord_sin"], a["design_chord_cos"])
    for i in range(n):
        ef, er = 2 * i, 2 * i + 1
        xa = rods[i][0]
        moved = xa - a["axle_x"][i]
        za = u[n + i]
        h0 = a["design_chord_height"][i]
        px[ef], pz[ef], px[er], pz[er] = _rolled_contacts(
            mx[ef], mz[ef], mx[er], mz[er], ps[ef], pc[ef], ps[er], pc[er], xa, za, h0, beta0[i],
            s["spring_end_slope_rate"], s["contact_roll_radius"],
        )  # fmt: skip
        span = px[er] - px[ef]
        wf = (px[er] - xa) / span
        wr = 1.0 - wf
        delta = za - (wf * pz[ef] + wr * pz[er] - h0)
        h = _hysteresis(delta, h_def[i], h_hys[i], s["spring_friction_band"], s["spring_friction_decay"])
        hist_new[hs["spring_deflection"]][i] = delta
        hist_new[hs["spring_hysteresis"]][i] = h
        f_elastic = a["design_spring_load"][i] + s["road_spring_stiffness"] * delta + h
        n_el = max(f_elastic, 0.0)
        mu, k_tan = s["friction_coefficient"], s["contact_tangential_stiffness"]
        lam_f, lam_r = a["elongation_front"][i], a["elongation_rear"][i]
        g = moved - lam_f * delta - (mx[ef] - a["design_contact_x"][ef])
        t[ef], hist_new[ef], stick[ef] = _return_map(g, h_slip[ef], mu * wf * n_el, k_tan)
        g = moved + lam_r * delta - (mx[er] - a["design_contact_x"][er])
        t[er], hist_new[er], stick[er] = _return_map(g, h_slip[er], mu * wr * n_el, k_tan)
        fs = f_elastic - lam_f * t[ef] + lam_r * t[er]
        if fs < 0.0:
            fs = 0.0
        fs_i.append(fs)
        nl_e[ef] = wf * fs
        nl_e[er] = wr * fs
    for i in range(n):
        f[n + i] += fs_i[i]
        h = t[2 * i] + t[2 * i + 1]
        f[0] += h * rods[i][1]
        f[n + i] += h * rods[i][2]
    for e in range(2 * n):
        body = data_i[1 + e]
        if body < 0:
            f[0] -= t[e] * (pz[e] - dh) - nl_e[e] * px[e]
        else:
            f[1 + body] -= t[e] * (pz[e] - pvz[body]) - nl_e[e] * (px[e] - pvx[body])
            f[0] -= t[e] * (pvz[body] - dh) - nl_e[e] * pvx[body]
    rec = np.zeros(core.record_length(n))
    rs = core.record_slices(n)
    for i in range(n):
        comp = a["design_tyre_compression"][i] + drv[i] - a["tyre_wear"][i] - u[n + i]
        push = s["tyre_stiffness"] * comp + s["tyre_damping"] * (drv[n + i] - v[n + i])
        ft = max(push, 0.0) if comp > 0.0 else 0.0
        f[n + i] -= ft
        f[n + i] += s["axle_weight"]
        rec[rs["tyre_load"]][i] = ft
    for j in range(n - 1):
        m_b = s["bush_stiffness"] * (u[1 + j] - u[0]) + s["bush_damping"] * (v[1 + j] - v[0])
        f[1 + j] += m_b
        f[0] -= m_b
    for j in range(n - 1):
        m_s = _stop_moment(u[1 + j] - u[0], s["equaliser_stop"], s["equaliser_stop_stiffness"])
        f[1 + j] += m_s
        f[0] -= m_s
        rec[rs["stop_moment"]][j] = m_s
    f[0] -= load_factor * s["payload_weight"] * s["payload_cg_x"] * cc
    rec[rs["spring_load"]] = fs_i
    rec[rs["friction_force"]] = t
    rec[rs["stick"]] = stick
    rec[rs["contact_shift"]] = np.asarray(px) - np.asarray(mx)
    rec[rs["plastic_slip"]] = hist_new[hs["plastic_slip"]]
    rec[rs["axle_position"]] = [r[0] for r in rods]
    rec[rs["spring_deflection"]] = hist_new[hs["spring_deflection"]]
    rec[rs["spring_hysteresis"]] = hist_new[hs["spring_hysteresis"]]
    return f, hist_new, rec


# ---- random states ---------------------------------------------------------------------------------------------
def random_states(bogie, rng, count):
    """(u, v, drive row, history): alternately near operation and out to the freedoms' limits.

    The axles follow the pitched and raised chassis within a few centimetres, so that the springs' deflections stay
    those of a bogie: near operation the chassis pitches by up to 1.7 degrees and the equalisers turn up to 14
    degrees from it, towards the limits up to 20 and 60 degrees (:func:`bogie.steel.nonlinear.limits`). Road inputs,
    load factors and histories (slips, deflections, hysteretic forces within the band) are random in both.
    """
    n = bogie.n_axles
    limits = nl.limits(bogie)
    band = bogie.spring_friction_band
    for k in range(count):
        v = rng.uniform(-1.0, 1.0, 2 * n)
        drv = np.concatenate([rng.uniform(-0.03, 0.03, n), rng.uniform(-0.5, 0.5, n), rng.uniform(0.25, 1.5, 1),
                              rng.uniform(-0.05, 0.05, 1)])  # fmt: skip
        if k % 2:
            pitch = rng.uniform(-limits[0], limits[0])
            turns = rng.uniform(-limits[1:n], limits[1:n])
            spread = 0.08
        else:
            pitch = rng.uniform(-0.03, 0.03)
            turns = pitch + rng.uniform(-0.25, 0.25, n - 1)
            spread = 0.03
        rise = drv[2 * n + 1] - np.asarray(bogie.axle_x) * math.sin(pitch) + rng.uniform(-spread, spread, n)
        u = np.concatenate([[pitch], turns, rise])
        hist = np.concatenate([rng.uniform(-0.01, 0.01, 2 * n), rng.uniform(-0.08, 0.08, n),
                               rng.uniform(-band, band, n)])  # fmt: skip
        yield u, v, drv, hist


def compiled_internal(u, v, drv, data_f, data_i, hist_old):
    """The force, new history and record of the compiled core, called through ``force`` as the integrator does."""
    n = int(data_i[0])
    ndof = 2 * n
    f, hist_new, rec = np.zeros(ndof), hist_old.copy(), np.zeros(core.record_length(n))
    kt, ct = np.zeros((ndof, ndof)), np.zeros((ndof, ndof))
    core.force(u, v, drv, data_f, data_i, hist_old, hist_new, f, kt, ct, rec, True, False, np.zeros(core.work_size(n)))
    return f, hist_new, rec


VARIANTS = {
    "preset": {},
    "fixed contacts": {"contact_roll_radius": 0.0},
    "no interleaf friction": {"spring_friction_band": 0.0},
    "large rolls, steep ends": {"contact_roll_radius": 0.5, "spring_end_slope_rate": 20.0},
    "flattening the other way": {"spring_end_slope_rate": -20.0, "spring_friction_band": 0.0},
    "worn tyres, tilted, close stops": {"tyre_wear": None, "chassis_tilt": math.radians(3.0), "equaliser_stop": 0.05},
}


def _bogie(make, changes):
    if "tyre_wear" in changes:
        changes = dict(changes, tyre_wear=tuple(0.002 * (k + 1) for k in range(make().n_axles)))
    return make(**changes)


def largest_differences(bogie, seed=0, count=N_STATES):
    """The largest differences of compiled and reference evaluations over random states, and the leaf end angles.

    Returns, by quantity (the force, each history variable, each recorded output), the largest difference over the
    states relative to the quantity's scale, and the |kappa delta| of every spring in every state: the flattening
    part of the leaf end angles. The force's scale is each state's largest |f|; a recorded or history variable's is
    its largest magnitude over all the states (an exact match where it is 0), because in one state it may be small
    (slips that happen to be a few micrometres) while it carries the round-off of positions metres from the king
    pin.
    """
    _, data_f, data_i = nl.pack(bogie)
    n = bogie.n_axles
    rng = np.random.default_rng(seed)
    pairs = [(compiled_internal(u, v, drv, data_f, data_i, hist), reference_internal(u, v, drv, data_f, data_i, hist))
             for u, v, drv, hist in random_states(bogie, rng, count)]  # fmt: skip
    quantities = {"force": lambda r: r[0]}
    for name, where in core.history_slices(n).items():
        quantities[f"history {name}"] = lambda r, where=where: r[1][where]
    for name, where in core.record_slices(n).items():
        quantities[f"record {name}"] = lambda r, where=where: r[2][where]
    answer = {}
    for name, take in quantities.items():
        new = np.array([take(p[0]) for p in pairs])
        old = np.array([take(p[1]) for p in pairs])
        scale = np.max(np.abs(old), axis=1, keepdims=True) if name == "force" else np.max(np.abs(old))
        answer[name] = float(np.max(np.abs(new - old) / np.maximum(scale, 1e-300)))
    deflections = np.array([p[1][1][core.history_slices(n)["spring_deflection"]] for p in pairs])
    return answer, np.abs(bogie.spring_end_slope_rate * deflections).ravel()


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("make", [tandem_trrl, triaxle_stage1])
def test_force_record_and_history_equal_the_former_formulas(make, variant):
    bogie = _bogie(make, VARIANTS[variant])
    differences, _ = largest_differences(bogie)
    worst = max(differences, key=differences.get)
    assert differences[worst] <= RELATIVE, f"{worst}: {differences[worst]:.3g} of its scale"


@pytest.mark.parametrize("variant", ["large rolls, steep ends", "flattening the other way"])
def test_the_states_compare_both_sides_of_the_series_bound(variant):
    # with steep leaf ends the flattening angle kappa d meets both the series and the library fallback (with the
    # presets' it stays within the series' bound)
    _, angles = largest_differences(_bogie(triaxle_stage1, VARIANTS[variant]), count=50)
    bound = core.SIN_COS_SERIES_BOUND
    assert np.mean(angles < bound) > 0.2 and np.mean(angles > bound) > 0.2


def test_the_reference_sees_a_change_of_physics():
    # the comparison can fail: a 1 % larger roll radius in the compiled core is far beyond round-off
    bogie = triaxle_stage1()
    _, data_f, data_i = nl.pack(bogie)
    changed = data_f.copy()
    changed[core.SCALARS.index("contact_roll_radius")] *= 1.01
    u, v, drv, hist = next(random_states(bogie, np.random.default_rng(1), 1))
    f_new = compiled_internal(u, v, drv, changed, data_i, hist)[0]
    f_old = reference_internal(u, v, drv, data_f, data_i, hist)[0]
    assert np.max(np.abs(f_new - f_old)) > 1e3 * RELATIVE * np.max(np.abs(f_old))


# ---- the series --------------------------------------------------------------------------------------------------
def _exact_sin_cos(x):
    """sin x and cos x of the double x to 40 digits (Taylor series in decimal arithmetic)."""
    getcontext().prec = 50
    x = Decimal(x)
    s, c, term_s, term_c, k = Decimal(0), Decimal(0), x, Decimal(1), 0
    while abs(term_s) > Decimal("1e-45") or abs(term_c) > Decimal("1e-45"):
        s, c = s + term_s, c + term_c
        term_s = -term_s * x * x / ((2 * k + 2) * (2 * k + 3))
        term_c = -term_c * x * x / ((2 * k + 1) * (2 * k + 2))
        k += 1
    return s, c


def test_series_are_within_an_ulp_up_to_their_bound():
    bound = core.SIN_COS_SERIES_BOUND
    rng = np.random.default_rng(2)
    xs = np.concatenate([rng.uniform(-bound, bound, 2000), np.linspace(0.9 * bound, bound, 200), [1e-300, 0.0]])
    for x in xs:
        s, c = core._sin_cos(float(x))
        exact_s, exact_c = _exact_sin_cos(float(x))
        assert abs(Decimal(s) - exact_s) <= Decimal(math.ulp(float(exact_s))), x
        assert abs(Decimal(c) - exact_c) <= Decimal(math.ulp(float(exact_c))), x


def test_beyond_the_bound_the_library_answers():
    for x in (math.nextafter(core.SIN_COS_SERIES_BOUND, 1.0), -1.0, 3.0, 100.0):
        assert core._sin_cos(x) == (math.sin(x), math.cos(x))
