"""The design guidance's settings (``docs/design.md``), in a module of their own so that what only reads settings
(params.yaml's loader) does not import the experiment: the design factors and their units, the settings class and
its error. :mod:`bogie.fleet.design.experiment` and :mod:`bogie.fleet.design.analysis` re-export them."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bogie.fleet.constants import GROUP_AXLES
from bogie.settings import FrozenMap, check_settings, check_value, setting

__all__ = ["FACTORS", "FACTOR_UNITS", "DesignError", "DesignSettings"]

#: the design factors, SI sample columns: bush stiffness [N m/rad], equaliser arm [m], pad radius [m], spring-end
#: friction coefficient [-] and the springs' interleaf friction band [N], in the order of ``design.json``'s keys
FACTORS: tuple[str, ...] = (
    "bush_stiffness",
    "equaliser_arm",
    "contact_roll_radius",
    "friction_coefficient",
    "spring_friction_band",
)
#: unit of each design factor's levels (SI)
FACTOR_UNITS: dict[str, str] = {
    "bush_stiffness": "N m/rad", "equaliser_arm": "m", "contact_roll_radius": "m", "friction_coefficient": "-",
    "spring_friction_band": "N",
}  # fmt: skip


class DesignError(ValueError):
    """The design study cannot be set up from these arguments (the message names the argument, its value, the
    allowed range and the unit)."""


def _levels(factor: Any, levels: Any) -> tuple[float, ...]:
    """A grid factor's levels as floats [SI], refused with a :class:`DesignError` naming what is wrong."""
    if factor not in FACTORS:
        raise DesignError(f"grid: {factor!r} is not a design factor; allowed: {', '.join(FACTORS)}")
    where, unit = f"grid[{factor!r}] = {levels!r}", FACTOR_UNITS[factor]
    if isinstance(levels, (str, bytes)) or not isinstance(levels, Sequence | np.ndarray) or len(levels) == 0:
        raise DesignError(f"{where}: must be a sequence of one or more levels, in {unit}")
    for i, v in enumerate(levels):
        check_value(f"grid[{factor!r}][{i}]", v, unit, low=0.0, error=DesignError)
    out = tuple(float(v) for v in levels)
    if len(set(out)) != len(out):
        raise DesignError(f"{where}: lists a level twice")
    return out


@dataclass(frozen=True)
class DesignSettings:
    """The controlled experiment's settings (``docs/design.md``), checked when made; each number setting's unit,
    range and doc are declared with it (:mod:`bogie.settings`).

    ``grid`` maps a design factor (:data:`FACTORS`) to its levels [SI: N m/rad, m, m, -, N]: the representative
    designs are every combination, the other factors at today's typical values (the fleet distributions' medians);
    the order of the factors and levels is the order of the designs. ``groups`` are the axle groups whose designs
    are studied (``tandem``, ``triaxle``); each also runs its air-sprung group.

    Raises
    ------
    DesignError
        Naming the setting, its value, the allowed values and the unit.
    """

    grid: Mapping[str, Sequence[float]]
    groups: tuple[str, ...] = tuple(GROUP_AXLES)
    n_conditions: int = setting(
        20, unit="-", low=2, whole=True,
        doc="Operating conditions (tilt, tyre wear, payload, approach road) every design runs over.",
    )  # fmt: skip
    tilt_step_deg: float = setting(
        0.5, unit="degree", low=0.0, low_open=True,
        doc="Step of the chassis-tilt grid, outward from level over the tilt distribution's bounds.",
    )  # fmt: skip
    n_space_filling: int = setting(
        6, unit="-", low=0, whole=True,
        doc="Further designs per group, a scrambled Sobol' design over all five factors' fleet distributions.",
    )  # fmt: skip
    target_share: float = setting(
        0.95, unit="-", low=0.0, high=1.0, low_open=True, high_open=True,
        doc="The share of bogies within 5 % a design must keep.",
    )  # fmt: skip
    confidence_level: float = setting(
        0.95, unit="-", low=0.0, high=1.0, low_open=True, high_open=True, doc="Of the shares' Wilson intervals."
    )

    def __post_init__(self) -> None:
        groups = (self.groups,) if isinstance(self.groups, str) else tuple(self.groups)
        if not groups or len(set(groups)) != len(groups) or not set(groups) <= set(GROUP_AXLES):
            raise DesignError(
                f"groups = {self.groups!r}: must be one or more distinct axle groups among {', '.join(GROUP_AXLES)}"
            )
        object.__setattr__(self, "groups", groups)
        if not isinstance(self.grid, Mapping) or not self.grid:
            raise DesignError(f"grid = {self.grid!r}: must map one or more of {', '.join(FACTORS)} to their levels")
        object.__setattr__(self, "grid", FrozenMap({f: _levels(f, v) for f, v in self.grid.items()}))
        check_settings(self, DesignError)
