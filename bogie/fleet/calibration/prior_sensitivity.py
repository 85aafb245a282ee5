"""Does the calibrated fleet depend on the tilt prior? (issue 43 Must 6; ``docs/calibration.md``, "Prior sensitivity").

The chassis tilt's priors are the least sourced of the calibration's (an assumption from a trade table of fifth-wheel
heights, :mod:`bogie.fleet.calibration.priors`). The posterior is drawn again with their sd halved and doubled, on
the same synthetic likelihood (the same table, survey and covariances: only the prior changes), the same seed, draws
and chains; each fitted quantity's median is compared with the posterior's own, in units of the posterior's own
credible interval's width. A median that moves by more than :data:`DEPENDS` of it depends on the prior.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from bogie.fleet.calibration.posterior import Posterior, posterior
from bogie.fleet.calibration.priors import Prior
from bogie.fleet.calibration.problem import Problem
from bogie.fleet.constants import CALIBRATION_QUANTITIES

__all__ = ["DEPENDS", "PRIOR_SCALES", "TILT_PRIORS", "prior_sensitivity", "scaled_priors"]

#: the factors the tilt priors' sd (the normal's sd, the half-normal's scale) is scaled by [-]: the issue's
PRIOR_SCALES: dict[str, float] = {"halved": 0.5, "doubled": 2.0}
#: the priors scaled: the tilt's centre and spread, one argument makes both (bogie.fleet.calibration.priors)
TILT_PRIORS: tuple[str, ...] = ("chassis_tilt_mean_deg", "chassis_tilt_sd_deg")
#: a median that moves by more than this share of the posterior's credible interval's width depends on the prior
#: [-]: a convention (a quarter of the interval: a move a reader of the interval would notice)
DEPENDS = 0.25


def scaled_priors(priors: Mapping[str, Prior], factor: float) -> dict[str, Prior]:
    """``priors`` with each normal prior of :data:`TILT_PRIORS` of sd times ``factor`` (the others as they are)."""
    out = dict(priors)
    for q in TILT_PRIORS:
        p = priors.get(q)
        if p is not None and p.kind == "normal":
            out[q] = dataclasses.replace(p, b=p.b * factor, source=f"{p.source} (its sd times {factor:g}: the "
                                         "prior-sensitivity check)")  # fmt: skip
    return out


def prior_sensitivity(
    problem: Problem, priors: Mapping[str, Prior], post: Posterior, best: np.ndarray, draws: int, seed: int,
    confidence_level: float, chains: int, executor: Any = None,
) -> dict[str, Any] | None:  # fmt: skip
    """The posterior ``post`` of ``problem`` drawn again with the tilt's priors scaled by each of
    :data:`PRIOR_SCALES` (:func:`scaled_priors`; the same likelihood, seed, ``draws`` and ``chains``, the chains on
    ``executor``): per scale each
    fitted quantity's median and interval and whether it converged; per quantity the largest move of its median in
    units of ``post``'s interval width (``moves``); the quantities that move by more than :data:`DEPENDS`
    (``depends_on_prior``), whether any does (``depends``) and a sentence that says so. None when neither tilt prior
    is a normal one of a fitted quantity."""
    scaled = [q for q in TILT_PRIORS if q in problem.fitted and q in priors and priors[q].kind == "normal"]
    if not scaled or post.likelihood is None:
        return None
    fits, moves = {}, dict.fromkeys(problem.fitted, 0.0)
    for name, factor in PRIOR_SCALES.items():
        again = posterior(problem, scaled_priors(priors, factor), best, draws, seed, confidence_level, chains,
                          executor=executor, likelihood=post.likelihood)  # fmt: skip
        fits[name] = {
            "tilt_prior_sd_deg": {q: priors[q].b * factor for q in scaled},
            "converged": again.converged,
            "quantities": {q: {k: again.summary[q][k] for k in ("median", "low", "high")} for q in problem.fitted},
        }  # fmt: skip
        for q in problem.fitted:
            width = post.summary[q]["high"] - post.summary[q]["low"]
            move = abs(again.summary[q]["median"] - post.summary[q]["median"])
            moves[q] = max(moves[q], move / width if width > 0.0 else (0.0 if move == 0.0 else np.inf))
    depends = [q for q in problem.fitted if moves[q] > DEPENDS]
    return {
        "priors_scaled": scaled, "scales": dict(PRIOR_SCALES), "threshold": DEPENDS, "fits": fits,
        "moves": moves, "depends": bool(depends), "depends_on_prior": depends,
        "sentence": _sentence(post, fits, moves, depends),
    }  # fmt: skip


def _sentence(post: Posterior, fits: Mapping[str, Any], moves: Mapping[str, float], depends: list[str]) -> str:
    """Whether the answer depends on the tilt prior, in words."""
    head = "With the chassis tilt's prior sd halved and doubled"
    if not depends:
        worst = max(moves, key=lambda q: moves[q])
        return (f"{head}, no fitted median moves by more than {DEPENDS:g} of its credible interval's width (the most, "
                f"{worst}, by {moves[worst]:.2f}): the answer does not depend on the tilt prior.")  # fmt: skip
    parts = []
    for q in depends:
        unit = CALIBRATION_QUANTITIES[q][2]
        runs = " and ".join(f"{fits[k]['quantities'][q]['median']:.3g}" for k in ("halved", "doubled"))
        parts.append(f"{q} moves from {post.summary[q]['median']:.3g} to {runs} {unit} ({moves[q]:.2f} of its "
                     "interval)")  # fmt: skip
    return (f"{head}, {'; '.join(parts)}: the answer depends on the tilt prior; the survey does not pin it, the prior "
            "does, so read it with the prior's source (docs/calibration.md).")  # fmt: skip
