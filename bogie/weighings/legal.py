"""The legal loads of an axle group by its position and spacing: Directive 96/53/EC Annex I, point 3 (maximum
authorised axle weights), as the UK and Northern Ireland tabulate them (the Road Vehicles (Authorised Weight)
Regulations 1998, SI 1998/3111, Schedule 3; its Northern Ireland twin SR 1999/258, Schedule 3, Tables V and VI,
read for this module). Issue 44 Must 4's table; ``docs/pavement.md``, "Axles above the single-axle limit".

| group | axles' spacing d [m] | limit |
|---|---|---|
| tandem of a trailer or semi-trailer (``trailer``) | <1.0; 1.0-1.3; 1.3-1.8; 1.8 and more | 11; 16; 18; 20 t |
| tandem of a motor vehicle (``drive``, ``steer``) | <1.0; 1.0-1.3; 1.3 and more | 11.5; 16; 18 t |
| tri-axle (any position) | 1.3 or less; over 1.3 | 21; 24 t |
| single driving axle / single non-driving axle | | 11.5 / 10 t |

A tandem's band holds its lower bound (1.0 <= d < 1.3 is 16 t); a tri-axle's 1.3 m is in its lower band (21 t).

*Named choices.* A motor vehicle's tandem 1.3 m or more apart may carry 19 t with twin tyres and road-friendly (air or
equivalent) suspension on the driving axle, or twin tyres on each driving axle and none over 9.5 t: a WIM record does
not say which, so 18 t is taken (Table V's item 4, the limit without either condition). The directive stops a
tri-axle's spacing at 1.4 m; beyond it the UK's Table V caps a tri-axle at 24 t in any circumstances, taken here. A
tri-axle's d is the shortest of its two spacings (Table VI: "the distance between any one axle comprised in the
triaxle and the nearer of the other 2 axles"). A spacing read at a file's resolution equal to a boundary is on the
boundary: the comparisons allow :data:`bogie.weighings._records.REL_TOL` (a conversion that rounds 1.3 m in its last
bits is still 1.3 m).

*Not yet used* by the wear tables, ``bogie weighings`` or the road stage, which hold one limit per size (issue 44
Must 4 is open: ``bogie weighings`` streams its groups through a spill that keeps no position or spacing).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie.weighings._records import REL_TOL

__all__ = ["EU_DRIVE_AXLE_KG", "EU_NON_DRIVING_AXLE_KG", "POSITIONS", "eu_axle_limit_kg", "eu_group_limit_kg"]

#: a single driving axle's and a single non-driving axle's limit, 96/53/EC Annex I [kg]
EU_DRIVE_AXLE_KG = 11_500.0
EU_NON_DRIVING_AXLE_KG = 10_000.0
#: the positions a group can have (``bogie.weighings.groups``' labels)
POSITIONS = ("steer", "drive", "trailer")
#: (spacing below which, limit [kg]) for each kind of tandem, and the limit at and beyond the last bound
_TRAILER_TANDEM = ((1.0, 11_000.0), (1.3, 16_000.0), (1.8, 18_000.0)), 20_000.0
_MOTOR_TANDEM = ((1.0, 11_500.0), (1.3, 16_000.0)), 18_000.0


def _stepped(d: NDArray[np.float64], steps: tuple[tuple[float, float], ...], beyond: float) -> NDArray[np.float64]:
    out = np.full(d.shape, beyond)
    for bound, limit in reversed(steps):  # d < bound (a d on the bound, to REL_TOL, is not below it)
        out = np.where(d < bound * (1.0 - REL_TOL), limit, out)
    return out


def eu_group_limit_kg(group: str, position: ArrayLike, spacing_m: ArrayLike) -> NDArray[np.float64]:
    """The legal load of each group of kind ``group`` (``tandem``, ``triaxle``) at ``position`` (``steer``, ``drive``,
    ``trailer``; one, or one per group) with ``spacing_m`` (a tandem's spacing, a tri-axle's shortest; one per
    group) [kg], from the module docstring's table; NaN where the spacing is not a positive finite number.

    Raises
    ------
    ValueError
        naming the argument, for a group other than a tandem or tri-axle or a position not in :data:`POSITIONS`.
    """
    d = np.atleast_1d(np.asarray(spacing_m, dtype=float))
    where = np.broadcast_to(np.asarray(position, dtype=object), d.shape)
    unknown = sorted({str(p) for p in where.ravel() if p not in POSITIONS})
    if unknown:
        raise ValueError(f"position = {unknown[0]!r}: must be one of {', '.join(POSITIONS)}")
    if group == "tandem":
        motor = np.isin(where, ("steer", "drive"))
        out = np.where(motor, _stepped(d, *_MOTOR_TANDEM), _stepped(d, *_TRAILER_TANDEM))
    elif group == "triaxle":
        out = np.where(d <= 1.3 * (1.0 + REL_TOL), 21_000.0, 24_000.0)
    else:
        raise ValueError(f"group = {group!r}: must be tandem or triaxle (96/53/EC Annex I's groups)")
    valid = np.isfinite(d) & (d > 0.0)
    return np.where(valid, out, math.nan)


def eu_axle_limit_kg(position: Any) -> NDArray[np.float64]:
    """The single-axle limit an axle of a group at ``position`` is held to for the indicator [kg]: a drive group's
    axles are driving axles (11.5 t), the others non-driving (10 t). A steer tandem's axles are taken as
    non-driving."""
    where = np.atleast_1d(np.asarray(position, dtype=object))
    unknown = sorted({str(p) for p in where.ravel() if p not in POSITIONS})
    if unknown:
        raise ValueError(f"position = {unknown[0]!r}: must be one of {', '.join(POSITIONS)}")
    return np.where(where == "drive", EU_DRIVE_AXLE_KG, EU_NON_DRIVING_AXLE_KG).astype(float)
