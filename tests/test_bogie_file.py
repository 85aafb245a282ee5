"""A bogie of one's own in a YAML file (bogie.bogie_file, issue 31 item 6): exact values, the error style, the fleet."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from _fleets import PRESETS, fleet

import bogie.fleet as bf
from bogie import tandem_trrl, triaxle_stage1
from bogie.bogie_file import FILE_KEYS, BogieFileError, base_bogie, load_bogie, read_bogie_text
from bogie.params import GRAVITY, PRESET_EQUALISER_STOP, Bogie
from bogie.steel.force.pack import design_wheel_loads
from bogie.steel.static import tilted_axle_loads

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "bogies" / "example_triaxle.yaml"

#: a tandem written by hand, every key, and below the Bogie its numbers make, worked out by hand in SI
HAND = """\
axle_x_m: [7.0, 8.4]
spring_front_half_length_mm: [520, 480]
spring_rear_half_length_mm: [480, 520]
equaliser_front_arm_mm: [220]
equaliser_rear_arm_mm: [220]
road_spring_stiffness_kn_mm: 0.75
tyre_stiffness_kn_mm: 1.5
tyre_radius_mm: 520
tyre_wear_mm: [2, 3.5]
tyre_damping_kn_s_m: 1.5
axle_mass_kg: 280
payload_mass_kg: 7000
payload_cg_x_m: 5.0
chassis_pitch_inertia_kg_m2: 250000
equaliser_inertia_kg_m2: 0.3
pad_drop_mm: 250
equaliser_front_tip_drop_mm: 10
equaliser_rear_tip_drop_mm: -10
spring_length_rate: 0.25
spring_end_slope_rate_rad_m: 1.5
contact_tangential_stiffness_kn_mm: 4
chassis_tilt_deg: 0.5
bush_stiffness_n_m_rad: 800
bush_damping_n_m_s_rad: 20
contact_roll_radius_mm: 60
friction_coefficient: 0.2
radius_rod_length_mm: [450, 700]
radius_rod_drop_mm: -20
equaliser_stop_deg: 12
equaliser_stop_stiffness_kn_m_rad: 90
spring_friction_band_kn: 1.5
spring_friction_decay_mm: 4
"""

HAND_BOGIE = Bogie(
    axle_x=(7.0, 8.4),
    spring_front_half_length=(0.52, 0.48),
    spring_rear_half_length=(0.48, 0.52),
    equaliser_front_arm=(0.22,),
    equaliser_rear_arm=(0.22,),
    road_spring_stiffness=750000.0,
    tyre_stiffness=1500000.0,
    tyre_radius=0.52,
    tyre_wear=(0.002, 0.0035),
    tyre_damping=1500.0,
    axle_mass=280.0,
    payload_mass=7000.0,
    payload_cg_x=5.0,
    chassis_pitch_inertia=250000.0,
    equaliser_inertia=0.3,
    pad_drop=0.25,
    equaliser_front_tip_drop=0.01,
    equaliser_rear_tip_drop=-0.01,
    spring_length_rate=0.25,
    spring_end_slope_rate=1.5,
    contact_tangential_stiffness=4000000.0,
    chassis_tilt=math.radians(0.5),  # degrees through math.radians, as the presets' stop angle
    bush_stiffness=800.0,
    bush_damping=20.0,
    contact_roll_radius=0.06,
    friction_coefficient=0.2,
    radius_rod_length=(0.45, 0.7),
    radius_rod_drop=-0.02,
    equaliser_stop=math.radians(12.0),
    equaliser_stop_stiffness=90000.0,
    spring_friction_band=1500.0,
    spring_friction_decay=0.004,
)

#: the preset tandem_trrl written out in the file's units (docs/presets.md), every key
TANDEM_TRRL = """\
axle_x_m: [7.345, 8.655]
spring_front_half_length_mm: [500, 500]
spring_rear_half_length_mm: [500, 500]
equaliser_front_arm_mm: [155]
equaliser_rear_arm_mm: [155]
road_spring_stiffness_kn_mm: 0.6
tyre_stiffness_kn_mm: 1.6
tyre_radius_mm: 500
tyre_wear_mm: [0, 0]
tyre_damping_kn_s_m: 2
axle_mass_kg: 300
payload_mass_kg: 6500
payload_cg_x_m: 4.8
chassis_pitch_inertia_kg_m2: 229385   # 6500 (4.8^2 + 3.5^2)
equaliser_inertia_kg_m2: 0.2
pad_drop_mm: 300
equaliser_front_tip_drop_mm: 0
equaliser_rear_tip_drop_mm: 0
spring_length_rate: 0.3
spring_end_slope_rate_rad_m: 2
contact_tangential_stiffness_kn_mm: 5
chassis_tilt_deg: 0
bush_stiffness_n_m_rad: 1000
bush_damping_n_m_s_rad: 0
contact_roll_radius_mm: 75
friction_coefficient: 0.3
radius_rod_length_mm: []
radius_rod_drop_mm: 0
equaliser_stop_deg: 15
equaliser_stop_stiffness_kn_m_rad: 84
spring_friction_band_kn: 2
spring_friction_decay_mm: 5
"""


def write(tmp_path, text, name="b.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_every_field_of_the_bogie_has_one_key_in_the_file():
    assert list(FILE_KEYS) == [f.name for f in dataclasses.fields(Bogie)]
    keys = [k.key for k in FILE_KEYS.values()]
    assert len(set(keys)) == len(keys)


def test_a_hand_written_file_gives_the_bogie_worked_out_by_hand(tmp_path):
    bogie = load_bogie(write(tmp_path, HAND))
    assert bogie == HAND_BOGIE
    assert bogie.n_axles == 2 and bogie.equaliser_pivot_x == pytest.approx((7.70,))
    # millimetres to metres exactly as the decimal reads: 700 mm is the float 0.7, not 700 * 0.001
    assert bogie.radius_rod_length[1] == 0.7 != 700 * 0.001


def test_the_preset_written_out_is_the_preset_bit_for_bit(tmp_path):
    assert load_bogie(write(tmp_path, TANDEM_TRRL)) == tandem_trrl()
    assert load_bogie(write(tmp_path, TANDEM_TRRL)).equaliser_stop == PRESET_EQUALISER_STOP


def test_absent_keys_take_the_named_preset_s_values(tmp_path):
    assert read_bogie_text("base: triaxle_stage1\n") == triaxle_stage1()
    text = "base: triaxle_stage1\nbush_stiffness_n_m_rad: 250\ntyre_wear_mm: [0, 4, 0]\n"
    assert read_bogie_text(text) == triaxle_stage1(bush_stiffness=250.0, tyre_wear=(0.0, 0.004, 0.0))


def test_the_axle_count_follows_the_file(tmp_path):
    four = (
        "base: triaxle_stage1\naxle_x_m: [6.0, 7.31, 8.62, 9.93]\n"
        "spring_front_half_length_mm: [500, 500, 500, 500]\nspring_rear_half_length_mm: [500, 500, 500, 500]\n"
        "equaliser_front_arm_mm: [155, 155, 155]\nequaliser_rear_arm_mm: [155, 155, 155]\n"
        "tyre_wear_mm: [0, 0, 0, 0]\n"
    )
    bogie = read_bogie_text(four)
    assert bogie.n_axles == 4 and len(bogie.equaliser_pivot_x) == 3


@pytest.mark.parametrize(
    ("text", "words"),
    [
        # unknown keys: all of them named at once, with the nearest key
        ("base: tandem_trrl\nbush_stifness: 3\ncolour: red\n",
         ["'bush_stifness'", "'colour'", "bush_stiffness_n_m_rad"]),
        # out of range: key, value, range and unit, in the file's unit
        ("base: tandem_trrl\nroad_spring_stiffness_kn_mm: 2000\n",
         ["road_spring_stiffness_kn_mm = 2000", "(0, 1000] kN/mm"]),
        ("base: tandem_trrl\nchassis_tilt_deg: 12\n", ["chassis_tilt_deg = 12", "[-10, 10] degree"]),
        ("base: tandem_trrl\ntyre_wear_mm: [1, 60]\n", ["tyre_wear_mm[1] = 60", "[0, 50] mm"]),
        ("base: tandem_trrl\npad_drop_mm: high\n", ["pad_drop_mm = 'high'", "not a number", "[0, 3000] mm"]),
        # every bad value at once
        ("base: tandem_trrl\nfriction_coefficient: -1\naxle_mass_kg: 1.0e+9\n",
         ["friction_coefficient = -1", "[0, 1.5] -", "axle_mass_kg = 1000000000.0", "[0, 5000] kg"]),
        # YAML 1.1 reads 3e2 (no dot, no sign) as text: said so
        ("base: tandem_trrl\naxle_mass_kg: 3e2\n", ["axle_mass_kg = '3e2' is not a number", "write 3.0e+2"]),
        # wrong number of values for the axle count
        ("base: tandem_trrl\ntyre_wear_mm: [1, 2, 3]\n",
         ["tyre_wear_mm = 3 values", "list of 2 values", "per axle", "mm"]),
        ("base: triaxle_stage1\naxle_x_m: [7.0, 8.31]\n", ["axle_x_m gives 2 axles", "triaxle_stage1 has 3",
                                                           "spring_front_half_length_mm"]),
        # no base: every key needed, all named
        ("axle_x_m: [7.0, 8.3]\n", ["missing keys", "tyre_radius_mm", "spring_friction_decay_mm", "base: <preset>"]),
        ("base: quad_axle\n", ["base = 'quad_axle'", "tandem_trrl, triaxle_stage1"]),
        # the fields do not fit together: named in SI and in the file's keys
        ("base: tandem_trrl\nequaliser_front_arm_mm: [200]\n", ["does not close", "equaliser_front_arm_mm [mm]"]),
        # bad YAML, a key twice, not a mapping
        ("base: tandem_trrl\naxle_x_m: [7.0, 8.3\n", ["not valid YAML"]),
        ("base: tandem_trrl\nbase: tandem_trrl\n", ["duplicated key base at line 2 (first at line 1)"]),
        ("- 1\n- 2\n", ["must be a mapping"]),
    ],
)  # fmt: skip
def test_each_bad_file_is_refused_naming_key_value_range_and_unit(tmp_path, text, words):
    path = write(tmp_path, text)
    with pytest.raises(BogieFileError) as excinfo:
        load_bogie(path)
    message = str(excinfo.value)
    assert message.startswith(str(path))
    for word in words:
        assert word in message, message


def test_a_missing_file_or_another_suffix_is_named(tmp_path):
    with pytest.raises(BogieFileError, match=r"nope\.yaml: no such bogie file"):
        load_bogie(tmp_path / "nope.yaml")
    with pytest.raises(BogieFileError, match=r"must end in \.yaml or \.yml"):
        load_bogie(write(tmp_path, "base: tandem_trrl\n", "b.txt"))
    with pytest.raises(ValueError, match="unknown base bogie 'tandem'"):
        base_bogie("tandem")


def test_the_example_file_is_a_valid_triaxle_and_not_the_preset():
    bogie = load_bogie(EXAMPLE)
    assert bogie.n_axles == 3 and bogie != triaxle_stage1()
    assert np.diff(bogie.axle_x) == pytest.approx([1.36, 1.36])
    # its payload puts about 12 t on this side's tyres: half the 24 t legal tri-axle load
    assert sum(design_wheel_loads(bogie)) / GRAVITY == pytest.approx(12000.0, rel=0.01)


# ---- the static loads at a tilt ----------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [tandem_trrl, triaxle_stage1, lambda: load_bogie(EXAMPLE)])
def test_level_loads_are_the_design_loads_and_a_tilt_keeps_the_king_pin_s_moment(make):
    bogie = make()
    assert tilted_axle_loads(bogie, 0.0) == pytest.approx(design_wheel_loads(bogie), rel=1e-12)
    tilted = tilted_axle_loads(bogie, math.radians(2.0))
    springs = tilted - bogie.axle_mass * GRAVITY
    # moments about the king pin: the springs carry m g x_cg whatever the tilt
    assert float(springs @ np.asarray(bogie.axle_x)) == pytest.approx(
        bogie.payload_mass * GRAVITY * bogie.payload_cg_x, rel=1e-12
    )
    assert np.all(np.diff(tilted) > 0.0)  # nose up: each axle heavier than the one ahead


def test_a_stiffer_bush_shares_a_tilt_worse():
    soft = tilted_axle_loads(triaxle_stage1(bush_stiffness=10.0), math.radians(2.0))
    stiff = tilted_axle_loads(triaxle_stage1(bush_stiffness=5000.0), math.radians(2.0))
    assert np.ptp(stiff) > np.ptp(soft) > 0.0


# ---- the fleet on a file's bogie ---------------------------------------------------------------------------------
def test_a_fleet_sampled_on_a_file_has_the_file_s_geometry_in_its_rows(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # the path is relative to the working directory, as the pipeline's are to the root
    name = "bogies/example_triaxle.yaml"
    rows = bf.sample_fleet(fleet(presets={**PRESETS, "triaxle": name}), 40, seed=7)
    tri = rows[rows["group"] == "triaxle"]
    assert len(tri) > 0 and set(tri["preset"]) == {name}
    assert set(rows.loc[rows["group"] == "tandem", "preset"]) == {"tandem_trrl"}
    file_bogie = load_bogie(name)
    for _, row in tri.head(5).iterrows():
        bogie = bf.bogie_from_sample(row.to_dict())
        assert bogie.axle_x == file_bogie.axle_x == (7.14, 8.5, 9.86)
        assert bogie.tyre_radius == 0.536 and bogie.road_spring_stiffness == 800000.0
        assert bogie.bush_stiffness == row["bush_stiffness"]  # the sampled inhibitors on the file's geometry
    # the design payload puts the legal load on the file's tyres: 24 t over both sides
    design = bf.design_bogie(name, 24e3 * GRAVITY)
    assert 2.0 * sum(design_wheel_loads(design)) == pytest.approx(24e3 * GRAVITY, rel=1e-12)


def test_a_fleet_refuses_a_file_with_the_wrong_axle_count_or_a_bad_file(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    with pytest.raises(bf.FleetError, match=r"presets\['tandem'\] = 'bogies/example_triaxle.yaml' has 3 axles"):
        fleet(presets={**PRESETS, "tandem": "bogies/example_triaxle.yaml"})
    with pytest.raises(bf.FleetError, match=r"presets\['triaxle'\] = 'bogies/none.yaml': .*no such bogie file"):
        fleet(presets={**PRESETS, "triaxle": "bogies/none.yaml"})
