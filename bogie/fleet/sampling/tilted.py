"""A fleet distribution moved to a given mean: the exponential tilt (``docs/calibration.md``, issue 30 Must 3).

The calibration fits the distributions of two inhibitors no source measures on a fleet, the contact-roll radius and
the equaliser bush's stiffness, without a new simulation: each calibration bogie keeps its sampled value, and a
fleet whose distribution has another mean is the same bogies **reweighted** (importance weights), or, simulated
directly, each bogie's value moved to the same rank under the new distribution (a quantile map).

The family. The fleet's distribution is uniform in ``y`` on ``[a, b]`` (``y = x`` for a uniform, ``y = ln x`` for a
log-uniform). Of all the densities on that support with a given mean of ``y``, the one of most entropy (the least
committal: Jaynes 1957) is the exponential tilt ``p(y) = t e^(t u) / (L (e^t - 1))``, ``u = (y - a) / L``,
``L = b - a``: one parameter ``t``, ``t = 0`` the fleet's own. Its mean is ``a + L g(t)``,
``g(t) = 1 / (1 - e^-t) - 1 / t`` (``g(0) = 1/2``), increasing from 0 to 1; its CDF ``expm1(t u) / expm1(t)``. So
the fitted quantity is the mean of ``y``: the mean radius [mm], the geometric mean stiffness [N m/rad]. The shape is
an assumption (one parameter, the least the data must identify); a two-parameter family would need data that tell a
distribution's spread from its mean, which the load shares do not (the calibration's own limits).

The weights ``p / q = t e^(t u) / expm1(t)`` are smooth in ``t`` (the distance stays smooth) but concentrate on
the bogies at one end as ``|t|`` grows: :func:`effective_fraction` is the share of the bogies that still count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from bogie import numerics
from bogie.fleet.sampling.distributions import Distribution, LogUniform, Uniform

__all__ = ["MAX_TILT", "Tilted", "effective_fraction"]

#: the largest |t| solved for [-]: a mean within 1/500 of the support's width from an end (weights e^500 apart)
MAX_TILT = 500.0


def _g(t: float) -> float:
    """The tilted uniform's mean on [0, 1]."""
    if abs(t) < 1e-6:
        return 0.5 + t / 12.0
    return -1.0 / math.expm1(-t) - 1.0 / t


@dataclass(frozen=True)
class Tilted:
    """The exponential tilts of a fleet distribution that is uniform (``log=False``) or log-uniform (``log=True``) in
    the quantity's unit, ``low`` and ``high`` its support.

    Build it with :meth:`of`; ``scale`` multiplies the quantity's values (SI) into the unit of the fitted mean
    (``1000`` for a radius in m fitted in mm)."""

    low: float
    high: float
    log: bool
    scale: float = 1.0

    @classmethod
    def of(cls, dist: Distribution, scale: float = 1.0) -> Tilted:
        """The family of ``dist``: a :class:`~bogie.fleet.sampling.distributions.Uniform` or a
        :class:`~bogie.fleet.sampling.distributions.LogUniform` (another kind has no such family here: ValueError)."""
        if type(dist) is Uniform:
            return cls(float(dist.low), float(dist.high), False, scale)
        if type(dist) is LogUniform:
            return cls(float(dist.low), float(dist.high), True, scale)
        raise ValueError(f"{dist!r}: only a uniform or a log-uniform fleet distribution can be moved to a new mean")

    def _y(self, x: np.ndarray | float) -> np.ndarray:
        x = np.asarray(x, dtype=float) * self.scale
        return numerics.log(x) if self.log else x

    @property
    def ends(self) -> tuple[float, float]:
        """The support in ``y`` (the quantity, or its log, in the fitted unit)."""
        a, b = self.low * self.scale, self.high * self.scale
        return (math.log(a), math.log(b)) if self.log else (a, b)

    @property
    def fleet_mean(self) -> float:
        """The fitted quantity of the fleet's own distribution (``t = 0``): its mean, or its geometric mean."""
        a, b = self.ends
        m = 0.5 * (a + b)
        return math.exp(m) if self.log else m

    def mean_range(self) -> tuple[float, float]:
        """The means a tilt reaches, in the fitted unit (open at both ends): the support."""
        a, b = self.ends
        return (math.exp(a), math.exp(b)) if self.log else (a, b)

    def tilt(self, mean: float) -> float:
        """The ``t`` whose distribution has the mean (geometric mean, for a log-uniform) ``mean`` [fitted unit].

        Raises
        ------
        ValueError
            If ``mean`` is not strictly inside the support (no distribution on it has that mean).
        """
        a, b = self.ends
        lo, hi = self.mean_range()
        if not (math.isfinite(mean) and lo < mean < hi):
            raise ValueError(f"mean {mean!r}: must lie strictly within the distribution's support ({lo:g}, {hi:g})")
        y = math.log(mean) if self.log else mean
        frac = (y - a) / (b - a)
        if abs(frac - 0.5) < 1e-12:
            return 0.0
        target = min(max(frac, _g(-MAX_TILT)), _g(MAX_TILT))
        return float(brentq(lambda t: _g(t) - target, -MAX_TILT, MAX_TILT, xtol=1e-12, rtol=1e-12))

    def _u(self, x: np.ndarray) -> np.ndarray:
        a, b = self.ends
        return np.clip((self._y(x) - a) / (b - a), 0.0, 1.0)

    def weights(self, x: np.ndarray, t: float) -> np.ndarray:
        """Each value's density ratio p_t / p_0, up to one factor common to all (normalise them where used):
        ``e^(t (u - 1))`` for ``t > 0``, ``e^(t u)`` otherwise, so that none overflows."""
        if t == 0.0:
            return np.ones(np.shape(x))
        u = self._u(x)
        return numerics.exp(t * (u - 1.0)) if t > 0.0 else numerics.exp(t * u)

    def moved(self, x: np.ndarray, t: float) -> np.ndarray:
        """Each value moved to its rank under the fleet's distribution, under the tilt ``t``: the direct simulation's
        values, in the unit of ``x`` (SI)."""
        if t == 0.0:
            return np.asarray(x, dtype=float)
        p = self._u(x)
        if t < 0.0:
            u = numerics.log1p(p * math.expm1(t)) / t
        else:
            u = 1.0 - numerics.log1p((1.0 - p) * math.expm1(-t)) / (-t)
        a, b = self.ends
        y = a + np.clip(u, 0.0, 1.0) * (b - a)
        return (numerics.exp(y) if self.log else y) / self.scale


def effective_fraction(weights: np.ndarray) -> float:
    """Kish's effective sample size over the sample's size, ``(sum w)^2 / (n sum w^2)`` [-]: 1 for equal weights."""
    w = np.asarray(weights, dtype=float)
    if not len(w) or not np.any(w > 0.0):
        return 0.0
    return float(w.sum() ** 2 / (len(w) * np.square(w).sum()))
