"""The calibration's priors and posterior (issue 30 Must 2): the priors' densities and sources, the summaries by
hand, the posterior around the truth of a known fleet, and a posterior piled against a bound flagged."""

import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_fleet_tilted import BUSH, FIT, RADIUS, TILT, TRUTH, radius_survey, radius_table

from bogie.fleet.calibration import fitting as F
from bogie.fleet.calibration import posterior as P
from bogie.fleet.calibration import problem as L
from bogie.fleet.calibration.priors import (
    TILT_MIX,
    TILT_PRIOR_SD_DEG,
    Prior,
    default_priors,
    log_prior,
    prior_draws,
    tilt_mixture,
)
from bogie.fleet.constants import CALIBRATION_QUANTITIES, PILED


def test_every_fittable_quantity_has_a_prior_with_a_source():
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    priors = default_priors(base, {"contact_roll_radius_mean_mm": (0.0, 120.0), "bush_stiffness_geomean": (1.0, 3e3)})
    assert set(priors) == set(CALIBRATION_QUANTITIES)
    assert all(len(p.source) > 40 for p in priors.values())
    # the sensor's prior is centred on the type's error; without a WIM protocol, on the quartz strip's 2 %
    assert priors["sensor_error_pct"].a == 2.0 and priors["sensor_error_pct"].b == pytest.approx(math.log(2.0))
    assert priors["contact_roll_radius_mean_mm"].describe().startswith("uniform(low 0, high 120): no source")


def test_the_tilt_prior_is_its_pairings_sd_and_the_default_fleet_sits_at_its_centre():
    # by hand, 8.1 m: 1 mm is 0.0070737 degree; matched: uniform +-85 mm, sd 85 / sqrt(3) = 49.07 mm = 0.3471 degree
    # (its own sd); low-deck: mean -250 mm = -1.7684 degree, sd 180 / sqrt(12) = 51.96 mm; mega: +250 mm, sd 28.87 mm
    only_matched = {"matched": (1.0, -85.0, 85.0)}
    assert tilt_mixture(only_matched) == pytest.approx((0.0, 0.34713), abs=1e-4)
    # E[theta] = (0.07 (-250) + 0.03 (250)) mm = -10 mm = -0.070737 degree; E[dh^2] = 0.9 (2408.3) + 0.07 (62500 +
    # 2700) + 0.03 (62500 + 833.3) = 2167.5 + 4564 + 1900 = 8631.5 mm^2, var 8631.5 - 100 = 8531.5: sd 92.37 mm
    mean, sd = tilt_mixture()
    assert mean == pytest.approx(-0.070737, abs=1e-5) and sd == pytest.approx(92.366 * 0.0070737, abs=1e-4)
    assert sum(w for w, _, _ in TILT_MIX.values()) == pytest.approx(1.0, abs=1e-12)
    # docs/calibration.md: 57 % beyond Meritor's 1 in 200 (0.29 degree), 10 % beyond one degree (each range uniform)
    per_mm = math.degrees(1e-3 / 8.1)

    def beyond(angle: float) -> float:
        # each range's length beyond +angle and below -angle over its whole length, by its share
        return sum(w * (max(hi - max(lo, angle / per_mm), 0.0) + max(min(hi, -angle / per_mm) - lo, 0.0)) / (hi - lo)
                   for w, lo, hi in TILT_MIX.values())  # fmt: skip

    assert round(100 * beyond(math.degrees(math.atan(1 / 200)))) == 57 and round(100 * beyond(1.0)) == 10
    # the priors' scale is the mixture's sd to 0.05 degree, and params.yaml's fleet is centred on the priors
    assert abs(sd - TILT_PRIOR_SD_DEG) <= 0.025
    tilt = yaml.safe_load((Path(__file__).parents[1] / "params.yaml").read_text())["distributions"]["chassis_tilt_deg"]
    priors = default_priors({})
    assert tilt["kind"] == "truncnormal" and tilt["mean"] == priors["chassis_tilt_mean_deg"].a
    assert tilt["sd"] == priors["chassis_tilt_sd_deg"].b == TILT_PRIOR_SD_DEG


def test_the_priors_log_densities_are_their_closed_forms():
    normal, lognormal = Prior("normal", 0.0, 0.6, "s"), Prior("lognormal", 2.0, math.log(2.0), "s")
    assert normal.log_density(0.6) - normal.log_density(0.0) == pytest.approx(-0.5)
    # a log-normal's density at its median e^sigma is e^(-sigma^2/2) / e^sigma of the one at its median... by hand:
    # ln p(4) - ln p(2) = -ln 2 - (ln 2 / ln 2)^2 / 2 = -0.693 - 0.5
    assert lognormal.log_density(4.0) - lognormal.log_density(2.0) == pytest.approx(-math.log(2.0) - 0.5)
    assert Prior("uniform", 0.0, 1.0, "s").log_density(1.5) == -math.inf
    log_uniform = Prior("loguniform", 1.0, 3000.0, "s")
    assert log_uniform.log_density(10.0) - log_uniform.log_density(100.0) == pytest.approx(math.log(10.0))
    assert log_prior({"x": normal}, {"x": 1.2, "y": 5.0}) == pytest.approx(-2.0)  # y has no prior: flat
    for bad in (("normal", 0.0, 0.0), ("uniform", 1.0, 1.0), ("loguniform", 0.0, 1.0), ("beta", 1.0, 2.0)):
        with pytest.raises(ValueError, match="must be one of"):
            Prior(*bad, "s")


def test_points_drawn_from_the_priors_follow_them_within_the_bounds():
    # 40,000 points of four quantities, each against its truncated distribution's closed form: a normal N(0, 0.65)
    # cut to [-1.5, 1.5] (alpha = 2.308: mean 0, variance 0.65^2 (1 - 2 alpha phi(alpha) / (2 Phi(alpha) - 1)) =
    # 0.3728, sd 0.6106); a log-uniform on [3, 3000] within bounds [10, 100] (ln x uniform on [ln 10, ln 100]: mean
    # 3.4539, sd (ln 10) / sqrt 12 = 0.6647); a log-normal of median 2 and sigma 0.5 cut to [1, 4] (ln(x/2) ~ N(0,
    # 0.5) cut at -+ln 2 = -+1.386 sd: mean 0 in the log); a quantity without a prior: uniform on [0, 1]
    priors = {
        "a": Prior("normal", 0.0, 0.65, "test"),
        "b": Prior("loguniform", 3.0, 3000.0, "test"),
        "c": Prior("lognormal", 2.0, 0.5, "test"),
    }
    names, bounds = ["a", "b", "c", "d"], [(-1.5, 1.5), (10.0, 100.0), (1.0, 4.0), (0.0, 1.0)]
    x = prior_draws(priors, names, bounds, 40_000, np.random.default_rng(1))
    assert all(np.all((x[:, i] >= lo) & (x[:, i] <= hi)) for i, (lo, hi) in enumerate(bounds))
    se = 1.0 / math.sqrt(40_000)  # a mean's standard error per unit sd
    alpha = 1.5 / 0.65
    phi, big_phi = math.exp(-alpha * alpha / 2) / math.sqrt(2 * math.pi), 0.5 * (1 + math.erf(alpha / math.sqrt(2)))
    sd_a = 0.65 * math.sqrt(1 - 2 * alpha * phi / (2 * big_phi - 1))
    assert abs(x[:, 0].mean()) < 4 * se * sd_a and x[:, 0].std() == pytest.approx(sd_a, rel=0.02)
    logs = np.log(x[:, 1])
    assert abs(logs.mean() - math.log(1000.0) / 2) < 4 * se * 0.6647 and logs.std() == pytest.approx(0.6647, rel=0.02)
    assert abs(np.log(x[:, 2] / 2.0).mean()) < 4 * se * 0.5
    assert abs(x[:, 3].mean() - 0.5) < 4 * se * math.sqrt(1 / 12)
    # seeded: the same points again; bounds that hold none of a prior's mass are an error that names the quantity
    assert np.array_equal(x[:5], prior_draws(priors, names, bounds, 5, np.random.default_rng(1)))
    with pytest.raises(ValueError, match="b: its bounds \\[4000, 5000\\] hold none of its prior loguniform"):
        prior_draws(priors, ["b"], [(4000.0, 5000.0)], 1, np.random.default_rng(1))
    with pytest.raises(ValueError, match="a: its bounds \\[20, 30\\]"):
        prior_draws(priors, ["a"], [(20.0, 30.0)], 1, np.random.default_rng(1))


def test_the_summaries_by_hand():
    # two tri-axle groups of shares (0.9, 1.0, 1.1) and (1.1, 1.0, 0.9), spreads 20 %; one tandem group weighted 3x
    tri = np.array([[0.9, 1.0, 1.1, 20.0], [1.1, 1.0, 0.9, 20.0]])
    tandem = np.array([[0.95, 1.05, 10.0], [1.05, 0.95, 10.0]])
    s = P.summaries({"tandem": tandem, "triaxle": tri}, {"tandem": np.array([3.0, 1.0]), "triaxle": np.ones(2)})
    # tandem: mean share 0 = (3 x 0.95 + 1.05) / 4 = 0.975; its weighted squares 3 x 0.025^2 + 0.075^2 = 0.0075 over
    # V1 - V2 / V1 = 4 - 10 / 4 = 1.5 (reliability weights): sd sqrt(0.005); spread mean 10, sd 0. Tri-axle: mean
    # shares 1.0, 1.0; squares 2 x 0.01 over 2 - 1: sds sqrt(0.02), 0, sqrt(0.02); spread 20, sd 0
    sd_t, sd_3 = math.sqrt(0.005), math.sqrt(0.02)
    np.testing.assert_allclose(s, [0.975, sd_t, 10.0, 0.0, 1.0, 1.0, sd_3, 0.0, sd_3, 20.0, 0.0], atol=1e-12)


@pytest.fixture(scope="module")
def fitted():
    table, observed = radius_table(), radius_survey()
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    settings = L.CalibrationSettings(FIT, seed=4, maxiter=30, popsize=8, bootstrap_resamples=4, posterior_draws=3000)
    return F.calibrate(L.make_problem(table, observed, FIT, base), settings)


def test_the_posterior_holds_the_known_fleet_and_is_narrower_than_its_prior(fitted):
    post = fitted.posterior
    assert len(post.draws) == 3000 and 0.15 < post.acceptance < 0.6
    # four chains of 750 (posterior_draws is the draws in all), each quantity's R-hat and ESS beside its interval
    assert post.chains == 4 and post.draws["chain"].tolist() == [k for k in range(4) for _ in range(750)]
    for q, truth in TRUTH.items():
        s = post.summary[q]
        assert 1.0 <= s["rhat"] < 1.1 and 100 < s["ess_bulk"] < 3000 and 100 < s["ess_tail"] < 3000, (q, s)
        assert s["low"] <= truth <= s["high"], (q, s)
        assert s["high"] - s["low"] < 0.2 * (FIT[q][1] - FIT[q][0]) and s["piled"] is None
    assert fitted.fitted["contact_roll_radius_mean_mm"]["at_bound"] is None


def test_a_posterior_piled_against_a_bound_is_flagged_with_its_share_of_draws():
    # the survey's mean radius is 35 mm; a range that starts at 50 mm leaves the posterior nowhere but its lower bound
    table, observed = radius_table(), radius_survey()
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    narrow = {**FIT, "contact_roll_radius_mean_mm": (50.0, 115.0)}
    settings = L.CalibrationSettings(narrow, seed=4, maxiter=20, popsize=8, bootstrap_resamples=0, posterior_draws=2000)
    result = F.calibrate(L.make_problem(table, observed, narrow, base), settings)
    finding = result.fitted["contact_roll_radius_mean_mm"]["at_bound"]
    assert finding["bound"] == "low" and finding["limit"] == 50.0 and finding["share_of_posterior"] >= PILED
    assert result.posterior.summary["contact_roll_radius_mean_mm"]["piled"] == "low"


@pytest.fixture(scope="module")
def radius_problem():
    table, observed = radius_table(), radius_survey()
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    problem = L.make_problem(table, observed, FIT, base)
    best = np.array([TRUTH[q] for q in problem.fitted])
    return problem, F.priors_for(problem, L.CalibrationSettings(FIT, seed=4)), best


def test_each_chain_is_its_own_same_bits_whatever_the_number_of_chains(radius_problem):
    # issue 43 Must 5: chain k is seeded by spawn key (3, k) alone, so 2 chains of 160 are the first two of 4 chains
    # of 160, bit for bit; and the same arguments give the same draws
    problem, priors, best = radius_problem
    two = P.posterior(problem, priors, best, 320, 4, 0.9, chains=2)
    four = P.posterior(problem, priors, best, 640, 4, 0.9, chains=4)
    again = P.posterior(problem, priors, best, 640, 4, 0.9, chains=4)
    assert list(four.draws.columns) == ["chain", *problem.fitted, "log_likelihood"]
    first_two = four.draws[four.draws["chain"] < 2].reset_index(drop=True)
    assert np.array_equal(two.draws.to_numpy(), first_two.to_numpy())
    assert np.array_equal(four.draws.to_numpy(), again.draws.to_numpy()) and four.summary == again.summary
    # the chains start apart: chain 0 at the fit, the others at points drawn within the bounds
    starts = four.draws.groupby("chain").first()
    assert starts[problem.fitted[0]].nunique() == 4
    # the pooled median is over every chain's draws
    q = problem.fitted[1]
    assert four.summary[q]["median"] == float(np.median(four.draws[q]))


def test_the_chains_on_a_process_pool_are_the_same_bits_as_in_this_process(radius_problem):
    # the chains run one task each on the executor (the stage's workers); each is seeded alone, so the draws, their
    # log-likelihoods and the acceptance do not depend on where they ran; the pool's processes import bogie afresh
    problem, priors, best = radius_problem
    here = P.posterior(problem, priors, best, 480, 4, 0.9, chains=3)
    with ProcessPoolExecutor(2) as pool:
        there = P.posterior(problem, priors, best, 480, 4, 0.9, chains=3, executor=pool)
    assert np.array_equal(here.draws.to_numpy(), there.draws.to_numpy())
    assert here.acceptance == there.acceptance and here.summary == there.summary


def test_a_short_posterior_is_called_unconverged_and_told_to_draw_more(radius_problem):
    problem, priors, best = radius_problem
    post = P.posterior(problem, priors, best, 200, 4, 0.9, chains=4)  # 50 draws a chain: far too few
    assert not post.converged and post.advice.startswith("unconverged")
    assert "raise posterior_draws (params.yaml calibrate.posterior_draws) from 200 to " in post.advice
    assert post.thresholds["rhat_below"] == 1.01 and post.thresholds["ess_bulk_and_tail_at_least"] == 400.0
    with pytest.raises(ValueError, match="chains = 0"):
        P.posterior(problem, priors, best, 200, 4, 0.9, chains=0)
