import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bogie.metrics import p
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.steel.static import equation1_mapping, nondimensional_loads, solve_static, wheel_loads

q_values = st.floats(min_value=0.0, max_value=1e4, allow_nan=False)
d_values = st.floats(min_value=-5.0, max_value=5.0, allow_nan=False)


def test_equation_1_exactly_for_three_axles():
    q, d = 4.3, 0.6
    a = np.array([[1 + q, -q, 0], [-q, 1 + 2 * q, -q], [0, -q, 1 + q]])
    expected = np.linalg.solve(a, [1 + d, 1, 1 - d])
    assert nondimensional_loads(q, d) == pytest.approx(expected, rel=1e-13)


@given(q=q_values, d=d_values, n=st.integers(2, 6))
@settings(max_examples=200, deadline=None)
def test_total_load_is_conserved(q, d, n):
    assert np.sum(nondimensional_loads(q, d, n)) == pytest.approx(n, rel=1e-12)


@given(q=q_values, n=st.integers(2, 6))
@settings(max_examples=50, deadline=None)
def test_zero_slope_gives_equal_loads(q, n):
    assert nondimensional_loads(q, 0.0, n) == pytest.approx(np.ones(n), rel=1e-12)


@given(q=q_values, d=d_values)
@settings(max_examples=100, deadline=None)
def test_reversing_slope_reverses_axle_order(q, d):
    assert nondimensional_loads(q, -d) == pytest.approx(nondimensional_loads(q, d)[::-1], rel=1e-12, abs=1e-12)


def test_p_falls_as_q_grows_and_grows_with_slope():
    q = np.linspace(0.0, 50.0, 200)
    for d in (0.2, 0.5, 0.8):
        pq = p(nondimensional_loads(q, d))
        assert np.all(np.diff(pq) < 0.0)
    ds = np.linspace(0.0, 2.0, 50)
    pd = p(nondimensional_loads(4.3, ds))
    assert np.all(np.diff(pd) > 0.0)
    assert p(nondimensional_loads(0.0, 0.5)) == pytest.approx(math.sqrt(2) * 0.5)


def test_free_bush_limit_and_broadcast_shape():
    assert nondimensional_loads(np.inf, 0.7) == pytest.approx([1.0, 1.0, 1.0])
    out = nondimensional_loads(np.array([[0.0], [1.0], [5.0]]), np.array([0.1, 0.2]), n_axles=4)
    assert out.shape == (3, 2, 4)


def test_stiff_bush_leaves_tilt_unequalised():
    # q = 0: no load transfer, each axle carries its own deflection
    assert nondimensional_loads(0.0, 0.4) == pytest.approx([1.4, 1.0, 0.6])
    assert nondimensional_loads(0.0, 0.4, n_axles=2) == pytest.approx([1.2, 0.8])


def test_nondimensional_loads_refuses_bad_input():
    with pytest.raises(ValueError, match=r"q = -1.0 is out of range: must be >= 0 - \(stiffness ratio .*inf: a free"):
        nondimensional_loads(-1.0, 0.1)
    with pytest.raises(ValueError, match="n_axles = 1"):
        nondimensional_loads(1.0, 0.1, n_axles=1)


@pytest.mark.parametrize("slope_deg", [0.0, 0.5, 1.0, 2.0, -1.5])
@pytest.mark.parametrize("k_b", [10.0, 609.0, 5000.0])
def test_dimensional_solve_maps_onto_equation_1(slope_deg, k_b):
    bogie = triaxle_stage1(bush_stiffness=k_b)
    alpha, psi = 0.057, math.radians(slope_deg)
    q, d = equation1_mapping(bogie, alpha, psi)
    assert q == pytest.approx(0.155**2 * bogie.combined_stiffness / (4 * k_b))
    assert d == pytest.approx(-psi * 1.31 / alpha)
    loads = wheel_loads(bogie, alpha, psi)
    assert loads / (alpha * bogie.combined_stiffness) == pytest.approx(nondimensional_loads(q, d), rel=1e-12)


def test_nose_up_overloads_rear_axle():
    for bogie in (triaxle_stage1(), tandem_trrl()):
        loads = wheel_loads(bogie, 0.05, math.radians(1.0))
        assert loads[-1] > loads[0]
        assert np.all(np.diff(loads) > 0)


@pytest.mark.parametrize("bogie", [triaxle_stage1(), tandem_trrl()])
def test_equilibrium_of_the_dimensional_solve(bogie):
    alpha, psi = 0.05, math.radians(1.2)
    wear = np.linspace(0.0, 0.008, bogie.n_axles)
    sol = solve_static(bogie, alpha, psi, wear)
    k_s = bogie.combined_stiffness
    # symmetric springs and arms: equaliser rotations move no load in total
    assert np.sum(sol.wheel_loads) == pytest.approx(k_s * (bogie.n_axles * alpha - wear.sum()), rel=1e-12)
    # each equaliser: moment of its two spring-end loads equals the bush moment
    for j, phi in enumerate(sol.equaliser_rotation):
        b = bogie.equaliser_front_arm[j]
        moment = b * 0.5 * sol.wheel_loads[j] - b * 0.5 * sol.wheel_loads[j + 1]
        assert moment == pytest.approx(bogie.bush_stiffness * phi, rel=1e-10)


@given(
    slope=st.floats(-3.0, 3.0),
    wear=st.lists(st.floats(0.0, 0.012), min_size=3, max_size=3),
)
@settings(max_examples=60, deadline=None)
def test_free_bush_equalises_any_tilt_and_wear(slope, wear):
    bogie = triaxle_stage1(bush_stiffness=0.0)
    loads = wheel_loads(bogie, 0.057, math.radians(slope), wear)
    assert loads == pytest.approx(np.full(3, loads.mean()), rel=1e-10)


def test_unequal_arms_free_bush_gives_the_lever_ratio():
    bogie = tandem_trrl(
        bush_stiffness=0.0,
        axle_x=(7.345, 8.655),
        equaliser_front_arm=(0.2,),
        equaliser_rear_arm=(0.11,),
    )
    loads = wheel_loads(bogie, 0.05, 0.01)
    assert loads[1] / loads[0] == pytest.approx(0.2 / 0.11, rel=1e-10)


def test_worn_tyre_unloads_its_axle_with_stiff_bush():
    bogie = triaxle_stage1(bush_stiffness=1e7)
    loads = wheel_loads(bogie, 0.057, 0.0, [0.0, 0.01, 0.0])
    assert loads[1] < loads[0] == pytest.approx(loads[2])
