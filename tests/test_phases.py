"""bogie.steel.phases: a weighing's phases in one compiled call, fixed or adaptive steps, only the readings kept."""

import math

import numpy as np
import pytest

from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import ISO8608Profile, Sinusoid
from bogie.road.wim import sensor_reading
from bogie.steel import nonlinear as nl
from bogie.steel import phases as ph


@pytest.fixture(scope="module")
def bogie():
    return triaxle_stage1().replace(bush_damping=20.0)


@pytest.fixture(scope="module")
def road():
    profile = ISO8608Profile("B", length=100.0, seed=3)
    return ph.RoadTable.from_profile(profile, -5.0, 60.0, profile.grid_spacing)


def test_fixed_steps_follow_the_fixed_step_integrator(bogie):
    # a load ramp and a hold in fixed 1 ms steps: the same Newmark residual and drive values as nonlinear.simulate
    ramp_in = nl.load_ramp(bogie, 0.25, 1.0, 1.0, 1e-3)
    hold_in = nl.hold(bogie, 1.0, 1e-3)
    first = nl.simulate(bogie, ramp_in)
    second = nl.simulate(bogie, hold_in, initial=first.final_state)
    phases = [ph.Phase(1.0, (0.25, 1.0), dt=1e-3), ph.Phase(1.0, 1.0, dt=1e-3, reading=ph.MeanReading(0.5, 1.0))]
    for check_every in (1, 16):
        run = ph.run(bogie, phases, check_every=check_every)
        assert run.success
        # checked at every step: the same converged states up to the Newton tolerance; unchecked corrections differ
        # from those by their own size, far below it
        assert np.max(np.abs(run.final_state.u - second.final_state.u)) < 1e-7
        window = second.t >= 0.5
        trapezoid = np.trapezoid(second.wheel_loads[window], second.t[window], axis=0) / 0.5
        assert run.phases[1].reading == pytest.approx(trapezoid, abs=0.5)
        assert run.phases[0].steps == 1000 and run.phases[1].steps == 1000


def test_unchecked_corrections_save_evaluations_without_moving_the_reading(bogie, road):
    phases = [ph.Phase(2.5, 1.0, road=road, speed=15.0, dt=1e-3, reading=ph.MeanReading(2.0, 2.5))]
    checked = ph.run(bogie, phases, check_every=1)
    default = ph.run(bogie, phases)
    assert checked.phases[0].unchecked == 0 and default.phases[0].unchecked > 1000
    assert default.phases[0].force_evaluations < 0.8 * checked.phases[0].force_evaluations
    assert np.max(np.abs(default.phases[0].reading - checked.phases[0].reading)) < 5.0  # N, of 28 kN wheel loads


def test_adaptive_steps_converge_to_the_fixed_step_reference(bogie, road):
    # a crawl over the road then a settle, adaptive with a falling tolerance against fixed steps of 0.125 ms
    def phases(tolerance, dt=1e-3):
        return [
            ph.Phase(3.0, 1.0, road=road, speed=1.4, front_axle_start=0.0, dt=dt, tolerance=tolerance),
            ph.Phase(1.5, 1.0, dt=dt, tolerance=tolerance, reading=ph.MeanReading(1.0, 1.5)),
        ]

    reference = ph.run(bogie, phases(None, 1.25e-4)).phases[1].reading
    errors, steps = [], []
    for tolerance in (2e-6, 2e-7, 2e-8):
        run = ph.run(bogie, phases(tolerance))
        assert run.success
        errors.append(np.max(np.abs(run.phases[1].reading - reference)))
        steps.append(sum(p.steps for p in run.phases))
    assert errors[2] < errors[0] and errors[2] < 2.0
    assert steps[0] < steps[1] < steps[2]
    assert steps[1] < 0.5 * 4500  # far fewer than fixed steps of 1 ms over the 4.5 s


def test_a_bogie_at_rest_stays_there_in_a_few_long_steps(bogie):
    hold = ph.Phase(3.0, 1.0, dt=1e-3, tolerance=1e-7, max_step=0.05, reading=ph.MeanReading(2.5, 3.0))
    run = ph.run(bogie, [hold], history=True)
    static = nl.simulate(bogie, nl.hold(bogie, 1e-3, 1e-3)).wheel_loads[0]
    assert run.phases[0].reading == pytest.approx(static, abs=1e-3)
    assert run.phases[0].steps < 120  # 3 s at most 50 ms, after the first 1 ms steps grow four-fold
    assert np.all(np.diff(run.t) <= 0.05 + 1e-12) and run.t[-1] == pytest.approx(3.0, abs=1e-12)
    assert 2.5 in run.t  # a step ends on the window's start


def test_a_sensor_reads_the_patch_weighted_mean_of_the_history(bogie):
    # a sinusoidal road at 20 m/s: the kernel's sensor integral equals bogie.road.wim.sensor_reading on its own history
    table = ph.RoadTable.from_profile(Sinusoid(0.004, 1.7, start=2.0), -5.0, 50.0, 0.003)
    speed, sensor_length, contact_length = 20.0, 0.5, 0.2
    half = 0.5 * (sensor_length + contact_length) / speed
    flat = 0.5 * abs(sensor_length - contact_length) / speed
    reading = ph.SensorReading(30.0 / speed, half, flat)
    run = ph.run(bogie, [ph.Phase(1.8, 1.0, road=table, speed=speed, dt=1e-3, reading=reading)], history=True)
    offsets = np.asarray(bogie.axle_x) - bogie.axle_x[0]
    expected = [
        sensor_reading(run.t, run.wheel_loads[:, i], 30.0 / speed + offsets[i] / speed, speed, sensor_length,
                       contact_length)
        for i in range(bogie.n_axles)
    ]  # fmt: skip
    assert run.phases[0].reading == pytest.approx(expected, rel=1e-12)
    # and it is a mean over the passage, not the force at the centre: the road moves the wheels over it
    at_centre = [np.interp(30.0 / speed + offsets[i] / speed, run.t, run.wheel_loads[:, i]) for i in range(3)]
    assert np.max(np.abs(np.subtract(expected, at_centre))) > 10.0


def test_readings_taken_only_near_their_window_are_the_bits_of_readings_taken_at_every_step(bogie, road):
    # without a history the kernel takes the tyre loads and stop moments only from a margin before a reading's window
    # to a step past it; with one, at every step. Both must give the same readings, flags and states, bit for bit:
    # fixed steps with a sensor mid-pass, adaptive steps with a mean reading after a crawl, and adaptive steps with a
    # sensor (its window is no step boundary: the margin is the phase's largest step)
    speed = 15.0
    half, flat = 0.35 / speed, 0.15 / speed
    cases = [
        [ph.Phase(2.5, 1.0, road=road, speed=speed, dt=1e-3, reading=ph.SensorReading(1.2, half, flat))],
        [
            ph.Phase(1.0, (0.4, 1.0), dt=1e-3, tolerance=1e-7),
            ph.Phase(3.0, 1.0, road=road, speed=1.4, front_axle_start=0.0, dt=1e-3, tolerance=3e-7),
            ph.Phase(1.5, 1.0, dt=1e-3, tolerance=1e-7, reading=ph.MeanReading(1.0, 1.5)),
        ],
        [ph.Phase(2.5, 1.0, road=road, speed=speed, dt=1e-3, tolerance=3e-7, max_step=0.01,
                  reading=ph.SensorReading(1.2, half, flat))],
    ]  # fmt: skip
    for phases in cases:
        quick, traced = ph.run(bogie, phases), ph.run(bogie, phases, history=True)
        assert quick.success and traced.success
        for a, b in zip(quick.phases, traced.phases):
            assert (a.reading is None) == (b.reading is None)
            if a.reading is not None:
                assert a.reading.tobytes() == b.reading.tobytes(), a.name
            assert (a.on_stop, a.steps, a.rejected) == (b.on_stop, b.steps, b.rejected)
        assert quick.final_state.u.tobytes() == traced.final_state.u.tobytes()
        assert np.all(np.isfinite(quick.phases[-1].reading)) and np.min(quick.phases[-1].reading) > 1e4


def test_results_are_a_pure_function_of_the_inputs(bogie, road):
    phases = [
        ph.Phase(2.0, (0.3, 0.9), dt=1e-3, tolerance=1e-7),
        ph.Phase(2.0, 0.9, road=road, speed=1.4, dt=1e-3, tolerance=2e-7, reading=ph.MeanReading(1.5, 2.0)),
    ]
    a, b = ph.run(bogie, phases), ph.run(bogie, phases)
    assert a.phases[1].reading.tobytes() == b.phases[1].reading.tobytes()
    assert [p.steps for p in a.phases] == [p.steps for p in b.phases]
    assert a.final_state.u.tobytes() == b.final_state.u.tobytes()
    assert a.final_state.history.tobytes() == b.final_state.history.tobytes()
    # and chained: the second phase from the first one's state gives the same as both in one call
    first = ph.run(bogie, phases[:1])
    second = ph.run(bogie, phases[1:], initial=first.final_state)
    assert second.phases[0].reading.tobytes() == a.phases[1].reading.tobytes()


def test_a_failed_phase_is_a_failed_run_with_its_reason_never_nan():
    bogie = tandem_trrl()
    # a 0.4 m wall taken at 20 m/s: the axles leave the model's range of validity
    table = ph.RoadTable(0.0, 0.01, np.r_[np.zeros(200), np.full(400, 0.4)])
    run = ph.run(bogie, [ph.Phase(0.2, 1.0, road=table, speed=20.0, front_axle_start=1.5, dt=1e-3, name="wall")])
    assert not run.success and run.final_state is None
    assert "phase 'wall'" in run.message and "at t = " in run.message
    assert run.phases[0].reading is None


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: ph.Phase(-1.0), r"duration = -1.0 is out of range: must be > 0 s"),
        (lambda: ph.Phase(1.0, dt=0.0), r"dt = 0.0 is out of range: must be in \(0, 1\] s \(at most the duration\)"),
        (lambda: ph.Phase(1.0, dt=2.0), r"dt = 2.0 is out of range: must be in \(0, 1\] s \(at most the duration\)"),
        (lambda: ph.Phase(1.0, tolerance=-1e-7), r"tolerance = -1e-07 is out of range: must be > 0 m"),
        (lambda: ph.Phase(1.0, load_factor=(0.2, 2.5)), r"load_factor = 2.5 is out of range: must be in \(0, 2\] -"),
        (lambda: ph.Phase(1.0, reading=ph.MeanReading(0.5, 1.5)), r"reading window \[0.5, 1.5\] s must lie in"),
        (lambda: ph.Phase(1.0, reading=ph.SensorReading(0.5, 0.01, 0.0)), r"needs a speed > 0 m/s"),
        (lambda: ph.RoadTable(0.0, 0.0, np.zeros(3)), r"dx = 0.0 is out of range: must be > 0 m"),
        (lambda: ph.RoadTable(0.0, 0.1, np.array([0.0, math.nan])), r"heights contains NaN"),
    ],
)
def test_bad_phases_are_refused_naming_the_parameter_value_range_and_unit(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_a_road_table_that_does_not_cover_the_axles_path_is_refused(bogie):
    table = ph.RoadTable(0.0, 0.01, np.zeros(100))  # 0 to 0.99 m
    expected = r"cover road distances \[-2.62, 14\] m but its road table covers \[0, 0.99\] m"
    with pytest.raises(ValueError, match=expected):
        ph.run(bogie, [ph.Phase(1.0, road=table, speed=14.0)])
    with pytest.raises(ValueError, match=r"check_every = 0 is out of range: must be a whole number >= 1 steps"):
        ph.run(bogie, [ph.Phase(1.0)], check_every=0)
