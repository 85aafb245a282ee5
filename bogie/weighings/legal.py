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

*Used* by :func:`bogie.weighings.wear.wear_statistics` when it is given no single limit (:func:`group_limits`, each
row's limits from its position and spacing), and so by ``bogie weighings``, the road stage and the report.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from bogie.weighings._records import REL_TOL
from bogie.weighings._tmg import TMG_LAYOUTS
from bogie.weighings.formats import FORMATS, LAYOUTS

__all__ = [
    "EU_DRIVE_AXLE_KG", "EU_NON_DRIVING_AXLE_KG", "EU_SOURCE", "POSITIONS", "eu_axle_limit_kg", "eu_group_limit_kg",
    "group_limits", "spacing_step_m",
]  # fmt: skip

#: a single driving axle's and a single non-driving axle's limit, 96/53/EC Annex I [kg]
EU_DRIVE_AXLE_KG = 11_500.0
EU_NON_DRIVING_AXLE_KG = 10_000.0
#: what :func:`group_limits` judges by when it is given no single limit: one line for a table's or a file's settings
EU_SOURCE = (
    "Directive 96/53/EC Annex I by each group's position and spacing (SI 1998/3111 and SR 1999/258, Schedule 3): "
    "trailer tandem 11/16/18/20 t below 1.0/1.3/1.8 m and beyond, motor-vehicle tandem 11.5/16/18 t, tri-axle 21 t "
    "up to 1.3 m, 24 t beyond; an axle 11.5 t in a drive group, 10 t elsewhere (bogie.weighings.legal)"
)
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


def group_limits(
    groups: pd.DataFrame, legal_group: Mapping[str, float] | None = None, legal_axle: float | None = None,
    spacing_step_m: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """Each row's legal group load and single-axle limit [kg]: ``legal_group`` (a limit per ``group`` size; a size it
    does not name: NaN) and ``legal_axle`` (one limit) when given, a stated single limit; None: the directive's, by
    each row's ``position`` and spacing (:func:`eu_group_limit_kg` of ``spacing_1`` for a tandem, the shorter of
    ``spacing_1`` and ``spacing_2`` for a tri-axle; NaN for another size; :func:`eu_axle_limit_kg`).
    ``spacing_step_m``: the step the file reads spacings at [m] (:func:`spacing_step_m`; 0: as read). A spacing read
    as d may be anything within half a step of it, and every limit grows with the spacing, so a group is judged at
    d + step / 2, in the vehicle's favour: an ASSUMPTION (no source says how a spacing read at a coarse step is to be
    judged; docs/pavement.md), so that a tri-axle 1.31 m apart read at 0.1 m as 1.3 m is given 24 t, not 21 t, and
    a survey's legal figures do not depend on its file's format.

    Raises
    ------
    ValueError
        naming the columns missing for the directive's limits (give single limits, or the columns).
    """
    size = groups["group"].astype(str).to_numpy()
    if legal_group is not None:
        group_kg = pd.Series(size).map(dict(legal_group)).to_numpy(dtype=float, na_value=math.nan)
    else:
        _needs(groups, ("position", "spacing_1", "spacing_2"), "legal_group")
        position = groups["position"].astype(str).to_numpy()
        d1, d2 = (groups[c].to_numpy(dtype=float) + spacing_step_m / 2.0 for c in ("spacing_1", "spacing_2"))
        group_kg = np.full(len(groups), math.nan)
        for name, d in (("tandem", d1), ("triaxle", np.fmin(d1, d2))):
            at = size == name
            if at.any():
                group_kg[at] = eu_group_limit_kg(name, position[at], d[at])
    if legal_axle is not None:
        return group_kg, np.full(len(groups), float(legal_axle))
    _needs(groups, ("position",), "legal_axle")
    return group_kg, eu_axle_limit_kg(groups["position"].astype(str).to_numpy())


def _needs(groups: pd.DataFrame, columns: tuple[str, ...], argument: str) -> None:
    missing = [c for c in columns if c not in groups.columns]
    if missing:
        raise ValueError(
            f"groups has no {', '.join(missing)} column: 96/53/EC's limits go by a group's position and spacing; "
            f"give {argument} (a stated single limit [kg]) or the columns"
        )


def spacing_step_m(fmt: str) -> float:
    """The step format ``fmt`` reads axle spacings at [m]: its spacing field's unit (CASTOR, BeDIT, DITIS and TMG 2001
    0.1 m, MON 1 mm, TMG 2013 0.1 ft; ``docs/weighings.md``); 0 for ``csv`` (spacings as written, in metres)."""
    if fmt in LAYOUTS:
        return next(f.scale for f in LAYOUTS[fmt].axles.fields if f.name == "spacing")
    if fmt in TMG_LAYOUTS:
        return TMG_LAYOUTS[fmt].spacing_unit_m
    if fmt == "csv":
        return 0.0
    raise ValueError(f"format {fmt!r} unknown; allowed: {', '.join(FORMATS)}")
