"""The calibrate stage: a synthetic survey recovered, the table's interpolation, the distance, bad input, the skip.

The synthetic survey is made by the simulator itself from known fleet values on an independent fleet (another
master seed: other bogies, roads and sensor draws than the calibration fleet's), written in the csv weighings format
and read back as a real survey would be.
"""

import copy
import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.stats import truncnorm

from bogie.fleet.calibration import attribution as A
from bogie.fleet.calibration import checks as K
from bogie.fleet.calibration import problem as L
from bogie.params import INHIBITORS
from pipeline import calibrate as C
from pipeline.config import ConfigError, parse_config

ROOT = Path(__file__).resolve().parents[2]
#: the known fleet of the synthetic survey (site roughness: the protocol's own, not fitted here)
#: the synthetic survey is read at its own WIM site (issue 43 Must 2): another seed's road, and a calibration bias of
#: +3 % on every reading
TRUTH = {
    "chassis_tilt_mean_deg": 0.8, "chassis_tilt_sd_deg": 0.5, "air_share": 0.4, "site_iri_m_km": 1.3,
    "sensor_error_pct": 3.0, "site_bias_pct": 3.0,
}  # fmt: skip
FIT = {
    "chassis_tilt_mean_deg": [-1.0, 1.5], "chassis_tilt_sd_deg": [0.1, 1.5], "air_share": [0.0, 1.0],
    "sensor_error_pct": [0.0, 8.0], "site_bias_pct": [-15.0, 15.0],
}  # fmt: skip


#: the calibration fleet of the recovery: the survey is on its own site (another seed's), the table on another, and
#: the between-site covariance comes from 2 x 32 of these bogies weighed on 16 more. Measured on 2026-12-06: with 60
#: bogies the posterior was unconverged and missed the sensor's truth (4.2 [3.2, 5.0] % against 3.0); with 150 it
#: converged and held every truth (tilt centre 0.72 [0.30, 1.05] degree, sensor 3.1 [2.2, 3.9] %). The default is 300.
RECOVERY_BOGIES = 150


def raw_params(n_bogies=60, **calibrate):
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["fleet"]["n_bogies"] = n_bogies
    raw["ablation"]["n_bogies"] = 10
    raw["execution"]["n_jobs"] = 2
    raw["calibrate"].update(
        n_bogies=n_bogies, tilt_step_deg=0.5, bootstrap_resamples=20, maxiter=20, popsize=6, fit=copy.deepcopy(FIT)
    )
    raw["calibrate"].update(calibrate)
    return raw


def synthetic_survey(path, n_vehicles=300, seed=777):
    """A survey of ``n_vehicles`` simulated groups of an independent fleet with the fleet values of TRUTH."""
    raw = raw_params(n_vehicles)
    raw["seed"] = seed
    config = parse_config(raw)
    frame = K.filtered(K.simulate_fleet(C.crn_table(config), TRUTH, executor=C.workers_map(config.execution)), 0.0)
    K.write_csv_survey(frame, path)
    return frame


def project(tmp_path, raw, survey="observed/s.csv"):
    raw = copy.deepcopy(raw)
    raw["observed"].update(path=survey, format="csv")
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    return [
        "--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "data" / "calibration"),
        "--metrics", str(tmp_path / "metrics" / "calibration.json"),
    ]  # fmt: skip


#: the attribution of the stage's run, unrounded (bogie.fleet.calibration.attribution.attribute_loads's answer)
ATTRIBUTED: dict = {}


@pytest.fixture(scope="module")
def recovered(tmp_path_factory):
    root = tmp_path_factory.mktemp("calibrate")
    synthetic_survey(root / "observed" / "s.csv")

    def attribute_loads(*args, **kwargs):
        out = attribute(*args, **kwargs)
        ATTRIBUTED.update(out)
        return out

    attribute = A.attribute_loads
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(A, "attribute_loads", attribute_loads)
        assert C.main(project(root, raw_params(RECOVERY_BOGIES))) == 0
    metrics = json.loads((root / "metrics" / "calibration.json").read_text())
    return root, metrics


# ---- recovery ----------------------------------------------------------------------------------------------------
def test_a_synthetic_survey_of_known_fleet_values_is_recovered_within_the_intervals(recovered):
    root, metrics = recovered
    assert set(metrics["fitted"]) == set(FIT)
    for name, entry in metrics["fitted"].items():
        assert entry["low"] <= TRUTH[name] <= entry["high"], (name, entry)
        assert entry["low"] <= entry["value"] <= entry["high"]
        # an interval that filled the bounds would recover anything: each is narrower than its bounds
        assert entry["high"] - entry["low"] < 0.8 * (FIT[name][1] - FIT[name][0]), (name, entry)
    # the unfitted quantities keep the fleet's: the site, the mean contact-roll radius of U(0, 120) mm and the
    # geometric mean of the log-uniform 1-3000 N m/rad bush stiffness
    fixed = {"site_iri_m_km": TRUTH["site_iri_m_km"], "contact_roll_radius_mean_mm": 60.0,
             "bush_stiffness_geomean": round(math.sqrt(3000.0), 4)}  # fmt: skip
    assert metrics["fixed"] == fixed
    # the posterior: its draws written, each quantity's credible interval around the truth, no draw piled up
    post = metrics["posterior"]
    assert set(post["quantities"]) == set(FIT) and set(post["priors"]) == set(FIT)
    # each truth inside its credible interval, at the level that makes the five checks together a 90 % one
    # (Bonferroni: 1 - 0.10 / 5 = 98 % each, from the draws). Five 90 % intervals all cover their truth only 59 % of
    # the time, whatever the code: the old check passed on 5d77e52's random stream by chance and failed when the
    # proposal's draws changed (issue 39: the proposal from an order-fixed Cholesky factor, not LAPACK's SVD), with
    # chassis_tilt_sd_deg's truth 0.5 just above its 90 % interval [0.134, 0.4999]
    draws = pd.read_csv(root / "data" / "calibration" / "posterior.csv")
    level = 1.0 - 0.10 / len(FIT)
    for name, entry in post["quantities"].items():
        low, high = np.quantile(draws[name], [(1 - level) / 2, (1 + level) / 2])
        assert low <= TRUTH[name] <= high, (name, low, high, entry)
        assert entry["low"] <= entry["median"] <= entry["high"] and entry["piled"] is None


def test_the_fit_is_closer_to_the_survey_than_the_default_fleet(recovered):
    root, metrics = recovered
    config = parse_config(yaml.safe_load((root / "params.yaml").read_text()))
    observed, _ = C.observed_groups(root / "observed" / "s.csv", config)
    # the default fleet (all steel, tilt 0.3 +- 0.8 degree, class B(10) sensor) weighed directly, same filters
    weighed = K.simulate_fleet(C.crn_table(config), C.defaults(config), executor=C.workers_map(config.execution))
    default = K.filtered(weighed, config.observed.min_group_load)
    problem_obs = {k: L.observed_quantities(v) for k, v in observed.loads.items() if len(v) >= L.MIN_GROUPS}
    scales = {k: np.std(v, axis=0) for k, v in problem_obs.items()}
    assert metrics["distance_direct"] < K.frame_distance(default, problem_obs, scales)


def test_outputs_have_the_weighings_shape_and_the_held_out_half(recovered):
    root, metrics = recovered
    keys = {"n_groups", "mean_spread_kg", "median_spread_pct", "share_outside_5pct", "share_over_10pct",
            "load_share_quantiles"}  # fmt: skip
    for side in (metrics["observed"], metrics["calibrated"], metrics["held_out"]):
        assert set(side["groups"]) == {"tandem", "triaxle"}
        for entry in side["groups"].values():
            assert set(entry) == keys
    held = metrics["held_out"]
    # alternate records: the two halves hold about the same number of groups
    total = metrics["observed"]["groups"]["triaxle"]["n_groups"]
    assert abs(held["groups"]["triaxle"]["n_groups"] - total / 2) <= 0.1 * total
    assert held["distance_held_out"] > 0.0 and held["distance_halves"] > 0.0
    assert set(held["fitted"]) == set(FIT)
    # the half fit's posterior, and none of it piled against a bound (the truth lies inside every range)
    assert set(held["posterior"]) == set(FIT) and held["posterior_piled"] == {}
    # the table's faithfulness: the direct simulation's distance against the table's, and the sampling floor
    faithful = metrics["table_faithful"]
    assert faithful["gap"] == pytest.approx(metrics["distance_direct"] - metrics["distance"], abs=2e-5)
    assert faithful["floor"] == held["distance_halves"] and faithful["faithful"] == (abs(faithful["gap"]) <= held[
        "distance_halves"])  # fmt: skip
    assert sorted(p.name for p in (root / "data" / "calibration").iterdir()) == sorted(
        ["ablation.csv", "attribution.csv", "bootstrap.csv", "calibrated.csv", "posterior.csv", "profiles.csv",
         "valley.csv", ".bogie-output"]
    )  # fmt: skip
    # every variant of the ablation was weighed on the calibrated fleet's tri-axles
    variants = {key.split("/")[0] for key in metrics["ablation"] if key.endswith("/triaxle")}
    assert variants == {"baseline", *INHIBITORS, "all"}


def test_the_fitted_values_are_offered_as_the_fleet_studys_settings_and_parse_to_that_fleet(recovered):
    # issue 31 item 8: the fitted values could not feed the fleet study
    _, metrics = recovered
    offer = metrics["fleet_study"]
    # the site's bias is the surveyed site's, not the fleet's: not offered (issue 43 Must 2)
    assert offer["not_settable"] == ["site_bias_pct"] and offer["command"].startswith("dvc exp run -S ")
    raw = raw_params()
    for arg in offer["command"].removeprefix("dvc exp run ").split(" -S "):
        key, value = arg.removeprefix("-S ").split("=")
        node = raw
        *path, last = key.split(".")
        for part in path:
            node = node[part]
        node[last] = float(value)
    config = parse_config(raw)
    fitted = {q: e["value"] for q, e in metrics["fitted"].items()}
    tilt = config.distributions["chassis_tilt"]
    assert math.degrees(tilt.mean) == pytest.approx(fitted["chassis_tilt_mean_deg"], abs=1e-4)
    assert math.degrees(tilt.sd) == pytest.approx(fitted["chassis_tilt_sd_deg"], abs=1e-4)
    assert {g: m["air"] for g, m in config.fleet.suspension_mix.items()} == {
        "tandem": pytest.approx(fitted["air_share"], abs=1e-4), "triaxle": pytest.approx(fitted["air_share"], abs=1e-4)
    }  # fmt: skip
    assert config.protocol.wim.axle_error_sd == pytest.approx(fitted["sensor_error_pct"] / 100, abs=1e-6)


def test_the_wim_inequality_is_attributed_to_its_causes_on_the_calibrated_fleet(recovered):
    root, metrics = recovered
    by_cause = metrics["attribution"]
    table = pd.read_csv(root / "data" / "calibration" / "attribution.csv")
    steel = by_cause["triaxle/steel"]
    causes = {"resolution", "sensor", "tilt", "dynamics"}
    assert steel["n_groups"] >= 10 and set(steel["shapley"]) == set(steel["one_at_a_time"]) == causes
    rows = table[(table["group"] == "triaxle") & (table["suspension"] == "steel")].set_index("scenario")
    # every on/off combination of the four causes, the named ones first
    assert len(rows) == 16 and list(rows.index[:5]) == ["as_observed", "no_resolution", "no_sensor", "no_tilt",
                                                        "no_dynamics"] and rows.index[-1] == "at_rest"  # fmt: skip
    for stat in ("share_outside_5pct", "share_over_10pct", "mean_spread_pct"):
        # each cause's one-at-a-time share is what switching it off removes, paired on the same groups
        for cause, scenario in (("sensor", "no_sensor"), ("tilt", "no_tilt"), ("dynamics", "no_dynamics")):
            share = steel["one_at_a_time"][cause][stat]
            assert share["value"] == pytest.approx(rows.loc["as_observed", stat] - rows.loc[scenario, stat], abs=2e-4)
            assert share["low"] <= share["value"] + 1e-4 and share["value"] <= share["high"] + 1e-4
        for cause in causes:
            share = steel["shapley"][cause][stat]
            assert share["low"] <= share["value"] + 1e-4 and share["value"] <= share["high"] + 1e-4
        assert steel["as_observed"][stat] == pytest.approx(rows.loc["as_observed", stat], abs=1e-4)
        total = rows.loc["as_observed", stat] - rows.loc["at_rest", stat]
        assert steel["total"][stat]["value"] == pytest.approx(total, abs=2e-4)
    # the survey's fleet (tilt 0.8 +- 0.5 degree): the tilt spreads the steel tri-axles' loads, the level fleet less
    assert steel["one_at_a_time"]["tilt"]["mean_spread_pct"]["low"] > 0.0
    assert steel["shapley"]["tilt"]["mean_spread_pct"]["low"] > 0.0
    # the air groups share load through their bags: at rest they are nearly equal whatever the tilt
    air = by_cause.get("triaxle/air")
    assert air is None or air["at_rest"]["mean_spread_pct"] < steel["at_rest"]["mean_spread_pct"]


def test_the_shapley_shares_of_the_real_weighings_add_up_to_as_observed_minus_at_rest(recovered):
    _, metrics = recovered
    assert set(ATTRIBUTED) == set(metrics["attribution"])
    for key, att in ATTRIBUTED.items():
        # unrounded: the four shares add up to the total, in the estimate and in each of the bootstrap's resamples
        np.testing.assert_allclose(att.total.value, att.means[0] - att.means[-1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(sum(e.value for e in att.shapley.values()), att.total.value, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sum(e.boot for e in att.shapley.values()), att.total.boot, rtol=0, atol=1e-12)
        single = sum(e.value for e in att.one_at_a_time.values())
        np.testing.assert_allclose(single + att.interaction.value, att.total.value, rtol=0, atol=1e-12)
        # the metrics are these, rounded
        entry = metrics["attribution"][key]
        for j, stat in enumerate(A.STATISTICS):
            assert entry["interaction"][stat]["value"] == round(float(att.interaction.value[j]), 4) + 0.0
            for cause, share in att.shapley.items():
                assert entry["shapley"][cause][stat]["value"] == round(float(share.value[j]), 4) + 0.0


# ---- the table and the distance ----------------------------------------------------------------------------------
def test_readings_interpolate_the_table_linearly_in_tilt_and_roughness():
    config = parse_config(raw_params(20, site_iri_levels_m_km=[1.0, 3.0]))
    table = C.crn_table(config)
    tilts, iris = table.tilts, table.iris
    # loads linear in tilt and roughness: 5000 + 100 tilt + 10 iri on every axle, any bogie
    grid = 5000.0 + 100.0 * tilts[:, None] + 10.0 * iris[None, :]
    loads = np.broadcast_to(grid[None, None, :, :, None], table.loads.shape).copy()
    table = dataclasses.replace(table, loads=loads, n_failed=0)
    values = {**C.defaults(config), "site_iri_m_km": 2.5, "sensor_error_pct": 0.0}
    got = L.fleet_readings(table, values)
    mu, sd = values["chassis_tilt_mean_deg"], values["chassis_tilt_sd_deg"]
    tilt = truncnorm.ppf(table.tilt_u, (-2 - mu) / sd, (2 - mu) / sd, loc=mu, scale=sd)
    # the sensor's part common to a pass (s_v, the protocol's quartz 1.5 %) multiplies every axle of a bogie alike
    passes = table.pass_factors()
    assert config.protocol.wim.vehicle_error_sd == 0.015 and np.all(passes != 1.0)
    np.testing.assert_allclose(passes, 1.0 + 0.015 * table.z_pass, rtol=1e-15)
    np.testing.assert_allclose(got[0, :, 0], (5000.0 + 100.0 * tilt + 25.0) * passes, rtol=1e-12)
    # the sensor's own error of each axle multiplies it by 1 + s z with the bogie's own normals
    noisy = L.fleet_readings(table, {**values, "sensor_error_pct": 2.0})
    np.testing.assert_allclose(noisy / got, np.broadcast_to(1.0 + 0.02 * table.z, got.shape), rtol=1e-12)


def test_the_distance_is_zero_between_equal_samples_and_grows_with_a_shift():
    rng = np.random.default_rng(1)
    loads = 8000.0 * (1.0 + 0.05 * rng.standard_normal((200, 3)))
    q = L.observed_quantities(loads)
    obs, w = {"triaxle": q}, {"triaxle": np.ones(len(q))}
    scales = {"triaxle": q.std(axis=0)}
    assert L.distance(obs, w, L.Simulated(obs, w), scales) == pytest.approx(0.0, abs=1e-12)
    shifted = loads * np.array([0.95, 1.0, 1.05])
    near = L.distance(obs, w, L.Simulated({"triaxle": L.observed_quantities(shifted)}, w), scales)
    far = loads * np.array([0.9, 1.0, 1.1])
    assert 0.0 < near < L.distance(obs, w, L.Simulated({"triaxle": L.observed_quantities(far)}, w), scales)


def test_observed_quantities_are_the_survey_statistics_definitions():
    q = L.observed_quantities(np.array([[7600.0, 8000.0, 8400.0]]))
    np.testing.assert_allclose(q, [[0.95, 1.0, 1.05, 10.0]])


# ---- bad input and the skip --------------------------------------------------------------------------------------
def test_without_a_survey_the_stage_skips_with_one_line(tmp_path, capsys):
    raw = raw_params(20)
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    args = ["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "out"),
            "--metrics", str(tmp_path / "m.json")]  # fmt: skip
    assert C.main(args) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("calibrate: skipped, no observed survey given")
    metrics = json.loads((tmp_path / "m.json").read_text())
    assert metrics["skipped"] is True and metrics["fitted"] is None


def _refused(tmp_path, raw, capsys, words, survey="observed/s.csv"):
    args = project(tmp_path, raw, survey)
    assert C.main(args) == 2
    err = capsys.readouterr().err
    for word in words:
        assert word in err, err
    assert not (tmp_path / "data").exists() and not (tmp_path / "metrics").exists()


def test_a_survey_with_no_group_passing_the_filters_is_refused(tmp_path, capsys):
    path = tmp_path / "observed" / "s.csv"
    path.parent.mkdir()
    # two light single axles and a 3-axle group of 6 t: nothing laden
    path.write_text(
        "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,axle_load_3,spacing_1,spacing_2\n"
        "2026-01-05T06:00:00.000,80,1,3,2000,2000,2000,1.31,1.31\n"
    )
    # with the way out: the survey can still be compared on the observed page (issue 31 item 8)
    words = ["observed.path", "at least 10 laden tandem or tri-axle groups", "set calibrate: null in params.yaml"]
    _refused(tmp_path, raw_params(20), capsys, words)


def test_a_missing_survey_file_is_refused(tmp_path, capsys):
    _refused(tmp_path, raw_params(20), capsys, ["observed.path", "no such file"], survey="observed/none.csv")


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"fit": {"payload_mass": [0.0, 1.0]}}, ["calibrate.fit.payload_mass", "not a fleet quantity"]),
        ({"fit": {"air_share": [0.8, 0.2]}}, ["calibrate.fit.air_share", "bounds inverted"]),
        ({"fit": {"air_share": [0.0, 1.5]}}, ["calibrate.fit.air_share", "within [0, 1]"]),
        # a static calibration drops the WIM quantities (tests/pipeline/test_validate_weighbridge.py): none is left
        ({"protocol": "static", "fit": {"sensor_error_pct": [0, 5]}}, ["calibrate.fit", "names only WIM quantities"]),
        ({"fit": {"site_iri_m_km": [0.5, 4.0]}}, ["site_iri_m_km", "site_iri_levels_m_km"]),
    ],
)
def test_bad_calibrate_settings_are_refused_naming_the_key(change, words):
    with pytest.raises(ConfigError) as err:
        parse_config(raw_params(20, **change))
    for word in words:
        assert word in str(err.value)


def test_a_quantity_the_fleet_does_not_have_is_refused(tmp_path, capsys):
    raw = raw_params(20)
    raw["distributions"]["chassis_tilt_deg"] = {"kind": "uniform", "low": -1.0, "high": 1.0}
    path = tmp_path / "observed" / "s.csv"
    path.parent.mkdir()
    path.write_text("timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2\n")
    _refused(tmp_path, raw, capsys, ["distributions.chassis_tilt_deg", "truncnormal"])
    raw = raw_params(20, fit={"site_iri_m_km": [1.0, 4.0]})
    raw["protocol"]["wim"].update(site_length_before_m=0.0, site_length_after_m=0.0)
    _refused(tmp_path, raw, capsys, ["site_iri_m_km", "no site"])


def test_a_survey_that_is_a_symlink_out_of_the_project_is_refused_before_it_is_read(tmp_path, capsys):
    # issue 28, item 3: the check of validate and observed (pipeline.config.observed_file), here too
    outside = tmp_path.parent / f"{tmp_path.name}-outside.csv"
    synthetic_survey(outside, n_vehicles=30)
    (tmp_path / "observed").mkdir()
    (tmp_path / "observed" / "s.csv").symlink_to(outside)
    words = ["observed.path = 'observed/s.csv'", f"points to {outside}", "observed/"]
    _refused(tmp_path, raw_params(20), capsys, words)


# ---- one executor (issue 29 Must 6) ------------------------------------------------------------------------------
def test_the_calibration_table_on_a_local_dask_cluster_is_the_table_on_this_machine():
    from dask.distributed import LocalCluster

    config = parse_config(raw_params(20, tilt_step_deg=1.0))
    loky = C.build_table(config, progress=lambda text: None)
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        execution = dataclasses.replace(config.execution, backend="dask", dask_scheduler=cluster.scheduler_address)
        dask = C.build_table(dataclasses.replace(config, execution=execution), progress=lambda text: None)
    # the same weighings, bit for bit, whoever computed them (each worker's numerics checked against this process's)
    np.testing.assert_array_equal(dask.loads, loky.loads)
    assert loky.loads.shape[:2] == (2, 20) and np.isfinite(loky.loads[..., 0]).mean() > 0.9


# ---- the same bits whoever computes (issue 39 Must 4) ------------------------------------------------------------
def _outputs(root: Path) -> dict[str, bytes]:
    files = [*sorted((root / "data" / "calibration").rglob("*")), root / "metrics" / "calibration.json"]
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in files if p.is_file()}


def test_the_calibration_is_the_same_bits_with_one_worker_two_or_a_dask_cluster(tmp_path):
    # every output: the fitted values, the posterior's draws and intervals, the bootstrap, the attribution, the tables;
    # the table, the bootstrap's refits and the between-site weighings all run on the executor (issue 43 Must 8)
    from dask.distributed import LocalCluster

    survey = tmp_path / "survey.csv"
    synthetic_survey(survey, n_vehicles=200)
    small = dict(tilt_step_deg=1.0, bootstrap_resamples=3, maxiter=3, popsize=3, posterior_draws=150)

    def calibrate(name: str, **execution) -> dict[str, bytes]:
        root = tmp_path / name
        (root / "observed").mkdir(parents=True)
        shutil.copy2(survey, root / "observed" / "s.csv")
        raw = raw_params(30, **small)
        raw["execution"].update(execution)
        args = project(root, raw)
        assert C.main(args) == 0
        return _outputs(root)

    one = calibrate("one", n_jobs=1)
    two = calibrate("two", n_jobs=2, chunk_size=3)
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        dask = calibrate("dask", backend="dask", dask_scheduler=cluster.scheduler_address)
    assert "metrics/calibration.json" in one and any(k.endswith("posterior.csv") or "posterior" in k for k in one), (
        sorted(one)
    )
    assert sorted(one) == sorted(two) == sorted(dask)
    assert [k for k in one if one[k] != two[k]] == []
    assert [k for k in one if one[k] != dask[k]] == []


def test_an_unconverged_posterior_is_said_with_what_to_change(tmp_path, capsys, monkeypatch):
    # issue 43 Must 5: after the fitted values the stage prints the posterior's advice when it did not converge, and
    # nothing more when it did (the calibration itself stubbed: the line is the stage's, the words the library's)
    import argparse

    (tmp_path / "observed").mkdir()
    (tmp_path / "observed" / "s.csv").write_text("timestamp\n")
    args = argparse.Namespace(**{k.lstrip("-"): v for k, v in zip(*[iter(project(tmp_path, raw_params(20)))] * 2)})
    said = "unconverged (thresholds: ...): raise posterior_draws (params.yaml calibrate.posterior_draws) to 9000"
    for converged, advice in ((False, said), (True, None)):
        metrics = {"skipped": False, "fitted": {"air_share": {"value": 0.31}}, "distance": 1.5,
                   "posterior": {"converged": converged, "advice": advice}}  # fmt: skip
        monkeypatch.setattr(C, "run", lambda config, path, log, m=metrics: (m, {}))
        monkeypatch.setattr(C, "write_outputs", lambda *a, **k: None)
        assert C._stage(args, lambda line: None) == 0
        out = capsys.readouterr().out.strip().splitlines()
        assert out[0].startswith("calibrate: air_share 0.31; distance 1.5")
        assert out[1:] == ([f"calibrate: posterior {said}"] if not converged else [])


def test_the_calibrated_fleet_is_the_posteriors_and_the_prior_free_minimum_a_diagnostic(recovered):
    # issue 43 Must 1: fitted (value, interval), the fleet offered to the study and the checks are the posterior's;
    # the distance's minimum without priors stays beside them, named as a diagnostic
    _, metrics = recovered
    post = metrics["posterior"]["quantities"]
    for name, entry in metrics["fitted"].items():
        assert entry["source"] == "posterior"
        assert (entry["value"], entry["low"], entry["high"]) == (
            post[name]["median"], post[name]["low"], post[name]["high"])  # fmt: skip
    free = metrics["prior_free_minimum"]
    assert "diagnostic" in free["note"] and set(free["fitted"]) == set(metrics["fitted"])
    assert free["distance"] <= metrics["distance"]  # the minimum, without the priors, is the distance's least
    offered = metrics["fleet_study"]["set"]
    assert offered["distributions.chassis_tilt_deg.mean"] == pytest.approx(
        metrics["fitted"]["chassis_tilt_mean_deg"]["value"], abs=1e-4)  # fmt: skip
    predictive = metrics["calibrated"]["posterior_predictive"]
    assert predictive["draws"] >= 2
    for size, stats in predictive.items():
        if isinstance(stats, dict):
            for s in stats.values():
                assert s["low"] <= s["median"] <= s["high"], (size, s)
