"""The calibration's posterior: the priors times a synthetic likelihood of the survey's summaries, sampled by MCMC
over the table of readings (``docs/calibration.md``, issue 30 Must 2).

The likelihood. Per size fitted, the survey is summarised by a few smooth statistics of its groups' quantities
(:func:`summaries`: the mean load share of each axle position but the last, the sd of each position's share, the
mean and sd of the spread). Their sampling distribution is taken as normal (Wood 2010's synthetic likelihood; Price
et al. 2018): ``s_obs ~ N(s(theta), S)``, ``s(theta)`` the calibration fleet's summaries at ``theta`` (from the
table, :func:`bogie.fleet.calibration.problem.simulated`), and ``S = S_obs + S_sim`` the summaries' covariance under a
bootstrap of the observed groups (the survey's sampling error) plus under a bootstrap of the calibration bogies at
the fit (the table's Monte Carlo error), both estimated once; for a WIM table on a shared site, plus ``1 + 1/K``
times the summaries' covariance between sites (:func:`site_covariance`: the survey's site and the table's K are
draws of the sites it could have been made at; issue 43 Must 2), averaged over points drawn from the priors
(:func:`prior_site_covariance`). A fixed covariance is the usual simplification; the summaries'
covariance changes little across the posterior's width.

The sampler: several chains of random-walk Metropolis (:data:`CHAINS` by default), the first from the fit, the others
from points drawn uniformly within the bounds (over-dispersed, as R-hat needs); each chain's proposal adapted
(Haario et al. 2001) over its own first quarter, which is then dropped; the rest are the posterior's draws, all
chains pooled. Chain k is seeded by spawn key (3, k) of the seed, so its draws do not depend on the other chains nor
on how many run. Whether they converged: :mod:`bogie.fleet.calibration.convergence` (R-hat and the bulk and tail
effective sample sizes per quantity, and what to change). Seeded: same arguments, same draws.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie import numerics
from bogie.fleet.calibration.convergence import ESS_MIN, RHAT_MAX, THRESHOLDS_SOURCE, advice, diagnostics
from bogie.fleet.calibration.priors import Prior, log_prior, prior_draws
from bogie.fleet.calibration.problem import Problem, _values, simulated
from bogie.fleet.calibration.settings import CalibrationSettings
from bogie.fleet.calibration.site import site_of
from bogie.fleet.calibration.table import (
    Mapper,
    bogie_tilts,
    map_tasks,
    moved_samples,
    protocol_spec,
    weigh_readings,
    wim_task,
)
from bogie.fleet.constants import AT_BOUND, PILED
from bogie.intervals import percentile_interval

__all__ = [
    "BOOTSTRAP", "CHAINS", "SITE_BOGIES", "SITE_POINTS", "START_TRIES", "Posterior", "posterior", "shrinkage_intensity",
    "prior_site_covariance", "site_bogies", "site_covariance", "site_part", "summaries", "synthetic_likelihood",
]  # fmt: skip

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
#: calibration bogies of each size weighed on every other site for the between-site covariance (the first of each
#: size, each as its steel and its air group) [-]: a convention, the cost of a site 4 x SITE_BOGIES weighings; the
#: covariance of so few bogies' summaries across sites includes their own interaction with the site, so it is, if
#: anything, too wide (docs/calibration.md, "The site")
SITE_BOGIES = 32
#: points drawn from the priors at which the between-site covariance is estimated, its mean over them entering the
#: likelihood (:func:`prior_site_covariance`) [-]: a convention, measured on the bench's three surveys
#: (bench/README.md); each costs a site study (2 x SITE_BOGIES bogies x 2 suspensions x ``sites`` weighings)
SITE_POINTS = 8


def _weighted_sd(x: np.ndarray, w: np.ndarray, about: np.ndarray, sites: np.ndarray | None) -> np.ndarray:
    """The weighted sd of ``x``'s columns about ``about`` (each row's own site's weighted mean), unbiased for
    reliability weights (the GNU Scientific Library's ``gsl_stats_wvariance`` factor, per site): the squares'
    weighted sum over the sum, over the sites, of ``V1 - V2 / V1`` (``V1``, ``V2``
    a site's sum of weights and of their squares: ``V1 (1 - 1 / n_eff)``, Kish's effective count ``n_eff``), so that
    ``n`` equal weights on one site divide by ``n - 1`` and on ``K`` sites by ``n - K``: a survey's one site and a
    table's ``K`` are read alike (docs/calibration.md, "A table over several sites"). NaN when no site has two
    effective groups."""
    labels = np.zeros(len(w), dtype=int) if sites is None else np.asarray(sites)
    dof = 0.0
    for k in np.unique(labels):
        wk = w[labels == k]
        v1 = float(wk.sum())
        dof += v1 - float((wk * wk).sum()) / v1 if v1 > 0.0 else 0.0
    if dof <= 0.0:
        return np.full(x.shape[1], math.nan)
    return np.sqrt(np.maximum((w[:, None] * (x - about) ** 2).sum(axis=0) / dof, 0.0))


def summaries(
    quantities: Mapping[str, np.ndarray], weights: Mapping[str, np.ndarray],
    sites: Mapping[str, np.ndarray] | None = None,
) -> np.ndarray:  # fmt: skip
    """The summaries of a survey, per size in the order of ``quantities`` (rows: groups; columns: each axle
    position's load share, then the spread [%]; ``weights`` per group): the mean share of each position but the
    last (the shares' mean is 1), the sd of each position's share (a tandem's first only: its two are equal), the
    spread's mean and sd. NaN where a size has no weight. With ``sites`` (per size, each row's WIM site: a table
    spread over several), each sd is about the row's own site's weighted mean (pooled within sites), so that it is
    one site's sd, as a survey's is, not widened by the sites' differences. Each sd is unbiased for the weights
    (:func:`_weighted_sd`: each site's mean costs its degree of freedom)."""
    out = []
    for size, q in quantities.items():
        n, w = q.shape[1] - 1, weights[size]
        if len(q) == 0 or w.sum() <= 0.0:
            out.extend([math.nan] * (n - 1 + (n if n > 2 else 1) + 2))
            continue
        mean = (w[:, None] * q).sum(axis=0) / w.sum()
        about = mean
        if sites is not None:
            about = np.empty_like(q)
            for k in np.unique(sites[size]):
                at = sites[size] == k
                about[at] = (w[at, None] * q[at]).sum(axis=0) / w[at].sum() if w[at].sum() > 0.0 else 0.0
        sd = _weighted_sd(q, w, about, None if sites is None else sites[size])
        out.extend([*mean[: n - 1], *sd[: (n if n > 2 else 1)], mean[n], sd[n]])
    return np.asarray(out, dtype=float)


def _sim_summaries(problem: Problem, sim: Any) -> np.ndarray:
    sites = None if sim.sites is None else {k: sim.sites[k] for k in problem.obs}
    return summaries({k: sim.quantities[k] for k in problem.obs}, {k: sim.weights[k] for k in problem.obs}, sites)


@dataclass
class SyntheticLikelihood:
    """``ln L(theta) = -(s_obs - s(theta))' S^-1 (s_obs - s(theta)) / 2`` (:func:`synthetic_likelihood`)."""

    problem: Problem
    observed: np.ndarray
    precision: np.ndarray
    covariance_obs: np.ndarray
    covariance_sim: np.ndarray
    covariance_site: np.ndarray  # between sites, of one site's summaries (entered 1 + 1/K times: the survey's site and
    # the table's K sites' mean)
    sites: int = 0  # the other sites it was estimated on
    shrinkage: float = 0.0  # how far its correlations were shrunk towards none (shrinkage_intensity) [-]
    points: int = 1  # the points drawn from the priors it was averaged over (1: at the fit alone; see posterior)

    def simulated(self, theta: np.ndarray) -> np.ndarray:
        p = self.problem
        sim = simulated(p.table, _values(theta, p.fitted, p.base), p.min_group_load_kg, None, p.weight_step_kg)
        return _sim_summaries(p, sim)

    def __call__(self, theta: np.ndarray) -> float:
        r = self.observed - self.simulated(theta)
        if not np.all(np.isfinite(r)):
            return -math.inf
        return -0.5 * float(numerics.matmul(numerics.matmul(r, self.precision), r))


def shrinkage_intensity(samples: np.ndarray) -> float:
    """How far to shrink the correlations of ``samples`` (rows: draws; columns: variables) towards none [0, 1]:
    Schaefer and Strimmer 2005's estimate for their target D (the diagonal of unequal variances; Statistical
    Applications in Genetics and Molecular Biology 4(1), art. 32, table 1), ``lambda = sum_{i != j} Var(r_ij) /
    sum_{i != j} r_ij^2``, ``r_ij`` the sample correlation, ``Var(r_ij) = n / (n - 1)^3 sum_k (w_kij - mean_k
    w_kij)^2`` with ``w_kij`` the product of draw k's standardised variables i and j; cut to [0, 1]. A variable
    that never varies is left out; 1 (no correlation kept) when fewer than two vary or none correlate."""
    x = np.asarray(samples, dtype=float)
    n = len(x)
    sd = np.sqrt(np.diag(numerics.cov(x))) if n >= 2 else np.zeros(x.shape[1])
    keep = sd > 0.0
    if keep.sum() < 2:
        return 1.0
    z = (x[:, keep] - x[:, keep].mean(axis=0)) / sd[keep]
    w = z[:, :, None] * z[:, None, :]
    w_mean = w.mean(axis=0)
    r = n / (n - 1) * w_mean
    gap = w - w_mean
    var_r = n / ((n - 1) * (n - 1) * (n - 1)) * (gap * gap).sum(axis=0)
    off = ~np.eye(z.shape[1], dtype=bool)
    squares = float((r[off] * r[off]).sum())
    return 1.0 if squares <= 0.0 else min(1.0, max(0.0, float(var_r[off].sum()) / squares))


def site_bogies(table: Any) -> np.ndarray:
    """The calibration bogies weighed on the other sites: the first :data:`SITE_BOGIES` of each size."""
    return np.sort(np.concatenate([np.flatnonzero(table.size == size)[:SITE_BOGIES] for size in np.unique(table.size)]))


def site_covariance(
    problem: Problem, best: np.ndarray, sites: int, executor: Executor | Mapper | None = None
) -> tuple[np.ndarray, int, float]:
    """The covariance of the survey's summaries between WIM sites, at the fit ``best``, and the sites it came from:
    :func:`site_bogies` weighed directly (their fitted tilts, steel and air) on each of ``sites`` other sites
    (:func:`bogie.fleet.calibration.site.site_of`, numbers K to K + ``sites`` - 1 after the table's K: their own
    roads, the bogies' own speeds), the same bogies, sensor errors and bias on each, so that only the site differs;
    a site whose summaries are not all defined (a size without a group) left out. Over the sites, a summary of m
    bogies varies by the site's own departure ``d`` and by the bogies' interaction with the site (variance ``g /
    m``, which the bootstraps of the survey and of the table already hold); the difference of two halves' summaries
    has no ``d`` and variance ``4 g / m``, so the site's own variance is the whole's less a quarter of the halves'
    difference's (at least 0), its correlations the whole's shrunk towards none by :func:`shrinkage_intensity` (a
    covariance, positive semi-definite); returned with the sites it came from and the shrinkage. Zeros (and 0
    sites, no shrinkage) for a static table, a table without a shared site or fewer than two sites."""
    table, d = problem.table, len(summaries(problem.obs, problem.unit_weights()))
    if table.protocol != "wim" or table.site is None or sites < 2:
        return np.zeros((d, d)), 0, 0.0
    values = _values(best, problem.fitted, problem.base)
    rows = site_bogies(table)
    tilt = np.radians(bogie_tilts(table, values))
    samples = moved_samples(table, values).to_dict("records")
    spec = protocol_spec(table, values["site_iri_m_km"])
    classes = list(table.samples["road_class"].astype(str))
    first = table.sites  # the table's own are sites 0 .. table.sites - 1
    others = [site_of(table.seed, table.study, classes, first + r) for r in range(sites)]  # once each, not per task
    tasks = [
        wim_task({**samples[i], "suspension": kind, "chassis_tilt": float(tilt[i])}, spec, site, float(table.speeds[i]))
        for site in others for kind in ("steel", "air") for i in rows
    ]  # fmt: skip
    loads = weigh_readings(tasks, executor).reshape(sites, 2, len(rows), 3)
    loads = loads * table.reading_factors(values, rows)[None, None]
    # the two halves of the bogies: alternate ones of each size
    order = np.zeros(len(rows), dtype=int)
    for size in np.unique(table.size[rows]):
        at = np.flatnonzero(table.size[rows] == size)
        order[at] = np.arange(len(at))
    halves = [order % 2 == 0, order % 2 == 1]

    def of(r: int, keep: np.ndarray) -> np.ndarray:
        sim = simulated(table, values, problem.min_group_load_kg, None, problem.weight_step_kg, loads[r][:, keep],
                        rows[keep])  # fmt: skip
        return _sim_summaries(problem, sim)

    whole, gap = [], []
    for r in range(sites):
        full, first, second = of(r, np.ones(len(rows), dtype=bool)), of(r, halves[0]), of(r, halves[1])
        if np.all(np.isfinite(full)) and np.all(np.isfinite(first - second)):
            whole.append(full)
            gap.append(first - second)
    if len(whole) < 2:
        return np.zeros((d, d)), len(whole), 0.0
    total = numerics.cov(np.asarray(whole))
    # the site's own variance: the whole's less the bogies' interaction with the site, a quarter of the halves' gap's
    own = np.maximum(np.diag(total) - np.diag(numerics.cov(np.asarray(gap))) / 4.0, 0.0)
    sd = np.sqrt(np.diag(total))
    corr = total / np.outer(np.where(sd > 0.0, sd, 1.0), np.where(sd > 0.0, sd, 1.0))
    # so few sites estimate the correlations badly and their inverse worse: shrunk towards none (Schaefer-Strimmer)
    shrink = shrinkage_intensity(np.asarray(whole))
    corr = (1.0 - shrink) * corr + shrink * np.diag(np.diag(corr))
    return corr * np.outer(np.sqrt(own), np.sqrt(own)), len(whole), shrink


def synthetic_likelihood(
    problem: Problem, best: np.ndarray, seed: int, sites: int = 0, executor: Executor | Mapper | None = None
) -> SyntheticLikelihood:
    """The synthetic likelihood of ``problem``'s survey, its covariance from :data:`BOOTSTRAP` resamples of the
    observed groups and of the calibration bogies at ``best`` (the fit), seeded by ``seed``, and twice the
    between-site covariance over ``sites`` other sites (:func:`site_covariance`, weighed on ``executor``)."""
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
    c_site, n_sites, shrink = site_covariance(problem, best, sites, executor)
    precision = _precision(c_obs, c_sim, c_site, problem.table.sites)
    return SyntheticLikelihood(problem, s_obs, precision, c_obs, c_sim, c_site, n_sites, shrink)


def site_part(table_sites: int) -> float:
    """How many times the between-site covariance enters the likelihood's: ``1 + 1 / table_sites`` (the survey's site
    departs from the population of sites by it, the table's mean over its ``table_sites`` sites by a ``1 /
    table_sites`` of it; docs/calibration.md, "The site")."""
    return 1.0 + 1.0 / table_sites


def _precision(c_obs: np.ndarray, c_sim: np.ndarray, c_site: np.ndarray, table_sites: int) -> np.ndarray:
    """The likelihood's precision from its covariance's parts."""
    # the survey's one site departs from the population of sites by c_site, the table's mean over its K sites by
    # c_site / K (docs/calibration.md, "The site")
    cov = c_obs + c_sim + site_part(table_sites) * c_site
    cov = cov + np.eye(len(cov)) * 1e-9 * max(float(np.trace(cov)) / len(cov), 1e-30)  # a ridge against rounding
    # a summary that is NaN in a resample (a size with no weight in it) leaves the covariance NaN: the precision is NaN
    # then, as numpy's inverse gave it, every likelihood NaN and no proposal accepted (issue 43 is to treat it)
    precision = numerics.inv(cov) if np.all(np.isfinite(cov)) else np.full_like(cov, np.nan)
    return precision


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
    #: the other sites the between-site covariance came from (0: none), and each source's share of the likelihood's
    #: covariance (its trace in the summaries' units over the total's): survey, table, between sites
    sites: int = 0
    covariance_shares: dict[str, float] | None = None
    likelihood: Any = None  # the synthetic likelihood it sampled (SyntheticLikelihood), for another prior

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


def _chain_task(task: tuple) -> tuple[np.ndarray, list, int]:
    """:func:`_chain` of one task ``(likelihood, priors, problem, best, draws, seed, k)``, importable (executors)."""
    like, priors, problem, best, draws, seed, k = task

    def target(theta: np.ndarray) -> tuple[float, float]:
        return _log_post(like, priors, problem, theta)

    return _chain(target, problem, best, draws, seed, k)


def _sample(
    like: SyntheticLikelihood, priors: Mapping[str, Prior], problem: Problem, best: np.ndarray, draws: int, seed: int,
    chains: int, executor: Executor | Mapper | None,
) -> tuple[np.ndarray, list]:  # fmt: skip
    """``chains`` chains of ``ceil(draws / chains)`` kept draws each on ``executor``: the draws (chains, draws,
    quantities) and each chain's :func:`_chain` result."""
    per_chain = -(-draws // chains)
    tasks = [(like, dict(priors), problem, best, per_chain, seed, k) for k in range(chains)]
    runs = map_tasks(_chain_task, tasks, executor)  # each chain on its own seed: the same bits wherever it runs
    return np.stack([r[0] for r in runs]), runs


def prior_site_covariance(
    problem: Problem, priors: Mapping[str, Prior], sites: int, seed: int, executor: Executor | Mapper | None = None,
    points: int = SITE_POINTS,
) -> tuple[np.ndarray, int, float, np.ndarray]:  # fmt: skip
    """The between-site covariance averaged over the fleets the priors allow: the mean of :func:`site_covariance`
    over ``sites`` other sites at ``points`` points drawn from ``priors`` within ``problem``'s bounds
    (:func:`bogie.fleet.calibration.priors.prior_draws`, seeded by spawn key (5,) of ``seed``). The site's effect
    depends on the fleet (air-sprung groups share equally on any road), and at the fit, a prior-free minimum, it
    may be a quarter of its size at the truth (docs/calibration.md, "The site"); averaged over the prior it does not
    depend on where the fit lands. Returned with the fewest sites any point kept, the mean shrinkage and the
    points."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(5,)))
    at = prior_draws(priors, list(problem.fitted), list(problem.bounds), points, rng)
    parts = [site_covariance(problem, theta, sites, executor) for theta in at]
    c_site = sum(part[0] for part in parts) / len(parts)
    return c_site, min(part[1] for part in parts), float(np.mean([part[2] for part in parts])), at


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
    chains: int = CHAINS, sites: int = 0, executor: Executor | Mapper | None = None,
    likelihood: SyntheticLikelihood | None = None,
) -> Posterior:  # fmt: skip
    """Sample the posterior of ``problem``'s fitted quantities: ``draws`` Metropolis steps kept in all, in ``chains``
    chains of ``ceil(draws / chains)`` each (:func:`_start`, :func:`_chain`), each chain's burn-in of a quarter of
    its draws adapting its proposal and dropped; credible intervals at ``confidence_level`` over all chains; R-hat and
    ESS per quantity, whether they meet :data:`~bogie.fleet.calibration.convergence.RHAT_MAX` and
    :data:`~bogie.fleet.calibration.convergence.ESS_MIN`, and what to change if not. The likelihood's covariance
    includes the between-site covariance over ``sites`` other sites averaged over :data:`SITE_POINTS` points drawn
    from the priors (:func:`prior_site_covariance`, weighed on ``executor``; 0: none); ``likelihood``: one already
    made for ``problem`` (:attr:`Posterior.likelihood` of another posterior of it; then ``sites`` is not used), None:
    made here. The chains run on ``executor`` too, one
    task each (:func:`~bogie.fleet.calibration.table.map_tasks`; None: here, one after another): each is seeded
    alone, so the draws are the same bits wherever they run."""
    if isinstance(chains, bool) or not isinstance(chains, int) or chains < 1:
        raise ValueError(f"chains = {chains!r}: must be a whole number >= 1")
    like = likelihood
    if like is None:
        like = synthetic_likelihood(problem, best, seed, 0, executor)
        if sites >= 2:  # (a table without a shared site gives zeros: site_covariance)
            c_site, n_sites, shrink, at = prior_site_covariance(problem, priors, sites, seed, executor)
            precision = _precision(like.covariance_obs, like.covariance_sim, c_site, problem.table.sites)
            like = dataclasses.replace(
                like, precision=precision, covariance_site=c_site, sites=n_sites, shrinkage=shrink, points=len(at)
            )  # fmt: skip
    kept, runs = _sample(like, priors, problem, best, draws, seed, chains, executor)
    per_chain = kept.shape[1]
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
    between = site_part(problem.table.sites) * like.covariance_site
    parts = {"survey": like.covariance_obs, "table": like.covariance_sim, "between_sites": between}
    # each summary in its own units: the trace of the covariance scaled by the total's diagonal
    scale = np.diag(sum(parts.values()))
    varies = scale > 0.0  # a summary that never varies (a spread read at a coarse resolution) has no share to give
    shares = {k: float(np.mean(np.diag(v)[varies] / scale[varies])) for k, v in parts.items()} if varies.any() else None
    return Posterior(
        frame, acceptance, summary, described, chains, said is None, said, like.sites, shares, like
    )  # fmt: skip
