"""Whether the posterior's chains have converged (issue 43 Must 5; ``docs/calibration.md``, "Convergence"): the
rank-normalised split-R-hat and the bulk and tail effective sample sizes of Vehtari, Gelman, Simpson, Carpenter and
Buerkner (2021, Bayesian Analysis 16(2):667-718), and the sentence that says what to change when they fall short.

``chains`` is an (M, N) array: M chains of N kept draws of one quantity. Each chain is split in halves (the middle
draw of an odd N dropped), so the 2M halves of N // 2 draws are what every formula below calls chains.

* split-R-hat of chains ``x`` (M chains, N draws): ``B = N/(M-1) sum_m (mean_m - mean)^2``, ``W = 1/M sum_m s_m^2``,
  ``var+ = (N-1)/N W + B/N``, ``R-hat = sqrt(var+ / W)``;
* rank normalisation: ``z = Phi^-1((r - 3/8) / (S + 1/4))``, ``r`` a draw's rank among all S draws (ties: their
  average rank), Blom's normal scores; ``R-hat = max(R-hat(z), R-hat(z of |x - median x|))`` (bulk and folded);
* ESS = ``M N / tau``, ``tau = -1 + 2 sum_{k=0..K} P_k``, ``P_k = rho_2k + rho_2k+1``,
  ``rho_t = 1 - (W - mean_m acov_m(t)) / var+`` (``acov_m(t) = 1/N sum_n (x_nm - mean_m)(x_n+t,m - mean_m)``);
  Geyer's initial monotone sequence: the sum stops before the first negative ``P_k`` and each ``P_k`` is cut to the
  one before it. As Stan and ArviZ: the next even lag's ``rho`` is added when positive, and ``tau >= 1/log10(MN)``;
* bulk-ESS: the ESS of ``z``; tail-ESS: the smaller ESS of the indicators ``x <= q_0.05`` and ``x <= q_0.95``.

The autocovariances are direct sums, lag by lag, only as far as Geyer's sequence reads them (numpy's sums, in their
fixed pairwise order; no FFT), so the numbers are the same bits on every machine (``docs/architecture.md``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.special import ndtri

__all__ = [
    "ESS_MIN", "RHAT_DISAGREE", "RHAT_MAX", "THRESHOLDS_SOURCE", "advice", "diagnostics", "ess", "rank_normal",
    "split_rhat",
]  # fmt: skip

#: R-hat below which chains are taken as mixed, and the bulk and tail ESS needed [-]: Vehtari et al. 2021's
#: recommendations (R-hat below 1.01; ESS above 400, about 100 a chain with four, for R-hat and ESS to be reliable)
RHAT_MAX = 1.01
ESS_MIN = 400.0
#: their source, in words
THRESHOLDS_SOURCE = (
    "Vehtari, Gelman, Simpson, Carpenter and Buerkner 2021, Bayesian Analysis 16(2):667-718, their "
    "recommendations: rank-normalised split-R-hat below 1.01, bulk and tail ESS at least 400"
)
#: R-hat from which the advice says the chains disagree (several modes, a valley), not only that they are short [-]:
#: the old threshold of Gelman and Rubin 1992 / Gelman et al. 2013 (BDA3, 11.4), here as a convention for the words
RHAT_DISAGREE = 1.1


def _split(chains: np.ndarray) -> np.ndarray:
    """Each chain's halves as chains of their own: (2M, N // 2); the middle draw of an odd N dropped."""
    half = chains.shape[1] // 2
    return np.concatenate([chains[:, :half], chains[:, chains.shape[1] - half :]])


def rank_normal(x: np.ndarray) -> np.ndarray:
    """Blom's normal scores of the ranks of all of ``x`` (ties: average ranks), in ``x``'s shape [-]."""
    flat = np.asarray(x, dtype=float).ravel()
    order = np.argsort(flat, kind="stable")
    s = flat[order]
    new = np.r_[True, s[1:] != s[:-1]]
    starts = np.flatnonzero(new)
    ends = np.r_[starts[1:], len(s)]
    average = (starts + ends - 1) / 2.0 + 1.0  # the average of the 1-based ranks of each run of equal values
    ranks = np.empty(len(flat))
    ranks[order] = average[np.cumsum(new) - 1]
    return ndtri((ranks - 0.375) / (len(flat) + 0.25)).reshape(np.shape(x))


def _moments(x: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Each chain's mean, W and var+ of chains ``x`` (M, N)."""
    m, n = x.shape
    means = x.mean(axis=1)
    w = float(((x - means[:, None]) ** 2).sum(axis=1).mean() / (n - 1))
    b_over_n = float(((means - means.mean()) ** 2).sum() / (m - 1)) if m > 1 else 0.0
    return means, w, (n - 1) / n * w + b_over_n


def _rhat(x: np.ndarray) -> float:
    m, n = x.shape
    if n < 2 or m < 2:
        return math.nan
    _, w, var_plus = _moments(x)
    return math.sqrt(var_plus / w) if w > 0.0 and math.isfinite(w) else math.nan


def split_rhat(chains: np.ndarray) -> float:
    """The split-R-hat of ``chains`` (M, N) as they are, not rank-normalised [-]; NaN for fewer than 4 draws a chain
    or chains that never move."""
    return _rhat(_split(np.asarray(chains, dtype=float)))


def _ess(x: np.ndarray) -> float:
    """The ESS of chains ``x`` (M, N) as they are (already split), Geyer's initial monotone sequence with Stan's
    refinements, in the index arithmetic of Stan and ArviZ (``_ess`` of ``arviz.stats.diagnostics``)."""
    m, n = x.shape
    if n < 4:
        return math.nan
    means, w, var_plus = _moments(x)
    if not (w > 0.0 and math.isfinite(w)):
        return math.nan
    c = x - means[:, None]

    def rho_at(t: int) -> float:  # 1 - (W - mean_m acov_m(t)) / var+, acov_m(t) summed directly over the lag
        return 1.0 - (w - float((c[:, : n - t] * c[:, t:]).sum(axis=1).mean() / n)) / var_plus

    rho = [0.0] * n
    rho[0] = even = 1.0
    rho[1] = odd = rho_at(1)
    t = 1
    while t < n - 3 and even + odd > 0.0:  # Geyer's initial positive sequence, a pair of lags at a time
        even, odd = rho_at(t + 1), rho_at(t + 2)
        if even + odd >= 0.0:
            rho[t + 1], rho[t + 2] = even, odd
        t += 2
    last = t - 2  # the last lag of the positive pairs
    if even > 0.0:  # Stan's refinement: the next even lag, counted once
        rho[last + 1] = even
    t = 1
    while t <= last - 2:  # Geyer's initial monotone sequence: no pair above the one before it
        if rho[t + 1] + rho[t + 2] > rho[t - 1] + rho[t]:
            rho[t + 1] = rho[t + 2] = (rho[t - 1] + rho[t]) / 2.0
        t += 2
    tau = -1.0 + 2.0 * math.fsum(rho[: last + 1]) + math.fsum(rho[last + 1 : last + 2])
    return m * n / max(tau, 1.0 / math.log10(m * n))  # Stan's floor on tau: ESS at most S log10 S


def ess(chains: np.ndarray) -> float:
    """The effective sample size of ``chains`` (M, N) after splitting them, not rank-normalised (module docstring)
    [-]; NaN for fewer than 8 draws a chain or chains that never move."""
    return _ess(_split(np.asarray(chains, dtype=float)))


def diagnostics(chains: np.ndarray) -> dict[str, float]:
    """``rhat`` (the larger of the bulk and folded rank-normalised split-R-hat), ``ess_bulk`` and ``ess_tail`` of
    one quantity's ``chains`` (M, N) [-], as Vehtari et al. 2021 define them (ranks among the split chains' draws,
    tail quantiles among all draws, as ArviZ)."""
    x = np.asarray(chains, dtype=float)
    if x.ndim != 2 or x.shape[1] < 4 or not np.all(np.isfinite(x)):
        return {"rhat": math.nan, "ess_bulk": math.nan, "ess_tail": math.nan}
    s = _split(x)
    z = rank_normal(s)
    rhat = max(_rhat(z), _rhat(rank_normal(np.abs(s - np.median(s)))))
    tails = [_ess(_split((x <= np.quantile(x, p)).astype(float))) for p in (0.05, 0.95)]
    tail = min(tails) if all(math.isfinite(e) for e in tails) else math.nan
    return {"rhat": rhat, "ess_bulk": _ess(z), "ess_tail": tail}


def _short(e: Mapping[str, Any]) -> bool:
    values = (e["rhat"], e["ess_bulk"], e["ess_tail"])
    return not all(math.isfinite(v) for v in values) or e["rhat"] >= RHAT_MAX or min(values[1:]) < ESS_MIN


def advice(per_quantity: Mapping[str, Mapping[str, Any]], draws: int, chains: int) -> str | None:
    """What to change when a quantity's R-hat or ESS misses its threshold, in words; None when none does.

    ``draws`` kept in all (``posterior_draws``). The draws suggested: ``draws x 400 / the smallest ESS`` (an ESS
    grows in proportion to the draws once the chains mix), at least twice ``draws`` when R-hat misses, rounded up to
    a thousand."""
    short = {q: e for q, e in per_quantity.items() if _short(e)}
    if not short:
        return None
    undefined = [q for q, e in short.items() if not all(math.isfinite(e[k]) for k in ("rhat", "ess_bulk", "ess_tail"))]
    if undefined:
        return (f"unconverged: R-hat and ESS are undefined for {', '.join(undefined)} (a chain that never moved: no "
                "proposal accepted; or fewer than 8 draws a chain): check that the likelihood is finite at the fit (a "
                "size without groups) and that the bounds leave the posterior room, or raise posterior_draws "
                f"(params.yaml calibrate.posterior_draws) from {draws} to at least {8 * chains}")  # fmt: skip
    q_ess = min(short, key=lambda q: min(short[q]["ess_bulk"], short[q]["ess_tail"]))
    low = min(short[q_ess]["ess_bulk"], short[q_ess]["ess_tail"])
    q_rhat = max(short, key=lambda q: short[q]["rhat"])
    worst = short[q_rhat]["rhat"]
    factor = max(ESS_MIN / low, 2.0 if worst >= RHAT_MAX else 1.0)
    target = int(math.ceil(draws * factor / 1000.0) * 1000)
    said = (f"unconverged (thresholds: R-hat < {RHAT_MAX}, bulk and tail ESS >= {ESS_MIN:.0f}; Vehtari et al. "
            f"2021): {', '.join(short)} short; the smallest ESS {low:.0f} ({q_ess}), the largest R-hat {worst:.3f} "
            f"({q_rhat})")  # fmt: skip
    if worst >= RHAT_DISAGREE:
        said += (f"; the {chains} chains disagree on {q_rhat}: the posterior may have several modes or a long valley "
                 "the sampler crosses slowly, so compare the chains (posterior.csv's column chain) and read the "
                 "trade-offs and the valley before trusting it")  # fmt: skip
    return f"{said}; raise posterior_draws (params.yaml calibrate.posterior_draws) from {draws} to {target}"
