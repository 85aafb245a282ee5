"""Probability distributions of the sampled bogie parameters, each with a vectorised inverse CDF.

Every distribution maps a uniform design point ``u`` in [0, 1) to a value through its inverse cumulative
distribution function :meth:`ppf`, so one Latin hypercube, Sobol' or Saltelli design of the unit hypercube can be
turned into any mix of marginals, and the fleet and the sensitivity design share exactly the same distributions.

The parameters of a distribution carry the unit of the quantity it describes; :meth:`scaled` converts them (for
example millimetres to metres) so the samples come out in SI. Invalid parameters raise :class:`ParameterError`,
which names the parameter so that :mod:`pipeline.config` can report the full key path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import MISSING, dataclass, fields, replace
from typing import Any, ClassVar

import numpy as np
from scipy.special import ndtr, ndtri

from bogie import numerics

#: an unbounded inverse CDF is infinite at u = 0; a design point there is read as this tail probability instead
#: (about 8.2 standard deviations), which no finite design of fewer than 2^53 points can resolve anyway
_U_TINY = 2.0**-53


class ParameterError(ValueError):
    """A distribution parameter with an invalid value.

    Parameters
    ----------
    param
        Name of the parameter as written in params.yaml (``low``, ``sd``, ``values[2]``...).
    value
        The offending value.
    expected
        What the value should be, in words.
    """

    def __init__(self, param: str, value: Any, expected: str) -> None:
        self.param = param
        self.value = value
        self.expected = expected
        super().__init__(f"{param} = {value!r}: {expected}")


def _finite(name: str, value: float) -> float:
    if not math.isfinite(value):
        raise ParameterError(name, value, "must be a finite number")
    return value


def _ordered(low: float, high: float) -> None:
    _finite("low", low)
    _finite("high", high)
    if not low < high:
        raise ParameterError("high", high, f"must be greater than low = {low!r}")


def truncated_standard_normal_ppf(u: Any, a: float, b: float) -> np.ndarray:
    """Inverse CDF of the standard normal truncated to [a, b] (a < b, either may be infinite) at ``u`` in [0, 1].

    x = Phi^-1(Phi(a) + u (Phi(b) - Phi(a))), with the interval reflected to the left of 0 where it lies right of it
    (Phi near 1 would lose digits there). scipy.special's ``ndtr`` and ``ndtri`` are scalar C functions;
    ``scipy.stats.truncnorm.ppf`` works in logarithms with numpy's ``log`` and ``log1p``, whose last bits depend on
    the loops numpy dispatches to on the CPU (``bogie/numerics.py``), so the samples did too. The two agree to 2e-14
    standard deviations for the bounds params.yaml can give (``tests/pipeline/test_portable.py``).
    """
    u = np.asarray(u, dtype=float)
    if a > 0.0:
        return -truncated_standard_normal_ppf(1.0 - u, -b, -a)
    low, high = ndtr(a), ndtr(b)
    return np.clip(ndtri(low + u * (high - low)), a, b)


def truncated_standard_normal_cdf(z: Any, a: float, b: float) -> np.ndarray:
    """The CDF at ``z`` of the standard normal truncated to [a, b] [-]: 0 below a, 1 above b.

    ``scipy.stats.truncnorm.cdf`` computes it through numpy's ``exp`` and ``log`` (SIMD loops the CPU picks); this is
    ``(Phi(z) - Phi(a)) / (Phi(b) - Phi(a))`` with scipy.special's scalar ``ndtr``, from the upper tail
    (``Phi(-a) - Phi(-z)`` over ``Phi(-a) - Phi(-b)``) when the interval is above 0, where Phi near 1 would lose
    digits."""
    z = np.asarray(z, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        if a > 0.0:
            top = ndtr(-a)
            out = (top - ndtr(-z)) / (top - ndtr(-b))
        else:
            low = ndtr(a)
            out = (ndtr(z) - low) / (ndtr(b) - low)
    out = np.clip(out, 0.0, 1.0)
    out = np.where(z <= a, 0.0, np.where(z >= b, 1.0, out))
    return np.where(np.isnan(z), np.nan, out)


def _unit_points(u: Any) -> np.ndarray:
    """``u`` as a float array, checked to lie in the unit interval."""
    u = np.asarray(u, dtype=float)
    if u.size and (np.nanmin(u) < 0.0 or np.nanmax(u) > 1.0 or np.isnan(u).any()):
        raise ValueError("design points u must lie in [0, 1]")
    return u


@dataclass(frozen=True)
class Distribution:
    """Base of the distributions: a name (``kind``), a support and a vectorised inverse CDF."""

    kind: ClassVar[str] = ""
    #: the parameters without unit whatever the quantity's (a log-normal's ``sigma``, a choice's ``weights``); the
    #: others are in the quantity's unit
    dimensionless: ClassVar[tuple[str, ...]] = ()
    #: the parameters that must be > 0, and those that must be >= 0, as data for params.yaml's form (the class's
    #: ``__post_init__`` refuses them otherwise; tests/test_fleet_distributions.py holds the two together)
    positive: ClassVar[tuple[str, ...]] = ()
    nonnegative: ClassVar[tuple[str, ...]] = ()

    def ppf(self, u: Any) -> np.ndarray:
        """Inverse cumulative distribution function at design points ``u`` in [0, 1) [unit of the quantity]."""
        raise NotImplementedError

    @property
    def support(self) -> tuple[float, float]:
        """Smallest and largest value a sample can take [unit of the quantity]."""
        raise NotImplementedError

    def quantile(self, q: float) -> Any:
        """The value below which a fraction ``q`` of the samples lie (``quantile(0.5)``: the median) [unit]."""
        value = self.ppf(np.array([q]))[0]
        return value.item() if isinstance(value, np.generic) else value

    def scaled(self, convert: Callable[[float], float]) -> Distribution:
        """The same distribution after a change of unit ``x -> convert(x)``, a linear map ``x -> c x`` with c > 0."""
        raise NotImplementedError

    @classmethod
    def parameter_names(cls) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Names of the required and of the optional parameters of this kind."""
        required = tuple(f.name for f in fields(cls) if f.default is MISSING and f.default_factory is MISSING)
        optional = tuple(f.name for f in fields(cls) if f.name not in required)
        return required, optional


@dataclass(frozen=True)
class Constant(Distribution):
    """A fixed value (a number, or a label for a categorical quantity)."""

    value: float | str
    kind: ClassVar[str] = "constant"

    def __post_init__(self) -> None:
        if not isinstance(self.value, str):
            _finite("value", float(self.value))

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        return np.full(u.shape, self.value, dtype=object if isinstance(self.value, str) else float)

    @property
    def support(self) -> tuple[float, float]:
        return (self.value, self.value)  # type: ignore[return-value]

    def scaled(self, convert: Callable[[float], float]) -> Constant:
        return replace(self, value=convert(self.value))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Uniform(Distribution):
    """Uniform on [low, high]."""

    low: float
    high: float
    kind: ClassVar[str] = "uniform"

    def __post_init__(self) -> None:
        _ordered(self.low, self.high)

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        return np.clip(self.low + u * (self.high - self.low), self.low, self.high)

    @property
    def support(self) -> tuple[float, float]:
        return (self.low, self.high)

    def scaled(self, convert: Callable[[float], float]) -> Uniform:
        return replace(self, low=convert(self.low), high=convert(self.high))


@dataclass(frozen=True)
class LogUniform(Distribution):
    """Uniform in log(x) on [low, high], low > 0: every decade equally likely."""

    low: float
    high: float
    kind: ClassVar[str] = "loguniform"
    positive: ClassVar[tuple[str, ...]] = ("low",)

    def __post_init__(self) -> None:
        if not self.low > 0.0:
            raise ParameterError("low", self.low, "must be > 0 for a log-uniform distribution")
        _ordered(self.low, self.high)

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        x = self.low * numerics.exp(u * math.log(self.high / self.low))
        return np.clip(x, self.low, self.high)

    @property
    def support(self) -> tuple[float, float]:
        return (self.low, self.high)

    def scaled(self, convert: Callable[[float], float]) -> LogUniform:
        return replace(self, low=convert(self.low), high=convert(self.high))


@dataclass(frozen=True)
class Normal(Distribution):
    """Normal with ``mean`` and standard deviation ``sd`` > 0; unbounded."""

    mean: float
    sd: float
    kind: ClassVar[str] = "normal"
    positive: ClassVar[tuple[str, ...]] = ("sd",)

    def __post_init__(self) -> None:
        _finite("mean", self.mean)
        if not (math.isfinite(self.sd) and self.sd > 0.0):
            raise ParameterError("sd", self.sd, "must be a finite number > 0")

    def ppf(self, u: Any) -> np.ndarray:
        u = np.clip(_unit_points(u), _U_TINY, 1.0 - _U_TINY)
        return self.mean + self.sd * ndtri(u)

    @property
    def support(self) -> tuple[float, float]:
        return (-math.inf, math.inf)

    def scaled(self, convert: Callable[[float], float]) -> Normal:
        return replace(self, mean=convert(self.mean), sd=convert(self.sd))


@dataclass(frozen=True)
class TruncNormal(Distribution):
    """Normal with ``mean`` and ``sd`` > 0 conditioned on [low, high] (mean and sd of the parent normal)."""

    mean: float
    sd: float
    low: float
    high: float
    kind: ClassVar[str] = "truncnormal"
    positive: ClassVar[tuple[str, ...]] = ("sd",)

    def __post_init__(self) -> None:
        Normal(self.mean, self.sd)
        _ordered(self.low, self.high)

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        a, b = (self.low - self.mean) / self.sd, (self.high - self.mean) / self.sd
        x = self.mean + self.sd * truncated_standard_normal_ppf(u, a, b)
        # the standardised bounds round-trip to low/high only to an ulp; a physical limit must hold exactly
        return np.clip(x, self.low, self.high)

    @property
    def support(self) -> tuple[float, float]:
        return (self.low, self.high)

    def scaled(self, convert: Callable[[float], float]) -> TruncNormal:
        return replace(
            self, mean=convert(self.mean), sd=convert(self.sd), low=convert(self.low), high=convert(self.high)
        )


@dataclass(frozen=True)
class LogNormal(Distribution):
    """Log-normal: log(x) is normal with mean log(``median``) and standard deviation ``sigma`` > 0.

    Optionally truncated to [``low``, ``high``] (0 <= low < high <= inf), which keeps the support of a heavy-tailed
    quantity inside a physical limit.
    """

    median: float
    sigma: float
    low: float = 0.0
    high: float = math.inf
    kind: ClassVar[str] = "lognormal"
    dimensionless: ClassVar[tuple[str, ...]] = ("sigma",)
    positive: ClassVar[tuple[str, ...]] = ("median", "sigma")
    nonnegative: ClassVar[tuple[str, ...]] = ("low",)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.median) and self.median > 0.0):
            raise ParameterError("median", self.median, "must be a finite number > 0")
        if not (math.isfinite(self.sigma) and self.sigma > 0.0):
            raise ParameterError("sigma", self.sigma, "must be a finite number > 0")
        if not (math.isfinite(self.low) and self.low >= 0.0):
            raise ParameterError("low", self.low, "must be a finite number >= 0")
        if not self.high > self.low:
            raise ParameterError("high", self.high, f"must be greater than low = {self.low!r}")

    @property
    def _truncated(self) -> bool:
        return self.low > 0.0 or math.isfinite(self.high)

    def _standard_bounds(self) -> tuple[float, float]:
        mu = math.log(self.median)
        a = (math.log(self.low) - mu) / self.sigma if self.low > 0.0 else -math.inf
        b = (math.log(self.high) - mu) / self.sigma if math.isfinite(self.high) else math.inf
        return a, b

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        if self._truncated:
            a, b = self._standard_bounds()
            z = truncated_standard_normal_ppf(np.clip(u, _U_TINY, 1.0 - _U_TINY), a, b)
        else:
            z = ndtri(np.clip(u, _U_TINY, 1.0 - _U_TINY))
        return np.clip(self.median * numerics.exp(self.sigma * z), self.low, self.high)

    @property
    def support(self) -> tuple[float, float]:
        return (self.low, self.high)

    def scaled(self, convert: Callable[[float], float]) -> LogNormal:
        high = convert(self.high) if math.isfinite(self.high) else math.inf
        return replace(self, median=convert(self.median), low=convert(self.low), high=high)


@dataclass(frozen=True)
class Choice(Distribution):
    """A discrete choice among ``values`` (numbers or labels) with relative ``weights`` (equal if omitted).

    The inverse CDF takes the first value whose cumulative weight exceeds u, so a stratified design gives each
    value its share of the points to within one point.
    """

    values: tuple[Any, ...]
    weights: tuple[float, ...] | None = None
    dimensionless: ClassVar[tuple[str, ...]] = ("weights",)
    kind: ClassVar[str] = "choice"

    def __post_init__(self) -> None:
        values = tuple(self.values)
        if not values:
            raise ParameterError("values", list(values), "must list at least one value")
        if len(set(values)) != len(values):
            raise ParameterError("values", list(values), "must not repeat a value")
        for i, v in enumerate(values):
            if not isinstance(v, str):
                _finite(f"values[{i}]", float(v))
        object.__setattr__(self, "values", values)
        if self.weights is not None:
            weights = tuple(float(w) for w in self.weights)
            if len(weights) != len(values):
                raise ParameterError("weights", list(weights), f"must give one weight per value ({len(values)} values)")
            for i, w in enumerate(weights):
                if not (math.isfinite(w) and w >= 0.0):
                    raise ParameterError(f"weights[{i}]", w, "must be a finite number >= 0")
            if sum(weights) <= 0.0:
                raise ParameterError("weights", list(weights), "must have a positive sum")
            object.__setattr__(self, "weights", weights)

    @property
    def probabilities(self) -> np.ndarray:
        """Probability of each value (the weights normalised to sum 1) [-]."""
        w = np.ones(len(self.values)) if self.weights is None else np.asarray(self.weights, dtype=float)
        return w / w.sum()

    def ppf(self, u: Any) -> np.ndarray:
        u = _unit_points(u)
        cumulative = np.cumsum(self.probabilities)
        cumulative[-1] = 1.0  # rounding must not leave a sliver of u above the last value
        index = np.minimum(np.searchsorted(cumulative, u, side="right"), len(self.values) - 1)
        labels = any(isinstance(v, str) for v in self.values)
        table = np.array(self.values, dtype=object if labels else float)
        return table[index]

    @property
    def support(self) -> tuple[float, float]:
        if any(isinstance(v, str) for v in self.values):
            raise TypeError("a choice among labels has no numeric support")
        return (min(self.values), max(self.values))

    def scaled(self, convert: Callable[[float], float]) -> Choice:
        return replace(self, values=tuple(convert(v) for v in self.values))


#: every supported kind by its name in params.yaml
KINDS: dict[str, type[Distribution]] = {
    cls.kind: cls for cls in (Constant, Uniform, LogUniform, Normal, TruncNormal, LogNormal, Choice)
}
