"""The weight resolution of a file of weighings: detected from the axle loads' residues, or set by the user.

A scale that weighs to 100 kg writes every axle load as a multiple of 100 kg, whatever unit its file format uses:
a MON file (kilograms) from such a site holds loads ending in 00. A unit conversion on the way (pounds to kilograms,
a truncation) can move each load one unit off the step: a real MON file held loads ending in 00 (12,776) or 99
(6,827) and almost never anything else (issue 41). The resolution is then 100 kg, not the format's 1 kg.

**Rule** (derivation and conventions in ``docs/weighings.md``, "Weight resolution"). For each candidate step s of
:data:`WEIGHT_STEPS_KG` that is a whole multiple of the format's unit u (1 kg for MON and for CSV files of whole
kilograms, 100 kg for CASTOR, BeDIT, DITIS and TMG 2001), count the loads on a multiple of s (*on*), and those at
most one unit from one (*near*: on, one unit below or one unit above). If the loads had the resolution u and their
residues modulo s were spread evenly, a load would be *on* with probability p_on = u / s and *near* with p_near =
3 u / s. A step is *supported* when at least :data:`ON_GRID_SHARE` of the loads are on (or, for s >= 10 u, near)
and the Chernoff bound of that happening by chance, exp(-N KL(share || p)), is at most :data:`MAX_CHANCE`. The
resolution is the largest supported step (the format's unit when none is). The counts add up over the chunks of a
file (:class:`ResidueCounts`), so that a file read in pieces gives the same answer as one read whole.

Loads that are not whole multiples of the format's unit (a CSV file of decimal kilograms) have no detected
resolution (None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from bogie.weighings.settings import GROUP_FILTER, MAX_RESOLUTION_KG, WEIGHT_STEPS_KG

__all__ = [
    "MAX_CHANCE", "MAX_RESOLUTION_KG", "ON_GRID_SHARE", "TOLERANT_FROM", "WEIGHT_STEPS_KG", "Resolution",
    "ResidueCounts", "check_resolution_kg", "detect_resolution",
]  # fmt: skip

assert all(WEIGHT_STEPS_KG[-1] % s == 0 for s in WEIGHT_STEPS_KG)  # ResidueCounts.add's one histogram
#: the least share of the axle loads on (or near) a multiple of a step for the step to be supported [-]: a real
#: file's odd loads (a WIM system's correction, a hand-edited record) are tolerated up to 1 in 100. A convention of
#: this project (no published source), named as one
ON_GRID_SHARE: float = 0.99
#: the largest chance, bounded by Chernoff's inequality, that loads of the format's resolution fall on a coarser
#: step's grid as often as they do [-]: over the ten candidate steps, a false detection has a chance below 1e-5.
#: A convention of this project, named as one
MAX_CHANCE: float = 1e-6
#: the one-unit tolerance applies to steps of at least this many units [-]: below, "near" covers 30 % or more of
#: all residues and says little
TOLERANT_FROM: int = 10


def check_resolution_kg(value: float | None, unit_kg: float | None, name: str = "resolution_kg") -> float | None:
    """A user's weight resolution [kg], checked: None (detect it), or a number in (0, :data:`MAX_RESOLUTION_KG`] kg
    and a whole multiple of the format's unit ``unit_kg`` (a scale cannot read finer than its file can write)."""
    if value is None:
        return None
    GROUP_FILTER["resolution_kg"].check(name, value, note="None: detect it from the file")
    if unit_kg is not None:
        units = value / unit_kg
        if abs(units - round(units)) > 1e-9 * units or round(units) < 1:
            raise ValueError(f"{name} = {value!r} kg is not a whole multiple of the format's weight unit "
                             f"({unit_kg:g} kg): the file cannot hold loads at that resolution")  # fmt: skip
    return float(value)


@dataclass
class ResidueCounts:
    """How many axle loads lie on, one unit below and one unit above a multiple of each candidate step.

    ``unit_kg`` is the format's weight unit (None for loads that are not whole kilograms); ``base_kg`` and
    ``base`` the unit the steps are counted in (1 kg, ``kg``; TMG 2013's pound, 0.45359237 kg, ``lb``).
    :meth:`add` takes the loads of one chunk [kg]; the counts of chunks add up."""

    unit_kg: float | None
    base_kg: float = 1.0
    base: str = "kg"
    n: int = 0
    whole: bool = True
    on: dict[int, int] = field(default_factory=dict)
    below: dict[int, int] = field(default_factory=dict)
    above: dict[int, int] = field(default_factory=dict)

    @property
    def unit(self) -> int:
        """The format's unit in the base unit (1 kg, 100 kg, 1 lb) [base]."""
        return int(round((self.unit_kg or self.base_kg) / self.base_kg))

    def steps(self) -> list[int]:
        """The candidate steps [base]: the multiples of the unit among :data:`WEIGHT_STEPS_KG` (in pounds for a
        file in pounds)."""
        if self.unit_kg is None:
            return []
        return [s for s in WEIGHT_STEPS_KG if s >= self.unit and s % self.unit == 0]

    def merge(self, other: ResidueCounts) -> None:
        """Add the counts of another chunk of the same file."""
        self.n += other.n
        self.whole = self.whole and other.whole
        for mine, theirs in ((self.on, other.on), (self.below, other.below), (self.above, other.above)):
            for s, k in theirs.items():
                mine[s] = mine.get(s, 0) + k

    def add(self, loads_kg: np.ndarray) -> None:
        """Count the loads of one chunk [kg] (NaN: no axle, ignored)."""
        values = np.ascontiguousarray(loads_kg, dtype=float).ravel()
        top = WEIGHT_STEPS_KG[-1]
        histogram = np.zeros(top, np.int64)
        # one compiled pass: the loads counted, whether all are whole units (a load in pounds comes back from
        # kilograms within a rounding of the conversion: 1e-6 lb is far below it), the residues modulo the largest
        # step (every candidate divides it: one histogram gives every count)
        n, whole = _residue_histogram(values, self.base_kg, histogram)
        if not n:
            return
        self.n += n
        if self.unit_kg is None or not self.whole:
            return
        if not whole:  # not whole units: no resolution (a CSV file of decimals)
            self.whole = False
            return
        residue = np.arange(top)
        unit = self.unit
        for s in self.steps():
            r = residue % s
            self.on[s] = self.on.get(s, 0) + int(histogram[r == 0].sum())
            self.below[s] = self.below.get(s, 0) + int(histogram[r == s - unit].sum()) if s > unit else 0
            self.above[s] = self.above.get(s, 0) + int(histogram[r == unit].sum()) if s > 2 * unit else 0


def _chance_log10(share: float, p: float, n: int) -> float:
    """log10 of the Chernoff bound exp(-n KL(share || p)) on a binomial(n, p) reaching ``share`` n (0: no bound)."""
    if share <= p:
        return 0.0
    kl = share * math.log(share / p)  # numerics-ok: one scalar of a decision with a margin, not a stored result
    if share < 1.0:
        kl += (1.0 - share) * math.log((1.0 - share) / (1.0 - p))  # numerics-ok: as above
    return -n * kl / math.log(10.0)  # numerics-ok: as above


@dataclass(frozen=True)
class Resolution:
    """A file's weight resolution: the step in use, where it came from, and the evidence for the detected one.

    ``step_kg`` is the resolution applied (None: none, the loads are not whole kilograms); ``source`` is
    ``detected`` (from the loads), ``format`` (no coarser step supported: the format's unit) or ``set`` (by the
    user; ``detected_kg`` is what detection found). ``on``, ``below``, ``above`` are the loads on, one unit below
    and one unit above a multiple of the detected step, of ``n_loads``; ``chance_log10`` is log10 of the bound on
    that many being near by chance (0 when the detected step is the unit itself)."""

    step_kg: float | None
    source: str
    detected_kg: float | None
    unit_kg: float | None
    n_loads: int
    on: int = 0
    below: int = 0
    above: int = 0
    chance_log10: float = 0.0
    base: str = "kg"
    base_kg: float = 1.0

    def _amount(self, kg: float) -> str:
        """A weight in the file's base unit: '100 kg', or '100 lb (45.359 kg)'."""
        if self.base == "kg":
            return f"{kg:g} kg"
        return f"{kg / self.base_kg:.6g} {self.base} ({kg:.5g} kg)"

    def describe(self) -> str:
        """The resolution in words: the step, where it came from and how sure the detection is."""
        if self.source == "set":
            found = self._amount(self.detected_kg) if self.detected_kg is not None else "none"
            return f"weight resolution {self._amount(self.step_kg)} (set; detected from the file: {found})"
        if self.step_kg is None:
            return "weight resolution: none detected (axle loads not whole kilograms)"
        unit = f"{self.unit_kg / self.base_kg:g} {self.base}"
        step = self._amount(self.step_kg)
        if self.source == "format":
            return f"weight resolution {step} (the format's unit; no coarser step fits the loads)"
        n = max(self.n_loads, 1)
        parts = [f"{100 * self.on / n:.1f} % on one"]
        if self.below:
            parts.append(f"{100 * self.below / n:.1f} % {unit} below")
        if self.above:
            parts.append(f"{100 * self.above / n:.1f} % {unit} above")
        near = self.on + self.below + self.above
        return (
            f"weight resolution {step} (detected: {near:,} of {self.n_loads:,} axle loads within {unit} "
            f"of a multiple of {step}: {', '.join(parts)}; loads of {unit} resolution would do so by "
            f"chance with probability below 1e{math.floor(self.chance_log10):d})"
        )

    def to_dict(self) -> dict:
        """The JSON form: ``step_kg``, ``source``, ``detected_kg``, ``unit_kg``, ``n_loads``, ``on``, ``below``,
        ``above`` (loads) and ``chance_log10``."""
        return {
            "step_kg": self.step_kg, "source": self.source, "detected_kg": self.detected_kg, "unit_kg": self.unit_kg,
            "n_loads": self.n_loads, "on": self.on, "below": self.below, "above": self.above,
            "chance_log10": round(self.chance_log10, 1), "base": self.base,
        }  # fmt: skip


def detect_resolution(counts: ResidueCounts, set_kg: float | None = None) -> Resolution:
    """The resolution the counts support (module text), or ``set_kg`` [kg] if given (the detection kept beside it)."""
    detected = _detect(counts)
    if set_kg is None:
        return detected
    return Resolution(float(set_kg), "set", detected.step_kg, counts.unit_kg, counts.n, detected.on, detected.below,
                      detected.above, detected.chance_log10, counts.base, counts.base_kg)  # fmt: skip


def _detect(counts: ResidueCounts) -> Resolution:
    base = (counts.base, counts.base_kg)
    if counts.unit_kg is None or not counts.whole or not counts.n:
        return Resolution(None, "detected", None, counts.unit_kg, counts.n, 0, 0, 0, 0.0, *base)
    unit = counts.unit
    n = counts.n
    for s in reversed(counts.steps()):
        if s == unit:
            break
        on, below, above = counts.on[s], counts.below[s], counts.above[s]
        tests = [(on / n, unit / s)]
        if s >= TOLERANT_FROM * unit:
            tests.append(((on + below + above) / n, 3 * unit / s))
        for share, p in tests:
            bound = _chance_log10(share, p, n)
            if share >= ON_GRID_SHARE and bound <= math.log10(MAX_CHANCE):  # numerics-ok: a constant's log
                tolerant = len(tests) == 2 and share > on / n
                step = s * counts.base_kg
                return Resolution(step, "detected", step, counts.unit_kg, n, on, below if tolerant else 0,
                                  above if tolerant else 0, bound, *base)  # fmt: skip
    step = unit * counts.base_kg
    return Resolution(step, "format", step, counts.unit_kg, n, n, 0, 0, 0.0, *base)


@njit(cache=True, nogil=True)
def _residue_histogram(values, base_kg, histogram):  # pragma: no cover - compiled
    """(loads that are not NaN, whether every one is a whole number of ``base_kg``); ``histogram`` counts their
    residues modulo its length (when whole)."""
    n = 0
    whole = True
    top = histogram.shape[0]
    for v in values:
        if v != v:
            continue
        n += 1
        if whole:
            b = v / base_kg
            w = math.floor(b + 0.5)
            if abs(b - w) > 1e-6:
                whole = False
            else:
                histogram[int(w) % top] += 1
    return n, whole
