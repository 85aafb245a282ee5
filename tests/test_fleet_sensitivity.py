"""bogie.fleet.sampling.sensitivity: the Sobol' sensitivity design with plain arguments; errors name what is wrong."""

import subprocess
import sys

import numpy as np
import pytest
from _fleets import DISTS, GROUP_LOAD, PRESETS, fleet

import bogie.fleet as bf
from bogie.fleet.sampling import sensitivity as S
from bogie.fleet.sampling.sample import COLUMNS

FACTORS = ("chassis_tilt", "tyre_wear", "bush_stiffness")


@pytest.fixture(scope="module")
def design():
    return bf.sensitivity_design(fleet(), FACTORS, "triaxle", base_size=8, seed=3)


# ---- the problem -------------------------------------------------------------------------------------------------
def test_a_triaxles_tyre_wear_is_three_variables_in_one_group():
    problem = bf.sensitivity_problem(FACTORS, "triaxle")
    assert problem["names"] == ["chassis_tilt", "tyre_wear_1", "tyre_wear_2", "tyre_wear_3", "bush_stiffness"]
    assert problem["groups"] == ["chassis_tilt", "tyre_wear", "tyre_wear", "tyre_wear", "bush_stiffness"]
    assert problem["num_vars"] == 5 and problem["bounds"] == [[0.0, 1.0]] * 5
    tandem = bf.sensitivity_problem(["tyre_wear"], "tandem")
    assert tandem["names"] == ["tyre_wear_1", "tyre_wear_2"] and tandem["groups"] == ["tyre_wear"] * 2


def test_each_call_gives_a_new_problem():
    # SALib adds keys to the problem it is given
    first = bf.sensitivity_problem(FACTORS, "triaxle")
    first["names"].append("x")
    assert len(bf.sensitivity_problem(FACTORS, "triaxle")["names"]) == 5


def test_every_numeric_fleet_quantity_may_be_a_factor_and_road_class_may_not():
    assert set(bf.SENSITIVITY_FACTORS) == set(bf.FLEET_QUANTITIES) - {"road_class"}
    assert bf.sensitivity_problem(bf.SENSITIVITY_FACTORS, "tandem")["num_vars"] == len(bf.SENSITIVITY_FACTORS) + 1


# ---- the design --------------------------------------------------------------------------------------------------
def test_the_design_has_n_times_groups_plus_two_rows_of_the_sample_columns(design):
    assert len(design) == 8 * (3 + 2)
    assert {c: str(t) for c, t in design.dtypes.items()} == COLUMNS
    assert design["sample_id"].tolist() == list(range(40))
    assert design["base_id"].tolist() == [i // 5 for i in range(40)]
    assert (design["study"] == "sensitivity").all() and (design["group"] == "triaxle").all()
    assert (design["n_axles"] == 3).all() and (design["preset"] == PRESETS["triaxle"]).all()
    assert (design["suspension"] == "steel").all() and (design["legal_group_load"] == GROUP_LOAD["triaxle"]).all()
    assert not design.isna().any().any()


def test_non_factors_are_at_their_median_and_share_one_road_and_sensor(design):
    # the test fleet's medians by hand: Uniform(0.5, 1) -> 0.75, Uniform(0.12, 0.28) -> 0.20, Choice(A, B) -> B
    assert (design["payload_fraction"] == 0.75).all()
    assert design["equaliser_arm"].to_numpy() == pytest.approx(0.20, abs=1e-15)
    assert (design["road_class"] == "B").all()
    assert (design["road_seed"] == bf.road_seed(3, "sensitivity", 0)).all()
    assert (design["sensor_seed"] == bf.sensor_seed(3, "sensitivity", 0)).all()
    # a factor varies, within its distribution's support: Uniform(-0.03, 0.03) [rad], Uniform(0, 0.012) [m]
    assert design["chassis_tilt"].nunique() > 8 and design["chassis_tilt"].abs().max() <= 0.03
    wear = design[["tyre_wear_1", "tyre_wear_2", "tyre_wear_3"]].to_numpy()
    assert ((0.0 <= wear) & (wear <= 0.012)).all() and len(np.unique(wear)) > 8


def test_a_tandem_has_no_third_axles_wear_and_its_wear_at_the_median_when_not_a_factor():
    design = bf.sensitivity_design(fleet(), ["bush_damping"], "tandem", 4, seed=0)
    assert len(design) == 4 * 3 and (design["n_axles"] == 2).all()
    assert (design["tyre_wear_1"] == 0.006).all() and (design["tyre_wear_2"] == 0.006).all()
    assert (design["tyre_wear_3"] == 0.0).all()


def test_each_saltelli_block_changes_one_factor_group_at_a_time(design):
    problem = bf.sensitivity_problem(FACTORS, "triaxle")
    names, groups = problem["names"], problem["groups"]
    for _, rows in design.groupby("base_id"):
        block = rows[names].to_numpy()
        a, b = block[0], block[-1]
        for k, factor in enumerate(dict.fromkeys(groups)):
            mine = np.array([g == factor for g in groups])
            assert (block[1 + k][~mine] == a[~mine]).all() and (block[1 + k][mine] == b[mine]).all()


def test_the_factors_are_salibs_design_through_the_fleets_distributions(design):
    from SALib.sample import sobol

    problem = bf.sensitivity_problem(FACTORS, "triaxle")
    u = sobol.sample(problem, 8, calc_second_order=False, scramble=True, seed=bf.design_seed(3, "sensitivity"))
    assert (design["chassis_tilt"].to_numpy() == DISTS["chassis_tilt"].ppf(u[:, 0])).all()
    assert (design["tyre_wear_2"].to_numpy() == DISTS["tyre_wear"].ppf(u[:, 2])).all()
    assert (design["bush_stiffness"].to_numpy() == DISTS["bush_stiffness"].ppf(u[:, 4])).all()


def test_same_arguments_same_design_another_seed_another(design):
    assert bf.sensitivity_design(fleet(), list(FACTORS), "triaxle", 8, 3).equals(design)
    other = bf.sensitivity_design(fleet(), FACTORS, "triaxle", 8, 4)
    assert not np.array_equal(other["chassis_tilt"], design["chassis_tilt"])


def test_a_group_outside_the_fleets_axle_mix_is_designed_from_its_preset():
    only_tandem = fleet(axle_mix={"tandem": 1.0})
    design = bf.sensitivity_design(only_tandem, ["chassis_tilt"], "triaxle", 2, 1)
    assert (design["preset"] == PRESETS["triaxle"]).all() and len(design) == 2 * 3


def test_salib_loads_only_when_a_design_is_made():
    # the simulate stage's workers import the sampling modules and need none of SALib
    code = "import sys, bogie.fleet.sampling.sensitivity; print('SALib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# ---- bad arguments -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"factors": ["chassis_tilt", "tilt"]}, r"factors\[1\] = 'tilt'.*must be one of bush_stiffness, .*tyre_wear"),
        ({"factors": ["road_class"]}, r"factors\[0\] = 'road_class' is categorical.*must be one of bush_stiffness"),
        ({"factors": ["tyre_wear", "tyre_wear"]}, r"factors\[1\] = 'tyre_wear' is listed twice"),
        ({"factors": []}, r"factors = \[\] is not a list of factor names: must be at least one of bush_stiffness"),
        ({"factors": "tyre_wear"}, r"factors = 'tyre_wear' is not a list"),
        ({"group": "quad"}, r"group = 'quad'.*must be one of tandem, triaxle"),
        ({"base_size": 12}, r"base_size = 12 is not a power of 2"),
        ({"base_size": 1}, r"base_size = 1\b.*must be a whole number >= 2"),
        ({"base_size": 8.0}, r"base_size = 8.0\b.*must be a whole number"),
        ({"seed": -1}, r"seed = -1\b.*must be a whole number >= 0"),
        ({"fleet": DISTS}, r"fleet = \{'bush_stiffness'.*\.\.\. is a dict: must be a bogie.fleet.Fleet"),
        (
            {"fleet": fleet(axle_mix={"tandem": 1.0}, presets={"tandem": "tandem_trrl"})},
            r"fleet, for the design's group 'triaxle' \(not in its axle_mix\): presets.*triaxle",
        ),
    ],
)
def test_bad_arguments_are_refused_naming_them(kwargs, message):
    args = {"fleet": fleet(), "factors": FACTORS, "group": "triaxle", "base_size": 8, "seed": 3, **kwargs}
    with pytest.raises(bf.FleetError, match=message):
        bf.sensitivity_design(**args)


def test_the_names_are_bogie_fleets():
    for name in ("SENSITIVITY_FACTORS", "sensitivity_design", "sensitivity_problem"):
        assert name in bf.__all__ and getattr(bf, name) is getattr(S, name)
