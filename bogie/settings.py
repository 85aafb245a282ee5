"""Settings declared once: each field of a library settings class carries its unit, range and doc as data.

A settings class (:class:`bogie.fleet.StaticProtocol`, :class:`bogie.fleet.DesignSettings`, ...) is a frozen
dataclass whose plain number fields are made by :func:`setting`; its ``__post_init__`` calls :func:`check_settings`,
which refuses a value out of its declared range with the class's error, naming the field, the value, what is allowed
and the unit. The pipeline's params.yaml schema reads the same declarations (:func:`declared`) to build its fields
(``pipeline/config/fields.py``, ``library_field``), keeping only its key's unit suffix and any stricter project bound:
a key's range, unit and doc are written here and nowhere else (issue 42 Must 1).

One argument check, one message (issue 42 Must 2): the library refuses a number out of its range with
:meth:`Setting.check` (a declared field) or :func:`check_value` (a plain argument; :func:`refusal` for the text alone,
where a check finds the bad value in an array or lets through more than :func:`check_value` would), and the message
reads

    ``{name} = {value} is out of range: must be {allowed} {unit}``

``allowed`` is ``in [0, 1]``, ``in (0, 0.5]``, ``> 0``, ``>= 1`` or ``a whole number >= 2``, with ``, or None``
where None is allowed; a value of the wrong kind (a bool, a text, an array where a number is wanted, a float where a
whole number is) reads ``is not a number (text)``, ``is not a whole number (float)`` in place of ``is out of range``;
a name not among a setting's choices, ``is unknown: must be one of a, b``.
The unit is written bare after what is allowed, as the library writes it (``m``, ``N m/rad``, ``-`` for a
dimensionless value), never in brackets; an explanation, if the check has one, comes last in parentheses. The value is
shown as the user wrote it: ``0.001``, not ``np.float64(0.001)``. For example:

    ``beta = 0.7 is out of range: must be in (0, 0.5] - (Newmark parameter)``
    ``seed = 1.5 is not a whole number (float): must be a whole number >= 0 -``
    ``tyre_damping = 'soft' is not a number (text): must be in [0, 1e+07] N s/m``
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "FrozenMap", "MapSetting", "Setting", "check_settings", "check_value", "declared", "documented", "map_setting",
    "refusal", "setting",
]  # fmt: skip

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

    def bounds(self) -> str:
        """The bounds in words: ``in [0, 1]``, ``in (0, 0.5]``, ``> 0``, ``<= 1``; empty if there is none."""
        lo = None if self.low is None else f"{self.low:g}"
        hi = None if self.high is None else f"{self.high:g}"
        if lo is not None and hi is not None:
            return f"in {'(' if self.low_open else '['}{lo}, {hi}{')' if self.high_open else ']'}"
        if lo is not None:
            return f"{'>' if self.low_open else '>='} {lo}"
        if hi is not None:
            return f"{'<' if self.high_open else '<='} {hi}"
        return ""

    def allowed(self) -> str:
        """What is allowed, in words: ``a whole number >= 2``, ``a finite number in (0, 1)``, ``one of a, b``."""
        if self.choices is not None:
            return "one of " + ", ".join(self.choices) + (", or None" if self.optional else "")
        kind = "a whole number" if self.whole else "a finite number"
        bounds = self.bounds()
        return (f"{kind} {bounds}" if bounds else kind) + (", or None" if self.optional else "")

    def contains(self, value: Any) -> bool:
        """Whether ``value`` is allowed."""
        if value is None:
            return self.optional
        if self.choices is not None:
            return isinstance(value, str) and value in self.choices
        return _in_range(value, self.low, self.high, self.low_open, self.high_open, self.whole)

    def check(self, name: str, value: Any, error: type[Exception] = ValueError, note: str = "") -> None:
        """Nothing if ``value`` is allowed, else ``error`` with :meth:`refusal`'s message."""
        if not self.contains(value):
            raise error(self.refusal(name, value, note))

    def refusal(self, name: str, value: Any, note: str = "") -> str:
        """The library's one message refusing ``value`` of ``name`` (the module docstring's form): the name, the value
        as written, why (``is out of range``, ``is not a number (text)``, ``is not a whole number (float)``), what is
        allowed and the unit, then ``note`` in parentheses if given. It says what the value is, not whether it is
        allowed: call it for a value the check refused."""
        if self.choices is not None:
            why = "is unknown"
            must = self.allowed()
        else:
            if isinstance(value, _BOOL) or not isinstance(value, _NUMBER):
                why = f"is not a number ({_kind(value)})"
            elif self.whole and not isinstance(value, _WHOLE):
                why = f"is not a whole number ({_kind(value)})"
            else:
                why = "is out of range"
            bounds = self.bounds()
            if self.whole:
                must = f"a whole number {bounds}" if bounds else "a whole number"
            else:
                must = bounds or "a finite number"
            must = f"{must} {self.unit}" + (", or None" if self.optional else "")
        return f"{name} = {_show(value)} {why}: must be {must}" + (f" ({note})" if note else "")


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
    optional: bool = False,
    note: str = "",
    error: type[Exception] = ValueError,
) -> Any:
    """An argument that is not a settings field, checked as a declared one would be (:meth:`Setting.check`):
    ``value`` as an int (``whole``) or a float (None if ``optional`` and None), else ``error`` with
    :meth:`Setting.refusal`'s message, ``note`` appended. A number is Python's or numpy's, a 0-d array too."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if value is None and optional:
        return None
    # Setting.contains without making a Setting (an argument is checked on every call: a weighing's phases, ...)
    if not _in_range(value, low, high, low_open, high_open, whole):
        spec = Setting(unit, "", low, high, low_open, high_open, whole, optional)
        raise error(spec.refusal(name, value, note))
    return int(value) if whole else float(value)


def refusal(
    name: str,
    value: Any,
    unit: str = "-",
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    whole: bool = False,
    optional: bool = False,
    note: str = "",
) -> str:
    """:meth:`Setting.refusal`'s message for a value a check of its own refused (a check over an array, one that
    lets through what :func:`check_value` would not): the same arguments as :func:`check_value`'s."""
    return Setting(unit, "", low, high, low_open, high_open, whole, optional).refusal(name, value, note)


#: what a number is: Python's or numpy's (not a bool: True is not 1 N m/rad); a whole number; a bool
_NUMBER, _WHOLE, _BOOL = (int, float, np.integer, np.floating), (int, np.integer), (bool, np.bool_)


def _in_range(value: Any, low: float | None, high: float | None, low_open: bool, high_open: bool, whole: bool) -> bool:
    """Whether ``value`` (not None) is a number within the bounds: :meth:`Setting.contains`' test of a number."""
    if isinstance(value, _BOOL):
        return False
    if whole:
        if not isinstance(value, _WHOLE):
            return False
    elif isinstance(value, _NUMBER):
        value = float(value)  # compared as the float it is taken as (a float32 at a bound is not rounded up)
        if not math.isfinite(value):
            return False
    else:
        return False
    if low is not None and (value <= low if low_open else value < low):
        return False
    return not (high is not None and (value >= high if high_open else value > high))


def _kind(value: Any) -> str:
    """What a value is, in a refusal: ``text`` for a string, else its type's name (``bool``, ``list``, ``float``)."""
    return "text" if isinstance(value, str | bytes) else type(value).__name__


def _show(value: Any) -> str:
    """A value as the user wrote it: ``0.001``, not numpy's ``np.float64(0.001)``."""
    return repr(value.item()) if isinstance(value, np.generic) else repr(value)


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


@dataclass(frozen=True)
class MapSetting:
    """The declaration of a mapping setting with fixed keys: one value per axle group (``legal_group_load``), a mix of
    fractions summing to one (``axle_mix``), or a mapping of such mappings (``suspension_mix``).

    Attributes
    ----------
    unit
        The unit of its values (``-`` for fractions and names).
    doc
        One sentence: what it is.
    keys
        The keys it may have; at least one of them.
    entry
        Each value's declaration (a :class:`Setting`, or a :class:`MapSetting` for a mapping of mappings); None:
        a name the class checks itself (a preset or a bogie file).
    total
        The sum its values must have (within :data:`TOTAL_TOLERANCE`), or None.
    optional
        It has a default (its meaning in ``doc``).
    """

    unit: str
    doc: str
    keys: tuple[str, ...]
    entry: Setting | MapSetting | None = None
    total: float | None = None
    optional: bool = False

    def check(self, name: str, value: Any, error: type[Exception] = ValueError) -> None:
        """Nothing if ``value`` is a mapping of allowed keys and values (and sum), else ``error`` naming ``name`` (an
        entry: ``name['key']``), the value, what is allowed and the unit."""
        if not isinstance(value, Mapping) or not value or any(k not in self.keys for k in value):
            shown = dict(value) if isinstance(value, Mapping) else value
            keys = ", ".join(self.keys)
            raise error(f"{name} = {shown!r} has a key not allowed: keys must be among {keys}, at least one")
        if self.entry is not None:
            for key, item in value.items():
                self.entry.check(f"{name}[{key!r}]", item, error)
        if self.total is not None:
            total = sum(float(v) for v in value.values())
            if abs(total - self.total) > TOTAL_TOLERANCE:
                raise error(
                    f"{name} = {dict(value)!r}: the fractions must sum to {self.total:g}, they sum to {total:g}"
                )


#: a mapping's values must sum to its :attr:`MapSetting.total` within this [-]
TOTAL_TOLERANCE = 1e-9


def map_setting(
    default: Any = dataclasses.MISSING,
    *,
    unit: str,
    doc: str,
    keys: Iterable[str],
    entry: Setting | MapSetting | None = None,
    total: float | None = None,
    default_factory: Any = dataclasses.MISSING,
) -> Any:
    """A dataclass field declared as a :class:`MapSetting` (``optional`` if it has a default)."""
    optional = default is not dataclasses.MISSING or default_factory is not dataclasses.MISSING
    spec = MapSetting(unit, doc, tuple(keys), entry, total, optional)
    return dataclasses.field(default=default, default_factory=default_factory, metadata={KEY: spec})


def documented(cls: type) -> type:
    """Class decorator (above ``@dataclass``): the declared fields of ``cls`` appended to its docstring's
    ``Parameters`` section (name, doc, what is allowed, unit), so that each field's doc is written once, in its
    declaration."""
    lines = []
    for name, spec in declared(cls).items():
        if isinstance(spec, MapSetting):
            entry = spec.entry
            text = f"{spec.doc} A mapping with keys among {', '.join(spec.keys)}"
            text += f", each {entry.allowed()}" if isinstance(entry, Setting) else ""
        else:
            allowed = spec.allowed()
            text = f"{spec.doc} {allowed[0].upper()}{allowed[1:]}"
        lines.append(f"    {name}\n        {text} [{spec.unit}].")
    cls.__doc__ = (cls.__doc__ or "").rstrip() + "\n" + "\n".join(lines) + "\n"
    return cls
