import dataclasses
import math

import numpy as np
import pytest

from bogie.params import GRAVITY, INHIBITORS, Bogie, design_spring_loads
from bogie.presets import preset, tandem_trrl, triaxle_stage1


def test_presets_are_valid_and_triaxle_has_q_of_stage1():
    assert tandem_trrl().n_axles == 2
    tri = triaxle_stage1()
    assert tri.n_axles == 3
    assert tri.q(0) == pytest.approx(4.3, rel=1e-12)
    assert tri.q(1) == pytest.approx(4.3, rel=1e-12)


def test_triaxle_design_load_deflects_by_reference_alpha():
    tri = triaxle_stage1()
    loads = design_spring_loads(tri)
    assert loads == pytest.approx([tri.combined_stiffness * 0.057] * 3, rel=1e-12)


def test_design_loads_balance_the_chassis_about_the_king_pin():
    for bogie in (tandem_trrl(), triaxle_stage1(), tandem_trrl(equaliser_front_arm=(0.2,), equaliser_rear_arm=(0.11,))):
        loads = design_spring_loads(bogie)
        moment = sum(w * x for w, x in zip(loads, bogie.axle_x))
        assert moment == pytest.approx(bogie.payload_mass * GRAVITY * bogie.payload_cg_x, rel=1e-12)


def test_derived_geometry_closes():
    b = triaxle_stage1()
    assert b.equaliser_pivot_x == pytest.approx((6.69 + 0.5 + 0.155, 8.0 + 0.5 + 0.155))
    assert b.front_hanger_x == pytest.approx(6.19)
    assert b.rear_hanger_x == pytest.approx(9.81)
    assert b.kingpin_height_offset == 0.0
    tilted = b.replace(chassis_tilt=math.radians(1.0))
    assert tilted.kingpin_height_offset == pytest.approx(8.0 * math.tan(math.radians(1.0)))


def test_replace_switches_one_inhibitor_off_and_nothing_else():
    b = tandem_trrl()
    off = dataclasses.replace(b, friction_coefficient=0.0)
    assert off.friction_coefficient == 0.0
    changed = {f.name for f in dataclasses.fields(b) if getattr(b, f.name) != getattr(off, f.name)}
    assert changed == {"friction_coefficient"}
    all_off = b.without()
    assert {name: getattr(all_off, name) for name in INHIBITORS} == INHIBITORS


@pytest.mark.parametrize(
    "field, value, fragment",
    [
        ("road_spring_stiffness", -1.0, "road_spring_stiffness = -1.0 is out of range: must be in (0, 1e+09] N/m"),
        ("tyre_stiffness", 0.0, "tyre_stiffness = 0.0 is out of range"),
        ("axle_mass", -5.0, "axle_mass = -5.0 is out of range: must be in [0, 5000] kg"),
        ("payload_mass", float("nan"), "payload_mass = nan is out of range"),
        ("bush_stiffness", float("inf"), "bush_stiffness = inf is out of range: must be in [0, 1e+07] N m/rad"),
        ("bush_damping", -1.0, "bush_damping = -1.0 is out of range: must be in [0, 1e+06] N m s/rad"),
        ("friction_coefficient", 1.6, "friction_coefficient = 1.6 is out of range: must be in [0, 1.5] -"),
        ("friction_coefficient", -0.1, "friction_coefficient = -0.1"),
        ("contact_roll_radius", -0.01, "contact_roll_radius = -0.01 is out of range: must be in [0, 0.5] m"),
        ("chassis_tilt", math.radians(10.5), "chassis_tilt = 0.1832"),
        ("tyre_damping", "soft", "tyre_damping = 'soft' is not a number"),
        ("equaliser_stop", -0.1, "equaliser_stop = -0.1 is out of range: must be in (0, 3.14159] rad"),
        ("equaliser_stop_stiffness", 2e9, "equaliser_stop_stiffness = 2000000000.0 is out of range"),
    ],
)
def test_validation_names_field_value_range_and_unit(field, value, fragment):
    with pytest.raises(ValueError) as err:
        tandem_trrl(**{field: value})
    assert fragment in str(err.value)
    assert field in str(err.value)


def test_tilt_limit_is_ten_degrees():
    tandem_trrl(chassis_tilt=math.radians(9.99))
    with pytest.raises(ValueError, match=r"chassis_tilt .* \[-0.174533, 0.174533\] rad"):
        tandem_trrl(chassis_tilt=-math.radians(10.01))


def test_wrong_number_of_per_axle_values():
    with pytest.raises(ValueError, match="tyre_wear has 3 values but the bogie has 2 axles"):
        tandem_trrl(tyre_wear=(0.0, 0.001, 0.002))
    with pytest.raises(ValueError, match="equaliser_front_arm has 2 values but the bogie has 1 equalisers"):
        tandem_trrl(equaliser_front_arm=(0.155, 0.155))
    with pytest.raises(ValueError, match=r"tyre_wear\[1\] = 0.07 is out of range: must be in \[0, 0.05\] m"):
        tandem_trrl(tyre_wear=(0.0, 0.07))
    with pytest.raises(ValueError, match="at least 2 axle positions"):
        Bogie(**{**_fields(tandem_trrl()), "axle_x": (8.0,)})


def test_geometry_that_does_not_close_is_refused():
    with pytest.raises(ValueError, match=r"geometry does not close at equaliser 0.*equaliser_front_arm\[0\]"):
        tandem_trrl(equaliser_front_arm=(0.2,))


def test_inertia_below_point_mass_is_refused():
    with pytest.raises(ValueError, match="chassis_pitch_inertia"):
        tandem_trrl(chassis_pitch_inertia=1000.0)


def test_unknown_preset_and_inhibitor():
    with pytest.raises(ValueError, match="unknown preset 'quad'"):
        preset("quad")
    with pytest.raises(ValueError, match="unknown inhibitor 'bush'"):
        tandem_trrl().without("bush")


def test_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        tandem_trrl().bush_stiffness = 3.0


def _fields(b):
    return {f.name: getattr(b, f.name) for f in dataclasses.fields(b)}


@pytest.mark.parametrize("make", [tandem_trrl, triaxle_stage1])
@pytest.mark.parametrize("arm", [0.12, 0.25, 0.28])
def test_longer_arms_keep_the_axles_the_springs_symmetric_and_the_loads_equal(make, arm):
    from bogie.params import with_equaliser_arms

    base = make()
    longer = with_equaliser_arms(base, arm)
    assert longer.axle_x == base.axle_x
    assert longer.equaliser_pivot_x == pytest.approx(base.equaliser_pivot_x)
    assert longer.spring_front_half_length == pytest.approx(longer.spring_rear_half_length)
    assert longer.spring_front_half_length[0] == pytest.approx(0.5 - (arm - 0.155))
    loads = design_spring_loads(longer)
    assert loads == pytest.approx([loads[0]] * base.n_axles, rel=1e-12)


def test_range_tables_are_public_and_drive_the_validation():
    from bogie.params import AXLE_RANGES, EQUALISER_RANGES, SCALAR_RANGES, FieldRange

    assert SCALAR_RANGES["bush_stiffness"] == FieldRange(0.0, 1e7, "N m/rad", True)
    assert AXLE_RANGES["tyre_wear"].high == 0.05 and EQUALISER_RANGES["equaliser_front_arm"].low == 0.01
    b = tandem_trrl()
    for name, r in SCALAR_RANGES.items():
        assert r.contains(getattr(b, name)), name
        outside = r.low if not r.low_inclusive else r.low - max(1.0, abs(r.low))
        with pytest.raises(ValueError, match=f"{name} = .* out of range"):
            b.replace(**{name: outside})
        with pytest.raises(ValueError, match=f"{name} = .* out of range"):
            b.replace(**{name: r.high * 2 + 1.0})


def test_field_range_contains_its_limits_as_declared():
    from bogie.params import FieldRange

    open_low = FieldRange(0.0, 1.0, "m", False)
    assert not open_low.contains(0.0) and open_low.contains(1e-300) and open_low.contains(1.0)
    assert not open_low.contains(1.0 + 1e-12) and not open_low.contains(float("nan"))
    assert FieldRange(0.0, 1.0, "m", True).contains(0.0)


def test_pipeline_takes_the_bogie_ranges_from_the_public_table_only():
    from pathlib import Path

    from bogie.params import AXLE_RANGES, SCALAR_RANGES
    from pipeline.config import QUANTITIES

    assert QUANTITIES["tyre_wear_mm"].range is AXLE_RANGES["tyre_wear"]
    assert QUANTITIES["chassis_tilt_deg"].range is SCALAR_RANGES["chassis_tilt"]
    pipeline = Path(__file__).resolve().parents[1] / "pipeline"
    private = [p.name for p in pipeline.glob("*.py") if "from bogie.params import _" in p.read_text(encoding="utf-8")]
    assert private == []


def test_numpy_numbers_are_accepted_where_python_numbers_are():
    base = triaxle_stage1()
    wear = np.array([0.001, 0.0, 0.002])
    b = base.replace(tyre_wear=wear, bush_stiffness=np.float64(500.0), bush_damping=np.int64(3))
    assert b.tyre_wear == (0.001, 0.0, 0.002) and b.bush_stiffness == 500.0 and b.bush_damping == 3.0
    assert all(type(v) is float for v in (*b.tyre_wear, b.bush_stiffness, b.bush_damping))
    assert base.replace(chassis_tilt=np.array(0.01)).chassis_tilt == 0.01  # a 0-d array is a number
    # a scalar where one value per axle is needed: the field's own message, not numpy's "truth value" error
    with pytest.raises(ValueError, match=r"tyre_wear = 0.001 must be a sequence of 3 values \(one per axle\) in m"):
        base.replace(tyre_wear=np.float64(0.001))


@pytest.mark.parametrize(("value", "kind"), [(True, "bool"), (np.bool_(False), "bool"), ("1000", "text")])
def test_booleans_and_numeric_text_are_not_numbers(value, kind):
    with pytest.raises(ValueError, match=rf"bush_stiffness = .* is not a number \({kind}\): must be in \[0, "):
        triaxle_stage1().replace(bush_stiffness=value)
    with pytest.raises(ValueError, match=r"tyre_wear\[1\] = .* is not a number"):
        triaxle_stage1().replace(tyre_wear=(0.0, value, 0.0))


#: every field of the two presets as they were before issue 29 wrote their shared values once, copied out by hand
#: (the floats as Python prints them: each reads back to the same bits); a preset must keep every bit of each
PRESETS_BEFORE_ISSUE_29 = {
    "tandem_trrl": {
        "axle_x": (7.345, 8.655),
        "spring_front_half_length": (0.5, 0.5),
        "spring_rear_half_length": (0.5, 0.5),
        "equaliser_front_arm": (0.155,),
        "equaliser_rear_arm": (0.155,),
        "road_spring_stiffness": 600000.0,
        "tyre_stiffness": 1600000.0,
        "tyre_radius": 0.5,
        "axle_mass": 300.0,
        "payload_mass": 6500.0,
        "payload_cg_x": 4.8,
        "chassis_pitch_inertia": 229385.0,
        "tyre_wear": (0.0, 0.0),
        "tyre_damping": 2000.0,
        "equaliser_inertia": 0.2,
        "pad_drop": 0.3,
        "equaliser_front_tip_drop": 0.0,
        "equaliser_rear_tip_drop": 0.0,
        "spring_length_rate": 0.3,
        "spring_end_slope_rate": 2.0,
        "contact_tangential_stiffness": 5000000.0,
        "chassis_tilt": 0.0,
        "bush_stiffness": 1000.0,
        "bush_damping": 0.0,
        "contact_roll_radius": 0.075,
        "friction_coefficient": 0.3,
        "radius_rod_length": (),
        "radius_rod_drop": 0.0,
        "equaliser_stop": 0.2617993877991494,
        "equaliser_stop_stiffness": 84000.0,
        "spring_friction_band": 2000.0,
        "spring_friction_decay": 0.005,
    },
    "triaxle_stage1": {
        "axle_x": (6.69, 8.0, 9.31),
        "spring_front_half_length": (0.5, 0.5, 0.5),
        "spring_rear_half_length": (0.5, 0.5, 0.5),
        "equaliser_front_arm": (0.155, 0.155),
        "equaliser_rear_arm": (0.155, 0.155),
        "road_spring_stiffness": 600000.0,
        "tyre_stiffness": 1600000.0,
        "tyre_radius": 0.5,
        "axle_mass": 300.0,
        "payload_mass": 12677.23102585488,
        "payload_cg_x": 4.8,
        "chassis_pitch_inertia": 447379.4829024187,
        "tyre_wear": (0.0, 0.0, 0.0),
        "tyre_damping": 2000.0,
        "equaliser_inertia": 0.2,
        "pad_drop": 0.3,
        "equaliser_front_tip_drop": 0.0,
        "equaliser_rear_tip_drop": 0.0,
        "spring_length_rate": 0.3,
        "spring_end_slope_rate": 2.0,
        "contact_tangential_stiffness": 5000000.0,
        "chassis_tilt": 0.0,
        "bush_stiffness": 609.5137420718817,
        "bush_damping": 0.0,
        "contact_roll_radius": 0.075,
        "friction_coefficient": 0.3,
        "radius_rod_length": (),
        "radius_rod_drop": 0.0,
        "equaliser_stop": 0.2617993877991494,
        "equaliser_stop_stiffness": 84000.0,
        "spring_friction_band": 2000.0,
        "spring_friction_decay": 0.005,
    },
}


def _bits(value):
    """A field's value as exact bits: a float's hex, a tuple's floats' hexes (0.0 and -0.0 differ)."""
    if isinstance(value, tuple):
        return tuple(_bits(v) for v in value)
    return float(value).hex() if isinstance(value, float) else value


@pytest.mark.parametrize("name", ["tandem_trrl", "triaxle_stage1"])
def test_each_preset_keeps_every_field_bit_for_bit(name):
    """The presets write their shared values once (issue 29): each field is still exactly what it was."""
    bogie = preset(name)
    expected = PRESETS_BEFORE_ISSUE_29[name]
    assert [f.name for f in dataclasses.fields(bogie)] == list(expected)
    assert {k: _bits(getattr(bogie, k)) for k in expected} == {k: _bits(v) for k, v in expected.items()}


def test_the_presets_and_the_range_table_are_importable_from_params_as_before():  # the presets with a warning
    import subprocess
    import sys

    import bogie.params as params
    import bogie.presets as presets
    import bogie.ranges as ranges

    for name in presets.__all__:  # moved to bogie.presets: found for one release with a DeprecationWarning
        with pytest.warns(DeprecationWarning, match=f"bogie.presets.{name}"):
            assert getattr(params, name) is getattr(presets, name), name
    for name in ("FieldRange", "SCALAR_RANGES", "AXLE_RANGES", "EQUALISER_RANGES"):
        assert getattr(params, name) is getattr(ranges, name), name
    # whichever module a process imports first (bogie/__init__ imports bogie.params before bogie.presets)
    check = "import bogie.params as p, bogie.presets as q; assert p.preset is q.preset and p.PRESETS is q.PRESETS"
    for first in ("bogie.presets", "bogie.ranges", "bogie.params"):
        subprocess.run([sys.executable, "-c", f"import {first}; {check}"], check=True)


def test_a_preset_asked_of_bogie_params_is_found_with_a_warning_naming_its_new_home():
    import bogie.params as params
    import bogie.presets as presets

    with pytest.warns(DeprecationWarning, match="moved to bogie.presets.tandem_trrl"):
        assert params.tandem_trrl is presets.tandem_trrl
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        params.no_such_name  # noqa: B018
