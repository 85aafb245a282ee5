"""The posterior's convergence diagnostics (issue 43 Must 5; bogie.fleet.calibration.convergence): R-hat and the
effective sample sizes of Vehtari et al. 2021 on chains whose answer is known by hand or in closed form, and the
advice an unconverged posterior gets. ArviZ is not installed here, so no comparison with it: the facts below are
its (and Stan's) documented behaviour."""

import math

import numpy as np
import pytest
from scipy.special import ndtri

from bogie.fleet.calibration import convergence as C


def ar1(rho, chains, n, seed):
    """``chains`` stationary AR(1) chains of ``n`` draws, ``x_t = rho x_t-1 + e_t``, unit innovations."""
    e = np.random.default_rng(seed).standard_normal((chains, n))
    x = np.empty_like(e)
    x[:, 0] = e[:, 0] / math.sqrt(1.0 - rho**2)  # started in the stationary distribution
    for t in range(1, n):
        x[:, t] = rho * x[:, t - 1] + e[:, t]
    return x


def test_the_thresholds_are_the_papers():
    assert (C.RHAT_MAX, C.ESS_MIN) == (1.01, 400.0)
    assert "Bayesian Analysis 16(2):667-718" in C.THRESHOLDS_SOURCE


def test_split_rhat_and_the_rank_normal_scores_by_hand():
    # one chain 1, 2, 3, 4 split into (1, 2) and (3, 4): means 1.5 and 3.5, s^2 = 0.5 each, so W = 0.5;
    # B = N / (M - 1) sum (mean_m - mean)^2 = 2 x (1 + 1) = 4; var+ = (1/2) 0.5 + 4 / 2 = 2.25; R-hat = sqrt(4.5)
    assert C.split_rhat(np.array([[1.0, 2.0, 3.0, 4.0]])) == pytest.approx(math.sqrt(4.5), rel=1e-14)
    # an odd chain loses its middle draw: 1, 2, 99, 3, 4 is the chain above
    assert C.split_rhat(np.array([[1.0, 2.0, 99.0, 3.0, 4.0]])) == pytest.approx(math.sqrt(4.5), rel=1e-14)
    # ranks 4, 1, 2.5, 2.5 (the tie shares its average rank) of S = 4 draws: Phi^-1((r - 3/8) / (S + 1/4))
    z = C.rank_normal(np.array([[3.0, 1.0, 2.0, 2.0]]))
    expected = ndtri((np.array([4.0, 1.0, 2.5, 2.5]) - 0.375) / 4.25)
    np.testing.assert_allclose(z, expected[None, :], rtol=0, atol=0)


def test_independent_normal_chains_have_rhat_within_threshold_and_ess_near_their_draws():
    x = np.random.default_rng(43).standard_normal((4, 2000))
    d = C.diagnostics(x)
    assert d["rhat"] < C.RHAT_MAX
    # independent draws: ESS ~ the 8000 draws; over 40 seeds its estimate had sd 3 %, range 0.87-1.03 of them
    for key in ("ess_bulk", "ess_tail"):
        assert d[key] == pytest.approx(8000.0, rel=0.15), key
    assert C.advice({"q": d}, 8000, 4) is None


def test_an_ar1_chain_has_the_ess_of_its_closed_form():
    # an AR(1) chain's integrated autocorrelation time is (1 + rho) / (1 - rho): ESS = n (1 - rho) / (1 + rho),
    # 2105 for 4 chains of 10,000 at rho 0.9; over 40 seeds the estimate had sd 5.7 %: within 20 % (3.5 sd)
    x = ar1(0.9, 4, 10_000, seed=43)
    closed = 4 * 10_000 * (1 - 0.9) / (1 + 0.9)
    assert C.ess(x) == pytest.approx(closed, rel=0.2)
    assert C.diagnostics(x)["ess_bulk"] == pytest.approx(closed, rel=0.2)  # ranks keep the autocorrelation
    assert C.diagnostics(x)["rhat"] < C.RHAT_MAX


def test_chains_with_shifted_means_are_unconverged_and_the_advice_says_what_to_change():
    x = np.random.default_rng(43).standard_normal((4, 1000))
    x[3] += 1.0  # one chain one sd off: it sits elsewhere
    d = C.diagnostics(x)
    assert d["rhat"] > 1.05 and d["ess_bulk"] < C.ESS_MIN
    fine = C.diagnostics(np.random.default_rng(1).standard_normal((4, 1000)))
    said = C.advice({"air_share": d, "other": fine}, 4000, 4)
    assert said.startswith("unconverged (thresholds: R-hat < 1.01, bulk and tail ESS >= 400")
    assert "air_share short" in said and "other" not in said.split(";")[0]
    assert "the 4 chains disagree on air_share" in said and "valley" in said
    # the draws for ESS 400 at the smallest ESS now, rounded up to a thousand
    target = int(math.ceil(4000 * C.ESS_MIN / min(d["ess_bulk"], d["ess_tail"]) / 1000.0) * 1000)
    assert said.endswith(f"raise posterior_draws (params.yaml calibrate.posterior_draws) from 4000 to {target}")


def test_too_few_effective_draws_alone_ask_for_more_draws_without_calling_the_chains_in_disagreement():
    x = ar1(0.99, 4, 1000, seed=5)  # mixed, but slowly: about 20 effective draws of 4000
    d = C.diagnostics(x)
    said = C.advice({"q": d}, 4000, 4)
    assert d["ess_bulk"] < C.ESS_MIN and said is not None and "raise posterior_draws" in said
    assert ("disagree" in said) == (d["rhat"] >= C.RHAT_DISAGREE)


def test_a_chain_that_never_moved_has_no_rhat_or_ess_and_is_unconverged():
    x = np.ones((4, 100))
    d = C.diagnostics(x)
    assert all(math.isnan(d[k]) for k in ("rhat", "ess_bulk", "ess_tail"))
    assert "never moved" in C.advice({"q": d}, 400, 4)
    assert math.isnan(C.diagnostics(np.zeros((2, 3)))["rhat"])  # fewer than 4 draws a chain
