"""How a calibration fits (``docs/calibration.md``), in a module of their own so that what only reads settings
(params.yaml's loader) does not import the calibration: the settings class, the check of its bounds and its error.
:mod:`bogie.fleet.calibration.problem` re-exports them."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from bogie.fleet.constants import CALIBRATION_QUANTITIES
from bogie.settings import check_settings, setting

__all__ = ["ORDER", "CalibrationError", "CalibrationSettings", "check_fit"]


class CalibrationError(ValueError):
    """An input that calibration cannot use (named, with what was expected)."""


#: the fitted quantities in the order of the optimiser's vector
ORDER: tuple[str, ...] = tuple(CALIBRATION_QUANTITIES)


def check_fit(fit: Mapping[str, Sequence[float]]) -> None:
    """Refuse bounds that are not ``{quantity: (low, high)}`` within the quantity's range, naming them and the unit.

    Raises
    ------
    CalibrationError
        If ``fit`` is empty, names a quantity not in :data:`~bogie.fleet.constants.CALIBRATION_QUANTITIES`, or has
        bounds that are not two finite numbers ``low < high`` within the quantity's range.
    """
    if not fit:
        raise CalibrationError(f"fit = {dict(fit)!r}: name at least one quantity to fit: {', '.join(ORDER)}")
    for name, bounds in fit.items():
        if name not in CALIBRATION_QUANTITIES:
            allowed = ", ".join(ORDER)
            raise CalibrationError(f"fit[{name!r}]: not a fleet quantity calibration can fit; allowed: {allowed}")
        low, high, unit = CALIBRATION_QUANTITIES[name]
        numbers = len(bounds) == 2 and all(
            not isinstance(b, bool) and isinstance(b, (int, float)) and math.isfinite(b) for b in bounds
        )
        if not numbers or not bounds[0] < bounds[1] or bounds[0] < low or bounds[1] > high:
            expected = f"must be (low, high), low < high, within [{low:g}, {high:g}] {unit}"
            raise CalibrationError(f"fit[{name!r}] = {tuple(bounds)!r}: {expected}")


@dataclass(frozen=True)
class CalibrationSettings:
    """How a calibration fits: the quantities and their bounds, the optimiser's settings, the bootstrap, the
    posterior; each number setting's unit, range and doc declared with it (:mod:`bogie.settings`).

    ``fit`` maps a quantity to (low, high), the bounds of each fitted quantity in the unit of its name
    (:data:`~bogie.fleet.constants.CALIBRATION_QUANTITIES`). ``priors`` maps a quantity to a
    :class:`bogie.fleet.calibration.priors.Prior`; None: :func:`bogie.fleet.calibration.priors.default_priors` (each
    documented with its source); a quantity left out is flat over its bounds.
    """

    fit: Mapping[str, tuple[float, float]]
    seed: int = setting(
        unit="-", low=0, whole=True,
        doc="Seed of the differential evolution (the fit's; resample b of the bootstrap is fitted with seed + 1 + b) "
        "and of the bootstrap's resampling.",
    )  # fmt: skip
    bootstrap_resamples: int = setting(
        50, unit="-", low=0, whole=True, doc="Bootstrap resamples of the fitted values' intervals (0: none)."
    )
    confidence_level: float = setting(
        0.9, unit="-", low=0.0, high=1.0, low_open=True, high_open=True, doc="Of the fitted values' intervals."
    )
    maxiter: int = setting(40, unit="-", low=1, whole=True, doc="Generations of scipy's differential evolution.")
    popsize: int = setting(
        8, unit="-", low=2, whole=True, doc="Population of the differential evolution, per fitted quantity."
    )
    posterior_draws: int = setting(
        160_000, unit="-", low=0, whole=True,
        doc="Metropolis draws of the posterior kept, in all chains together (each chain keeps an equal share, rounded "
        "up), a quarter more in each chain adapting its sampler first (0: no posterior; "
        "bogie.fleet.calibration.posterior).",
    )  # fmt: skip
    chains: int = setting(
        4, unit="-", low=1, whole=True,
        doc="Chains of the posterior's sampler, the first from the fit, the others from points drawn within the "
        "bounds; their R-hat and effective sample sizes say whether it converged "
        "(bogie.fleet.calibration.convergence).",
    )  # fmt: skip
    sites: int = setting(
        16, unit="-", low=0, whole=True,
        doc="Other WIM sites the calibration bogies are weighed on, at the fit, for the summaries' covariance between "
        "sites in the posterior's likelihood (a WIM table on a shared site; 0 or 1: none; "
        "bogie.fleet.calibration.posterior.site_covariance).",
    )  # fmt: skip
    table_sites: int = setting(
        1, unit="-", low=1, whole=True,
        doc="WIM sites the calibration bogies are spread over in the table (bogie i on site i mod table_sites), so "
        "that the table stands for the population of sites and not one: the between-site covariance then enters "
        "the likelihood 1 + 1/table_sites times (a WIM table on a shared site; 1: every bogie on one site; "
        "docs/calibration.md, 'The site').",
    )  # fmt: skip
    priors: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        check_fit(self.fit)
        object.__setattr__(self, "fit", {q: (float(b[0]), float(b[1])) for q, b in self.fit.items()})
        check_settings(self, CalibrationError)
