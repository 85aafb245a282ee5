"""Verification of the Newmark / generalised-alpha integrator: each test asserts a number."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from bogie.steel.newmark import generalized_alpha, integrate_linear


def _three_dof(damped: bool):
    M = np.diag([2.0, 1.0, 1.5])
    K = np.array([[300.0, -100.0, 0.0], [-100.0, 250.0, -150.0], [0.0, -150.0, 400.0]])
    C = 0.02 * K + 0.1 * M if damped else np.zeros((3, 3))
    return M, C, K


def _exact_free(M, C, K, u0, v0, t):
    n = M.shape[0]
    minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ K, -minv @ C]])
    return expm(A * t) @ np.concatenate([u0, v0])


def test_sdof_average_acceleration_keeps_amplitude_and_has_the_exact_newmark_period():
    omega, dt, n = 2.0 * np.pi, 0.05, 2000
    u, v, a = integrate_linear([[1.0]], [[0.0]], [[omega**2]], np.zeros((n + 1, 1)), [1.0], [0.0], dt, n)
    big = omega * dt
    period = (2 * np.pi / omega) * big / (2 * np.arctan(big / 2))
    t = np.arange(n + 1) * dt
    assert np.max(np.abs(u[:, 0] - np.cos(2 * np.pi * t / period))) < 1e-10
    # amplitude: the discrete energy (u^2 + v^2 / omega^2) is invariant
    energy = u[:, 0] ** 2 + (v[:, 0] / omega) ** 2
    assert np.ptp(energy) < 1e-12


def test_second_order_convergence_against_matrix_exponential():
    M, C, K = _three_dof(damped=True)
    u0, v0 = np.array([0.01, -0.02, 0.015]), np.array([0.0, 0.1, -0.05])
    t_end = 2.0
    exact = _exact_free(M, C, K, u0, v0, t_end)[:3]
    errors = []
    for n in (200, 400, 800):
        u, _, _ = integrate_linear(M, C, K, np.zeros((n + 1, 3)), u0, v0, t_end / n, n)
        errors.append(np.max(np.abs(u[-1] - exact)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.7) & (ratios < 4.3)), ratios


def test_generalized_alpha_is_second_order_too():
    M, C, K = _three_dof(damped=True)
    u0, v0 = np.array([0.01, -0.02, 0.015]), np.zeros(3)
    exact = _exact_free(M, C, K, u0, v0, 2.0)[:3]
    errors = []
    for n in (400, 800):
        u, _, _ = integrate_linear(M, C, K, np.zeros((n + 1, 3)), u0, v0, 2.0 / n, n, rho_inf=0.8)
        errors.append(np.max(np.abs(u[-1] - exact)))
    assert 3.6 < errors[0] / errors[1] < 4.4


def test_undamped_energy_drift_below_1e_10_over_10000_steps():
    M, C, K = _three_dof(damped=False)
    n = 10_000
    u, v, _ = integrate_linear(M, C, K, np.zeros((n + 1, 3)), [0.01, -0.02, 0.015], [0.0, 0.1, -0.05], 0.01, n)
    energy = 0.5 * np.einsum("ti,ij,tj->t", v, M, v) + 0.5 * np.einsum("ti,ij,tj->t", u, K, u)
    assert np.max(np.abs(energy - energy[0])) / energy[0] < 1e-10


def test_forced_response_matches_radau_at_small_dt():
    M, C, K = _three_dof(damped=True)
    force = lambda t: np.array([50.0 * np.sin(7.0 * t), 0.0, 20.0 * np.cos(3.0 * t)])  # noqa: E731
    dt, n = 5e-4, 4000
    u, _, _ = integrate_linear(M, C, K, force, np.zeros(3), np.zeros(3), dt, n)
    minv = np.linalg.inv(M)

    def rhs(t, y):
        return np.concatenate([y[3:], minv @ (force(t) - C @ y[3:] - K @ y[:3])])

    t = np.arange(n + 1) * dt
    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(6), method="Radau", t_eval=t, rtol=1e-10, atol=1e-12)
    scale = np.max(np.abs(sol.y[:3]))
    assert np.max(np.abs(u - sol.y[:3].T)) / scale < 1e-5


def test_massless_freedom_matches_statically_condensed_system():
    # freedom 2 has no mass and no damping: its equation is algebraic
    M = np.diag([3.0, 1.0, 0.0])
    K = np.array([[400.0, -100.0, -200.0], [-100.0, 300.0, -100.0], [-200.0, -100.0, 500.0]])
    C = np.zeros((3, 3))
    C[:2, :2] = [[2.0, -0.5], [-0.5, 1.0]]
    load = lambda t: np.array([10.0 * np.sin(4.0 * t), 0.0, 30.0 * np.cos(2.0 * t)])  # noqa: E731
    dt, n = 0.002, 2000
    u0 = np.linalg.solve(K, load(0.0))
    u, _, _ = integrate_linear(M, C, K, load, u0, np.zeros(3), dt, n)
    # condensed: u2 = (R2 - K20 u0 - K21 u1) / K22
    m, s = [0, 1], [2]
    k_red = K[np.ix_(m, m)] - K[np.ix_(m, s)] @ K[np.ix_(s, m)] / K[2, 2]
    load_red = lambda t: load(t)[m] - K[np.ix_(m, s)][:, 0] * load(t)[2] / K[2, 2]  # noqa: E731
    ur, _, _ = integrate_linear(M[np.ix_(m, m)], C[np.ix_(m, m)], k_red, load_red, u0[m], np.zeros(2), dt, n)
    assert np.max(np.abs(u[:, :2] - ur)) < 1e-12 * max(1.0, np.max(np.abs(ur)))
    t = np.arange(n + 1) * dt
    u2 = np.array([(load(ti)[2] - K[2, 0] * a - K[2, 1] * b) / K[2, 2] for ti, a, b in zip(t, ur[:, 0], ur[:, 1])])
    assert np.max(np.abs(u[:, 2] - u2)) < 1e-12


@pytest.mark.parametrize("rho_inf", [0.0, 0.5, 0.9])
def test_generalized_alpha_damps_the_highest_frequencies_to_rho_inf(rho_inf):
    # omega dt = 1e4: the step is far longer than the period, the amplitude falls by rho_inf per step (the root is
    # double, so amplitude ~ (c1 + c2 k) rho^k: measure far out, where the linear factor changes slowly)
    omega, dt, n = 1e4, 1.0, 400
    u, v, _ = integrate_linear(
        [[1.0]], [[0.0]], [[omega**2]], np.zeros((n + 1, 1)), [1.0], [0.0], dt, n, rho_inf=rho_inf
    )
    amp = np.sqrt(u[:, 0] ** 2 + (v[:, 0] / omega) ** 2)
    if rho_inf == 0.0:
        assert amp[-1] < 1e-6
    else:
        rate = (amp[-1] / amp[200]) ** (1 / 200)
        assert rate == pytest.approx(rho_inf, rel=5e-3)


def test_average_acceleration_does_not_damp_the_highest_frequencies():
    omega, dt, n = 1e4, 1.0, 40
    u, v, _ = integrate_linear([[1.0]], [[0.0]], [[omega**2]], np.zeros((n + 1, 1)), [1.0], [0.0], dt, n)
    amp = np.sqrt(u[:, 0] ** 2 + (v[:, 0] / omega) ** 2)
    # no decay at all: what is left is roundoff of a correction formed from terms of size omega^2 u = 1e8
    assert np.max(np.abs(amp - 1.0)) < 1e-7


def test_generalized_alpha_parameters():
    am, af, beta, gamma = generalized_alpha(1.0)
    assert (am, af, beta, gamma) == pytest.approx((0.5, 0.5, 0.25, 0.5))
    with pytest.raises(ValueError, match=r"rho_inf = 1.5 is out of range: must be in \[0, 1\]"):
        generalized_alpha(1.5)


def test_singular_system_fails_with_a_message_not_nan():
    with pytest.raises(RuntimeError, match="singular iteration matrix at t = 0 s"):
        integrate_linear(
            np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((11, 2)), [0, 0], [0, 0], 0.1, 10
        )


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match=r"dt = -0.1 is out of range: must be > 0 s"):
        integrate_linear([[1.0]], [[0.0]], [[1.0]], np.zeros((11, 1)), [0.0], [0.0], -0.1, 10)
    with pytest.raises(ValueError, match=r"R has shape \(5, 1\)"):
        integrate_linear([[1.0]], [[0.0]], [[1.0]], np.zeros((5, 1)), [0.0], [0.0], 0.1, 10)
    with pytest.raises(ValueError, match="beta = 0.7 is out of range"):
        integrate_linear([[1.0]], [[0.0]], [[1.0]], np.zeros((11, 1)), [0.0], [0.0], 0.1, 10, beta=0.7)


@pytest.mark.parametrize("rho_inf", [None, 0.8])
def test_linear_loop_gives_the_general_newton_kernels_histories(rho_inf):
    # integrate_linear factors once and makes one correction per step; the general kernel iterates Newton on the
    # same residual: for a linear system both must give the same numbers
    from bogie.steel.newmark import MODEL_LINEAR, consistent_acceleration, integrate

    M, C, K = _three_dof(damped=True)
    M[2, 2] = 0.0  # a massless freedom too
    n = 500
    t = np.arange(n + 1) * 0.01
    loads = np.column_stack([50.0 * np.sin(7.0 * t), np.zeros(n + 1), 20.0 * np.cos(3.0 * t)])
    u0 = np.linalg.solve(K, loads[0])
    u, v, a = integrate_linear(M, C, K, loads, u0, np.zeros(3), 0.01, n, rho_inf=rho_inf)
    a0 = consistent_acceleration(M, K @ u0 - loads[0])
    general = integrate(
        MODEL_LINEAR, M, loads, np.concatenate([K.ravel(), C.ravel()]), np.array([3]), u0, np.zeros(3), a0,
        np.zeros(0), 0.01, n, np.full(3, 1e-9), rho_inf=rho_inf,
    )  # fmt: skip
    assert general.success
    assert np.max(np.abs(u - general.u)) < 1e-9 * np.max(np.abs(u))
    assert np.max(np.abs(v - general.v)) < 1e-8 * np.max(np.abs(v))


def test_compiled_lu_solves_a_pivoting_system():
    from bogie.lu import lu_factor, lu_solve

    a = np.array([[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]])
    b = np.array([1.0, 2.0, 3.0])
    lu, piv, x = a.copy(), np.zeros(3, dtype=np.int64), b.copy()
    assert lu_factor(lu, piv)
    lu_solve(lu, piv, x)
    assert x == pytest.approx(np.linalg.solve(a, b), rel=1e-14)
    assert not lu_factor(np.zeros((2, 2)), np.zeros(2, dtype=np.int64))
