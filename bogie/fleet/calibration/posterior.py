"""The calibration's posterior: the priors times a synthetic likelihood of the survey's summaries, sampled by MCMC
over the table of readings (``docs/calibration.md``, issue 30 Must 2).

The likelihood. Per size fitted, the survey is summarised by a few smooth statistics of its groups' quantities
(:func:`summaries`: the mean load share of each axle position but the last, the sd of each position's share, the
mean and sd of the spread). Their sampling distribution is taken as normal (Wood 2010's synthetic likelihood; Price
et al. 2018): ``s_obs ~ N(s(theta), S)``, ``s(theta)`` the calibration fleet's summaries at ``theta`` (from the
table, :func:`bogie.fleet.calibration.problem.simulated`), and ``S = S_obs + S_sim`` the summaries' covariance under a
bootstrap of the observed groups (the survey's sampling error) plus under a bootstrap of the calibration bogies at
the fit (the table's Monte Carlo error), both estimated once. A fixed covariance is the usual simplification; the
summaries' covariance changes little across the posterior's width.

The sampler: random-walk Metropolis from the fit, its proposal adapted (Haario et al. 2001) over the first quarter
of the draws, which are then dropped; the rest are the posterior's draws. Seeded: same arguments, same draws.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie import numerics
from bogie.fleet.calibration.priors import Prior, log_prior
from bogie.fleet.calibration.problem import Problem, _values, simulated
from bogie.fleet.constants import AT_BOUND, PILED
from bogie.intervals import percentile_interval

__all__ = ["BOOTSTRAP", "Posterior", "posterior", "summaries", "synthetic_likelihood"]

#: bootstrap resamples of each side for the summaries' covariance [-]; a convention (no source), like the sampler's
#: first proposal (a fiftieth of each bound's width) and its burn-in (a quarter of the draws); the adapted
#: proposal's scale 2.38^2 / d is Gelman, Roberts and Gilks 1996's optimal scaling, as Haario et al. 2001 use it
BOOTSTRAP = 200


def _weighted_sd(x: np.ndarray, w: np.ndarray, mean: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum((w[:, None] * (x - mean) ** 2).sum(axis=0) / w.sum(), 0.0))


def summaries(quantities: Mapping[str, np.ndarray], weights: Mapping[str, np.ndarray]) -> np.ndarray:
    """The summaries of a survey, per size in the order of ``quantities`` (rows: groups; columns: each axle
    position's load share, then the spread [%]; ``weights`` per group): the mean share of each position but the
    last (the shares' mean is 1), the sd of each position's share (a tandem's first only: its two are equal), the
    spread's mean and sd. NaN where a size has no weight."""
    out = []
    for size, q in quantities.items():
        n, w = q.shape[1] - 1, weights[size]
        if len(q) == 0 or w.sum() <= 0.0:
            out.extend([math.nan] * (n - 1 + (n if n > 2 else 1) + 2))
            continue
        mean = (w[:, None] * q).sum(axis=0) / w.sum()
        sd = _weighted_sd(q, w, mean)
        out.extend([*mean[: n - 1], *sd[: (n if n > 2 else 1)], mean[n], sd[n]])
    return np.asarray(out, dtype=float)


def _sim_summaries(problem: Problem, sim: Any) -> np.ndarray:
    return summaries({k: sim.quantities[k] for k in problem.obs}, {k: sim.weights[k] for k in problem.obs})


@dataclass
class SyntheticLikelihood:
    """``ln L(theta) = -(s_obs - s(theta))' S^-1 (s_obs - s(theta)) / 2`` (:func:`synthetic_likelihood`)."""

    problem: Problem
    observed: np.ndarray
    precision: np.ndarray
    covariance_obs: np.ndarray
    covariance_sim: np.ndarray

    def simulated(self, theta: np.ndarray) -> np.ndarray:
        p = self.problem
        sim = simulated(p.table, _values(theta, p.fitted, p.base), p.min_group_load_kg, None, p.weight_step_kg)
        return _sim_summaries(p, sim)

    def __call__(self, theta: np.ndarray) -> float:
        r = self.observed - self.simulated(theta)
        if not np.all(np.isfinite(r)):
            return -math.inf
        return -0.5 * float(numerics.matmul(numerics.matmul(r, self.precision), r))


def synthetic_likelihood(problem: Problem, best: np.ndarray, seed: int) -> SyntheticLikelihood:
    """The synthetic likelihood of ``problem``'s survey, its covariance from :data:`BOOTSTRAP` resamples of the
    observed groups and of the calibration bogies at ``best`` (the fit), seeded by ``seed``."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(2,)))
    ones = problem.unit_weights()
    s_obs = summaries(problem.obs, ones)
    obs_draws = []
    for _ in range(BOOTSTRAP):
        w = {k: rng.multinomial(len(v), np.full(len(v), 1.0 / len(v))).astype(float) for k, v in problem.obs.items()}
        obs_draws.append(summaries(problem.obs, w))
    values = _values(best, problem.fitted, problem.base)
    n = len(problem.table.size)
    sim_draws = []
    for _ in range(BOOTSTRAP):
        slots = rng.multinomial(n, np.full(n, 1.0 / n)).astype(float)
        sim = simulated(problem.table, values, problem.min_group_load_kg, slots, problem.weight_step_kg)
        sim_draws.append(_sim_summaries(problem, sim))
    c_obs, c_sim = (numerics.cov(np.asarray(d)) for d in (obs_draws, sim_draws))
    cov = c_obs + c_sim
    cov = cov + np.eye(len(cov)) * 1e-9 * max(float(np.trace(cov)) / len(cov), 1e-30)  # a ridge against rounding
    # a summary that is NaN in a resample (a size with no weight in it) leaves the covariance NaN: the precision is NaN
    # then, as numpy's inverse gave it, every likelihood NaN and no proposal accepted (issue 43 is to treat it)
    precision = numerics.inv(cov) if np.all(np.isfinite(cov)) else np.full_like(cov, np.nan)
    return SyntheticLikelihood(problem, s_obs, precision, c_obs, c_sim)


@dataclass
class Posterior:
    """The posterior's draws (one row each: the fitted quantities, ``log_likelihood``), the acceptance rate [-], and
    per quantity its ``median``, the equal-tailed credible interval ``low``, ``high``, the shares of the draws
    within :data:`~bogie.fleet.constants.AT_BOUND` of each bound, and ``piled`` (``low``/``high``/None)."""

    draws: pd.DataFrame
    acceptance: float
    summary: dict[str, dict[str, Any]]
    priors: dict[str, str]


def _log_post(like, priors, problem, theta) -> tuple[float, float]:
    if any(not lo <= t <= hi for t, (lo, hi) in zip(theta, problem.bounds)):
        return -math.inf, -math.inf
    lp = log_prior(priors, dict(zip(problem.fitted, theta)))
    if not math.isfinite(lp):
        return -math.inf, -math.inf
    ll = like(theta)
    return lp + ll, ll


def posterior(
    problem: Problem, priors: Mapping[str, Prior], best: np.ndarray, draws: int, seed: int, confidence_level: float
) -> Posterior:
    """Sample the posterior of ``problem``'s fitted quantities: ``draws`` Metropolis steps from ``best``, the first
    quarter adapting the proposal and dropped; credible intervals at ``confidence_level``."""
    like = synthetic_likelihood(problem, best, seed)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3,)))
    d = len(best)
    width = np.array([hi - lo for lo, hi in problem.bounds])
    cov = np.diag((width / 50.0) ** 2)
    theta = np.asarray(best, dtype=float).copy()
    lp, ll = _log_post(like, priors, problem, theta)
    if not math.isfinite(lp):  # the fit itself has no prior density (a bound): start at the bounds' centre
        theta = np.array([(lo + hi) / 2 for lo, hi in problem.bounds])
        lp, ll = _log_post(like, priors, problem, theta)
    burn = max(draws // 4, 1)
    chain, lls, accepted = [], [], 0
    for step in range(burn + draws):
        if step < burn and step >= 100 and step % 50 == 0:  # Haario's adaptive proposal, during burn-in only
            past = np.asarray(chain[-min(len(chain), 2000) :])
            cov = (2.38**2 / d) * numerics.cov(past.reshape(len(past), d)) + np.diag((width * 1e-4) ** 2)
        proposal = numerics.multivariate_normal(rng, theta, cov)
        lp_new, ll_new = _log_post(like, priors, problem, proposal)
        if math.log(rng.random()) < lp_new - lp:
            theta, lp, ll = proposal, lp_new, ll_new
            accepted += step >= burn
        chain.append(theta.copy())
        lls.append(ll)
    kept = np.asarray(chain[burn:])
    frame = pd.DataFrame(kept, columns=list(problem.fitted))
    frame["log_likelihood"] = lls[burn:]
    summary = {}
    for i, q in enumerate(problem.fitted):
        x, (lo, hi) = kept[:, i], problem.bounds[i]
        margin = AT_BOUND * (hi - lo)
        share_low, share_high = float(np.mean(x <= lo + margin)), float(np.mean(x >= hi - margin))
        piled = "low" if share_low >= PILED else "high" if share_high >= PILED else None
        low, high = percentile_interval(x, confidence_level)
        summary[q] = {
            "median": float(np.median(x)), "low": float(low), "high": float(high),
            "share_at_low": share_low, "share_at_high": share_high,
            "piled": piled,
        }  # fmt: skip
    flat = "flat over the bounds (no prior given)"
    described = {q: priors[q].describe() if q in priors else flat for q in problem.fitted}
    return Posterior(frame, accepted / draws, summary, described)
