"""bogie.fleet.design.experiment: the design experiment with plain arguments (issue 29), no params file, no pipeline.

The analysis reads a hand-made runs table whose answers are worked out here. A tandem with axle loads
W0 = 1 + s, W1 = 1 - s [10 kN] is within 5 % while (W0 - W1) / W0 = 2 |s| / (1 + |s|) <= 0.05, that is
|s| <= 0.05 / 1.95 = 0.02564; with s = a t + b (t the tilt in degrees) that is t in [(-0.02564 - b) / a,
(0.02564 - b) / a]. The loads are linear in t, so the grid's interpolation is exact.
"""

import math
from concurrent.futures import ProcessPoolExecutor
from statistics import NormalDist

import numpy as np
import pandas as pd
import pytest
from _fleets import DISTS, fleet
from _fleets import PRESETS as PRESETS_

import bogie.fleet as bf
from bogie.fleet.design import analysis as A
from bogie.fleet.design import experiment as L

STATIC = bf.StaticProtocol(load_time=2.0, approach_length=5.0, crawl_speed=1.4, settle_time=3.0, dt=1e-3,
                           step_tolerance=2e-7)  # fmt: skip
LIMIT = 0.05 / 1.95  # the largest |s| within 5 %


def wilson(k, n, confidence=0.95):
    """The Wilson score interval by its formula (E. B. Wilson 1927), z from the normal quantile."""
    z = NormalDist().inv_cdf(0.5 + confidence / 2)
    p = k / n
    centre, half = p + z * z / (2 * n), z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return (centre - half) / (1 + z * z / n), (centre + half) / (1 + z * z / n)


# ---- the analysis on a hand-made runs table ----------------------------------------------------------------------
TILTS = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
#: design -> (kind, suspension, slope a [1/degree], offset b, bush [N m/rad], distance [-])
CASES = {
    "tandem-typical": ("typical", "steel", 0.02, 0.01, 55.0, 0.0),
    "tandem-grid-00": ("grid", "steel", 0.01, 0.0, 1.0, 0.5),
    "tandem-grid-01": ("grid", "steel", 0.03, 0.01, 3000.0, 0.6),
    "tandem-air": ("air", "air", 0.0, 0.0, 55.0, math.nan),
}
#: each condition's own tilt [degree]: 7 level, 3 at 1.5 degree; an 11th whose own-tilt run failed
OWN = [0.0] * 7 + [1.5] * 3 + [0.0]


def hand_runs():
    rows = []
    for design, (_, _, a, b, _, _) in CASES.items():
        for c, own in enumerate(OWN):
            for slot, t in [(A.FLEET_SLOT, own), *enumerate(TILTS)]:
                s = a * t + b
                failed = c == 10 and slot == A.FLEET_SLOT
                rows.append({
                    "design": design, "condition": c, "slot": slot, "status": "failed" if failed else "ok",
                    "chassis_tilt": math.radians(t), "axle_load_1": math.nan if failed else 1e4 * (1 + s),
                    "axle_load_2": math.nan if failed else 1e4 * (1 - s),
                    "outside_5pct": None if failed else 2 * abs(s) / (1 + abs(s)) > 0.05,
                    "over_10pct": None if failed else 1 + abs(s) > 1.10,
                    "max_deviation": math.nan if failed else abs(s),
                })  # fmt: skip
    return pd.DataFrame(rows)


def hand_designs():
    return pd.DataFrame([{
        "design": d, "group": "tandem", "kind": kind, "suspension": suspension, "bush_stiffness": bush,
        "equaliser_arm": 0.25, "contact_roll_radius": 0.0, "friction_coefficient": 0.26,
        "spring_friction_band": 2000.0, "bush_damping": 17.0, "spring_friction_decay": 0.005, "distance": distance,
    } for d, (kind, suspension, _, _, bush, distance) in CASES.items()])  # fmt: skip


def test_the_analysis_gives_the_hand_worked_shares_intervals_tolerances_and_front():
    a = bf.analyse_designs(hand_runs(), hand_designs(), TILTS, 0.95, 0.95)
    table = a.designs.set_index("design")
    # best first: the front by share (grid-00 100 %, typical 70 % nearer than grid-01's 70 %), the rest, the air
    assert a.designs["design"].tolist() == ["tandem-grid-00", "tandem-typical", "tandem-grid-01", "tandem-air"]
    assert table["pareto"].tolist() == [True, True, False, False]
    typ = table.loc["tandem-typical"]
    # own tilts: s = 0.01 at level (within), 0.04 at 1.5 degree (outside 5 %: 0.077; within 10 %: 1.04)
    assert (typ["n_runs"], typ["n_failed"], typ["n_conditions"], typ["n_curve_conditions"]) == (66, 1, 10, 11)
    assert (typ["within_5pct"], typ["within_10pct"]) == (7, 10)
    assert typ["share_within_5pct"] == pytest.approx(0.7) and typ["share_within_10pct"] == 1.0
    assert (typ["share_within_5pct_low"], typ["share_within_5pct_high"]) == pytest.approx(wilson(7, 10), abs=1e-12)
    assert (typ["share_within_10pct_low"], typ["share_within_10pct_high"]) == pytest.approx(wilson(10, 10), abs=1e-12)
    assert typ["mean_max_deviation"] == pytest.approx((7 * 0.01 + 3 * 0.04) / 10)
    # s = 0.02 t + 0.01 within 5 % for t in [-1.782, 0.782]: on the 0.01 degree axis 0.78 up, 1.78 down
    assert math.floor(100 * (LIMIT - 0.01) / 0.02) / 100 == 0.78
    assert (typ["tilt_tolerance_nose_up_deg"], typ["tilt_tolerance_nose_down_deg"]) == pytest.approx((0.78, 1.78))
    assert typ["share_within_5pct_at_tolerance"] == 1.0 and typ["share_within_5pct_level"] == 1.0
    # s = 0.03 t + 0.01: t in [-1.188, 0.521]; s = 0.01 t: |t| <= 2.56, beyond the grid's end
    steep = table.loc["tandem-grid-01"]
    assert (steep["tilt_tolerance_nose_up_deg"], steep["tilt_tolerance_nose_down_deg"]) == pytest.approx((0.52, 1.18))
    assert (table.loc["tandem-grid-00", ["tilt_tolerance_nose_up_deg", "tilt_tolerance_nose_down_deg"]] == 2.0).all()
    curve = a.curves[a.curves["design"] == "tandem-typical"].set_index("tilt_deg")["share_within_5pct"]
    assert curve.loc[0.78] == 1.0 and curve.loc[0.79] == 0.0 and curve.loc[-1.78] == 1.0 and curve.loc[-1.79] == 0.0
    # linear loads are interpolated exactly: the check agrees with every run at its own tilt
    assert len(a.check) == 4 * 10
    np.testing.assert_allclose(a.check["max_deviation_interpolated"], a.check["max_deviation_direct"], atol=1e-12)
    assert (a.check["within_interpolated"] == a.check["within_direct"]).all()


def test_the_sentences_say_the_hand_worked_numbers():
    a = bf.analyse_designs(hand_runs(), hand_designs(), TILTS, 0.95, 0.95)
    words = bf.guidance_sentences(a.designs, TILTS, 0.95)
    low = round(100 * wilson(10, 10)[0])
    assert low == 72
    assert words == [
        "With a free bearing, fixed contact points (0 mm pads) and a 250 mm arm (friction 0.26, springs' band "
        "2.0 kN), 95 % of tandems stay within 5 % from at least 2.0 degrees nose down to at least 2.0 degrees nose "
        "up: the widest tilt tolerance of the 3 tandem designs.",
        "Today's typical tandem, with a 55 N m/rad bush, fixed contact points (0 mm pads) and a 250 mm arm (friction "
        "0.26, springs' band 2.0 kN), keeps 95 % within 5 % only from 1.8 degrees nose down to 0.8 degrees nose up: "
        "an operator running it should keep the fifth-wheel height mismatch within that tilt.",
        "Across the fleet's own tilts, wear, payloads and roads the best tandem design, with a free bearing, fixed "
        "contact points (0 mm pads) and a 250 mm arm (friction 0.26, springs' band 2.0 kN), keeps 100 % (72-100 %) "
        "within 5 %, the 95 % target; today's typical design 70 %.",
        "The air-sprung tandem group on the same trailer keeps 95 % within 5 % from at least 2.0 degrees nose down "
        "to at least 2.0 degrees nose up, and 100 % across the fleet's conditions.",
    ]


def test_the_tilt_tolerance_of_a_monotone_share_curve():
    fine = np.round(np.arange(-2.0, 2.0 + 1e-9, 0.01), 6)
    share = np.where(fine >= 0.0, 1.0 - 0.06 * fine, 1.0 + 0.07 * fine)  # >= 0.95 for t in [-0.714, 0.833]
    up, down, at = bf.tilt_tolerance(fine, share, 0.95)
    assert (up, down) == (0.83, 0.71)
    assert at == pytest.approx(min(1.0 - 0.06 * 0.83, 1.0 - 0.07 * 0.71))
    # below the target already on level ground: no tolerance, and the level share
    assert bf.tilt_tolerance(fine, share - 0.1, 0.95) == (None, None, pytest.approx(0.9))


# ---- the experiment's rows ---------------------------------------------------------------------------------------
def test_the_experiment_runs_every_design_over_the_same_conditions_and_tilts():
    f = fleet()
    typical = L.typical_design(f)
    assert typical["bush_stiffness"] == pytest.approx(math.sqrt(3000.0)) and typical["equaliser_arm"] == 0.2
    settings = bf.DesignSettings(grid={"bush_stiffness": [typical["bush_stiffness"], 1.0]}, groups=("tandem",),
                                 n_conditions=3, tilt_step_deg=0.5, n_space_filling=2)  # fmt: skip
    exp = bf.design_experiment(f, settings, seed=7)
    # the tilt range is +-0.03 rad = +-1.719 degree: level outward by 0.5 degree, both ends kept
    d = math.degrees(0.03)
    np.testing.assert_allclose(exp.tilts, [-d, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, d], rtol=0, atol=1e-9)
    # the grid design equal to the typical one is not run twice
    assert exp.designs["design"].tolist() == ["tandem-typical", "tandem-grid-01", "tandem-space-00",
                                              "tandem-space-01", "tandem-air"]  # fmt: skip
    assert len(exp.samples) == 5 * 3 * (9 + 1)
    free = exp.designs.set_index("design").loc["tandem-grid-01"]
    assert free["distance"] == pytest.approx(0.5, abs=1e-3)  # rank 0 of the bush, the other factors at their median
    assert exp.designs.set_index("design").loc["tandem-typical", "distance"] == pytest.approx(0.0, abs=1e-3)
    for column in ("payload_fraction", "tyre_wear_1", "tyre_wear_2", "road_class", "road_seed", "chassis_tilt"):
        per = [rows.sort_values(["condition", "slot"])[column].tolist() for _, rows in exp.samples.groupby("design")]
        assert all(p == per[0] for p in per), column
    own = exp.samples[exp.samples["slot"] == A.FLEET_SLOT].drop_duplicates("condition")
    np.testing.assert_array_equal(own["chassis_tilt"].to_numpy(), exp.conditions["chassis_tilt"].to_numpy())
    # the same seed, the same rows; another seed, other conditions
    pd.testing.assert_frame_equal(bf.design_experiment(f, settings, 7).samples, exp.samples, check_exact=True)
    other = L.conditions(f, 3, seed=8)
    assert not np.array_equal(other["chassis_tilt"].to_numpy(), exp.conditions["chassis_tilt"].to_numpy())


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"grid": {"bush_damping": [1.0]}}, r"grid: 'bush_damping' is not a design factor; allowed: bush_stiffness"),
        ({"grid": {"equaliser_arm": [0.2, -0.1]}}, r"grid\['equaliser_arm'\]\[1\] = -0.1 is out of range: must be >= "),
        ({"grid": {"bush_stiffness": [1.0, 1.0]}}, r"grid\['bush_stiffness'\] = \[1.0, 1.0\]: lists a level twice"),
        ({"grid": {"spring_friction_band": []}}, r"grid\['spring_friction_band'\] = \[\]: .* one or more levels, in N"),
        ({"grid": {}}, r"grid = \{\}: must map one or more of bush_stiffness"),
        ({"groups": ("quad",)}, r"groups = \('quad',\): must be one or more distinct axle groups among tandem"),
        ({"n_conditions": 1}, r"n_conditions = 1 is out of range: must be a whole number >= 2 -"),
        ({"n_space_filling": 1.5}, r"n_space_filling = 1.5 is not a whole number \(float\): .* >= 0 -"),
        ({"tilt_step_deg": 0.0}, r"tilt_step_deg = 0.0 is out of range: must be > 0 degree"),
        ({"target_share": 1.5}, r"target_share = 1.5 is out of range: must be in \(0, 1\) -"),
        ({"confidence_level": 0.0}, r"confidence_level = 0.0 is out of range: must be in \(0, 1\) -"),
    ],
)
def test_bad_settings_are_refused_naming_the_argument_value_range_and_unit(changes, message):
    with pytest.raises(bf.DesignError, match=message):
        bf.DesignSettings(**{"grid": {"bush_stiffness": [1.0]}, **changes})


def test_bad_arguments_of_the_steps_are_refused():
    nose_up = fleet(distributions={**DISTS, "chassis_tilt": bf.Uniform(0.01, 0.03)})
    with pytest.raises(bf.DesignError, match=r"chassis_tilt'\]: its range \[0.57\d*, 1.7\d*\] degree must include"):
        L.tilt_grid(nose_up, 0.5)
    with pytest.raises(bf.DesignError, match=r"seed = -1 is out of range: must be a whole number >= 0 -"):
        L.conditions(fleet(), 3, seed=-1)
    with pytest.raises(bf.DesignError, match=r"tilts = .*strictly increasing, in degree"):
        bf.analyse_designs(hand_runs(), hand_designs(), TILTS[::-1], 0.95, 0.95)
    with pytest.raises(bf.DesignError, match=r"confidence_level = 1 is out of range: must be in \(0, 1\) -"):
        bf.analyse_designs(hand_runs(), hand_designs(), TILTS, 0.95, 1)
    with pytest.raises(bf.DesignError, match="runs: the columns slot are missing"):
        bf.analyse_designs(hand_runs().drop(columns="slot"), hand_designs(), TILTS, 0.95, 0.95)
    with pytest.raises(bf.DesignError, match="static = .*must be a bogie.fleet.StaticProtocol"):
        bf.weigh_designs(bf.design_experiment(fleet(), bf.DesignSettings(grid={"bush_stiffness": [1.0]}), 1), None)


# ---- weighed --------------------------------------------------------------------------------------------------------
def test_a_small_study_weighed_here_and_in_worker_processes_gives_the_same_tables():
    settings = bf.DesignSettings(grid={"bush_stiffness": [300.0]}, groups=("tandem",), n_conditions=2,
                                 tilt_step_deg=2.0, n_space_filling=0)  # fmt: skip
    here = bf.study_designs(fleet(), settings, seed=7, static=STATIC)
    # typical, grid-00 and the air reference x 2 conditions x (3 tilts: -1.72, 0, 1.72, and each own)
    assert len(here.runs) == 3 * 2 * 4 and (here.runs["status"] == "ok").all()
    assert here.analysis.designs["n_runs"].tolist() == [8, 8, 8] and len(here.guidance) == 4
    # the air group shares its load through connected bags: within 5 % at every tilt of the grid
    air = here.analysis.designs.set_index("design").loc["tandem-air"]
    assert air["tilt_tolerance_nose_up_deg"] == pytest.approx(math.degrees(0.03), abs=0.01)
    with ProcessPoolExecutor(2) as pool:
        there = bf.study_designs(fleet(), settings, seed=7, static=STATIC, executor=pool)
    pd.testing.assert_frame_equal(there.runs, here.runs, check_exact=True)
    for name in ("designs", "curves", "check"):
        pd.testing.assert_frame_equal(getattr(there.analysis, name), getattr(here.analysis, name), check_exact=True)
    assert there.guidance == here.guidance


# ---- the designer's own bogie (issue 45 Must 4) ------------------------------------------------------------------
EXAMPLE = __import__("pathlib").Path(__file__).resolve().parents[1] / "bogies" / "example_triaxle.yaml"


def test_a_bogie_file_base_is_weighed_as_its_own_named_design_with_the_files_values():
    from bogie.bogie_file import base_bogie
    from bogie.fleet.sampling.sample import bogie_from_sample

    f = fleet(presets={**PRESETS_, "triaxle": str(EXAMPLE)})
    settings = bf.DesignSettings(grid={"bush_stiffness": [1.0]}, groups=("triaxle",), n_conditions=2,
                                 tilt_step_deg=2.0, n_space_filling=0)  # fmt: skip
    exp = bf.design_experiment(f, settings, seed=7)
    assert exp.designs["design"].tolist() == ["triaxle-typical", "triaxle-own", "triaxle-grid-00", "triaxle-air"]
    own = exp.designs.set_index("design").loc["triaxle-own"]
    # the example file's values (bogies/example_triaxle.yaml), in SI
    expected = {"bush_stiffness": 1000.0, "equaliser_arm": 0.18, "contact_roll_radius": 0.075,
                "friction_coefficient": 0.25, "spring_friction_band": 500.0, "bush_damping": 0.0,
                "spring_friction_decay": 0.005}  # fmt: skip
    assert {k: own[k] for k in expected} == pytest.approx(expected, rel=1e-12)
    assert own["kind"] == "own" and 0.0 < own["distance"] < 1.2
    # its rows build the file's bogie, under each condition's tilt, wear and payload
    row = exp.samples[exp.samples["design"] == "triaxle-own"].iloc[0]
    built, file = bogie_from_sample(row.to_dict()), base_bogie(str(EXAMPLE))
    for field in ("bush_stiffness", "contact_roll_radius", "equaliser_front_arm", "equaliser_rear_arm",
                  "spring_front_half_length", "spring_rear_half_length", "spring_friction_band"):  # fmt: skip
        assert getattr(built, field) == pytest.approx(getattr(file, field), rel=1e-12), field


def test_a_files_arms_of_several_lengths_are_kept_as_they_are(tmp_path):
    from bogie.fleet.sampling.sample import bogie_from_sample

    text = EXAMPLE.read_text(encoding="utf-8")
    text = text.replace("equaliser_rear_arm_mm: [180, 180]", "equaliser_rear_arm_mm: [200, 200]")
    text = text.replace("spring_front_half_length_mm: [500, 500, 500]", "spring_front_half_length_mm: [500, 480, 480]")
    path = tmp_path / "uneven.yaml"
    path.write_text(text, encoding="utf-8")
    f = fleet(presets={**PRESETS_, "triaxle": str(path)})
    settings = bf.DesignSettings(grid={"bush_stiffness": [1.0]}, groups=("triaxle",), n_conditions=2)
    exp = bf.design_experiment(f, settings, seed=7)
    own = exp.designs.set_index("design").loc["triaxle-own"]
    assert math.isnan(own["equaliser_arm"]) and math.isfinite(own["distance"])
    built = bogie_from_sample(exp.samples[exp.samples["design"] == "triaxle-own"].iloc[0].to_dict())
    assert built.equaliser_front_arm == pytest.approx((0.18, 0.18)) and built.equaliser_rear_arm == pytest.approx(
        (0.2, 0.2)
    )
    assert built.spring_front_half_length == pytest.approx((0.5, 0.48, 0.48))
    assert "its own arms of several lengths" in A.describe(own.to_dict())


def test_the_own_design_is_weighed_and_its_sentence_names_the_file_beside_the_typical_and_the_best():
    f = fleet(presets={**PRESETS_, "triaxle": str(EXAMPLE)})
    settings = bf.DesignSettings(grid={"bush_stiffness": [1.0]}, groups=("triaxle",), n_conditions=2,
                                 tilt_step_deg=2.0, n_space_filling=0)  # fmt: skip
    study = bf.study_designs(f, settings, seed=7, static=STATIC)
    table = study.analysis.designs.set_index("design")
    assert table.loc["triaxle-own", "n_runs"] == 2 * 4 and table.loc["triaxle-own", "n_failed"] == 0
    # per group: tolerance, typical, own, fleet, air
    assert len(study.guidance) == 5
    sentence = study.guidance[2]
    share = table.loc["triaxle-own", "share_within_5pct"]
    assert sentence.startswith(f"Your tri-axle ({EXAMPLE}), with a 1000 N m/rad bush, 75 mm pads and a 180 mm arm")
    assert f"keeps {100 * share:.0f} % (" in sentence and "today's typical" in sentence
    assert "the best of the 3 designs" in sentence
