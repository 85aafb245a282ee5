"""bogie.fleet: a fleet study with plain arguments (issue 29 Must 1); the errors name what is wrong."""

import dataclasses
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd
import pytest
from _fleets import DISTS, PRESETS, fleet

import bogie.fleet as bf
from bogie.fleet.weighing.observed import simulated_readings
from bogie.params import GRAVITY

STATIC = bf.StaticProtocol(load_time=2.0, approach_length=5.0, crawl_speed=1.4, settle_time=3.0, dt=1e-3)
WIM = bf.WimProtocol(speed=22.0, approach_length=30.0, dt=1e-3, sensor="quartz")


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"distributions": {k: v for k, v in DISTS.items() if k != "tyre_wear"}}, "missing tyre_wear"),
        ({"distributions": {**DISTS, "tilt": bf.Uniform(0, 1)}}, "unknown tilt"),
        ({"distributions": {**DISTS, "road_class": bf.Choice(("A", "Z"))}}, "ISO 8608 classes"),
        ({"axle_mix": {"tandem": 0.5, "triaxle": 0.6}}, "sum to 1, they sum to 1.1"),
        ({"axle_mix": {"quad": 1.0}}, "keys must be among tandem, triaxle"),
        ({"presets": {**PRESETS, "triaxle": "nope"}}, r"presets\['triaxle'\] = 'nope': must be one of tandem_trrl"),
        ({"legal_group_load": {"tandem": 1.0}}, "a value is needed for triaxle"),
        (
            {"legal_group_load": {"tandem": -1.0, "triaxle": 1.0}},
            r"legal_group_load\['tandem'\] = -1.0 is out of range: must be > 0 N",
        ),
        ({"suspension_mix": {"tandem": {"steel": 1.0}}}, "a mix is needed for triaxle"),
    ],
)
def test_a_fleet_that_cannot_be_sampled_is_refused_naming_what_is_wrong(changes, message):
    with pytest.raises(bf.FleetError, match=message):
        fleet(**changes)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"n_bogies": 0}, "n_bogies = 0"), ({"n_bogies": 2.5}, "n_bogies = 2.5"), ({"sampling": "grid"}, "sampling"),
     ({"seed": -1}, "seed = -1")],
)  # fmt: skip
def test_bad_sampling_arguments_are_refused(kwargs, message):
    with pytest.raises(bf.FleetError, match=message):
        bf.sample_fleet(fleet(), **{"n_bogies": 4, "seed": 1, **kwargs})


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: dataclasses.replace(STATIC, dt=0.0), r"StaticProtocol.dt = 0.0 is out of range: must be > 0 s"),
        (
            lambda: dataclasses.replace(STATIC, step_tolerance=-1e-7),
            r"StaticProtocol.step_tolerance = -1e-07 is out of range: must be > 0 m, or None",
        ),
        (lambda: dataclasses.replace(WIM, speed=math.nan), r"WimProtocol.speed = nan is out of range: .* m/s"),
        (
            lambda: dataclasses.replace(WIM, site_length_after=-5.0),
            r"site_length_after = -5.0 is out of range: must be >= 0 m",
        ),
        (lambda: dataclasses.replace(WIM, sensor="Quartz"), "sensor = 'Quartz' is unknown: must be one of none"),
        (
            lambda: dataclasses.replace(WIM, sensor_axle_error=0.5),
            r"sensor_axle_error = 0.5 is out of range: must be in \[0, 0.5\) -, or None",
        ),
    ],
)
def test_bad_protocol_settings_are_refused_with_their_unit(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_the_sample_follows_the_mix_and_the_seed_and_keeps_each_quantity_in_its_distribution():
    samples = bf.sample_fleet(fleet(axle_mix={"tandem": 0.25, "triaxle": 0.75}), n_bogies=40, seed=3)
    assert (samples["group"] == "tandem").sum() == 10  # a stratified design: the share to within one bogie
    assert samples["n_axles"].tolist() == [2 if g == "tandem" else 3 for g in samples["group"]]
    assert samples["tyre_wear_3"][samples["group"] == "tandem"].eq(0.0).all()  # no third axle, no wear
    assert samples["bush_stiffness"].between(1.0, 3000.0).all() and set(samples["road_class"]) <= {"A", "B"}
    again = bf.sample_fleet(fleet(axle_mix={"tandem": 0.25, "triaxle": 0.75}), n_bogies=40, seed=3)
    pd.testing.assert_frame_equal(samples, again, check_exact=True)
    other = bf.sample_fleet(fleet(axle_mix={"tandem": 0.25, "triaxle": 0.75}), n_bogies=40, seed=4)
    assert not np.array_equal(other["bush_stiffness"], samples["bush_stiffness"])


def test_weighing_in_worker_processes_gives_the_table_of_this_process_bit_for_bit():
    samples = bf.sample_fleet(fleet(), n_bogies=6, seed=5)
    here = bf.weigh_fleet(samples, {"static": STATIC, "wim": WIM})
    with ProcessPoolExecutor(2) as pool:
        there = bf.weigh_fleet(samples, {"static": STATIC, "wim": WIM}, executor=pool, chunk_rows=4)
    pd.testing.assert_frame_equal(here, there, check_exact=True)
    assert (here["status"] == "ok").all()
    # the static reading carries the group's weight: its axle loads sum to the group load, both sides [N]
    loads = here[[f"axle_load_{i + 1}" for i in range(3)]].to_numpy().sum(axis=1)
    np.testing.assert_allclose(loads, here["group_load"], rtol=1e-12)


def test_a_sample_that_is_no_valid_bogie_is_a_failed_row_with_its_reason_never_dropped():
    samples = bf.sample_fleet(fleet(), n_bogies=3, seed=6)
    samples.loc[1, "friction_coefficient"] = -0.5
    runs = bf.weigh_fleet(samples, {"static": STATIC})
    assert runs["status"].astype(str).tolist() == ["ok", "failed", "ok"]
    failed = runs.iloc[1]
    assert "invalid bogie" in failed["message"] and "friction_coefficient" in failed["message"]
    assert math.isnan(failed["axle_load_1"]) and pd.isna(failed["outside_5pct"])


@pytest.mark.parametrize(
    ("protocols", "message"),
    [({}, "none given"), ({"weighbridge": STATIC}, "'weighbridge' unknown"),
     ({"wim": STATIC}, "must be a WimProtocol")],
)  # fmt: skip
def test_unknown_protocols_are_refused(protocols, message):
    with pytest.raises(ValueError, match=message):
        bf.weigh_fleet(bf.sample_fleet(fleet(), n_bogies=2, seed=1), protocols)


def test_the_simulated_readings_count_every_run_left_out_and_keep_the_rest():
    samples = bf.sample_fleet(fleet(), n_bogies=4, seed=7)
    samples.loc[2, "friction_coefficient"] = -0.5  # one bogie fails under both protocols
    runs = bf.weigh_fleet(samples, {"static": STATIC, "wim": WIM})
    light = float(runs.loc[runs["status"] == "ok", "group_load"].min()) / GRAVITY + 1.0  # the lightest reading goes
    readings, counts = simulated_readings(runs, min_group_load_kg=light, position="all")
    total = {k: sum(c[k] for c in counts.values()) for k in ("n_runs", "n_failed", "n_light", "n_kept")}
    assert total["n_runs"] == 8 and total["n_failed"] == 2 and total["n_light"] == 1
    assert total["n_kept"] == len(readings) == 8 - 2 - 1 - sum(c["n_airborne"] for c in counts.values())
    assert simulated_readings(runs, 0.0, "drive")[0].empty  # a simulated bogie is a trailer's group
