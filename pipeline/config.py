"""Loading and validating params.yaml.

:func:`load_params` returns the raw mapping (used by the ``figure2`` stage). :func:`load_config` parses the sections
of the Monte Carlo fleet pipeline into frozen dataclasses, validates every value and converts it to SI once: keys
ending in ``_mm``, ``_deg``, ``_t`` or ``_s`` / ``_m`` / ``_m_s`` give their unit in the name; everything in a
:class:`Config` is SI ([m], [rad], [N], [s], [kg]). A bad value raises :class:`ConfigError` (a ``ValueError``)
whose message names the key path, the value and the expected form, range and unit.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import yaml

from bogie.params import _AXLE_RANGES, _SCALAR_RANGES, GRAVITY, PRESETS, preset
from pipeline.constants import GROUP_AXLES
from pipeline.distributions import KINDS, Choice, Constant, Distribution, ParameterError

#: axle-count groups of the fleet and their number of axles

#: ISO 8608 road roughness classes, smoothest first
ROAD_CLASSES: tuple[str, ...] = ("A", "B", "C", "D", "E", "F", "G", "H")

PROTOCOLS: tuple[str, ...] = ("static", "wim")
SAMPLINGS: tuple[str, ...] = ("lhs", "sobol")
BACKENDS: tuple[str, ...] = ("loky", "dask")

#: top-level sections that other stages read themselves (load_config accepts them without looking inside)
OTHER_SECTIONS: tuple[str, ...] = ("figure2",)


def load_params(path: str | Path = "params.yaml") -> dict[str, Any]:
    """The parsed params.yaml as a dict (empty if the file is empty)."""
    with open(path, encoding="utf-8") as fh:
        data = yaml.safe_load(fh)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: the top level must be a mapping of keys to values, got {type(data).__name__}")
    return data


class ConfigError(ValueError):
    """A bad value in params.yaml; :attr:`key` is its dotted key path (``distributions.bush_stiffness.low``)."""

    def __init__(self, key: str, message: str) -> None:
        self.key = key
        super().__init__(message)


class FrozenMap(Mapping):
    """A read-only, hashable, picklable mapping (the dict-valued fields of the frozen config)."""

    def __init__(self, items: Mapping | Iterable[tuple[Any, Any]] = ()) -> None:
        self._data = dict(items)

    def __getitem__(self, key: Any) -> Any:
        return self._data[key]

    def __iter__(self) -> Iterator:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __hash__(self) -> int:
        return hash(tuple(self._data.items()))

    def __repr__(self) -> str:
        return f"FrozenMap({self._data!r})"


# ---- the sampled quantities --------------------------------------------------------------------------------------
def _identity(x: float) -> float:
    return x


def _mm_to_m(x: float) -> float:
    # a division keeps round millimetre values bit-equal to the metre limits (50 / 1000 == 0.05)
    return x / 1000.0


def _m_to_mm(x: float) -> float:
    return x * 1000.0


@dataclass(frozen=True)
class Quantity:
    """One sampled quantity: its params.yaml key and unit, its SI name (Bogie field, sample column) and range."""

    key: str
    name: str
    unit: str
    yaml_unit: str
    low: float
    high: float
    low_inclusive: bool
    to_si: Callable[[float], float] = _identity
    from_si: Callable[[float], float] = _identity
    labels: tuple[str, ...] = ()

    @property
    def range_text(self) -> str:
        """The allowed range in params.yaml units, e.g. ``[0, 50] mm``."""
        bracket = "[" if self.low_inclusive else "("
        return f"{bracket}{self.from_si(self.low):g}, {self.from_si(self.high):g}]{_unit_text(self.yaml_unit)}"


def _bogie_quantity(
    key: str,
    name: str,
    yaml_unit: str | None = None,
    to_si: Callable[[float], float] = _identity,
    from_si: Callable[[float], float] = _identity,
) -> Quantity:
    low, high, unit, low_inclusive = {**_SCALAR_RANGES, **_AXLE_RANGES}[name]
    return Quantity(key, name, unit, yaml_unit or unit, low, high, low_inclusive, to_si, from_si)


#: every entry of ``distributions:``, by params.yaml key; Bogie quantities take their range from bogie.params
QUANTITIES: dict[str, Quantity] = {
    q.key: q
    for q in (
        _bogie_quantity("bush_stiffness", "bush_stiffness"),
        _bogie_quantity("bush_damping", "bush_damping"),
        _bogie_quantity("friction_coefficient", "friction_coefficient"),
        _bogie_quantity("contact_roll_radius_mm", "contact_roll_radius", "mm", _mm_to_m, _m_to_mm),
        _bogie_quantity("tyre_wear_mm", "tyre_wear", "mm", _mm_to_m, _m_to_mm),
        _bogie_quantity("chassis_tilt_deg", "chassis_tilt", "degree", math.radians, math.degrees),
        # every equaliser arm of a bogie, the axle spacing kept (params.with_equaliser_arms)
        Quantity("equaliser_arm_mm", "equaliser_arm", "m", "mm", 0.05, 0.5, True, _mm_to_m, _m_to_mm),
        # up to half as much again as the legal load: overloaded trailers are part of what a survey finds
        Quantity("payload_fraction", "payload_fraction", "-", "-", 0.0, 1.5, False),
        Quantity("road_class", "road_class", "-", "ISO 8608 class", 0.0, 0.0, True, labels=ROAD_CLASSES),
    )
}


# ---- the configuration ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FleetConfig:
    """The fleet study.

    Attributes
    ----------
    size
        Number of bogies [-].
    sampling
        ``lhs`` (Latin hypercube) or ``sobol`` (scrambled Sobol'), both from scipy.stats.qmc.
    axle_mix
        Fraction of the fleet in each axle group [-], summing to 1.
    presets
        Name of the base bogie (a bogie.params preset) of each group.
    legal_group_load
        Legal load of each group, both sides together [N].
    legal_axle_load
        Legal load of a single axle, both sides together [N].
    """

    size: int
    sampling: str
    axle_mix: FrozenMap
    presets: FrozenMap
    legal_group_load: FrozenMap
    legal_axle_load: float

    @property
    def groups(self) -> tuple[str, ...]:
        """The axle groups in a fixed order (fewest axles first), whatever the order in params.yaml."""
        return tuple(self.axle_mix)


@dataclass(frozen=True)
class StaticProtocol:
    """Static weighbridge: load [s], crawl over an approach [m] at walking pace [m/s], settle [s]; time step [s]."""

    load_time: float
    approach_length: float
    crawl_speed: float
    settle_time: float
    dt: float


@dataclass(frozen=True)
class WimProtocol:
    """Weigh-in-motion pass: road speed [m/s] over an approach [m]; time step [s]."""

    speed: float
    approach_length: float
    dt: float


@dataclass(frozen=True)
class ProtocolConfig:
    """Which protocols the simulation runs (``run``) and the settings of each."""

    run: tuple[str, ...]
    static: StaticProtocol
    wim: WimProtocol


@dataclass(frozen=True)
class SensitivityConfig:
    """The Sobol' sensitivity design.

    Attributes
    ----------
    group
        Axle group whose base bogie the design perturbs.
    base_size
        Saltelli base sample size N, a power of 2 [-].
    factors
        SI names of the perturbed quantities (``tyre_wear`` stands for every axle's wear, one SALib group).
    bootstrap_resamples
        Bootstrap resamples for the confidence intervals [-].
    confidence_level
        Confidence level of those intervals [-].
    protocol
        Protocol whose results are analysed.
    """

    group: str
    base_size: int
    factors: tuple[str, ...]
    bootstrap_resamples: int
    confidence_level: float
    protocol: str


@dataclass(frozen=True)
class AblationConfig:
    """The switch-off ablation: the first ``size`` fleet bogies, each with the inhibitors removed in turn."""

    size: int


@dataclass(frozen=True)
class ExecutionConfig:
    """How the simulation runs: joblib ``backend``, workers, samples per chunk, dask scheduler address."""

    backend: str
    n_jobs: int
    chunk_size: int
    dask_scheduler: str | None


@dataclass(frozen=True)
class Config:
    """The validated pipeline parameters, all SI.

    ``distributions`` maps the SI name of each sampled quantity (``bush_stiffness``, ``bush_damping``,
    ``friction_coefficient``, ``contact_roll_radius`` [m], ``tyre_wear`` [m], ``chassis_tilt`` [rad],
    ``payload_fraction``, ``road_class``) to its distribution in SI units.
    """

    seed: int
    fleet: FleetConfig
    distributions: FrozenMap
    protocol: ProtocolConfig
    sensitivity: SensitivityConfig
    ablation: AblationConfig
    execution: ExecutionConfig


# ---- checking helpers ----------------------------------------------------------------------------------------
# Every getter takes the parent mapping and the key, so that a missing key and a bad value get the same
# description of the expected form: "missing key fleet.size: expected an integer in [1, 10000000]".
_ABSENT = object()


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _fail(key: str, value: Any, expected: str) -> NoReturn:
    raise ConfigError(key, f"{key} = {value!r}: {expected}")


def _get(raw: Mapping[str, Any], path: str, name: str, expected: str) -> Any:
    value = raw.get(name, _ABSENT)
    if value is _ABSENT:
        key = _join(path, name)
        raise ConfigError(key, f"missing key {key}: expected {expected.removeprefix('must be ')}")
    return value


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _unit_text(unit: str) -> str:
    return "" if unit in ("-", "[-]") else f" {unit}"


def _keys_text(keys: Iterable[str]) -> str:
    return f"a mapping with the keys {', '.join(keys)}"


def _section(raw: Any, path: str, allowed: Iterable[str]) -> dict[str, Any]:
    """``raw`` checked to be a mapping with no key outside ``allowed`` (a typo is an error, never ignored)."""
    allowed = tuple(allowed)
    if not isinstance(raw, dict):
        _fail(path, raw, f"must be {_keys_text(allowed)}")
    for name in raw:
        if name not in allowed:
            close = difflib.get_close_matches(str(name), allowed, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            key = _join(path, str(name))
            raise ConfigError(key, f"unknown key {key}{hint}: {path or 'the top level'} takes {', '.join(allowed)}")
    return raw


def _subsection(raw: Mapping[str, Any], path: str, name: str, allowed: Iterable[str]) -> dict[str, Any]:
    allowed = tuple(allowed)
    return _section(_get(raw, path, name, _keys_text(allowed)), _join(path, name), allowed)


def _number(
    raw: Mapping[str, Any],
    path: str,
    name: str,
    unit: str,
    low: float | None = None,
    high: float | None = None,
    low_inclusive: bool = True,
) -> float:
    """A finite number in [low, high] (or (low, high]) given in ``unit``."""
    key = _join(path, name)
    if low is None:
        expected = f"must be a number{_unit_text(unit) and f' in{_unit_text(unit)}'}"
    elif high is None:
        expected = f"must be a number {'>=' if low_inclusive else '>'} {low:g}{_unit_text(unit)}"
    else:
        expected = f"must be a number in {'[' if low_inclusive else '('}{low:g}, {high:g}]{_unit_text(unit)}"
    value = _get(raw, path, name, expected)
    if isinstance(value, str):
        try:
            float(value)
        except ValueError:
            pass
        else:
            _fail(key, value, f"is text, not a number ({expected}); YAML reads 1e3 as text, write 1.0e3")
    if not _is_number(value) or not math.isfinite(value):
        _fail(key, value, expected)
    if (low is not None and (value < low if low_inclusive else value <= low)) or (high is not None and value > high):
        _fail(key, value, expected)
    return float(value)


def _integer(raw: Mapping[str, Any], path: str, name: str, low: int, high: int | None = None) -> int:
    expected = f"must be an integer >= {low}" if high is None else f"must be an integer in [{low}, {high}]"
    value = _get(raw, path, name, expected)
    if not isinstance(value, int) or isinstance(value, bool) or value < low or (high is not None and value > high):
        _fail(_join(path, name), value, expected)
    return value


def _word(raw: Mapping[str, Any], path: str, name: str, allowed: Iterable[str], what: str) -> str:
    allowed = tuple(allowed)
    expected = f"must be one of {', '.join(allowed)}"
    value = _get(raw, path, name, expected)
    if not isinstance(value, str) or value not in allowed:
        _fail(_join(path, name), value, f"unknown {what}: {expected}")
    return value


def _name_list(raw: Mapping[str, Any], path: str, name: str, allowed: Iterable[str], what: str) -> tuple[str, ...]:
    """A non-empty list of distinct names from ``allowed``."""
    allowed = tuple(allowed)
    key = _join(path, name)
    expected = f"must be a non-empty list of {what}s from {', '.join(allowed)}"
    value = _get(raw, path, name, expected)
    if not isinstance(value, list) or not value:
        _fail(key, value, expected)
    for i, item in enumerate(value):
        if item not in allowed:
            close = difflib.get_close_matches(str(item), allowed, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            _fail(f"{key}[{i}]", item, f"unknown {what}{hint}: must be one of {', '.join(allowed)}")
    if len(set(value)) != len(value):
        _fail(key, value, f"lists a {what} twice")
    return tuple(value)


# ---- sections --------------------------------------------------------------------------------------------------
def _parse_fleet(raw: Mapping[str, Any]) -> FleetConfig:
    path = "fleet"
    sec = _subsection(
        raw, "", path, ("size", "sampling", "axle_mix", "presets", "legal_group_load_t", "legal_axle_load_t")
    )
    size = _integer(sec, path, "size", 1, 10_000_000)
    sampling = _word(sec, path, "sampling", SAMPLINGS, "sampling method")

    mix_raw = _subsection(sec, path, "axle_mix", GROUP_AXLES)
    mix = {g: _number(mix_raw, f"{path}.axle_mix", g, "[-] (a fraction)", 0.0, 1.0) for g in GROUP_AXLES}
    if abs(sum(mix.values()) - 1.0) > 1e-9:
        _fail(f"{path}.axle_mix", sec["axle_mix"], f"the fractions must sum to 1, they sum to {sum(mix.values()):g}")

    presets_raw = _subsection(sec, path, "presets", GROUP_AXLES)
    presets = {}
    for group, n_axles in GROUP_AXLES.items():
        name = _word(presets_raw, f"{path}.presets", group, PRESETS, "preset")
        if preset(name).n_axles != n_axles:
            _fail(f"{path}.presets.{group}", name, f"has {preset(name).n_axles} axles but a {group} has {n_axles}")
        presets[group] = name

    loads_raw = _subsection(sec, path, "legal_group_load_t", GROUP_AXLES)
    loads = {}
    for group, n_axles in GROUP_AXLES.items():
        tonnes = _number(loads_raw, f"{path}.legal_group_load_t", group, "t", 0.0, 200.0, low_inclusive=False)
        # the design bogie needs a positive payload: the legal load must exceed the group's own unsprung mass
        unsprung = 2 * n_axles * preset(presets[group]).axle_mass / 1000.0
        if tonnes <= unsprung:
            _fail(
                f"{path}.legal_group_load_t.{group}",
                loads_raw[group],
                f"must exceed the unsprung mass of the {presets[group]} axles, {unsprung:g} t",
            )
        loads[group] = tonnes * 1000.0 * GRAVITY
    axle_tonnes = _number(sec, path, "legal_axle_load_t", "t", 0.0, 100.0, low_inclusive=False)
    return FleetConfig(
        size=size,
        sampling=sampling,
        axle_mix=FrozenMap(mix),
        presets=FrozenMap(presets),
        legal_group_load=FrozenMap(loads),
        legal_axle_load=axle_tonnes * 1000.0 * GRAVITY,
    )


def _distribution_argument(raw: Mapping[str, Any], key: str, name: str, quantity: Quantity) -> Any:
    """One parameter of a distribution, type-checked, in params.yaml units."""
    path = _join(key, name)
    if name == "values":
        what = f"{quantity.yaml_unit}s" if quantity.labels else f"numbers in {quantity.yaml_unit}"
        value = _get(raw, key, name, f"a non-empty list of {what}")
        if not isinstance(value, list) or not value:
            _fail(path, value, f"must be a non-empty list of {what}")
        for i, v in enumerate(value):
            if quantity.labels and v not in quantity.labels:
                _fail(f"{path}[{i}]", v, f"unknown {quantity.yaml_unit}: must be one of {', '.join(quantity.labels)}")
            if not quantity.labels and not _is_number(v):
                _fail(f"{path}[{i}]", v, f"must be a number in {quantity.yaml_unit}")
        return tuple(value) if quantity.labels else tuple(float(v) for v in value)
    if name == "weights":
        value = raw[name]
        if value is not None and (not isinstance(value, list) or not all(_is_number(w) for w in value)):
            _fail(path, value, "must be a list of numbers, one relative weight per value [-]")
        return None if value is None else tuple(float(w) for w in value)
    if name == "value" and quantity.labels:
        value = raw[name]
        if value not in quantity.labels:
            _fail(path, value, f"unknown {quantity.yaml_unit}: must be one of {', '.join(quantity.labels)}")
        return value
    return _number(raw, key, name, "[-]" if name == "sigma" else quantity.yaml_unit)


def _check_support(key: str, raw: Mapping[str, Any], dist: Distribution, quantity: Quantity) -> None:
    """Refuse a distribution (in SI) that can sample outside the physical range of its quantity."""
    q = quantity

    def inside(x: float) -> bool:
        return (x >= q.low if q.low_inclusive else x > q.low) and x <= q.high

    where = f"outside the allowed range {q.range_text} of {q.name}"
    if isinstance(dist, Constant):
        if not inside(dist.value):
            _fail(f"{key}.value", raw["value"], f"is {where}")
        return
    if isinstance(dist, Choice):
        for i, v in enumerate(dist.values):
            if not inside(v):
                _fail(f"{key}.values[{i}]", raw["values"][i], f"is {where}")
        return
    lo, hi = dist.support
    if math.isinf(lo) or math.isinf(hi):
        bounds = "low and high" if math.isinf(lo) else "high"
        hint = "use kind truncnormal with low and high" if dist.kind == "normal" else f"give {bounds}"
        _fail(
            f"{key}.kind",
            raw["kind"],
            f"is unbounded but {q.name} must stay in {q.range_text}: {hint} inside that range to truncate it",
        )
    if not inside(lo):
        _fail(f"{key}.low", raw.get("low", q.from_si(lo)), f"lets samples fall {where}")
    if not inside(hi):
        _fail(f"{key}.high", raw["high"], f"lets samples fall {where}")


def _parse_distribution(raw: Mapping[str, Any], key: str, quantity: Quantity) -> Distribution:
    """One entry of ``distributions:``, validated, converted to SI."""
    kinds = ("choice", "constant") if quantity.labels else tuple(KINDS)
    if not isinstance(raw, dict):
        _fail(key, raw, "must be a mapping such as {kind: uniform, low: ..., high: ...}")
    kind = _get(raw, key, "kind", f"one of {', '.join(kinds)}")
    if kind not in KINDS:
        _fail(f"{key}.kind", kind, f"unknown distribution kind: must be one of {', '.join(KINDS)}")
    if kind not in kinds:
        _fail(f"{key}.kind", kind, f"{quantity.name} is categorical: must be one of {', '.join(kinds)}")
    cls = KINDS[kind]
    required, optional = cls.parameter_names()
    _section(raw, key, ("kind", *required, *optional))
    args = {name: _distribution_argument(raw, key, name, quantity) for name in (*required, *optional) if name in raw}
    for name in required:
        if name not in args:
            expected = f"a number in {quantity.yaml_unit} (kind {kind} takes {', '.join(required)})"
            _get(raw, key, name, expected)
    try:
        dist = cls(**args)
    except ParameterError as exc:
        value = raw.get(exc.param, exc.value)
        # sigma and the weights are dimensionless whatever the quantity
        unit = "" if exc.param.split("[")[0] in ("sigma", "weights") else _unit_text(quantity.yaml_unit)
        _fail(_join(key, exc.param), value, f"{exc.expected}{unit and f', in{unit}'}")
    if quantity.labels:
        return dist
    si = dist.scaled(quantity.to_si)
    _check_support(key, raw, si, quantity)
    return si


def _parse_distributions(raw: Mapping[str, Any]) -> FrozenMap:
    sec = _subsection(raw, "", "distributions", QUANTITIES)
    result = {}
    for key, q in QUANTITIES.items():
        entry = _get(
            sec, "distributions", key, f"a distribution of {q.name} in {q.yaml_unit}, e.g. {{kind: uniform, ...}}"
        )
        result[q.name] = _parse_distribution(entry, f"distributions.{key}", q)
    return FrozenMap(result)


def _parse_protocol(raw: Mapping[str, Any]) -> ProtocolConfig:
    sec = _subsection(raw, "", "protocol", ("run", "static", "wim"))
    run = _name_list(sec, "protocol", "run", PROTOCOLS, "protocol")

    path = "protocol.static"
    st = _subsection(
        sec, "protocol", "static", ("load_time_s", "approach_length_m", "crawl_speed_m_s", "settle_time_s", "dt_s")
    )
    static = StaticProtocol(
        load_time=_number(st, path, "load_time_s", "s", 0.0, 600.0, low_inclusive=False),
        approach_length=_number(st, path, "approach_length_m", "m", 0.0, 1000.0, low_inclusive=False),
        # walking pace or a little faster; more is not a static weighing
        crawl_speed=_number(st, path, "crawl_speed_m_s", "m/s", 0.0, 5.0, low_inclusive=False),
        settle_time=_number(st, path, "settle_time_s", "s", 0.0, 600.0),
        dt=_number(st, path, "dt_s", "s", 0.0, 0.01, low_inclusive=False),
    )
    path = "protocol.wim"
    wm = _subsection(sec, "protocol", "wim", ("speed_m_s", "approach_length_m", "dt_s"))
    wim = WimProtocol(
        # 50 m/s = 180 km/h: above it the value was most likely given in km/h
        speed=_number(wm, path, "speed_m_s", "m/s", 0.0, 50.0, low_inclusive=False),
        approach_length=_number(wm, path, "approach_length_m", "m", 0.0, 10_000.0, low_inclusive=False),
        dt=_number(wm, path, "dt_s", "s", 0.0, 0.01, low_inclusive=False),
    )
    return ProtocolConfig(run=run, static=static, wim=wim)


def _parse_sensitivity(raw: Mapping[str, Any], protocols: tuple[str, ...]) -> SensitivityConfig:
    path = "sensitivity"
    sec = _subsection(
        raw, "", path, ("group", "base_size", "factors", "bootstrap_resamples", "confidence_level", "protocol")
    )
    group = _word(sec, path, "group", GROUP_AXLES, "axle group")
    base_size = _integer(sec, path, "base_size", 2, 2**20)
    if base_size & (base_size - 1):
        _fail(f"{path}.base_size", base_size, "must be a power of 2 (Sobol' sequences balance only then), e.g. 512")
    factors = _name_list(sec, path, "factors", QUANTITIES, "factor")
    resamples = _integer(sec, path, "bootstrap_resamples", 1, 100_000)
    level = _number(sec, path, "confidence_level", "[-]", 0.0, 1.0, low_inclusive=False)
    if level >= 1.0:
        _fail(f"{path}.confidence_level", sec["confidence_level"], "must be a number in (0, 1)")
    protocol = _word(sec, path, "protocol", PROTOCOLS, "protocol")
    if protocol not in protocols:
        _fail(f"{path}.protocol", protocol, f"is not run: protocol.run lists only {', '.join(protocols)}")
    return SensitivityConfig(
        group=group,
        base_size=base_size,
        factors=tuple(QUANTITIES[name].name for name in factors),
        bootstrap_resamples=resamples,
        confidence_level=level,
        protocol=protocol,
    )


def _parse_ablation(raw: Mapping[str, Any], fleet_size: int) -> AblationConfig:
    sec = _subsection(raw, "", "ablation", ("size",))
    size = _integer(sec, "ablation", "size", 1)
    if size > fleet_size:
        _fail("ablation.size", size, f"must not exceed fleet.size = {fleet_size}: the ablation reuses fleet bogies")
    return AblationConfig(size=size)


def _parse_execution(raw: Mapping[str, Any]) -> ExecutionConfig:
    path = "execution"
    sec = _subsection(raw, "", path, ("backend", "n_jobs", "chunk_size", "dask_scheduler"))
    backend = _word(sec, path, "backend", BACKENDS, "backend")
    n_jobs = _integer(sec, path, "n_jobs", 1, 4096)
    chunk_size = _integer(sec, path, "chunk_size", 1, 10_000_000)
    address = 'an address such as "tcp://127.0.0.1:8786"'
    scheduler = _get(sec, path, "dask_scheduler", f"null or {address}")
    if scheduler is not None and (not isinstance(scheduler, str) or "://" not in scheduler):
        _fail(f"{path}.dask_scheduler", scheduler, f"must be null or {address}")
    if backend == "dask" and scheduler is None:
        _fail(f"{path}.dask_scheduler", scheduler, f"backend dask needs the scheduler's address: {address}")
    return ExecutionConfig(backend=backend, n_jobs=n_jobs, chunk_size=chunk_size, dask_scheduler=scheduler)


def parse_config(raw: Mapping[str, Any]) -> Config:
    """Validate the parsed params.yaml and convert it to SI.

    Parameters
    ----------
    raw
        The mapping read from params.yaml (:func:`load_params`).

    Returns
    -------
    Config
        Every pipeline parameter, SI.

    Raises
    ------
    ConfigError
        At the first bad key, naming its key path, value and the expected form, range and unit.
    """
    sections = ("seed", "fleet", "distributions", "protocol", "sensitivity", "ablation", "execution")
    top = _section(dict(raw), "", (*sections, *OTHER_SECTIONS))
    fleet = _parse_fleet(top)
    protocol = _parse_protocol(top)
    return Config(
        seed=_integer(top, "", "seed", 0, 2**63 - 1),
        fleet=fleet,
        distributions=_parse_distributions(top),
        protocol=protocol,
        sensitivity=_parse_sensitivity(top, protocol.run),
        ablation=_parse_ablation(top, fleet.size),
        execution=_parse_execution(top),
    )


def load_config(path: str | Path = "params.yaml") -> Config:
    """Read, validate and convert params.yaml (see :func:`parse_config`).

    Raises
    ------
    ConfigError
        For a bad key, or a file that is not a YAML mapping.
    OSError
        If the file cannot be read.
    """
    try:
        raw = load_params(path)
    except yaml.YAMLError as exc:
        raise ConfigError("", f"{path} is not valid YAML: {exc}") from None
    except ValueError as exc:
        raise ConfigError("", str(exc)) from None
    return parse_config(raw)
