"""Air-sprung groups (issue 14, item 1; derivation in docs/air-suspension.md).

Connected bags reach one pressure at rest, so their loads differ only through the effective area at each bag's
height: under tilt and tyre wear an air group is within a percent or two of equal where the steel tri-axle is
over ten percent out. In motion the pressures part and come back together with the pipe's time constant.
"""

import math

import numpy as np
import pytest

from bogie import air
from bogie.air import dynamics as air_dynamics
from bogie.air import static as air_static
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.results import DynamicResult
from bogie.road import RampedStep
from bogie.steel import nonlinear, static

PAIRS = [(air.air_tandem, tandem_trrl), (air.air_triaxle, triaxle_stage1)]
MAKERS = [air.air_tandem, air.air_triaxle]


def _tilted_worn(make, tilt_deg, worn_axle):
    b = make(chassis_tilt=math.radians(tilt_deg))
    wear = [0.0] * b.n_axles
    wear[worn_axle] = 0.010
    return b.replace(tyre_wear=tuple(wear))


def _parted(bogie, fraction=0.02):
    """The levelled state with a share of the front bag's air moved to the rear bag: pressures parted."""
    s = air_static.equilibrium(bogie)
    m = s.gas_mass.copy()
    m[0] += fraction * m[0]
    m[-1] -= fraction * s.gas_mass[0]
    return air_static.AirState(s.u, s.v, m)


def _decay_time(t, dp, start, end):
    sel = (t > start) & (t < end)
    return -1.0 / np.polyfit(t[sel], np.log(np.abs(dp[sel])), 1)[0]


@pytest.mark.parametrize("make_air, make_steel", PAIRS)
def test_presets_carry_the_steel_presets_loads_on_bags_in_the_documented_ranges(make_air, make_steel):
    b, steel = make_air(), make_steel()
    assert b.axle_x == steel.axle_x and b.payload_mass == steel.payload_mass
    assert (b.tyre_stiffness, b.axle_mass, b.chassis_pitch_inertia) == (
        steel.tyre_stiffness,
        steel.axle_mass,
        steel.chassis_pitch_inertia,
    )
    loads = air_static.static_wheel_loads(b)
    np.testing.assert_allclose(loads, b.design_bag_load + b.axle_mass * 9.81, rtol=1e-12)
    # moments about the king pin: the bags carry the payload's moment, as the steel springs do
    assert sum(x * (w - b.axle_mass * 9.81) for x, w in zip(b.axle_x, loads)) == pytest.approx(
        b.payload_mass * 9.81 * b.payload_cg_x, rel=1e-12
    )
    assert b.design_gauge_pressure == pytest.approx(5.5e5)
    assert 0.03 <= b.bag_effective_area <= 0.05 and 0.010 <= b.bag_volume <= 0.025
    frequency = math.sqrt(air.bag_stiffness(b) * 9.81 / b.design_bag_load) / (2.0 * math.pi)
    assert 1.0 < frequency < 1.5
    assert air.pipe_time_constant(b) == pytest.approx(air.PRESET_PIPE_TIME_CONSTANT, rel=1e-12)


@pytest.mark.parametrize("make", MAKERS)
@pytest.mark.parametrize("tilt_deg", [1.0, 2.0])
@pytest.mark.parametrize("worn", [0, -1])
def test_static_loads_under_tilt_and_wear_differ_only_by_the_effective_area(make, tilt_deg, worn):
    b = _tilted_worn(make, tilt_deg, worn)
    state = air_static.equilibrium(b)
    out = air_static.state_loads(b, state)
    p = out["bag_pressure"]
    np.testing.assert_allclose(p, p[0], rtol=1e-10)  # one pressure at rest
    assert np.mean(out["bag_extension"]) == pytest.approx(0.0, abs=1e-10)  # the valve has levelled
    force = out["bag_force"]
    np.testing.assert_allclose(force / force.mean() - 1.0, air_static.area_load_spread(b, state), atol=1e-10)
    # the heights from the geometry alone: the valve levels the mean height, so the chassis pitches by the tilt
    # plus the mean wear over the group's distance from the king pin; each bag lengthens by its tyre's wear; the
    # tyres' share of the load differences is second order: the closed form A'/A_0 (e_i - mean e) to 3 %
    x = np.asarray(b.axle_x)
    wear = np.asarray(b.tyre_wear)
    pitch = math.tan(b.chassis_tilt) + wear.mean() / x.mean()
    e_geom = -(x - x.mean()) * pitch + (wear - wear.mean())
    predicted = b.bag_area_rate / b.bag_effective_area * e_geom
    np.testing.assert_allclose(force / force.mean() - 1.0, predicted, atol=0.03 * np.max(np.abs(predicted)))
    wheel = out["wheel_loads"]
    air_dev = np.max(np.abs(wheel / wheel.mean() - 1.0))
    assert air_dev < 0.025
    # the steel tri-axle in the same tilt and wear (Stage 2, q = 4.3) is far more unequal
    steel = triaxle_stage1()
    steel_wear = [0.0, 0.0, 0.0]
    steel_wear[worn] = 0.010
    w_steel = static.wheel_loads(steel, 0.057, math.radians(tilt_deg), tyre_wear=steel_wear)
    steel_dev = np.max(np.abs(w_steel / w_steel.mean() - 1.0))
    assert steel_dev > 5.0 * air_dev and steel_dev > 0.05


@pytest.mark.parametrize("make", MAKERS)
def test_a_constant_effective_area_shares_exactly_whatever_the_tilt_and_wear(make):
    b = _tilted_worn(make, 2.0, 0).replace(bag_area_rate=0.0)
    out = air_static.state_loads(b, air_static.equilibrium(b))
    np.testing.assert_allclose(out["bag_force"], out["bag_force"].mean(), rtol=1e-10)


def test_the_valve_shut_keeps_the_air_and_still_equalises_the_pressures():
    b = _tilted_worn(air.air_triaxle, 1.5, 0)
    total = 3 * b.design_gas_mass
    state = air_static.equilibrium(b, gas_mass=total)
    out = air_static.state_loads(b, state)
    assert np.sum(state.gas_mass) == pytest.approx(total, rel=1e-12)
    np.testing.assert_allclose(out["bag_pressure"], out["bag_pressure"][0], rtol=1e-10)
    # a tilt at fixed air moves the mean height (the valve would have corrected it) but not the sharing rule
    np.testing.assert_allclose(
        out["bag_force"] / out["bag_force"].mean() - 1.0, air_static.area_load_spread(b, state), atol=1e-10
    )


@pytest.mark.parametrize("make", MAKERS)
def test_the_equilibrium_is_at_rest_in_the_simulation(make):
    b = _tilted_worn(make, 1.0, 0)
    run = air_dynamics.simulate(b, nonlinear.hold(b, 2.0, 0.05))
    assert isinstance(run, DynamicResult) and run.success, run.message
    np.testing.assert_allclose(run.wheel_loads, np.broadcast_to(run.wheel_loads[0], run.wheel_loads.shape), rtol=1e-7)
    np.testing.assert_allclose(run.wheel_loads[0], air_static.static_wheel_loads(b), rtol=1e-10)


def test_the_pressure_equalisation_time_constant_with_volumes_held_is_the_closed_form():
    # tyres near rigid and a chassis too heavy to move in the run: the bags' volumes are held
    b = air.air_tandem(tyre_stiffness=1e8, chassis_pitch_inertia=1e9)
    run = air_dynamics.simulate(b, nonlinear.hold(b, 5.0, 0.02), initial=_parted(b), valve=False)
    p = run.extras["bag_pressure"]
    tau = _decay_time(run.t, p[:, 0] - p[:, 1], 1.0, 5.0)
    assert tau == pytest.approx(air.pipe_time_constant(b), rel=0.01)  # V / (n R T C)
    assert air.equalisation_time_constant(b) == pytest.approx(air.pipe_time_constant(b), rel=0.002)


@pytest.mark.parametrize("make", MAKERS)
def test_the_pressure_equalisation_time_constant_on_the_tyres_is_the_series_closed_form(make):
    b = make()
    run = air_dynamics.simulate(b, nonlinear.hold(b, 8.0, 0.02), initial=_parted(b), valve=False)
    p = run.extras["bag_pressure"]
    tau = _decay_time(run.t, p[:, 0] - p.mean(axis=1), 3.0, 8.0)
    slowest = air_static.coupled_time_constants(b)[0]
    assert tau == pytest.approx(slowest, rel=0.01)
    # the tyre in series with the gas (chassis held) to 2 %; the chassis's pitch adds the rest
    assert tau == pytest.approx(air.equalisation_time_constant(b), rel=0.02)
    assert tau > air.pipe_time_constant(b)
    # the air only moves between the bags
    total = run.extras["gas_mass"].sum(axis=1)
    np.testing.assert_allclose(total, np.full_like(total, total[0]), rtol=1e-9)


@pytest.mark.parametrize("make", MAKERS)
def test_pressures_part_over_a_road_step_and_reequalise_with_the_time_constant(make):
    b = make()
    inputs = nonlinear.road_inputs(b, RampedStep(rise=0.025), 10.0, 8.0, 0.005, front_axle_start=-2.0)
    run = air_dynamics.simulate(b, inputs)
    assert run.success, run.message
    p = run.extras["bag_pressure"]
    dp = p[:, 0] - p[:, -1]
    peak = np.max(np.abs(dp))
    assert peak > 0.1 * b.design_gauge_pressure  # parted by more than 0.5 bar while the wheels climb
    # the wheels leave the road coming off the plateau; a tyre cut off while compressed still dissipates
    assert np.min(run.wheel_loads) == 0.0
    assert np.all(run.extras["dissipation_rate"] >= 0.0)
    assert abs(dp[-1]) < 0.002 * peak
    # the tail after the bounce has died away decays with the slowest time constant
    tau = _decay_time(run.t, dp, 5.0, 8.0)
    assert tau == pytest.approx(air_static.coupled_time_constants(b)[0], rel=0.05)
    # and the wheel loads return to equal
    assert np.max(np.abs(run.wheel_loads[-1] / run.wheel_loads[-1].mean() - 1.0)) < 1e-3


@pytest.mark.parametrize("method", ["rk4", "lsoda"])
@pytest.mark.parametrize("make", MAKERS)
def test_energy_dissipated_is_never_negative_and_the_balance_closes(make, method):
    b = make()
    inputs = nonlinear.road_inputs(b, RampedStep(rise=0.025), 5.0, 5.0, 0.005, front_axle_start=-1.0)
    run = air_dynamics.simulate(b, inputs, method=method)
    assert run.success, run.message
    w = run.extras
    dissipations = ("damper_dissipation", "tyre_dissipation", "pipe_dissipation", "valve_dissipation")
    assert np.all(w["dissipation_rate"] >= 0.0)  # at every recorded state, by construction of each term
    dissipated = sum(w[name][-1] for name in dissipations)
    for name in dissipations:
        # The running totals between rows are the integrator's interpolation, so non-decreasing only to its
        # accuracy: the same 1e-6 of the energy dissipated to which the balance below closes. (Each term's own total
        # is no yardstick: LSODA controls a total's error in joules, atol 1e-9 of the design bag load, and its
        # interpolant dips where the valve switches: 1.1e-4 J of the air tandem's 17.5 J of valve work here, 2.3e-4
        # J with numba compiling for Haswell, 5.6 and 12 atol, against 1.35e-3 J allowed.)
        assert np.all(np.diff(w[name]) >= -1e-6 * dissipated), name
        assert w[name][-1] > 0.0, name
    start = air_dynamics.stored_energy(b, air_static.equilibrium(b))
    end = air_dynamics.stored_energy(b, run.final_state)
    supplied = w["road_work"][-1] + w["supply_energy"][-1] - w["vent_energy"][-1]
    assert end - start == pytest.approx(supplied - dissipated, abs=1e-6 * dissipated)
    assert dissipated > 10.0  # a real event: tens of joules through the dampers and the pipe


@pytest.mark.parametrize(
    "changes, words",
    [
        ({"bag_volume": -0.01}, ["bag_volume = -0.01", "(0, 0.5] m^3"]),
        ({"polytropic_index": 2.0}, ["polytropic_index = 2.0", "[1, 1.67] -"]),
        ({"pipe_conductance": "fast"}, ["pipe_conductance = 'fast'", "not a number", "kg/(s Pa)"]),
        ({"supply_pressure": 3e5}, ["supply_pressure = 300000.0", "design gauge pressure", "Pa"]),
        ({"tyre_wear": (0.0, 0.1)}, ["tyre_wear[1] = 0.1", "[0, 0.05] m"]),
        ({"tyre_wear": (0.0,)}, ["tyre_wear has 1 values", "2 axles"]),
        ({"axle_x": (8.0, 7.0)}, ["axle_x", "increase front to rear"]),
    ],
)
def test_bad_inputs_are_refused_naming_field_value_range_and_unit(changes, words):
    with pytest.raises(ValueError) as err:
        air.air_tandem(**changes)
    for word in words:
        assert word in str(err.value)


def test_unconnected_bags_need_each_bags_air_to_be_at_rest():
    b = air.air_tandem(pipe_conductance=0.0)
    with pytest.raises(ValueError, match=r"pipe_conductance = 0.0 kg/\(s Pa\).*one value per bag \(2 values, kg\)"):
        air_static.equilibrium(b)
    m = np.full(2, b.design_gas_mass)
    state = air_static.equilibrium(b.replace(chassis_tilt=math.radians(1.0)), gas_mass=m)
    out = air_static.state_loads(b.replace(chassis_tilt=math.radians(1.0)), state)
    # each bag keeps its air: the compressed rear bag's pressure rises, and the loads part far more than connected
    assert out["bag_pressure"][1] > out["bag_pressure"][0]
    connected = air_static.static_wheel_loads(air.air_tandem(chassis_tilt=math.radians(1.0)))
    assert np.ptp(out["wheel_loads"]) > 3.0 * np.ptp(connected)


def test_parted_pressures_settle_to_the_shut_valve_equilibrium_losing_what_was_dissipated():
    b = air.air_triaxle()
    start = _parted(b, 0.03)
    run = air_dynamics.simulate(b, nonlinear.hold(b, 20.0, 0.05), initial=start, valve=False)
    assert run.success, run.message
    w = run.extras
    dissipated = sum(w[name][-1] for name in ("damper_dissipation", "tyre_dissipation", "pipe_dissipation"))
    assert w["road_work"][-1] == 0.0 and w["valve_dissipation"][-1] == 0.0
    lost = air_dynamics.stored_energy(b, start) - air_dynamics.stored_energy(b, run.final_state)
    assert lost == pytest.approx(dissipated, rel=1e-6)
    assert w["pipe_dissipation"][-1] > 0.5 * dissipated  # the pipe's throttling, not the dampers, takes most
    # where it settles is the static solve with the valve shut and the same air
    rest = air_static.equilibrium(b, gas_mass=float(np.sum(start.gas_mass)))
    np.testing.assert_allclose(run.final_state.u, rest.u, atol=1e-7)
    np.testing.assert_allclose(
        run.wheel_loads[-1], air_static.static_wheel_loads(b, gas_mass=np.sum(start.gas_mass)), rtol=1e-6
    )
