"""Equaliser bump stops (``docs/models.md``, "Equaliser stops"): held rotation, no effect when far, zero inside,
equal and opposite, conservative; and ``equilibrium`` refusing solutions outside the freedoms' limits."""

import math

import numpy as np
import pytest

from bogie.params import (
    GRAVITY,
    INHIBITORS,
    NO_STOP,
    PRESET_EQUALISER_STOP,
    PRESET_EQUALISER_STOP_STIFFNESS,
    SCALAR_RANGES,
)
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import RampedStep
from bogie.steel import nonlinear as nl
from bogie.steel.force import core

TWO_DEGREES = math.radians(2.0)


def _laden(bogie, dt=0.002):
    """Load from empty to full, then settle: a static state reached the way a real loading would."""
    return nl.simulate(bogie, nl.load_ramp(bogie, 0.25, 1.0, 2.0, dt).then(nl.hold(bogie, 2.0, dt)))


def _force(bogie, u, drive=None, hist=None):
    """The compiled f = -Q at rest at u with the history ``hist`` (zeros if None), and the record."""
    n = bogie.n_axles
    _, data_f, data_i = nl.pack(bogie)
    drive = np.r_[np.zeros(2 * n), 1.0, bogie.kingpin_height_offset] if drive is None else drive
    f = np.zeros(2 * n)
    rec = np.zeros(core.record_length(n))
    hist = np.zeros(core.history_length(n)) if hist is None else np.asarray(hist, dtype=float)
    core.force(
        np.asarray(u, dtype=float), np.zeros(2 * n), drive, data_f, data_i, hist, hist.copy(), f,
        np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n)), rec, True, False, np.zeros(core.work_size(n)),
    )  # fmt: skip
    return f, rec[core.record_slices(n)["stop_moment"]]


def _potential(phi, stop, k):
    """The stop's strain energy V(phi) [J] (docs/models.md), written here from the derivation alone."""
    e = abs(phi) - stop
    e0 = core.STOP_ONSET
    if e <= 0.0:
        return 0.0
    if e < e0:
        return k * e**3 / (6.0 * e0)
    return 0.5 * k * (e - 0.5 * e0) ** 2 + k * e0**2 / 24.0


def test_presets_have_the_documented_stop_and_it_is_in_the_public_table():
    for make in (tandem_trrl, triaxle_stage1):
        b = make()
        assert b.equaliser_stop == pytest.approx(math.radians(15.0))
        assert b.equaliser_stop_stiffness == 8.4e4
        assert b.without().equaliser_stop == b.equaliser_stop  # not an inhibitor: a limit of travel
    # the pad's derivation: 60 x 60 x 12 mm, 60 IRHD (E 4.45 MPa, k 0.57) at 0.15 m
    shape = 0.06 * 0.06 / (4 * 0.06 * 0.012)
    e_c = 4.45e6 * (1.0 + 2.0 * 0.57 * shape**2)
    assert PRESET_EQUALISER_STOP_STIFFNESS == pytest.approx(e_c * 0.06 * 0.06 / 0.012 * 0.15**2, rel=0.01)
    assert PRESET_EQUALISER_STOP == pytest.approx(math.asin(0.04 / 0.155), rel=0.01)
    assert SCALAR_RANGES["equaliser_stop"].contains(NO_STOP)
    assert not SCALAR_RANGES["equaliser_stop"].contains(0.0)


@pytest.mark.parametrize(
    "field, value, fragment",
    [
        ("equaliser_stop", 0.0, "equaliser_stop = 0.0 is out of range: must be in (0, 3.14159] rad"),
        ("equaliser_stop", 4.0, "equaliser_stop = 4.0 is out of range"),
        ("equaliser_stop", math.inf, "equaliser_stop = inf is out of range"),
        (
            "equaliser_stop_stiffness",
            -1.0,
            "equaliser_stop_stiffness = -1.0 is out of range: must be in [0, 1e+09] N m/rad",
        ),
    ],
)
def test_stop_fields_are_validated_with_field_value_range_and_unit(field, value, fragment):
    with pytest.raises(ValueError) as err:
        triaxle_stage1(**{field: value})
    assert fragment in str(err.value)


def test_a_free_triaxle_equaliser_at_two_degrees_is_held_by_its_stop():
    free = triaxle_stage1(bush_stiffness=0.0, chassis_tilt=TWO_DEGREES)
    held = _laden(free)
    loose = _laden(free.replace(equaliser_stop=NO_STOP))
    assert held.success and loose.success
    stop, k = free.equaliser_stop, free.equaliser_stop_stiffness
    rot = np.abs(held.extras["equaliser_rotation"])
    moment = np.abs(held.extras["stop_moment"])
    # within the stop plus the contact's compliance (onset and the pad's compression under its moment), every step
    assert np.all(rot <= stop + 0.5 * core.STOP_ONSET + moment / k + 1e-9)
    assert np.max(moment[-1]) > 50.0  # it carries load at the end: a valid run, recorded
    assert np.max(np.abs(loose.extras["equaliser_rotation"][-1])) > math.radians(18.0)  # without: 18.3 degrees
    assert np.all(loose.extras["stop_moment"] == 0.0)
    # the stop moment acts only beyond the stop angle, with the sign of the rotation
    beyond = rot > stop
    assert np.all(moment[~beyond] == 0.0)
    assert np.all(np.sign(held.extras["stop_moment"][beyond]) == np.sign(held.extras["equaliser_rotation"][beyond]))


def test_a_stop_far_away_changes_nothing():
    # a step run that turns the equalisers a few degrees: stops off, stops at 80 degrees, a zero stiffness and the
    # preset's 15 degrees (never reached here) all give the same bits
    base = triaxle_stage1()
    inputs = nl.road_inputs(base, RampedStep(rise=0.02), 1.0, 4.0, 0.002, -0.5)
    runs = [
        nl.simulate(base.replace(**c), inputs)
        for c in (
            {"equaliser_stop": NO_STOP},
            {"equaliser_stop": math.radians(80.0)},
            {"equaliser_stop_stiffness": 0.0, "equaliser_stop": math.radians(1.0)},
            {},
        )
    ]
    assert np.max(np.abs(runs[0].extras["equaliser_rotation"])) > math.radians(1.0)
    assert np.max(np.abs(runs[3].extras["equaliser_rotation"])) < base.equaliser_stop
    for r in runs[1:]:
        assert np.array_equal(r.wheel_loads, runs[0].wheel_loads)
        assert np.array_equal(r.extras["equaliser_rotation"], runs[0].extras["equaliser_rotation"])
        assert np.all(r.extras["stop_moment"] == 0.0)


def test_the_stop_moment_is_zero_inside_equal_and_opposite_and_follows_its_law():
    bogie = triaxle_stage1(bush_stiffness=0.0, friction_coefficient=0.0)
    off = bogie.replace(equaliser_stop=NO_STOP)
    stop, k, e0 = bogie.equaliser_stop, bogie.equaliser_stop_stiffness, core.STOP_ONSET
    for phi, expected in (
        (0.9 * stop, 0.0),
        (-0.9 * stop, 0.0),
        (stop + 0.5 * e0, 0.5 * k * (0.5 * e0) ** 2 / e0),
        (-(stop + 0.01), -k * (0.01 - 0.5 * e0)),
    ):
        u = np.array([0.01, 0.01 + phi, 0.002, 0.001, 0.0, -0.001])
        f_on, m_on = _force(bogie, u)
        f_off, m_off = _force(off, u)
        assert m_on[0] == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert m_off[0] == 0.0 and m_on[1] == 0.0
        diff = f_on - f_off
        # on equaliser 0 (f = -Q: it resists), the reaction on the chassis, nothing on the axles or equaliser 1
        assert diff[1] == pytest.approx(expected, rel=1e-9, abs=1e-9)
        assert diff[0] == pytest.approx(-expected, rel=1e-9, abs=1e-9)
        assert np.all(diff[2:] == 0.0)


def test_the_held_equilibrium_balances_the_chassis_about_the_king_pin():
    # the stop is internal to the bogie (equal and opposite), so the whole still balances the payload's moment
    bogie = triaxle_stage1(bush_stiffness=0.0, friction_coefficient=0.0, chassis_tilt=TWO_DEGREES)
    n = bogie.n_axles
    state = nl.equilibrium(bogie, np.r_[np.zeros(2 * n), 1.0, bogie.kingpin_height_offset])
    f, moment = _force(bogie, state.u, hist=state.history)
    assert np.max(np.abs(moment)) > 50.0  # the stop carries load in this equilibrium
    phi = state.u[1:n] - state.u[0]
    assert np.all(np.abs(phi) <= bogie.equaliser_stop + 0.5 * core.STOP_ONSET + np.abs(moment) / 8.4e4 + 1e-9)
    tol = nl.residual_tolerance(bogie)
    assert np.all(np.abs(f) <= tol)
    run = nl.static_loads(bogie, nl.hold(bogie, 1.0, 1.0), initial=state)
    springs = run.extras["spring_load"][-1]
    weight = bogie.payload_mass * GRAVITY * bogie.payload_cg_x * math.cos(state.u[0])
    assert np.sum(springs * np.asarray(bogie.axle_x)) == pytest.approx(weight, rel=3e-3)
    # the equalisers: each balances its tip loads' moment against the stop alone (bush free): the moment the stop
    # carries is the imbalance the equaliser could not turn away
    assert np.all(np.abs(f[1:n]) <= tol[1:n])


def test_the_stop_is_conservative():
    # the recorded moment is the derivative of the stop's strain energy, so a closed path stores nothing
    bogie = triaxle_stage1(bush_stiffness=0.0, friction_coefficient=0.0)
    stop, k = bogie.equaliser_stop, bogie.equaliser_stop_stiffness
    for phi in np.r_[np.linspace(stop - 0.002, stop + 0.02, 23), -np.linspace(stop - 0.002, stop + 0.02, 23)]:
        u = np.array([0.0, phi, 0.0, 0.0, 0.0, 0.0])
        _, m = _force(bogie, u)
        h = 1e-6
        dv = (_potential(phi + h, stop, k) - _potential(phi - h, stop, k)) / (2 * h)
        assert m[0] == pytest.approx(dv, rel=1e-5, abs=1e-3)
    # a frictionless quasi-static tilt cycle into the stop and back: no hysteresis (nothing dissipated)
    free = tandem_trrl(**INHIBITORS).replace(tyre_damping=0.0)
    n = free.n_axles
    xb = free.bogie_centre_x
    tilts = np.radians(np.r_[np.linspace(0.0, 3.0, 31), np.linspace(3.0, 1.0, 21)[1:]])
    rows = len(tilts)
    zeros = np.zeros((rows, n))
    path = nl.static_loads(free, nl.Inputs(1.0, zeros, zeros.copy(), np.ones(rows), xb * np.tan(tilts)))
    assert path.success
    assert np.max(np.abs(path.extras["stop_moment"])) > 50.0  # the cycle did load the stop
    direct = nl.equilibrium(free, np.r_[np.zeros(2 * n), 1.0, xb * math.tan(math.radians(1.0))])
    on_way_up = int(np.argmin(np.abs(tilts[:31] - math.radians(1.0))))
    # to the solver's tolerance (a free, frictionless equaliser is soft: its residual tolerance is 3e-6 rad)
    assert path.final_state.u == pytest.approx(direct.u, abs=1e-5)
    assert path.wheel_loads[-1] == pytest.approx(path.wheel_loads[on_way_up], rel=1e-5)


def test_equilibrium_refuses_a_solution_outside_the_freedoms_limits():
    # the case: a tri-axle with 40 mm tip drops at 2 degrees, inhibitors off. Without stops the static
    # Newton returned equaliser 0 at 75.5 degrees (73.7 relative) on a slack spring: now refused by name
    case = dict(**INHIBITORS, equaliser_front_tip_drop=0.04, equaliser_rear_tip_drop=0.04, chassis_tilt=TWO_DEGREES)
    loose = triaxle_stage1(**case, equaliser_stop=NO_STOP)
    drive = np.r_[np.zeros(6), 1.0, loose.kingpin_height_offset]
    # following the equilibrium up from the level bogie finds none inside the limits either: the free equalisers
    # with low pads are inverted pendulums, and beyond about 0.8 degrees they have nowhere to stop
    with pytest.raises(
        ValueError,
        match=r"equaliser_0 = 75\.\d+ degrees, beyond its limit of \+-60 degrees.*"
        r"following the equilibrium from the design state: stopped at \d+(\.\d+)? % of the way",
    ):
        nl.equilibrium(loose, drive)
    # with the stops the equalisers cannot get there: the direct Newton does not converge, and the continuation
    # from the level bogie finds the equilibrium with both equalisers on their stops
    held = triaxle_stage1(**case)
    state = nl.equilibrium(held, drive)
    assert np.all(np.abs(state.u) <= nl.limits(held))
    phi = state.u[1:3] - state.u[0]
    _, moment = _force(held, state.u, hist=state.history)
    assert np.all(np.abs(phi) > held.equaliser_stop)  # on the stops, nose up turns them nose down
    assert np.all(np.abs(phi) <= held.equaliser_stop + 0.5 * core.STOP_ONSET + np.abs(moment) / 8.4e4 + 1e-9)
    loads = nl.static_loads(held, nl.hold(held, 1.0, 1.0), initial=state).wheel_loads[-1]
    # the rear axle overloads, the front unloads, as the preface says of a tipped trailer: 16 / 26 / 38 kN
    assert loads[0] < loads[1] < loads[2] and (loads.max() - loads.mean()) / loads.mean() > 0.3
