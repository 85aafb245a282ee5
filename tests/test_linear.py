import math

import numpy as np
import pytest

from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import Flat
from bogie.steel import linear, static


def test_freedoms_and_matrix_properties():
    m = linear.matrices(tandem_trrl())
    assert m.dofs == ("chassis_pitch", "equaliser_0", "axle_0", "axle_1", "tyre_0", "tyre_1")
    assert np.allclose(m.K, m.K.T) and np.allclose(m.C, m.C.T)
    assert np.all(np.linalg.eigvalsh(m.K) > 0.0)
    tri = linear.matrices(triaxle_stage1())
    assert tri.K.shape == (9, 9)
    # tyre contact nodes carry no mass
    assert np.all(np.diag(tri.M)[6:] == 0.0)


@pytest.mark.parametrize("bogie", [tandem_trrl(), triaxle_stage1()])
def test_design_position_is_an_equilibrium_with_equal_loads(bogie):
    m = linear.matrices(bogie)
    assert np.allclose(linear.static_state(bogie, m), 0.0)
    assert np.ptp(m.design_wheel_loads) < 1e-9 * m.design_wheel_loads[0]


@pytest.mark.parametrize("make", [tandem_trrl, triaxle_stage1])
@pytest.mark.parametrize("tilt_deg", [-1.5, 0.5, 2.0])
def test_static_state_agrees_with_the_stage_2_model(make, tilt_deg):
    # the linear dynamic model at rest is the Stage 2 model with stiff ground springs (1000 x the tyre)
    bogie = make(axle_mass=0.0, chassis_tilt=math.radians(tilt_deg))
    m = linear.matrices(bogie)
    u = linear.static_state(bogie, m)
    loads = linear.wheel_loads_from_state(bogie, m, u, np.zeros_like(u), np.zeros(bogie.n_axles))
    pitch = u[0]
    drop = m.design_wheel_loads[0] / bogie.combined_stiffness
    alpha = drop - bogie.kingpin_height_offset + bogie.bogie_centre_x * pitch
    expected = static.solve_static(bogie, alpha, pitch)
    assert loads == pytest.approx(expected.wheel_loads, rel=2e-3)
    phi = u[1 : bogie.n_axles] - pitch
    assert phi == pytest.approx(expected.equaliser_rotation, rel=5e-3, abs=1e-7)


def test_nose_up_overloads_rear_and_free_bush_equalises_statically():
    stiff = tandem_trrl(chassis_tilt=math.radians(1.0))
    m = linear.matrices(stiff)
    loads = linear.wheel_loads_from_state(stiff, m, linear.static_state(stiff, m), np.zeros(6), np.zeros(2))
    assert loads[1] > loads[0]
    free = stiff.replace(bush_stiffness=0.0)
    m = linear.matrices(free)
    loads = linear.wheel_loads_from_state(free, m, linear.static_state(free, m), np.zeros(6), np.zeros(2))
    assert np.ptp(loads) < 1e-8 * loads.mean()


def test_chassis_moment_balance_about_the_king_pin():
    bogie = triaxle_stage1(chassis_tilt=math.radians(1.0), axle_mass=0.0)
    m = linear.matrices(bogie)
    loads = linear.wheel_loads_from_state(bogie, m, linear.static_state(bogie, m), np.zeros(9), np.zeros(3))
    # small angles: the wheel loads' moment about the king pin carries the weight's moment
    moment = np.sum(loads * np.asarray(bogie.axle_x))
    assert moment == pytest.approx(bogie.payload_mass * 9.81 * bogie.payload_cg_x, rel=1e-9)


def test_flat_road_run_stays_at_rest():
    r = linear.simulate(tandem_trrl(), Flat(), speed=10.0, dt=0.01, n_steps=100)
    assert r.success
    assert np.max(np.abs(r.wheel_loads - r.wheel_loads[0])) < 1e-6
    assert np.all(r.p < 1e-12)
