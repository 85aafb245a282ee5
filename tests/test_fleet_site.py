"""The WIM site in the calibration's observation model (issue 43 Must 2), the sensor's per-axle finding (Must 4) and
the prior sensitivity (Must 6): speeds and sites by hand, the site's bias in every kilogram and in no load share, one
site's road shared by the calibration bogies, the between-site covariance recovering a known site variance, and the
answer's dependence on the tilt prior said when it depends and when it does not.

Weighings are stand-ins with known answers (no simulation); the calibration's own recovery of a synthetic survey
with a site bias on another site is tests/pipeline/test_calibrate.py's.
"""

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from _fleets import DISTS, fleet
from test_fleet_calibration import FIT, TILT, analytic_table, synthetic_observed

import bogie.fleet as bf
from bogie.fleet.calibration import checks as K
from bogie.fleet.calibration import fitting as F
from bogie.fleet.calibration import posterior as P
from bogie.fleet.calibration import problem as L
from bogie.fleet.calibration import table as T
from bogie.fleet.calibration.prior_sensitivity import DEPENDS, prior_sensitivity, scaled_priors
from bogie.fleet.calibration.priors import SITE_BIAS_SD_PCT, default_priors, prior_draws
from bogie.fleet.calibration.site import SPEED_CLIP, SPEED_SD_M_S, Site, bogie_speeds, on_site, site_of
from bogie.fleet.sampling.seeds import site_seed, speed_normal

WIM = bf.WimProtocol(speed=22.0, approach_length=30.0, dt=1e-3, sensor="quartz")
WIM_TILT = bf.TruncNormal(0.0, math.radians(0.5), math.radians(-2.0), math.radians(2.0))


def wim_table(n=40, seed=5, shared_site=True):
    samples = bf.sample_fleet(fleet(distributions={**DISTS, "chassis_tilt": WIM_TILT}), n_bogies=n, seed=seed)
    return L.crn_table(samples, WIM_TILT, seed, "wim", WIM, [-2.0, 0.0, 2.0], [1.0, 3.0], shared_site=shared_site)


def recording(monkeypatch, module):
    """``module.weigh_readings`` replaced by one that reads 8000 kg on every axle and keeps the tasks it was given."""
    seen = []

    def fake(tasks, executor=None):
        seen.extend(tasks)
        return np.full((len(tasks), 3), 8000.0)

    monkeypatch.setattr(module, "weigh_readings", fake)
    return seen


# ---- speeds and sites --------------------------------------------------------------------------------------------
def test_each_bogie_has_its_own_speed_by_hand_and_sites_their_own_roads():
    ids = [0, 7, 3]
    v = bogie_speeds(5, "fleet", ids, 22.0, 1.5)
    for i, vi in zip(ids, v, strict=True):  # v = 22 + 1.5 z, z its own stream, clipped to +-3
        assert vi == 22.0 + 1.5 * float(np.clip(speed_normal(5, "fleet", i), -SPEED_CLIP, SPEED_CLIP))
    assert bogie_speeds(5, "fleet", [3], 22.0, 1.5)[0] == v[2]  # a bogie's speed does not depend on the others
    many = bogie_speeds(5, "fleet", range(4000), 22.0, SPEED_SD_M_S)
    assert abs(many.mean() - 22.0) < 0.1 and abs(many.std() - SPEED_SD_M_S) < 0.1 and many.min() >= 22.0 - 4.5
    assert site_of(5, "fleet", ["B", "A"], 0) == Site("B", site_seed(5, "fleet", 0))
    assert site_of(5, "fleet", ["B", "A"], 3) == Site("A", site_seed(5, "fleet", 3))  # classes cycled
    assert len({site_seed(5, "fleet", r) for r in range(20)}) == 20
    with pytest.raises(ValueError, match=r"speed_sd = 8.0 is out of range: must be in \[0, 7.33333\) m/s"):
        bogie_speeds(5, "fleet", ids, 22.0, 8.0)
    with pytest.raises(ValueError, match="road_class = 'Z': must be an ISO 8608 class"):
        Site("Z", 1)
    moved, spec = on_site({"road_class": "C", "road_seed": 9, "x": 1}, WIM, Site("A", 4), 20.5)
    assert moved == {"road_class": "A", "road_seed": 4, "x": 1} and spec.speed == 20.5 and WIM.speed == 22.0
    assert on_site({"road_seed": 9}, WIM, None, 20.5) == ({"road_seed": 9}, WIM)


def test_the_calibration_bogies_cross_one_site_at_their_own_speeds(monkeypatch):
    seen = recording(monkeypatch, T)
    table = T.build_table(wim_table().samples, WIM_TILT, 5, "wim", WIM, [-2.0, 0.0, 2.0], [1.0, 3.0])
    assert table.site == site_of(5, "fleet", list(table.samples["road_class"]))
    assert {(s["road_class"], s["road_seed"]) for s, _, _ in seen} == {(table.site.road_class, table.site.road_seed)}
    n = len(table.size)
    speeds = np.array([spec.speed for _, _, spec in seen]).reshape(2, n, 3, 2)  # kind, bogie, tilt, roughness
    assert np.array_equal(speeds, np.broadcast_to(table.speeds[None, :, None, None], speeds.shape))
    assert np.ptp(table.speeds) > 2.0
    seen.clear()  # without a shared site: each bogie's own road, the protocol's speed (the model of before)
    own = T.build_table(table.samples, WIM_TILT, 5, "wim", WIM, [-2.0, 0.0, 2.0], [1.0, 3.0], shared_site=False)
    assert own.site is None and own.speeds is None and {spec.speed for _, _, spec in seen} == {22.0}
    assert [s["road_seed"] for s, _, _ in seen[: 3 * 2 * n : 6]] == list(table.samples["road_seed"])


def test_a_table_over_several_sites_puts_bogie_i_on_site_i_mod_k_and_the_others_after_them(monkeypatch):
    seen = recording(monkeypatch, T)
    samples = wim_table().samples
    table = T.build_table(samples, WIM_TILT, 5, "wim", WIM, [-2.0, 0.0, 2.0], [1.0, 3.0], table_sites=3)
    classes, n = list(table.samples["road_class"]), len(table.size)
    own = [site_of(5, "fleet", classes, k) for k in range(3)]
    assert table.site == own[0] and [table.site_for(i) for i in range(5)] == [own[0], own[1], own[2], own[0], own[1]]
    roads = np.array([s["road_seed"] for s, _, _ in seen]).reshape(2, n, 3, 2)  # kind, bogie, tilt, roughness
    expected = np.array([own[i % 3].road_seed for i in range(n)])
    assert np.array_equal(roads, np.broadcast_to(expected[None, :, None, None], roads.shape))
    assert list(table.site_labels(np.array([0, 4, 8]))) == [0, 1, 2]
    # one site: every bogie on site 0, no labels (the summaries as before)
    one = dataclasses.replace(table, sites=1)
    assert one.site_for(7) == own[0] and one.site_labels(np.arange(4)) is None
    with pytest.raises(T.CalibrationError, match="table_sites"):
        T.crn_table(samples, WIM_TILT, 5, "wim", WIM, [-2.0, 0.0, 2.0], [1.0, 3.0], table_sites=0)
    # the between-site covariance's other sites come after the table's three: sites 3 and 4
    others = recording(monkeypatch, P)
    rng = np.random.default_rng(1)
    observed = L.Observed({"tandem": rng.uniform(7e3, 9e3, (30, 2)), "triaxle": rng.uniform(7e3, 9e3, (30, 3))},
                          {"tandem": np.arange(30), "triaxle": np.arange(30)})  # fmt: skip
    problem = L.make_problem(table, observed, {"air_share": (0.0, 1.0)}, L.base_values(WIM_TILT, 0.0, WIM))
    P.site_covariance(problem, np.array([0.0]), 2)
    assert {s["road_seed"] for s, _, _ in others} == {site_of(5, "fleet", classes, k).road_seed for k in (3, 4)}


def test_the_summaries_of_a_table_over_several_sites_take_each_sd_within_its_site():
    # two sites, tri-axle front shares 0.9, 1.1 on site 0 and 1.3, 1.5 on site 1 (equal weights): the mean is 1.2;
    # about the whole mean the squares sum to 0.09 + 0.01 + 0.01 + 0.09 = 0.2 over 4 - 1 degrees of freedom, within
    # each site to 4 x 0.01 = 0.04 over 4 - 2 (each site's mean costs one): sd sqrt(0.02)
    q = np.array([[0.9, 1.0, 1.1, 5.0], [1.1, 1.0, 0.9, 5.0], [1.3, 0.9, 0.8, 9.0], [1.5, 0.8, 0.7, 11.0]])
    w = {"triaxle": np.ones(4)}
    whole = P.summaries({"triaxle": q}, w)
    pooled = P.summaries({"triaxle": q}, w, {"triaxle": np.array([0, 0, 1, 1])})
    assert whole[0] == pytest.approx(1.2, abs=1e-12) and pooled[0] == pytest.approx(1.2, abs=1e-12)  # means alike
    assert whole[2] == pytest.approx(math.sqrt(0.2 / 3), abs=1e-12) and pooled[2] == pytest.approx(
        math.sqrt(0.02), abs=1e-12
    )
    # the spread: 5, 5 | 9, 11: within the sites (0 + 0 + 1 + 1) / 2 = 1; about the mean 7.5,
    # (6.25 + 6.25 + 2.25 + 12.25) / 3 = 9
    assert pooled[6] == pytest.approx(1.0, abs=1e-12) and whole[6] == pytest.approx(3.0, abs=1e-12)
    # one site: the same numbers as no sites at all
    same = P.summaries({"triaxle": q}, w, {"triaxle": np.zeros(4, dtype=int)})
    assert np.array_equal(same, whole)


def test_the_pooled_sd_is_unbiased_whatever_the_sites_and_the_weights():
    # 12 groups on K sites (site offsets of sd 3, far above the groups' sd 1), reliability weights uniform on
    # [0.2, 1]: the variance pooled within sites has expectation 1 for K = 1, 3 and 6. Over 4,000 surveys its mean
    # has a standard error under 0.012 (the variance of a variance of ~6-11 degrees of freedom, 2 / dof, over 4,000),
    # so 0.04 is over three of them; the plug-in (dividing by the weights' sum) would read 11/12, 9/12, 6/12 low
    rng = np.random.default_rng(7)
    for k in (1, 3, 6):
        sites = np.arange(12) % k
        reads = []
        for _ in range(4000):
            x = rng.normal(0.0, 1.0, 12) + rng.normal(0.0, 3.0, k)[sites]
            q = np.column_stack([1.0 + 0.01 * x, 1.0 - 0.01 * x, 10.0 + x])  # a tandem: shares, then the spread
            reads.append(P.summaries({"tandem": q}, {"tandem": rng.uniform(0.2, 1.0, 12)}, {"tandem": sites})[3] ** 2)
        assert np.mean(reads) == pytest.approx(1.0, abs=0.04), k


def test_a_size_with_one_group_on_each_site_has_no_sd():
    q = np.array([[0.9, 1.1, 5.0], [1.1, 0.9, 7.0]])
    s = P.summaries({"tandem": q}, {"tandem": np.ones(2)}, {"tandem": np.array([0, 1])})
    assert s[0] == pytest.approx(1.0, abs=1e-12) and s[2] == pytest.approx(6.0, abs=1e-12)
    assert np.isnan(s[1]) and np.isnan(s[3])


# ---- the site's bias ---------------------------------------------------------------------------------------------
def test_the_site_bias_scales_every_reading_and_no_load_share():
    table = wim_table()
    rng = np.random.default_rng(1)
    loads = rng.uniform(5000.0, 9000.0, table.loads.shape)
    loads[:, table.size == "tandem", :, :, 2] = np.nan
    table = dataclasses.replace(table, loads=loads)
    values = {**L.base_values(WIM_TILT, 0.3, WIM), "sensor_error_pct": 3.0}
    biased = {**values, "site_bias_pct": 5.0}
    # by hand: (1 + b) (1 + s_a z_i) (1 + s_v z_v), bogie 4's second axle
    z, zv = table.z[4, 1], table.z_pass[4]
    assert table.reading_factors(biased)[4, 1] == pytest.approx(1.05 * (1 + 0.03 * z) * (1 + WIM.vehicle_error_sd * zv))
    np.testing.assert_allclose(T.fleet_readings(table, biased), 1.05 * T.fleet_readings(table, values), rtol=1e-13)
    # the load shares and the spread in per cent are ratios: the bias cancels (no filter, no resolution)
    a, b = (L.simulated(table, v, 0.0) for v in (values, biased))
    for size in a.quantities:
        np.testing.assert_allclose(a.quantities[size], b.quantities[size], rtol=1e-12, atol=1e-12)
    # across the smallest-load filter it does not: 5 % heavier, more groups pass 20 t
    c, d = (L.simulated(table, v, 20_000.0) for v in (values, biased))
    assert sum(map(len, d.weights.values())) > sum(map(len, c.weights.values()))


def test_the_site_bias_has_its_sourced_prior():
    prior = default_priors(L.base_values(WIM_TILT, 0.0, WIM))["site_bias_pct"]
    assert (prior.kind, prior.a, prior.b) == ("normal", 0.0, SITE_BIAS_SD_PCT) and "Rys 2019" in prior.source
    # the source's arithmetic: a range of 11 kN over 77 stations, about 4.8 sd, of 55.5 kN; an sd of 4.1 %, rounded
    assert abs(100.0 * (61.0 - 50.0) / 4.8 / 55.5 - SITE_BIAS_SD_PCT) < 0.15


# ---- the between-site covariance ---------------------------------------------------------------------------------
#: the stand-in's site effect and each bogie's interaction with a site: sd of the outer axles' share [-]
SITE_SD, INTERACTION_SD = 0.02, 0.05


def site_weighings(site_sd):
    """Stand-in readings [kg]: the outer axles' shares -+ (d + g), d the site's own effect (sd ``site_sd``, its road
    seed's draw) and g the bogie's interaction with that site (sd INTERACTION_SD)."""

    def weigh(tasks, executor=None):
        out = np.full((len(tasks), 3), np.nan)
        for k, (s, _, _) in enumerate(tasks):
            seed = int(s["road_seed"]) % 2**32
            d = site_sd * np.random.default_rng([seed]).standard_normal()
            g = INTERACTION_SD * np.random.default_rng([seed, int(s["sample_id"])]).standard_normal()
            n = int(s["n_axles"])
            out[k, :n] = 8000.0 * (1.0 + (d + g) * np.linspace(-1.0, 1.0, n))
        return out

    return weigh


def test_the_between_site_covariance_holds_the_sites_own_variance_not_the_bogies(monkeypatch):
    table = wim_table(n=160)
    loads = np.full(table.loads.shape, 8000.0)
    loads[:, table.size == "tandem", :, :, 2] = np.nan
    table = dataclasses.replace(table, loads=loads)
    rng = np.random.default_rng(3)
    observed = L.Observed(
        {"tandem": rng.uniform(7e3, 9e3, (50, 2)), "triaxle": rng.uniform(7e3, 9e3, (50, 3))},
        {"tandem": np.arange(50), "triaxle": np.arange(50)},
    )  # fmt: skip
    base = {**L.base_values(WIM_TILT, 0.0, WIM), "sensor_error_pct": 0.0}
    problem = L.make_problem(table, observed, {"air_share": (0.0, 1.0)}, base)
    monkeypatch.setattr(P, "weigh_readings", site_weighings(SITE_SD))
    cov, sites, _ = P.site_covariance(problem, np.array([0.0]), 400)
    assert sites == 400 and np.all(np.linalg.eigvalsh(cov) > -1e-15)  # a covariance
    # the tri-axle's mean front share (summary 4) varies across sites by SITE_SD^2 = 4.0e-4 and by the 32 bogies'
    # interaction, INTERACTION_SD^2 / 32 = 0.8e-4, which the bootstraps already hold: the estimate keeps the first
    # (400 sites: the estimate's relative sd about 7 %, a tolerance of about 3 sd; uncorrected: 4.8e-4, 20 % high)
    assert cov[4, 4] == pytest.approx(SITE_SD**2, rel=0.2)
    monkeypatch.setattr(P, "weigh_readings", site_weighings(0.0))
    none, _, _ = P.site_covariance(problem, np.array([0.0]), 400)
    assert none[4, 4] < 0.25 * INTERACTION_SD**2 / 32  # no site effect: only the correction's noise is left
    # fewer than two sites, or a static table: none
    assert not P.site_covariance(problem, np.array([0.0]), 1)[0].any()
    static = L.make_problem(analytic_table(20), synthetic_observed(40), {"air_share": (0.0, 1.0)},
                            L.base_values(TILT, 0.0, None))  # fmt: skip
    zeros, n, shrink = P.site_covariance(static, np.array([0.5]), 16)
    assert n == 0 and not zeros.any() and shrink == 0.0


# ---- the sensor's per-axle error (Must 4) ------------------------------------------------------------------------
def test_a_per_axle_sensor_error_above_four_percent_is_said_in_words():
    above = F.sensor_finding({"sensor_error_pct": {"value": 4.7, "low": 4.0, "high": 5.3}})
    assert above["exceeds"] and above["bound_pct"] == 4.0
    assert "4.7 %, above the 4 % RMS" in above["finding"] and "not the sensor's error" in above["finding"]
    below = F.sensor_finding({"sensor_error_pct": {"value": 2.1, "low": 1.5, "high": 2.9}})
    assert not below["exceeds"] and below["finding"] is None
    assert F.sensor_finding({"air_share": {"value": 0.3}}) is None


# ---- prior sensitivity (Must 6) ----------------------------------------------------------------------------------
def sensitivity(n_observed):
    problem = L.make_problem(analytic_table(), synthetic_observed(n_observed), FIT, L.base_values(TILT, 0.0, None))
    settings = L.CalibrationSettings(FIT, seed=3, maxiter=20, popsize=8, bootstrap_resamples=0, posterior_draws=4000)
    result = F.calibrate(problem, settings)
    best = np.array([result.prior_free[q]["value"] for q in problem.fitted])
    priors = F.priors_for(problem, settings)
    return result, prior_sensitivity(problem, priors, result.posterior, best, 4000, 3, 0.9, 4)


def test_scaled_priors_change_the_tilts_sd_only():
    priors = default_priors(L.base_values(TILT, 0.0, None))
    halved = scaled_priors(priors, 0.5)
    # 0.65 degree halved (by hand: 0.325; a product of two exact binary halvings of the same double)
    assert halved["chassis_tilt_mean_deg"].b == pytest.approx(0.325, abs=1e-12) == halved["chassis_tilt_sd_deg"].b
    assert halved["air_share"] == priors["air_share"] and "times 0.5" in halved["chassis_tilt_mean_deg"].source


def test_a_large_survey_does_not_depend_on_the_tilt_prior_and_a_small_one_does():
    result, large = sensitivity(1500)
    assert set(large["fits"]) == {"halved", "doubled"} and large["priors_scaled"] == list(FIT)[:2]
    # the tilt priors' sd, 0.65 degree, doubled
    assert large["fits"]["doubled"]["tilt_prior_sd_deg"]["chassis_tilt_mean_deg"] == pytest.approx(1.3, abs=1e-12)
    # each move by hand: the largest |median - median| over the interval's width
    q = "chassis_tilt_mean_deg"
    s = result.posterior.summary[q]
    by_hand = max(abs(f["quantities"][q]["median"] - s["median"]) for f in large["fits"].values()) / (
        s["high"] - s["low"]
    )
    assert large["moves"][q] == pytest.approx(by_hand)
    assert not large["depends"] and large["sentence"].endswith("the answer does not depend on the tilt prior.")
    # 10 tri-axles, the fewest a fit takes: the prior, not the survey, holds the tilt. Measured 7 December 2026 with
    # the tilt priors' sd 0.65 degree: the tilt centre's median moves by 0.257 of its interval with 10, 0.146 with 11
    # and 0.215 with 12 (with sd 0.6, 12 were enough); with 1,500, by far less
    _, small = sensitivity(10)
    assert small["depends"] and any(small["moves"][q] > DEPENDS for q in small["depends_on_prior"])
    assert small["moves"]["chassis_tilt_mean_deg"] > 2.0 * large["moves"]["chassis_tilt_mean_deg"]
    assert "the answer depends on the tilt prior" in small["sentence"] and "degree" in small["sentence"]


def test_the_posterior_predictive_kilograms_carry_the_site_bias(monkeypatch):
    # every axle reads 8 t before the site's and the sensor's factors; the posterior's draws differ by the bias alone
    monkeypatch.setattr(K, "weigh_readings", lambda tasks, executor=None: np.full((len(tasks), 3), 8000.0))
    table = wim_table()
    base = {**L.base_values(WIM_TILT, 0.0, WIM), "sensor_error_pct": 0.0}
    draws = pd.DataFrame({"chain": 0, "site_bias_pct": [-5.0, 0.0, 5.0]})
    out = K.posterior_predictive(table, SimpleNamespace(draws=draws), base, 0.0, None, 0.9, draws=3)
    tri = out["triaxle"]["mean_group_load_kg"]
    # the same groups at each draw (no filter): the mean load scales by 1 + b, the pass's factor averaged alike; the
    # 90 % interval of three draws is their 5th and 95th percentiles, linear between: 1 + b of 0.955 and 1.045
    assert tri["high"] / tri["low"] == pytest.approx(1.045 / 0.955, rel=1e-6)  # rel: the metrics' rounding
    assert tri["median"] / tri["low"] == pytest.approx(1.0 / 0.955, rel=1e-6)
    factors = table.pass_factors()[table.size == "triaxle"]
    assert tri["median"] == pytest.approx(3 * 8000.0 * factors.mean(), rel=1e-6)
    # the load shares do not see it: one value over the draws
    share = out["triaxle"]["share_over_10pct"]
    assert share["low"] == share["high"]


def test_the_shrinkage_of_the_between_site_correlations_by_hand():
    # Schaefer and Strimmer 2005, target D. Two variables over 4 draws, deviations from their means (-1.5, -0.5, 0.5,
    # 1.5) and (-1.5, 0.5, -0.5, 1.5), both of variance 5/3: r = (2.25 - 0.25 - 0.25 + 2.25) / 5 = 0.8; the
    # standardised products w_k = d1 d2 / (5/3) = (1.35, -0.15, -0.15, 1.35), mean 0.6, so Var(r) = 4 / 27 x 4 x
    # 0.75^2 = 1/3, and lambda = 2 x (1/3) / (2 x 0.8^2) = 0.52083...
    x = np.array([[1.0, 1.0], [2.0, 3.0], [3.0, 2.0], [4.0, 4.0]])
    assert P.shrinkage_intensity(x) == pytest.approx((1 / 3) / 0.64, rel=1e-12)
    # exactly correlated variables (a column that never varies left out): r = 1, w_k = d1^2 / (5/3) = (1.35, 0.15,
    # 0.15, 1.35), mean 0.75, so Var(r) = 4 / 27 x 4 x 0.6^2 = 0.21333 and lambda the same (the estimate's own noise)
    line = np.column_stack([x[:, 0], 2.0 * x[:, 0] + 1.0, np.full(4, 7.0)])
    assert P.shrinkage_intensity(line) == pytest.approx(4 / 27 * 4 * 0.36, rel=1e-12)
    assert P.shrinkage_intensity(np.column_stack([x[:, 0], np.full(4, 7.0)])) == 1.0
    # 16 draws of 11 independent variables (as 16 sites and 11 summaries): what correlations they show is noise, so
    # most of it is shrunk away (measured 0.85 on this seed); 400 draws of 11 strongly correlated keep theirs (0.006)
    rng = np.random.default_rng(5)
    assert P.shrinkage_intensity(rng.standard_normal((16, 11))) > 0.8
    common = rng.standard_normal((400, 1))
    assert P.shrinkage_intensity(common + 0.3 * rng.standard_normal((400, 11))) < 0.05


def test_the_between_site_covariance_is_averaged_over_points_drawn_from_the_priors(monkeypatch):
    # the covariance at the fit may sit where the site matters little (a prior-free minimum at a corner): it is the
    # mean over SITE_POINTS points drawn from the priors, wherever the fit is. A stand-in covariance that grows with
    # the first quantity tells where it was evaluated
    problem = L.make_problem(analytic_table(), synthetic_observed(400), FIT, L.base_values(TILT, 0.0, None))
    d = len(P.summaries(problem.obs, problem.unit_weights()))
    priors = F.priors_for(problem, L.CalibrationSettings(FIT, seed=3))
    best = np.array([0.9 * problem.bounds[0][1], 0.5, 0.5])  # near the upper bound of the first quantity
    where = []

    def stand_in(problem_, theta, sites, executor=None):
        if sites < 2:  # the likelihood at the fit, made without a site (the real one gives zeros)
            return np.zeros((d, d)), 0, 0.0
        where.append(np.array(theta, dtype=float))
        return np.eye(d) * 1e-6 * (1.0 + float(theta[0]) ** 2), sites - len(where) % 2, 0.25 + 0.01 * len(where)

    monkeypatch.setattr(P, "site_covariance", stand_in)
    post = P.posterior(problem, priors, best, 800, 3, 0.9, chains=4, sites=16)
    assert len(where) == P.SITE_POINTS == 8 and not any(np.array_equal(w, best) for w in where)
    rng = np.random.default_rng(np.random.SeedSequence(3, spawn_key=(5,)))
    drawn = prior_draws(priors, list(problem.fitted), list(problem.bounds), 8, rng)
    assert np.array_equal(np.asarray(where), drawn)
    assert len({round(float(w[0]), 9) for w in where}) == 8  # eight different fleets, not one
    expected = sum(np.eye(d) * 1e-6 * (1.0 + float(w[0]) ** 2) for w in where) / 8
    assert np.array_equal(post.likelihood.covariance_site, expected) and post.likelihood.points == 8
    # the mean shrinkage, and the fewest sites any point kept (15 at the odd calls)
    assert post.likelihood.shrinkage == pytest.approx(0.25 + 0.01 * 4.5, rel=1e-12) and post.sites == 15
    # the precision is the one of the covariance's parts with the averaged site's
    like = post.likelihood
    precision = P._precision(like.covariance_obs, like.covariance_sim, expected, problem.table.sites)
    assert np.array_equal(like.precision, precision)
    # a likelihood given is used as it is: no first pass, no other covariance
    again = P.posterior(problem, priors, best, 800, 3, 0.9, chains=4, likelihood=post.likelihood)
    assert len(where) == 8 and again.likelihood is post.likelihood
