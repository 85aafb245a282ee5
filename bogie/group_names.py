"""The axle groups the project studies, defined once (issue 42 Must 2): a tandem of two axles and a tri-axle of
three, in that order everywhere (the fleet, the weighings' survey, the calibration, the report)."""

from __future__ import annotations

__all__ = ["GROUP_AXLES", "GROUP_NAMES", "GROUP_OF_AXLES"]

#: axles in each axle group [-], by the group's name
GROUP_AXLES: dict[str, int] = {"tandem": 2, "triaxle": 3}
#: the groups' names, in order
GROUP_NAMES: tuple[str, ...] = tuple(GROUP_AXLES)
#: each group's name by its number of axles
GROUP_OF_AXLES: dict[int, str] = {n: name for name, n in GROUP_AXLES.items()}
