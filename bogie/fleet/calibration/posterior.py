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

The sampler: several chains of random-walk Metropolis (:data:`CHAINS` by default), the first from the fit, the others
from points drawn uniformly within the bounds (over-dispersed, as R-hat needs); each chain's proposal adapted
(Haario et al. 2001) over its own first quarter, which is then dropped; the rest are the posterior's draws, all
chains pooled. Chain k is seeded by spawn key (3, k) of the seed, so its draws do not depend on the other chains nor
on how many run. Whether they converged: :mod:`bogie.fleet.calibration.convergence` (R-hat and the bulk and tail
effective sample sizes per quantity, and what to change). Seeded: same arguments, same draws.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie import numerics
from bogie.fleet.calibration.convergence import ESS_MIN, RHAT_MAX, THRESHOLDS_SOURCE, advice, diagnostics
from bogie.fleet.calibration.priors import Prior, log_prior
from bogie.fleet.calibration.problem import Problem, _values, simulated
from bogie.fleet.calibration.settings import CalibrationSettings
from bogie.fleet.constants import AT_BOUND, PILED
from bogie.intervals import percentile_interval

__all__ = ["BOOTSTRAP", "CHAINS", "START_TRIES", "Posterior", "posterior", "summaries", "synthetic_likelihood"]

#: bootstrap resamples of each side for the summaries' covariance [-]; a convention (no source), like the sampler's
#: first proposal (a fiftieth of each bound's width) and its burn-in (a quarter of the draws); the adapted
#: proposal's scale 2.38^2 / d is Gelman, Roberts and Gilks 1996's optimal scaling, as Haario et al. 2001 use it
BOOTSTRAP = 200
#: chains of the sampler unless told: ``CalibrationSettings.chains``' default (Vehtari et al. 2021's four), declared
#: there once [-]
CHAINS: int = CalibrationSettings.__dataclass_fields__["chains"].default
#: points drawn within the bounds for a chain's start before it starts from the fit instead (all without posterior
#: density: the likelihood NaN there) [-]; a convention
START_TRIES = 100


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
    """The posterior's draws (one row each: ``chain``, the fitted quantities, ``log_likelihood``; chain by chain), the
    acceptance rate [-], and per quantity its ``median``, the equal-tailed credible interval ``low``, ``high`` (all
    chains' draws pooled), the shares of the draws within :data:`~bogie.fleet.constants.AT_BOUND` of each bound,
    ``piled`` (``low``/``high``/None), ``rhat``, ``ess_bulk`` and ``ess_tail``
    (:func:`bogie.fleet.calibration.convergence.diagnostics`); the number of ``chains``, whether every quantity meets
    the thresholds (``converged``) and, when not, what to change (``advice``)."""

    draws: pd.DataFrame
    acceptance: float
    summary: dict[str, dict[str, Any]]
    priors: dict[str, str]
    chains: int
    converged: bool
    advice: str | None

    @property
    def thresholds(self) -> dict[str, Any]:
        """What ``converged`` asks of every quantity, and its source."""
        return {"rhat_below": RHAT_MAX, "ess_bulk_and_tail_at_least": ESS_MIN, "source": THRESHOLDS_SOURCE}


def _log_post(like, priors, problem, theta) -> tuple[float, float]:
    if any(not lo <= t <= hi for t, (lo, hi) in zip(theta, problem.bounds)):
        return -math.inf, -math.inf
    lp = log_prior(priors, dict(zip(problem.fitted, theta)))
    if not math.isfinite(lp):
        return -math.inf, -math.inf
    ll = like(theta)
    return lp + ll, ll


def _start(
    target, problem: Problem, best: np.ndarray, chain: int, rng: np.random.Generator
) -> tuple[np.ndarray, float, float]:
    """Chain 0 starts at the fit (at the bounds' centre if the fit has no posterior density); every other chain at a
    point drawn uniformly within the bounds from its own ``rng``, the first of :data:`START_TRIES` with a density (if
    none has, at chain 0's start). The start, with its log posterior and log likelihood (``target``'s)."""
    low, high = (np.array([b[i] for b in problem.bounds]) for i in (0, 1))
    if chain > 0:
        for _ in range(START_TRIES):
            theta = low + (high - low) * rng.random(len(low))
            lp, ll = target(theta)
            if math.isfinite(lp):
                return theta, lp, ll
    theta = np.asarray(best, dtype=float).copy()
    lp, ll = target(theta)
    if not math.isfinite(lp):  # the fit itself has no prior density (a bound): the bounds' centre
        theta = (low + high) / 2
        lp, ll = target(theta)
    return theta, lp, ll


def _chain(target, problem: Problem, best: np.ndarray, draws: int, seed: int, k: int) -> tuple[np.ndarray, list, int]:
    """Chain ``k``: ``draws`` kept Metropolis steps after a burn-in of a quarter of them that adapts the proposal;
    its draws, their log-likelihoods and the accepted kept steps. Seeded by spawn key (3, k) of ``seed`` alone."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3, k)))
    d = len(best)
    width = np.array([hi - lo for lo, hi in problem.bounds])
    cov = np.diag((width / 50.0) ** 2)
    theta, lp, ll = _start(target, problem, best, k, rng)
    burn = max(draws // 4, 1)
    chain, lls, accepted = [], [], 0
    for step in range(burn + draws):
        if step < burn and step >= 100 and step % 50 == 0:  # Haario's adaptive proposal, during burn-in only
            past = np.asarray(chain[max(len(chain) // 2, len(chain) - 2000) :])  # not the way in from a far start
            cov = (2.38**2 / d) * numerics.cov(past.reshape(len(past), d)) + np.diag((width * 1e-4) ** 2)
        proposal = numerics.multivariate_normal(rng, theta, cov)
        lp_new, ll_new = target(proposal)
        if math.log(rng.random()) < lp_new - lp:
            theta, lp, ll = proposal, lp_new, ll_new
            accepted += step >= burn
        chain.append(theta.copy())
        lls.append(ll)
    return np.asarray(chain[burn:]).reshape(draws, d), lls[burn:], accepted


def _quantity(x: np.ndarray, bounds: tuple[float, float], confidence_level: float) -> dict[str, Any]:
    """One quantity's summary of its draws ``x`` (chains, draws): over them all pooled, and its diagnostics."""
    pooled, (lo, hi) = x.ravel(), bounds
    margin = AT_BOUND * (hi - lo)
    share_low, share_high = float(np.mean(pooled <= lo + margin)), float(np.mean(pooled >= hi - margin))
    piled = "low" if share_low >= PILED else "high" if share_high >= PILED else None
    low, high = percentile_interval(pooled, confidence_level)
    return {
        "median": float(np.median(pooled)), "low": float(low), "high": float(high),
        "share_at_low": share_low, "share_at_high": share_high,
        "piled": piled, **diagnostics(x),
    }  # fmt: skip


def posterior(
    problem: Problem, priors: Mapping[str, Prior], best: np.ndarray, draws: int, seed: int, confidence_level: float,
    chains: int = CHAINS,
) -> Posterior:  # fmt: skip
    """Sample the posterior of ``problem``'s fitted quantities: ``draws`` Metropolis steps kept in all, in ``chains``
    chains of ``ceil(draws / chains)`` each (:func:`_start`, :func:`_chain`), each chain's burn-in of a quarter of
    its draws adapting its proposal and dropped; credible intervals at ``confidence_level`` over all chains; R-hat and
    ESS per quantity, whether they meet :data:`~bogie.fleet.calibration.convergence.RHAT_MAX` and
    :data:`~bogie.fleet.calibration.convergence.ESS_MIN`, and what to change if not."""
    if isinstance(chains, bool) or not isinstance(chains, int) or chains < 1:
        raise ValueError(f"chains = {chains!r}: must be a whole number >= 1")
    like = synthetic_likelihood(problem, best, seed)

    def target(theta: np.ndarray) -> tuple[float, float]:
        return _log_post(like, priors, problem, theta)

    per_chain = -(-draws // chains)
    runs = [_chain(target, problem, best, per_chain, seed, k) for k in range(chains)]
    kept = np.stack([r[0] for r in runs])  # (chains, draws, quantities)
    frame = pd.DataFrame(kept.reshape(chains * per_chain, -1), columns=list(problem.fitted))
    frame.insert(0, "chain", np.repeat(np.arange(chains), per_chain))
    frame["log_likelihood"] = [ll for r in runs for ll in r[1]]
    summary = {
        q: _quantity(kept[:, :, i], problem.bounds[i], confidence_level) for i, q in enumerate(problem.fitted)
    }  # fmt: skip
    said = advice(summary, draws, chains)
    flat = "flat over the bounds (no prior given)"
    described = {q: priors[q].describe() if q in priors else flat for q in problem.fitted}
    acceptance = sum(r[2] for r in runs) / (chains * per_chain)
    return Posterior(frame, acceptance, summary, described, chains, said is None, said)
