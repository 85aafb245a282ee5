"""The COST 323 class a whole WIM system reaches: its readings held against static weights of the same vehicles.

COST 323 (1999) classes a WIM system by a test: statically weighed vehicles pass over the site, and for each
criterion the relative errors ``R / W - 1`` of the results must lie within +-delta (:data:`COST323_TOLERANCES`) in
at least a share ``pi0`` of them. The specification sets ``pi0`` from the test conditions and the number of runs;
neither its formula nor its table could be read here (``docs/wim-site.md``), so ``required_share`` is an argument
(0.95, the conventional two-sided level, is an ASSUMPTION, not COST 323's value) and every criterion's share is
returned, so that a reader can apply their own ``pi0``.

The criteria a bogie's group gives (a simulated group is one trailer bogie, no whole vehicle): ``group`` (the
group's load) and ``axle_of_group`` (each of its axles). The class reached is the narrowest of the table whose every
criterion holds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from bogie.road.wim import COST323_TOLERANCES
from bogie.settings import check_value

__all__ = ["CRITERIA", "REQUIRED_SHARE", "ClassTest", "class_test", "relative_errors"]

#: the share of results a criterion must hold within +-delta: an ASSUMPTION (the conventional two-sided level), not
#: COST 323's pi0, which depends on the test conditions and the number of runs and could not be read here
REQUIRED_SHARE = 0.95
#: the criteria of a group of axles weighed alone, as COST 323 names them
CRITERIA: tuple[str, ...] = ("group", "axle_of_group")


def relative_errors(static: ArrayLike, wim: ArrayLike) -> dict[str, np.ndarray]:
    """Each criterion's relative errors ``R / W - 1`` [-]: ``group`` one per group (the sums of its axles),
    ``axle_of_group`` one per axle present.

    Parameters
    ----------
    static, wim
        (groups, axles) static loads ``W`` and WIM readings ``R`` of the same groups, in one unit; NaN for an axle a
        group does not have (in both).

    Raises
    ------
    ValueError
        If the shapes differ, an axle is present in one and not the other, or a static load is not positive.
    """
    w, r = np.atleast_2d(np.asarray(static, dtype=float)), np.atleast_2d(np.asarray(wim, dtype=float))
    if w.shape != r.shape or w.ndim != 2:
        raise ValueError(f"static {w.shape} and wim {r.shape}: must be arrays of the same (groups, axles) shape")
    present = np.isfinite(w)
    if not np.array_equal(present, np.isfinite(r)):
        raise ValueError("static and wim: an axle is present (finite) in one and not in the other")
    if np.any(w[present] <= 0.0):
        raise ValueError("static: every load present must be > 0")
    group = np.nansum(r, axis=1) / np.nansum(w, axis=1) - 1.0
    return {"group": group, "axle_of_group": r[present] / w[present] - 1.0}


@dataclass(frozen=True)
class ClassTest:
    """The outcome of :func:`class_test`.

    Attributes
    ----------
    shares
        One row per class (the index, :data:`COST323_TOLERANCES`' order) and a column per criterion: the share of
        results within +-delta [-].
    errors
        One row per criterion: ``n``, ``mean`` and ``sd`` of its relative errors [-].
    required_share
        The share each criterion must reach [-].
    reached
        The narrowest class whose every criterion reaches ``required_share``; None if no class does.
    """

    shares: pd.DataFrame
    errors: pd.DataFrame
    required_share: float
    reached: str | None


def class_test(
    static: ArrayLike, wim: ArrayLike, required_share: float = REQUIRED_SHARE, criteria: Sequence[str] = CRITERIA
) -> ClassTest:
    """The COST 323 class the readings ``wim`` of groups reach against their static loads ``static``.

    Parameters
    ----------
    static, wim
        As :func:`relative_errors`.
    required_share
        ``pi0``, the share of results each criterion must hold within +-delta [-], in (0, 1]; 0.95 is an assumption
        (module docstring).
    criteria
        Which criteria the class needs (:data:`CRITERIA`).

    Raises
    ------
    ValueError
        As :func:`relative_errors`; if ``required_share`` is not in (0, 1], a criterion is unknown, or there is no
        group.
    """
    share = required_share
    check_value("required_share", share, "-", low=0.0, low_open=True, high=1.0)
    unknown = [c for c in criteria if c not in CRITERIA]
    if unknown or not criteria:
        raise ValueError(f"criteria = {list(criteria)!r}: must be one or more of {', '.join(CRITERIA)}")
    errors = relative_errors(static, wim)
    if len(errors["group"]) == 0:
        raise ValueError("static, wim: no group to test")
    shares = pd.DataFrame(
        {c: [float(np.mean(np.abs(errors[c]) <= tol[c] / 100.0)) for tol in COST323_TOLERANCES.values()]
         for c in criteria},
        index=pd.Index(list(COST323_TOLERANCES), name="accuracy_class"),
    )  # fmt: skip
    summary = pd.DataFrame(
        {"n": [len(errors[c]) for c in criteria], "mean": [float(np.mean(errors[c])) for c in criteria],
         "sd": [float(np.std(errors[c], ddof=1)) if len(errors[c]) > 1 else float("nan") for c in criteria]},
        index=pd.Index(list(criteria), name="criterion"),
    )  # fmt: skip
    met = shares.index[(shares >= share).all(axis=1)]
    return ClassTest(shares, summary, float(share), str(met[0]) if len(met) else None)
