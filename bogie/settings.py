"""Settings declared once: each field of a library settings class carries its unit, range and doc as data.

A settings class (:class:`bogie.fleet.StaticProtocol`, :class:`bogie.fleet.DesignSettings`, ...) is a frozen
dataclass whose plain number fields are made by :func:`setting`; its ``__post_init__`` calls :func:`check_settings`,
which refuses a value out of its declared range with the class's error, naming the field, the value, what is allowed
and the unit. The pipeline's params.yaml schema reads the same declarations (:func:`declared`) to build its fields
(``pipeline/config/fields.py``, ``library_field``), keeping only its key's unit suffix and any stricter project bound:
a key's range, unit and doc are written here and nowhere else (issue 42 Must 1).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FrozenMap", "Setting", "check_settings", "check_value", "declared", "setting"]

#: the metadata key of a declared field
KEY = "bogie.setting"


@dataclass(frozen=True)
class Setting:
    """The declaration of a number setting.

    Attributes
    ----------
    unit
        Its unit, as the library takes it (``-`` for a count or a fraction; ``degree``, ``m``, ``s``, ...).
    doc
        One sentence: what it is.
    low, high
        Its bounds (None: unbounded on that side) [unit].
    low_open, high_open
        Whether the bound itself is excluded (``> low``, ``< high``).
    whole
        A whole number (an ``int``; not a bool, not a float with no fraction).
    optional
        None is allowed (its meaning in ``doc``).
    choices
        A name, one of these (``unit`` is then ``-`` and the bounds None).
    """

    unit: str
    doc: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    whole: bool = False
    optional: bool = False
    choices: tuple[str, ...] | None = None

    def allowed(self) -> str:
        """What is allowed, in words: ``a whole number >= 2``, ``a finite number in (0, 1)``, ``one of a, b``."""
        if self.choices is not None:
            return "one of " + ", ".join(self.choices) + (", or None" if self.optional else "")
        kind = "a whole number" if self.whole else "a finite number"
        lo = None if self.low is None else f"{self.low:g}"
        hi = None if self.high is None else f"{self.high:g}"
        if lo is not None and hi is not None:
            text = f"{kind} in {'(' if self.low_open else '['}{lo}, {hi}{')' if self.high_open else ']'}"
        elif lo is not None:
            text = f"{kind} {'>' if self.low_open else '>='} {lo}"
        elif hi is not None:
            text = f"{kind} {'<' if self.high_open else '<='} {hi}"
        else:
            text = kind
        return text + (", or None" if self.optional else "")

    def contains(self, value: Any) -> bool:
        """Whether ``value`` is allowed."""
        if value is None:
            return self.optional
        if self.choices is not None:
            return isinstance(value, str) and value in self.choices
        if isinstance(value, bool | np.bool_):
            return False
        if self.whole:
            if not isinstance(value, int | np.integer):
                return False
        elif not isinstance(value, int | float | np.integer | np.floating) or not math.isfinite(value):
            return False
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        return not (self.high is not None and (value >= self.high if self.high_open else value > self.high))

    def check(self, name: str, value: Any, error: type[Exception] = ValueError) -> None:
        """Nothing if ``value`` is allowed, else ``error`` naming ``name``, the value, what is allowed and the
        unit."""
        if not self.contains(value):
            raise error(f"{name} = {value!r}: must be {self.allowed()} [{self.unit}]")


def setting(
    default: Any = dataclasses.MISSING,
    *,
    unit: str,
    doc: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    whole: bool = False,
    choices: tuple[str, ...] | None = None,
) -> Any:
    """A dataclass field declared as a :class:`Setting` (None allowed if ``default`` is None)."""
    spec = Setting(unit, doc, low, high, low_open, high_open, whole, default is None, choices)
    return dataclasses.field(default=default, metadata={KEY: spec})


def declared(cls: type) -> dict[str, Setting]:
    """The declared settings of the dataclass ``cls``, by field name, in field order."""
    return {f.name: f.metadata[KEY] for f in dataclasses.fields(cls) if KEY in f.metadata}


def check_settings(obj: Any, error: type[Exception] = ValueError, prefix: str = "") -> None:
    """Check every declared setting of the dataclass ``obj`` (:meth:`Setting.check`, each named ``prefix +
    name``); the values are left as they were given."""
    for name, spec in declared(type(obj)).items():
        spec.check(prefix + name, getattr(obj, name), error)


def check_value(
    name: str,
    value: Any,
    unit: str = "-",
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    whole: bool = False,
    error: type[Exception] = ValueError,
) -> Any:
    """An argument that is not a settings field, checked as a declared one would be (:meth:`Setting.check`):
    ``value`` as an int (``whole``) or a float, else ``error`` naming ``name``, the value, what is allowed and
    ``unit``."""
    Setting(unit, "", low, high, low_open, high_open, whole).check(name, value, error)
    return int(value) if whole else float(value)


class FrozenMap(Mapping):
    """A read-only, hashable, picklable mapping (a settings class's mapping field; the configuration's)."""

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
