"""How the rules of params.yaml read it (:mod:`pipeline.config.rules`): a :class:`View` of the mapping as written,
whose keys a field check or an earlier rule found bad are :class:`Unavailable`; a broken rule as a
:class:`RuleError`; what the settings mean that several rules read (the tilt grids' sizes, the calibration's
protocol), and the bounds on what the settings cost (:data:`MAX_RUNS`, :data:`BYTES_PER_RUN`)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel, TypeAdapter, ValidationError

from bogie.fleet.constants import (
    SURVEY_PROTOCOLS,
)
from bogie.fleet.sampling.distributions import ParameterError
from bogie.params import INHIBITORS
from pipeline.config.distributions import NumericSpec
from pipeline.config.errors import locate

#: the most runs (sample rows) one study may have [-]: fleet.n_bogies' own bound; a larger study is a typo or a
#: step far finer than any result needs
MAX_RUNS = 10_000_000

#: memory one sample row or run costs at a stage's peak: its sample row (about 0.6 KiB with pandas' overheads) and its
#: runs' results with their derived columns (about 1 KiB each under each protocol) [bytes]; pipeline.sample's
#: BYTES_PER_BOGIE is this figure. Measured (bench/README.md, bench_stage_memory, 8 December 2026): the survey stage
#: grows about 1.6 kB a fleet run, 3.3 kB a bogie of two protocols, about 12 % above this at 10^6 bogies
BYTES_PER_RUN = 3 * 1024

#: runs of each ablation bogie: the baseline, each inhibitor off, all off
ABLATION_VARIANTS = len(INHIBITORS) + 2


class Unavailable(Exception):
    """A value a rule needs is missing or itself bad: the rule is not evaluated (the bad key is reported)."""


@dataclass(frozen=True)
class RuleError:
    """A broken rule: the key path it names, the value as written there and what was expected."""

    key: str
    value: Any
    expected: str


def _touches(bad: str, path: str) -> bool:
    """Whether an error at key path ``bad`` makes the value at ``path`` unusable (the same key, above or below it)."""
    if bad in ("", path):
        return True
    return any(a.startswith(b + sep) for a, b in ((path, bad), (bad, path)) for sep in (".", "["))


def _above(bad: str, path: str) -> bool:
    """Whether an error at key path ``bad`` is at ``path`` or above it (a mapping's own error, not an entry's)."""
    return bad in ("", path) or any(path.startswith(bad + sep) for sep in (".", "["))


class View:
    """The values of params.yaml as written, by dotted key path, with the schema's defaults for keys left out.

    Parameters
    ----------
    schema
        The model of the whole file (:class:`pipeline.config.schema.Params`).
    raw
        The mapping read from params.yaml.
    bad
        Key paths of the errors found in it: a value at, above or below one of them is :class:`Unavailable`.
    """

    def __init__(self, schema: type[BaseModel], raw: Mapping[str, Any], bad: Sequence[str] = ()) -> None:
        self.schema, self.raw, self.bad = schema, raw, list(bad)
        #: what the rules derive from the file more than once (the tilt distribution's bounds), by name
        self.derived: dict[str, Any] = {}

    def get(self, path: str) -> Any:
        """The value at ``path``; raises :class:`Unavailable` if it is bad, or missing without a default."""
        if any(_touches(bad, path) for bad in self.bad):
            raise Unavailable(path)
        return self._value(path)

    def entries(self, path: str) -> dict[str, Any]:
        """The entries of the mapping at ``path`` (a mapping with free keys: ``calibrate.fit``, ``design.grid``) whose
        own values are valid, by key: a bad entry leaves the others to check. Raises :class:`Unavailable` if the
        mapping itself, or a key above it, is bad."""
        if any(_above(bad, path) for bad in self.bad):
            raise Unavailable(path)
        mapping = self._value(path)
        if not isinstance(mapping, Mapping):
            raise Unavailable(path)
        good = lambda name: not any(_touches(bad, f"{path}.{name}") for bad in self.bad)  # noqa: E731
        return {name: value for name, value in mapping.items() if isinstance(name, str) and good(name)}

    def names(self, path: str) -> tuple[str, ...]:
        """The keys of the mapping at ``path`` as written, whatever their values (see :meth:`entries`)."""
        if any(_above(bad, path) for bad in self.bad) or not isinstance(mapping := self._value(path), Mapping):
            raise Unavailable(path)
        return tuple(name for name in mapping if isinstance(name, str))

    def section(self, name: str) -> None:
        """Raise :class:`Unavailable` if the optional section ``name`` is not given (null: no such study), or is itself
        bad (a bad key inside it leaves the rest to check)."""
        if any(_above(bad, name) for bad in self.bad) or self._value(name) is None:
            raise Unavailable(name)

    def _value(self, path: str) -> Any:
        parts = path.split(".")
        node: Any = self.raw
        for i, part in enumerate(parts):
            if not isinstance(node, Mapping):
                raise Unavailable(path)
            if part in node:
                node = node[part]
                continue
            field = locate(self.schema, parts[: i + 1]).field
            if field is None or field.is_required():
                raise Unavailable(path)
            node = field.get_default(call_default_factory=True)
            node = node.model_dump() if isinstance(node, BaseModel) else node
        return node


Rule = Callable[[View], Iterator[RuleError]]

_SPEC = TypeAdapter(NumericSpec)


def _tilt_support(view: View) -> tuple[float, float]:
    """The bounds of distributions.chassis_tilt_deg [degree]."""
    if "tilt_support" not in view.derived:
        try:
            spec = _SPEC.validate_python(view.get("distributions.chassis_tilt_deg"))
            view.derived["tilt_support"] = spec.build().support
        except (ValidationError, ParameterError):
            raise Unavailable("distributions.chassis_tilt_deg") from None
    return view.derived["tilt_support"]


def calibration_tilt_count(low: float, high: float, step: float) -> int:
    """Tilts of the calibration table's grid: evenly spaced over [low, high] at most ``step`` apart, both ends [-]."""
    return max(2, math.ceil((high - low) / step - 1e-9) + 1)


def design_tilt_count(low: float, high: float, step: float) -> int:
    """At most the tilts of the design's tolerance grid: level, outward by ``step`` to ``low`` and ``high`` [-]."""
    return math.floor(max(high, 0.0) / step) + math.floor(max(-low, 0.0) / step) + 3


def _calibrates(view: View) -> None:
    """Raise :class:`Unavailable` (the rule does not apply) when no calibration will run: no ``calibrate`` section,
    or no observed survey to calibrate to (``observed.path`` null: the stage skips, docs/calibration.md), so that a
    small fleet (``dvc exp run -S fleet.n_bogies=40``) is not refused for a calibration that will not run."""
    view.section("calibrate")
    if view.get("observed.path") is None:
        raise Unavailable("observed.path")


def survey_protocol(protocol: str, kind: str) -> str:
    """The protocol a calibration holds against the survey: ``calibrate.protocol``, or for ``auto`` the one of
    ``observed.kind`` (:data:`bogie.fleet.constants.SURVEY_PROTOCOLS`: a WIM file, wim; a weighbridge file, static)."""
    return SURVEY_PROTOCOLS[kind] if protocol == "auto" else protocol


def why_static(protocol: str) -> str:
    """Why a calibration whose ``calibrate.protocol`` is ``protocol`` is static, in words."""
    return "observed.kind is weighbridge" if protocol == "auto" else "calibrate.protocol is static"


def calibration_protocol(view: View) -> str:
    """:func:`survey_protocol` of params.yaml as written."""
    return survey_protocol(view.get("calibrate.protocol"), view.get("observed.kind"))
