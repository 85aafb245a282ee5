"""Leaf-spring hysteresis (interleaf friction, Fancher's form): docs/models.md, "Leaf-spring hysteresis"."""

import math

import numpy as np
import pytest

from bogie.params import INHIBITORS
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import RampedStep, axle_heights
from bogie.steel import nonlinear as nl
from bogie.steel.force import core

BAND = 2000.0  # [N]
DECAY = 0.005  # [m]


def _only_band(make, band=BAND, **changes):
    """A preset with every inhibitor off but the leaf springs' friction band."""
    return make(**{**INHIBITORS, "spring_friction_band": band, "spring_friction_decay": DECAY, **changes})


def _static_path(bogie, factors, initial=None, road=None):
    factors = np.asarray(factors, dtype=float)
    heights = np.zeros((len(factors), bogie.n_axles)) if road is None else road
    inputs = nl.Inputs(1.0, heights, np.zeros_like(heights), factors, np.zeros(len(factors)))
    run = nl.static_loads(bogie, inputs, initial=initial)
    assert run.success, run.message
    return run


def _trapezoid_work(force, displacement):
    """Work of a force along a path, by the trapezoid rule over the rows [J]."""
    return float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(displacement)))


def _loop_work(band, decay, span):
    """Closed form: work absorbed per cycle by a repeating loop of deflection span ``span`` [J]."""
    top = band * math.tanh(span / (2.0 * decay))
    return 2.0 * band * span - 2.0 * (band + top) * decay * (1.0 - math.exp(-span / decay))


def test_hysteretic_force_follows_the_fancher_branches_whatever_the_step():
    # load from the empty trailer and take it off again: a loading branch from the relaxed start (h = 0)
    # and, after the reversal, an unloading branch; h on each is the closed form of the recorded deflection
    bogie = _only_band(tandem_trrl)
    for rows in (61, 241):  # two step sizes: the rule composes exactly, so h depends only on the deflection
        factors = np.r_[np.linspace(0.25, 1.0, rows), np.linspace(1.0, 0.25, rows)[1:]]
        run = _static_path(bogie, factors)
        delta = run.extras["spring_deflection"]
        h = run.extras["spring_hysteresis"]
        assert h[0] == pytest.approx([0.0, 0.0], abs=1e-9)
        top = rows - 1
        for i in range(bogie.n_axles):
            assert np.all(np.diff(delta[: top + 1, i]) > 0.0) and np.all(np.diff(delta[top:, i]) < 0.0)
            loading = BAND - BAND * np.exp(-(delta[: top + 1, i] - delta[0, i]) / DECAY)
            h_r = loading[-1]
            unloading = -BAND + (h_r + BAND) * np.exp(-(delta[top, i] - delta[top:, i]) / DECAY)
            assert h[: top + 1, i] == pytest.approx(loading, abs=1e-6 * BAND)
            assert h[top:, i] == pytest.approx(unloading, abs=1e-6 * BAND)
        # the unloading ends more than 3 decay lengths after the reversal: within 5 % of the band's width 2 b of the
        # lower envelope (2 b exp(-3) = 0.0996 b)
        assert np.all(delta[top] - delta[-1] > 3 * DECAY)
        assert np.all(h[-1] < -0.9 * BAND)


@pytest.mark.parametrize("make", [tandem_trrl, triaxle_stage1], ids=["tandem", "triaxle"])
def test_a_slow_load_cycle_dissipates_the_loop_work_the_load_puts_in(make):
    # the payload cycles 1.0 -> 0.3 -> 1.0 three times (quasi-statically); the third cycle repeats the second, so
    # the state returns to where the cycle began and the energy balance over it has no stored-energy term:
    # work of the payload on the chassis pitch = work absorbed by the springs' hysteresis (everything else off)
    bogie = _only_band(make)
    n_half = 200
    down = np.linspace(1.0, 0.3, n_half + 1)
    cycle = np.r_[down, down[::-1][1:]]
    factors = np.r_[np.linspace(0.25, 1.0, 101), *[cycle[1:]] * 3]
    run = _static_path(bogie, factors)
    last = slice(len(factors) - len(cycle), len(factors))
    theta = run.extras["chassis_pitch"][last]
    load = run.extras["load_factor"][last]
    # the payload's weight at its centre of gravity, about the king pin: Q_theta = lf W x_cg cos(theta)
    moment = load * bogie.payload_mass * 9.81 * bogie.payload_cg_x * np.cos(theta)
    work_in = _trapezoid_work(moment, theta)
    delta = run.extras["spring_deflection"][last]
    h = run.extras["spring_hysteresis"][last]
    absorbed = [_trapezoid_work(h[:, i], delta[:, i]) for i in range(bogie.n_axles)]
    # the cycle closes: the same configuration and history at its start and end
    u = np.c_[run.extras["chassis_pitch"], run.extras["equaliser_rotation"], run.extras["axle_displacement"]]
    assert u[last][-1] == pytest.approx(u[last][0], abs=1e-7)
    assert h[-1] == pytest.approx(h[0], abs=1e-3 * BAND)
    # each spring's loop absorbs the closed form's work for its span; all of them the work put in
    for i in range(bogie.n_axles):
        span = float(np.ptp(delta[:, i]))
        assert span > 3 * DECAY
        assert absorbed[i] == pytest.approx(_loop_work(BAND, DECAY, span), rel=2e-3)
    assert sum(absorbed) > 0.5 * bogie.n_axles * BAND * DECAY
    assert work_in == pytest.approx(sum(absorbed), rel=2e-3)


def test_without_the_band_the_load_cycle_loop_closes():
    # rows 0-100 load the trailer, 101-300 take 70 % off, 301-500 put it back: row 100 + k and row 500 - k carry
    # the same load, on the way down and on the way up
    down = np.linspace(1.0, 0.3, 201)
    factors = np.r_[np.linspace(0.25, 1.0, 101), down[1:], down[::-1][1:]]
    k = np.arange(0, 201)
    work = {}
    for band in (0.0, BAND):
        bogie = _only_band(tandem_trrl, band=band)
        run = _static_path(bogie, factors)
        delta = run.extras["spring_deflection"]
        gap = np.max(np.abs(delta[100 + k] - delta[500 - k]))
        theta = run.extras["chassis_pitch"][100:]
        moment = run.extras["load_factor"][100:] * bogie.payload_mass * 9.81 * bogie.payload_cg_x * np.cos(theta)
        work[band] = _trapezoid_work(moment, theta)
        if band == 0.0:
            # the same deflections both ways (to the solver's tolerance, 0.2 N / 0.6 kN/mm), no hysteretic force
            assert np.all(run.extras["spring_hysteresis"] == 0.0)
            assert gap < 1e-6
        else:
            assert gap > 0.25 * 2 * BAND / 6e5  # a loop: 2 b / K_R = 6.7 mm apart on the envelopes, less inside
    # the work over the cycle without the band is nothing against the band's
    assert work[BAND] > 0.5 * BAND * DECAY
    assert abs(work[0.0]) < 1e-4 * work[BAND]


def _over_the_step(bogie, rows=700):
    """Load the trailer from empty, then roll it quasi-statically over the 25 mm ramped step and off it."""
    loaded = _static_path(bogie, np.linspace(0.25, 1.0, 151))
    road = axle_heights(RampedStep(), bogie.axle_x, 4.8, np.linspace(0.0, 1.0, rows), -0.5)
    run = _static_path(bogie, np.ones(rows), initial=loaded.final_state, road=road)
    assert np.all(road[0] == 0.0) and np.all(road[-1] == 0.0) and road.max() == pytest.approx(0.025)
    return loaded, run


def test_with_a_free_equaliser_the_band_changes_the_geometry_but_not_the_loads():
    # the preface: hysteresis "causes geometric change in the system without changing load". A free, level
    # equaliser balances its spring ends whatever the springs' state, so the loads stay equal (to second order in
    # the rotations); the laden springs sit on the loading envelope, b / K_R higher, which turns the equaliser
    on, run_on = _over_the_step(_only_band(tandem_trrl))
    off, run_off = _over_the_step(_only_band(tandem_trrl, band=0.0))
    for run in (on, run_on, off, run_off):
        w = run.wheel_loads[-1]
        assert abs(w[1] - w[0]) < 1.0  # N, of 22 kN
    assert np.all(on.extras["spring_hysteresis"][-1] > 0.95 * BAND)  # loaded: on the loading envelope
    raised = on.extras["spring_deflection"][-1] - off.extras["spring_deflection"][-1]
    assert raised == pytest.approx([-BAND / 6e5] * 2, rel=0.05)  # b / K_R = 3.3 mm less deflection
    turn_on = run_on.extras["equaliser_rotation"][-1, 0]
    turn_off = run_off.extras["equaliser_rotation"][-1, 0]
    assert abs(turn_off) < 1e-6 and abs(turn_on) > 2e-3  # rad


def test_through_a_stiff_bush_the_band_leaves_a_load_difference_that_the_step_changes():
    # the same with the preset's bush stiffness, the pivot's "sufficient rotational stiffness": band off, the
    # bogie comes off the step with equal loads, as it went on; band on, the loads differ before and after, and
    # the step's deflections leave the springs at another point of their loops, so the difference changes
    k_b = tandem_trrl().bush_stiffness
    on, run_on = _over_the_step(_only_band(tandem_trrl, bush_stiffness=k_b))
    off, run_off = _over_the_step(_only_band(tandem_trrl, band=0.0, bush_stiffness=k_b))
    diff = {name: r.wheel_loads[-1, 1] - r.wheel_loads[-1, 0] for name, r in
            (("on", on), ("run_on", run_on), ("off", off), ("run_off", run_off))}  # fmt: skip
    assert abs(diff["off"]) < 0.5 and abs(diff["run_off"]) < 0.5
    assert abs(diff["on"]) > 10.0 and abs(diff["run_on"]) > 3.0
    assert abs(diff["run_on"] - diff["on"]) > 10.0
    # during the step the loads differ by kN either way: the band only changes what is left afterwards
    assert np.max(np.abs(np.diff(run_on.wheel_loads, axis=1))) > 1000.0
    # the bush moment K_B phi is what holds the difference: the equaliser turned relative to the chassis
    assert abs(run_on.extras["equaliser_rotation"][-1, 0]) > 1e-4


def test_history_has_the_springs_state_and_a_wrong_history_is_refused():
    bogie = tandem_trrl()
    state = nl.equilibrium(bogie, np.r_[np.zeros(4), 1.0, bogie.kingpin_height_offset])
    where = core.history_slices(2)
    assert state.history.shape == (core.history_length(2),) == (8,)
    assert np.all(state.history[where["spring_hysteresis"]] == 0.0)  # relaxed: on the elastic line
    assert np.all(state.slip == state.history[where["plastic_slip"]])
    short = nl.State(u=state.u, v=state.v, a=state.a, history=state.history[:4])
    with pytest.raises(ValueError, match=r"initial.history has shape \(4,\).*8 entries"):
        nl.simulate(bogie, nl.hold(bogie, 0.01, 0.01), initial=short)
