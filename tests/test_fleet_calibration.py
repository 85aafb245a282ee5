"""bogie.fleet.calibration with plain arguments (issue 29): known fleet values recovered, the table, bad arguments.

The recovery test needs no simulation: the calibration fleet's table holds readings that are a known function of the
tilt (a steel group's outer axles share its load 1 -+ 0.02 per degree of tilt, an air group's axles equally), and the
observed survey is drawn from the same functions for an independent fleet of known tilt distribution and air share.
The fit must find those values back from the distributions of the load shares and the spread alone.
"""

import dataclasses
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd
import pytest
from _fleets import DISTS, fleet

import bogie.fleet as bf
from bogie.fleet.calibration import checks as K
from bogie.fleet.calibration import fitting as F
from bogie.fleet.calibration import problem as L
from bogie.weighings.survey import observed_survey

STATIC = bf.StaticProtocol(load_time=2.0, approach_length=5.0, crawl_speed=1.4, settle_time=3.0, dt=1e-3)
WIM = bf.WimProtocol(speed=22.0, approach_length=30.0, dt=1e-3, sensor="quartz")
#: the fleet's tilt distribution [rad]: centre 0.3 degree, spread 0.8 degree, within +-2 degrees
TILT = bf.TruncNormal(math.radians(0.3), math.radians(0.8), math.radians(-2.0), math.radians(2.0))
GRID = np.linspace(-2.0, 2.0, 17)  # [degree]
#: the observed fleet's values: what the fit must find
TRUTH = {"chassis_tilt_mean_deg": 0.8, "chassis_tilt_sd_deg": 0.5, "air_share": 0.3}
FIT = {"chassis_tilt_mean_deg": (-1.0, 1.5), "chassis_tilt_sd_deg": (0.1, 1.5), "air_share": (0.0, 1.0)}
#: the outer axles' load share per degree of tilt of a steel tri-axle [1/degree]
SLOPE = 0.02


def steel_loads(tilt_deg):
    """A steel tri-axle's axle loads [kg] at a tilt [degree]: 8 t an axle, the front and rear -+ SLOPE a degree."""
    return 8000.0 * (1.0 + SLOPE * np.multiply.outer(tilt_deg, [-1.0, 0.0, 1.0]))


def analytic_table(n=400, seed=11):
    """A static calibration table of ``n`` tri-axles whose readings are :func:`steel_loads` (air: 8 t each axle)."""
    rng = np.random.default_rng(seed)
    samples = pd.DataFrame({
        "sample_id": np.arange(n), "group": "triaxle", "chassis_tilt": TILT.ppf(rng.random(n)),
        "sensor_seed": 1000 + np.arange(n),
    })  # fmt: skip
    table = L.crn_table(samples, TILT, seed=1, protocol="static", settings=STATIC, tilts=GRID)
    loads = np.full(table.loads.shape, np.nan)
    loads[0, :, :, 0, :] = steel_loads(GRID)[None, :, :]
    loads[1, :, :, 0, :] = 8000.0
    return dataclasses.replace(table, loads=loads)


def synthetic_observed(n=1500, seed=12):
    """``n`` tri-axle groups of an independent fleet with the values of TRUTH."""
    rng = np.random.default_rng(seed)
    dist = dataclasses.replace(
        TILT, mean=math.radians(TRUTH["chassis_tilt_mean_deg"]), sd=math.radians(TRUTH["chassis_tilt_sd_deg"])
    )
    tilt = np.degrees(dist.ppf(rng.random(n)))
    air = rng.random(n) < TRUTH["air_share"]
    loads = np.where(air[:, None], 8000.0, steel_loads(tilt))
    return L.Observed({"tandem": np.zeros((0, 2)), "triaxle": loads}, {"tandem": np.zeros(0), "triaxle": np.arange(n)})


@pytest.fixture(scope="module")
def recovered():
    table, observed = analytic_table(), synthetic_observed()
    settings = L.CalibrationSettings(FIT, seed=3, maxiter=30, popsize=8, bootstrap_resamples=8)
    problem = L.make_problem(table, observed, settings.fit, L.base_values(TILT, 0.0, None))
    return problem, F.calibrate(problem, settings)


def test_known_fleet_values_are_fitted_back_from_the_load_shares_and_spread(recovered):
    problem, result = recovered
    # Monte Carlo error of the estimates: about 0.5 degree x sqrt(1/400 + 1/1500) = 0.03 degree for the tilt's
    # centre and spread, sqrt(0.3 x 0.7 / 1500) = 0.012 for the air share; the tolerances are some 5 of those
    tolerance = {"chassis_tilt_mean_deg": 0.15, "chassis_tilt_sd_deg": 0.15, "air_share": 0.06}
    for name, entry in result.fitted.items():
        assert abs(entry["value"] - TRUTH[name]) < tolerance[name], (name, entry)
        assert entry["low"] <= entry["value"] <= entry["high"] and list(FIT[name]) == entry["bounds"]
        assert entry["at_bound"] is None, (name, entry)  # the truth lies well inside every range
    # the fleet the fit started from (params: 0.3 +- 0.8 degree, all steel) is no answer: outside every tolerance
    base = problem.base
    assert all(abs(base[q] - TRUTH[q]) > tolerance[q] for q in TRUTH)
    # the optimiser found at least the truth's distance, and the truth is far closer than the base fleet
    f = problem.objective(problem.unit_weights(), None)
    at_truth = f(np.array([TRUTH[q] for q in problem.fitted]))
    at_base = f(np.array([base[q] for q in problem.fitted]))
    assert result.distance <= at_truth < 0.2 * at_base


def test_the_bootstrap_the_valley_and_the_profiles_are_around_the_fit(recovered):
    problem, result = recovered
    assert list(result.bootstrap.columns) == ["resample", *problem.fitted, "distance"]
    assert len(result.bootstrap) == 8 and np.isfinite(result.bootstrap["distance"]).all()
    assert len(result.valley) == F.VALLEY_POINTS**2 and result.valley["distance"].min() >= result.distance - 1e-12
    for name, profile in result.profiles.groupby("quantity"):
        # each profile is lowest at the grid point next to the fitted value (the others at theirs)
        step = (FIT[name][1] - FIT[name][0]) / (F.PROFILE_POINTS - 1)
        lowest = profile.loc[profile["distance"].idxmin(), "value"]
        assert abs(lowest - result.prior_free[name]["value"]) <= step + 1e-12, (name, lowest)
    # the calibrated fleet is the posterior's: its medians, priors included; the prior-free minimum is the profiles'
    assert result.values == {**problem.base, **{q: e["value"] for q, e in result.fitted.items()}}
    for name, entry in result.fitted.items():
        summary = result.posterior.summary[name]
        assert entry["source"] == "posterior" and (entry["value"], entry["low"], entry["high"]) == (
            summary["median"], summary["low"], summary["high"])  # fmt: skip
    assert result.distance == problem.objective(problem.unit_weights(), None)(
        np.array([result.fitted[q]["value"] for q in problem.fitted])) >= result.prior_free_distance  # fmt: skip


def test_a_fit_piled_against_a_bound_is_flagged_with_its_side_value_and_refits():
    # the survey's air share is 0.3; a range that stops at 0.2 leaves the fit nowhere to go but its upper bound
    table, observed = analytic_table(), synthetic_observed()
    narrow = {**FIT, "air_share": (0.0, 0.2)}
    settings = L.CalibrationSettings(narrow, seed=3, maxiter=30, popsize=8, bootstrap_resamples=8)
    result = F.calibrate(L.make_problem(table, observed, narrow, L.base_values(TILT, 0.0, None)), settings)
    # the prior-free minimum (the diagnostic) sits at the bound and its refits pile there
    finding = result.prior_free["air_share"]["at_bound"]
    assert finding["bound"] == "high" and finding["limit"] == 0.2
    assert 0.2 - F.AT_BOUND * 0.2 <= finding["value"] <= 0.2 and finding["share_of_refits"] >= F.PILED
    # and so does the posterior, the calibrated fleet: flagged with the share of its draws at the bound
    finding = result.fitted["air_share"]["at_bound"]
    assert finding["bound"] == "high" and finding["limit"] == 0.2 and finding["share_of_posterior"] >= F.PILED


def test_a_held_out_half_too_small_to_fit_gives_its_reason_not_a_distance_of_zero():
    table = analytic_table()
    small = synthetic_observed(n=15)  # 8 even records: fewer than MIN_GROUPS
    settings = L.CalibrationSettings(FIT, seed=3, maxiter=2, popsize=4, bootstrap_resamples=0)
    held = K.held_out(table, small, settings, L.base_values(TILT, 0.0, None), 0.0)
    assert held["groups"] is None and "distance_fit_half" not in held
    assert held["reason"] == f"observed: 0 tandem, 8 triaxle groups; a fit needs at least {L.MIN_GROUPS} of one size"


def test_at_a_bound_means_within_two_percent_of_the_width_or_a_quarter_of_the_refits():
    bounds = (0.1, 1.5)  # width 1.4: 2 % is 0.028
    assert F.at_bound(0.1, bounds) == "low" and F.at_bound(0.127, bounds) == "low"
    assert F.at_bound(0.13, bounds) is None and F.at_bound(1.473, bounds) == "high" and F.at_bound(1.47, bounds) is None
    assert F.bound_finding(0.8, bounds, [0.7, 0.8, 0.9]) is None
    # the fit inside, but 2 of 8 refits (a quarter) at the lower bound: piled against it
    found = F.bound_finding(0.5, bounds, [0.1, 0.11, 0.5, 0.6, 0.5, 0.7, 0.4, 0.5])
    assert found == {"bound": "low", "value": 0.5, "limit": 0.1, "share_of_refits": 0.25}
    assert F.bound_finding(0.5, bounds, [0.1, 0.5, 0.6, 0.5, 0.7, 0.4, 0.5, 0.5]) is None  # 1 of 8: not piled
    # the fit at its bound without a bootstrap: flagged, no share
    assert F.bound_finding(1.5, bounds, []) == {"bound": "high", "value": 1.5, "limit": 1.5, "share_of_refits": None}


def test_a_survey_file_gives_its_groups_their_records_and_halves(tmp_path):
    rng = np.random.default_rng(4)
    loads = np.round(8000.0 + 500.0 * rng.standard_normal((12, 3)))
    frame = pd.DataFrame({"n_axles": 3, "group": "triaxle", **{f"axle_load_{i + 1}": loads[:, i] for i in range(3)}})
    K.write_csv_survey(frame, tmp_path / "s.csv")
    observed = L.observed_groups(observed_survey(tmp_path / "s.csv", "csv", position="trailer"))
    np.testing.assert_array_equal(observed.loads["triaxle"], loads)  # whole kilograms, as written
    assert observed.loads["tandem"].shape == (0, 2) and list(observed.record["triaxle"]) == list(range(12))
    np.testing.assert_array_equal(observed.half(1).loads["triaxle"], loads[1::2])
    K.write_csv_survey(frame.iloc[:9], tmp_path / "few.csv")
    with pytest.raises(L.CalibrationError, match="0 tandem, 9 triaxle groups .* at least 10 laden"):
        L.observed_groups(observed_survey(tmp_path / "few.csv", "csv", position="trailer"))


def test_the_table_of_real_weighings_is_the_same_on_worker_processes():
    samples = bf.sample_fleet(fleet(distributions={**DISTS, "chassis_tilt": TILT}), n_bogies=4, seed=5)
    tilts = [-2.0, 0.0, 2.0]
    here = L.build_table(samples, TILT, 5, "static", STATIC, tilts)
    with ProcessPoolExecutor(2) as pool:
        there = L.build_table(samples, TILT, 5, "static", STATIC, tilts, executor=pool)
    np.testing.assert_array_equal(there.loads, here.loads)
    assert here.loads.shape == (2, 4, 3, 1, 3) and here.n_failed == 0
    tandem = here.size == "tandem"
    assert tandem.any() and np.isnan(here.loads[:, tandem, :, :, 2]).all()
    present = ~np.isnan(here.loads)
    assert (here.loads[present] > 0.0).all() and present.sum() == 2 * 3 * (2 * tandem.sum() + 3 * (~tandem).sum())
    # the tilt moves load: every bogie's front axle reads differently at each tilt of the grid [kg]
    assert (np.abs(np.diff(here.loads[:, :, :, 0, 0], axis=2)) > 1.0).all()


def test_the_bootstrap_refits_are_the_same_bits_on_worker_processes():
    # issue 43 Must 8: the refits run on the executor; each is seeded by its number, its resample drawn here in order
    table, observed = analytic_table(200), synthetic_observed(300)
    problem = L.make_problem(table, observed, FIT, L.base_values(TILT, 0.0, None))
    chosen = L.CalibrationSettings(FIT, seed=3, maxiter=5, popsize=5, bootstrap_resamples=4)
    said = []
    here = F._bootstrap(problem, chosen, said.append)
    with ProcessPoolExecutor(2) as pool:
        there = F._bootstrap(problem, chosen, lambda text: None, pool)
    assert there.equals(here) and len(here) == 4 and here["resample"].tolist() == [0, 1, 2, 3]
    assert said[0] == "calibrate: bootstrap, 4 refits on the executor" and len(said) == 5
    assert here[list(FIT)].nunique().min() == 4  # four different resamples, four different refits


def settings(**changes):
    return L.CalibrationSettings(**{"fit": FIT, "seed": 1, **changes})


def crn(protocol="static", spec=STATIC, tilts=GRID, levels=()):
    return L.crn_table(analytic_table(5).samples, TILT, 1, protocol, spec, tilts, levels)


def problem(fit=FIT, min_group_load_kg=0.0):
    return L.make_problem(
        analytic_table(5), synthetic_observed(20), fit, L.base_values(TILT, 0.0, None), min_group_load_kg
    )


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: settings(fit={"air_share": (0.0, 1.5)}), ["fit['air_share']", "(0.0, 1.5)", "within [0, 1] -"]),
        (lambda: settings(fit={"chassis_tilt_sd_deg": (1.0, 0.5)}), ["chassis_tilt_sd_deg", "low < high", "5] degree"]),
        (lambda: settings(fit={"payload": (0.0, 1.0)}), ["fit['payload']", "air_share"]),
        (lambda: settings(maxiter=0), ["maxiter = 0", ">= 1"]),
        (lambda: settings(popsize=1), ["popsize = 1", ">= 2"]),
        (lambda: settings(confidence_level=1.0), ["confidence_level = 1.0", "(0, 1)"]),
        (lambda: crn(tilts=[1.0, 0.0]), ["tilts = [1.0, 0.0]", "increasing", "in degree"]),
        (lambda: crn("wim", WIM, levels=[2.0, 1.0]), ["site_iri_levels = [2.0, 1.0]", "in m/km"]),
        (lambda: crn("dynamic"), ["protocol = 'dynamic'", "static, wim"]),
        (lambda: crn("wim"), ["settings", "WimProtocol"]),
        (lambda: problem({"sensor_error_pct": (0.0, 5.0)}), ["sensor_error_pct", "WIM protocol", "static"]),
        (lambda: problem(min_group_load_kg=-1.0), ["min_group_load_kg = -1.0", "is out of range", "[0, 100000] kg"]),
    ],
)
def test_bad_arguments_are_refused_naming_the_argument_its_value_and_unit(make, words):
    with pytest.raises(L.CalibrationError) as err:
        make()
    for word in words:
        assert word in str(err.value), str(err.value)


def test_the_ablation_states_a_size_the_baseline_has_no_laden_group_of(monkeypatch):
    # issue 40 item 3: calibrate.n_bogies 20 on a 1,500-vehicle MON survey ended in KeyError: 'triaxle' when the
    # baseline kept no laden tri-axle and a variant did; now its buys_points is NaN (null in the metrics)
    import numpy as np
    import pandas as pd

    from bogie.fleet.calibration import checks as K

    def fake(table, values, variant, steel_only=False, executor=None):
        rows = [{"group": "tandem", "n_axles": 2, "axle_load_1": 8000.0, "axle_load_2": 8200.0, "axle_load_3": np.nan}]
        if variant != "baseline":
            rows.append({"group": "triaxle", "n_axles": 3, "axle_load_1": 7000.0, "axle_load_2": 7600.0,
                         "axle_load_3": 8100.0})  # fmt: skip
        return pd.DataFrame(rows)

    monkeypatch.setattr(K, "simulate_fleet", fake)
    table = K.ablation(None, {}, 0.0)
    tri = table[table["group"] == "triaxle"]
    assert len(tri) and tri["buys_points"].isna().all()
    tandem = table[(table["group"] == "tandem") & (table["variant"] == "baseline")]
    assert float(tandem["buys_points"].iloc[0]) == 0.0
