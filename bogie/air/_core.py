"""Compiled fixed-step integrator of the air-sprung group (``docs/air-suspension.md``, "Numerics").

The equations are those of :func:`bogie.air.dynamics._forces` and ``_rates``, re-derived here on packed arrays
(the bag's area and volume, p = K (m / V)^n and the specific enthalpy of :mod:`bogie.air`). State y (4n + 9 for n
axles): ``[theta, z (n), theta_dot, z_dot (n), gas mass (n), the 7 running integrals of WORK_TERMS]``.

Packed parameters (built by :func:`bogie.air.dynamics._pack`): ``par`` the scalars of :data:`SCALARS` in that
order, ``x`` the axle positions, ``wear`` the tyre wear. Drive: ``road`` (rows, n), ``load`` (rows,), ``rise``
(rows,), the king pin's total rise; each is linear in time between rows.

Classical RK4 with ``substeps`` equal steps per input row, so that each step lies inside one linear segment of the
drive.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SCALARS = (
    "bag_effective_area",
    "bag_area_rate",
    "bag_volume",
    "polytropic_index",
    "gas_constant",
    "atmospheric_pressure",
    "pipe_conductance",
    "valve_dead_band",
    "valve_time_constant",
    "supply_pressure",
    "damper_damping",
    "tyre_stiffness",
    "tyre_damping",
    "design_tyre_compression",
    "axle_mass",
    "payload_moment",
    "chassis_pitch_inertia",
    "gravity",
)
_A0, _AR, _V0, _N, _K, _PA, _C, _BAND, _TAUV, _PS, _CD, _KT, _CT, _C0, _MA, _WX, _I, _G = range(len(SCALARS))
#: number of running work integrals (WORK_TERMS of bogie.air.dynamics)
N_WORK = 7
#: status codes
OK, EMPTIED, NOT_FINITE = 0, 1, 2


@njit(cache=True, inline="always")
def _enthalpy(n_poly: float, k: float, p: float) -> float:
    """eta(p) of :func:`bogie.air.specific_enthalpy` [J/kg]."""
    rho = (p / k) ** (1.0 / n_poly)
    if n_poly == 1.0:
        return k * (math.log(rho) + 1.0)
    return n_poly * k * rho ** (n_poly - 1.0) / (n_poly - 1.0)


@njit(cache=True)
def evaluate(par, x, wear, y, road, road_rate, load, rise, rise_rate, valve, dy, rec):
    """Rates ``dy`` of state ``y`` and the record ``rec`` = [tyre (n), extension (n), gauge pressure (n), bag force
    (n), the 7 powers]; returns a status code (:data:`EMPTIED` if a bag emptied or closed)."""
    # longer than 60 lines: one evaluation of the right-hand side, called by the ODE solver at every stage; its
    # parts (bag pressures, the valve, each axle's rates and powers) share the per-axle arrays and scalars, and as
    # calls of their own would pass them in and out at every stage
    n = x.shape[0]
    theta = y[0]
    theta_d = y[n + 1]
    sin_t, cos_t = math.sin(theta), math.cos(theta)
    n_poly, k, p_a, cc = par[_N], par[_K], par[_PA], par[_C]
    e = np.empty(n)
    e_d = np.empty(n)
    area = np.empty(n)
    vol = np.empty(n)
    p = np.empty(n)
    for i in range(n):
        e[i] = rise - x[i] * sin_t - y[1 + i]
        e_d[i] = rise_rate - x[i] * cos_t * theta_d - y[n + 2 + i]
        area[i] = par[_A0] + par[_AR] * e[i]
        vol[i] = par[_V0] + par[_A0] * e[i] + 0.5 * par[_AR] * e[i] * e[i]
        m = y[2 * n + 2 + i]
        if not (vol[i] > 0.0 and m > 0.0):
            return EMPTIED
        p[i] = k * (m / vol[i]) ** n_poly
    p_mean = 0.0
    e_mean = 0.0
    for i in range(n):
        p_mean += p[i]
        e_mean += e[i]
    p_mean /= n
    e_mean /= n
    error = 0.0
    if valve:
        error = math.copysign(max(abs(e_mean) - par[_BAND], 0.0), e_mean)
    p_supply = par[_PS] + p_a
    eta_s = _enthalpy(n_poly, k, p_supply)
    eta_a = _enthalpy(n_poly, k, p_a)
    eta_mean = _enthalpy(n_poly, k, p_mean)
    powers = np.zeros(N_WORK)
    moment = 0.0
    for i in range(n):
        zi, zdi, m = y[1 + i], y[n + 2 + i], y[2 * n + 2 + i]
        bag = (p[i] - p_a) * area[i]
        damper = par[_CD] * e_d[i]
        comp = par[_C0] + road[i] - wear[i] - zi
        rel = road_rate[i] - zdi
        push = par[_KT] * comp + par[_CT] * rel
        tyre = max(push, 0.0) if comp > 0.0 else 0.0
        eta = _enthalpy(n_poly, k, p[i])
        pipe = cc * (p_mean - p[i])
        fill = 0.0
        vent = 0.0
        if valve:
            flow = -(m / vol[i]) * area[i] * error / par[_TAUV]
            if flow > 0.0 and p[i] < p_supply:
                fill = flow
            elif flow < 0.0:
                vent = -flow
        moment += x[i] * (bag - damper)
        dy[1 + i] = zdi
        dy[n + 2 + i] = (tyre - bag + damper) / par[_MA] - par[_G]
        dy[2 * n + 2 + i] = pipe + fill - vent
        powers[0] += damper * e_d[i]
        powers[1] += (tyre - par[_KT] * max(comp, 0.0)) * rel
        powers[2] += cc * (p[i] - p_mean) * (eta - eta_mean)
        powers[3] += fill * (eta_s - eta) + vent * (eta - eta_a)
        powers[4] += tyre * road_rate[i]
        powers[5] += fill * eta_s
        powers[6] += vent * eta_a
        rec[i] = tyre
        rec[n + i] = e[i]
        rec[2 * n + i] = p[i] - p_a
        rec[3 * n + i] = bag
    dy[0] = theta_d
    dy[n + 1] = (load * par[_WX] - moment) * cos_t / par[_I]
    for j in range(N_WORK):
        dy[3 * n + 2 + j] = powers[j]
        rec[4 * n + j] = powers[j]
    return OK


@njit(cache=True)
def _drive_at(road, load, rise, row, s, dt, r_out, rr_out):
    """The drive inside segment ``row`` at fraction ``s``: fills road and road rate, returns (load, rise, rate)."""
    n = road.shape[1]
    for i in range(n):
        rate = (road[row + 1, i] - road[row, i]) / dt
        rr_out[i] = rate
        r_out[i] = road[row, i] + s * rate * dt
    rise_rate = (rise[row + 1] - rise[row]) / dt
    return load[row] + s * (load[row + 1] - load[row]), rise[row] + s * rise_rate * dt, rise_rate


@njit(cache=True)
def integrate(par, x, wear, y0, road, load, rise, dt, substeps, valve):
    """RK4 over every input row; returns (states (rows, m), records (rows, 4n + 7), rows done, status)."""
    n_rows = road.shape[0]
    n = x.shape[0]
    size = y0.shape[0]
    ys = np.zeros((n_rows, size))
    recs = np.zeros((n_rows, 4 * n + N_WORK))
    r = np.empty(n)
    rr = np.empty(n)
    dy = np.empty(size)
    k1 = np.empty(size)
    k2 = np.empty(size)
    k3 = np.empty(size)
    k4 = np.empty(size)
    yt = np.empty(size)
    y = y0.copy()
    h = dt / substeps
    for row in range(n_rows):
        seg = row if row < n_rows - 1 else n_rows - 2
        s_row = 0.0 if row < n_rows - 1 else 1.0
        ld, rs, rsr = _drive_at(road, load, rise, seg, s_row, dt, r, rr)
        status = evaluate(par, x, wear, y, r, rr, ld, rs, rsr, valve, dy, recs[row])
        if status != OK:
            return ys, recs, row, status
        ys[row] = y
        if row == n_rows - 1:
            break
        for sub in range(substeps):
            s0 = sub / substeps
            sh = 0.5 / substeps
            stages = (k1, k2, k3, k4)
            for st in range(4):
                if st == 0:
                    s = s0
                    for j in range(size):
                        yt[j] = y[j]
                elif st < 3:
                    s = s0 + sh
                    kp = stages[st - 1]
                    for j in range(size):
                        yt[j] = y[j] + 0.5 * h * kp[j]
                else:
                    s = s0 + 2.0 * sh
                    for j in range(size):
                        yt[j] = y[j] + h * k3[j]
                ld, rs, rsr = _drive_at(road, load, rise, row, s, dt, r, rr)
                status = evaluate(par, x, wear, yt, r, rr, ld, rs, rsr, valve, stages[st], dy)
                if status != OK:
                    return ys, recs, row + 1, status
            for j in range(size):
                y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            for j in range(size):
                if not math.isfinite(y[j]):
                    return ys, recs, row + 1, NOT_FINITE
    return ys, recs, n_rows, OK
