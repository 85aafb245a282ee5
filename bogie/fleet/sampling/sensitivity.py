"""The Sobol' sensitivity design of a fleet's quantities: SALib's Saltelli sampling around one axle group's base bogie.

:func:`sensitivity_problem` is the SALib problem of the chosen factors over the unit hypercube (tyre wear one SALib
group of one variable per axle); :func:`sensitivity_design` is its Saltelli design, N (G + 2) rows for G factors,
each factor mapped through the fleet's own distribution and every other quantity held at its median, one row per
bogie with the columns of :data:`~bogie.fleet.sampling.sample.COLUMNS` (what :func:`bogie.fleet.weigh_fleet`
weighs). Pass the same problem to ``SALib.analyze.sobol.analyze`` with ``calc_second_order=False``
(``docs/sensitivity.md``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.constants import GROUP_AXLES
from bogie.fleet.sampling.sample import (
    FLEET_QUANTITIES,
    SCALAR_QUANTITIES,
    TYRE_WEAR_COLUMNS,
    Fleet,
    FleetError,
    study_frame,
)
from bogie.fleet.sampling.seeds import design_seed, road_seed, sensor_seed
from bogie.settings import Setting, check_value

__all__ = ["SENSITIVITY_FACTORS", "sensitivity_design", "sensitivity_problem"]

#: the quantities a Sobol' factor may be: every numeric quantity of a :class:`~bogie.fleet.sampling.sample.Fleet`
#: (:data:`~bogie.fleet.sampling.sample.FLEET_QUANTITIES` but the categorical ``road_class``); ``tyre_wear`` stands
#: for every axle's wear, one SALib group
SENSITIVITY_FACTORS: tuple[str, ...] = tuple(q for q in FLEET_QUANTITIES if q != "road_class")
#: the study's name: its rows' ``study`` column and the streams of its design, road and sensor seeds
_STUDY = "sensitivity"


def _factors(factors: Sequence[str]) -> tuple[str, ...]:
    """``factors`` as a tuple, else :class:`FleetError` naming the bad one, what is allowed and why."""
    try:
        names = () if isinstance(factors, str) else tuple(factors)
    except TypeError:
        names = ()
    allowed = ", ".join(SENSITIVITY_FACTORS)
    if not names:
        raise FleetError(f"factors = {factors!r} is not a list of factor names: must be at least one of {allowed}")
    for i, name in enumerate(names):
        if name == "road_class":
            raise FleetError(
                f"factors[{i}] = 'road_class' is categorical (ISO 8608 labels): must be one of {allowed} (a Sobol' "
                "factor is a numeric quantity)"
            )
        Setting("-", "", choices=SENSITIVITY_FACTORS).check(f"factors[{i}]", name, FleetError)
        if name in names[:i]:
            raise FleetError(f"factors[{i}] = {name!r} is listed twice: must be each factor once")
    return names


def _group(group: str) -> str:
    Setting("-", "", choices=tuple(GROUP_AXLES)).check("group", group, FleetError)
    return group


def sensitivity_problem(factors: Sequence[str], group: str) -> dict[str, Any]:
    """The SALib problem of a Sobol' sensitivity design, over the unit hypercube.

    One variable per factor, except tyre wear, which has one variable per axle of ``group`` (named ``tyre_wear_<i>``,
    the columns of :data:`~bogie.fleet.sampling.sample.TYRE_WEAR_COLUMNS`) gathered in the SALib group
    ``tyre_wear``: one index for the wear of every axle.

    Parameters
    ----------
    factors
        The perturbed quantities, in order: names of :data:`SENSITIVITY_FACTORS`, each once, at least one.
    group
        The axle group whose base bogie the design perturbs: ``tandem`` or ``triaxle``
        (:data:`bogie.fleet.constants.GROUP_AXLES`).

    Returns
    -------
    dict
        ``num_vars``, ``names``, ``bounds`` (all [0, 1]) and ``groups`` (one per factor, in the order of
        ``factors``). A new dict at every call: SALib adds keys to the one it is given.

    Raises
    ------
    FleetError
        A factor or a group that is not allowed, naming it and what is.
    """
    n_axles = GROUP_AXLES[_group(group)]
    names: list[str] = []
    groups: list[str] = []
    for factor in _factors(factors):
        members = list(TYRE_WEAR_COLUMNS[:n_axles]) if factor == "tyre_wear" else [factor]
        names += members
        groups += [factor] * len(members)
    return {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names), "groups": groups}


def _short(value: Any) -> str:
    """``value``'s repr, cut to 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _check_fleet(fleet: Fleet, group: str) -> None:
    """Refuse a fleet that cannot give ``group``'s base bogie (a group outside its axle mix was not checked)."""
    if not isinstance(fleet, Fleet):
        raise FleetError(f"fleet = {_short(fleet)} is a {type(fleet).__name__}: must be a bogie.fleet.Fleet")
    if group in fleet.axle_mix:
        return  # the Fleet checked its preset and legal load
    try:
        dataclasses.replace(fleet, axle_mix={group: 1.0}, suspension_mix={group: {"steel": 1.0}})
    except FleetError as exc:
        raise FleetError(f"fleet, for the design's group {group!r} (not in its axle_mix): {exc}") from None


def sensitivity_design(fleet: Fleet, factors: Sequence[str], group: str, base_size: int, seed: int) -> pd.DataFrame:
    """The Sobol' sensitivity design: SALib's Saltelli sampling of the factors, N (G + 2) rows.

    The base bogie is ``group``'s base bogie of ``fleet`` at its design payload, steel-sprung; each factor is mapped
    from SALib's unit design (:func:`sensitivity_problem`, scrambled Sobol', ``calc_second_order=False``) through
    its distribution in ``fleet``, and every other quantity is held at its distribution's median. All rows share
    one approach road, ``road_seed(seed, "sensitivity", 0)``: the road is a non-factor too, and a road per row would
    add variance that no factor explains. So do the WIM sensor's errors, ``sensor_seed(seed, "sensitivity", 0)``.

    Parameters
    ----------
    fleet
        What varies between the bogies and how (:class:`~bogie.fleet.sampling.sample.Fleet`): the factors'
        distributions and the other quantities' medians (SI), ``group``'s preset and legal group load.
    factors
        The perturbed quantities (:func:`sensitivity_problem`): names of :data:`SENSITIVITY_FACTORS`, each once.
    group
        The axle group of every row: ``tandem`` or ``triaxle``.
    base_size
        Saltelli's base sample size N [-]: a power of 2, at least 2 (Sobol' sequences balance only then).
    seed
        Master seed [-], a whole number >= 0: the design's scrambling (``design_seed(seed, "sensitivity")``), the
        road and the sensor come from it.

    Returns
    -------
    pandas.DataFrame
        N (G + 2) rows in SALib's order (``sample_id``; G = ``len(factors)``), the columns of
        :data:`~bogie.fleet.sampling.sample.COLUMNS`, SI; ``study`` is ``sensitivity`` and ``base_id`` the Saltelli
        base row a row belongs to (blocks of G + 2 consecutive rows: A, A with factor k from B, ..., B).

    Raises
    ------
    FleetError
        A bad argument, naming it, its value and what is allowed.
    """
    try:  # here: the simulate stage's workers need none of it, and the library's core does not depend on it
        from SALib.sample import sobol
    except ImportError:
        raise ImportError(
            "sensitivity_design needs SALib (Saltelli sampling), an optional dependency of bogie: "
            "pip install 'bogie[sensitivity]' (or the pipeline's extra)"
        ) from None

    problem = sensitivity_problem(factors, group)
    _check_fleet(fleet, group)
    n_base = check_value("base_size", base_size, whole=True, low=2, error=FleetError)
    if n_base & (n_base - 1):
        raise FleetError(
            f"base_size = {base_size!r} is not a power of 2: must be a whole number >= 2, a power of 2 such as 512 - "
            "(Sobol' sequences balance only then)"
        )
    seed = check_value("seed", seed, whole=True, low=0, error=FleetError)
    u = sobol.sample(problem, n_base, calc_second_order=False, scramble=True, seed=design_seed(seed, _STUDY))
    values = _design_values(fleet, problem["names"], u, seed)
    n_groups = len(dict.fromkeys(problem["groups"]))
    return study_frame(fleet, _STUDY, np.full(len(u), group, dtype=object), values, np.arange(len(u)) // (n_groups + 2))


def _design_values(fleet: Fleet, names: list[str], u: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    """Each sampled column of the design's rows: the factors' variables ``names`` mapped from the unit design ``u``
    through their distributions, every other quantity at its median, one road seed and one sensor seed."""
    n = len(u)
    dists = fleet.distributions
    values: dict[str, np.ndarray] = {}
    for name in (*SCALAR_QUANTITIES, "road_class"):
        values[name] = np.full(n, dists[name].quantile(0.5), dtype=object if name == "road_class" else float)
    for c in TYRE_WEAR_COLUMNS:
        values[c] = np.full(n, dists["tyre_wear"].quantile(0.5))
    for j, name in enumerate(names):
        values[name] = dists["tyre_wear" if name.startswith("tyre_wear_") else name].ppf(u[:, j])
    values["road_seed"] = np.full(n, road_seed(seed, _STUDY, 0), dtype=np.int64)
    values["sensor_seed"] = np.full(n, sensor_seed(seed, _STUDY, 0), dtype=np.int64)
    return values
