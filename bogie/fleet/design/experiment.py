"""The design guidance's controlled experiment: which suspension design keeps a fleet's groups within 5 %, and how
much chassis tilt a design tolerates (``docs/design.md``).

It answers two questions:

* a suspension designer's: which combination of bush stiffness, equaliser arm, pad radius (contact movement),
  spring-end friction and the springs' interleaf band keeps ``target_share`` of bogies within 5 % across the
  operating conditions a fleet sees;
* an operator's or a road authority's: for a given bogie, how much chassis tilt (fifth-wheel height mismatch) is
  tolerated before the group leaves the 5 % tolerance.

The experiment is controlled: every design of a group runs over the same ``n_conditions`` operating conditions
(common random numbers: the same sampled chassis tilt, tyre wear of each axle, payload and approach road, drawn
from the fleet's own distributions, :func:`conditions`), by the static protocol. Each condition is run at its own
sampled tilt (the shares within 5 % and 10 % "across the fleet's conditions") and on a grid of tilts from level
outward (:func:`tilt_grid`; the tilt tolerance). The designs (:func:`design_points`): every combination of the
grid's levels with the other factors at today's typical values (the medians of the fleet's distributions,
:func:`typical_design`), that typical design itself, and ``n_space_filling`` designs of a scrambled Sobol' sequence
over all five factors' fleet distributions. The air-sprung group of the same trailer (:func:`bogie.air.from_steel`)
runs over the same conditions as a reference.

:func:`design_experiment` makes the experiment's sample rows, :func:`weigh_designs` weighs them
(:func:`bogie.fleet.weigh_fleet`, any executor), :func:`bogie.fleet.design.analysis.analyse_designs` analyses the
runs and :func:`study_designs` does all three. A failed run is a ``failed`` row, left out of its design's shares and
counted in ``n_failed``. Same arguments and seed, same tables: whatever the executor or the number of workers.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import qmc

from bogie.bogie_file import base_bogie, is_bogie_file
from bogie.fleet.constants import GROUP_AXLES
from bogie.fleet.design.analysis import (
    FACTORS,
    FLEET_SLOT,
    HELD,
    DesignAnalysis,
    DesignError,
    analyse_designs,
    guidance_sentences,
)
from bogie.fleet.design.settings import FACTOR_UNITS, DesignSettings
from bogie.fleet.sampling.distributions import Distribution
from bogie.fleet.sampling.sample import (
    COLUMNS,
    TYRE_WEAR_COLUMNS,
    Fleet,
    design_seed,
    road_seed,
    sensor_seed,
    study_frame,
)
from bogie.fleet.weighing.settings import StaticProtocol
from bogie.fleet.weighing.weigher import CHUNK_ROWS, weigh_fleet
from bogie.settings import check_value

__all__ = [
    "CONDITION_DIMENSIONS", "FACTORS", "FACTOR_UNITS", "FLEET_SLOT", "HELD", "DesignError", "DesignExperiment",
    "DesignSettings", "DesignStudy", "conditions", "design_experiment", "design_points", "design_samples",
    "experiment_runs", "own_design", "study_designs", "tilt_grid", "typical_design", "weigh_designs",
    "weigh_own_design",
]  # fmt: skip

#: the operating conditions, in the order of their design's dimensions (the order is part of the draws)
CONDITION_DIMENSIONS: tuple[str, ...] = ("chassis_tilt", "payload_fraction", *TYRE_WEAR_COLUMNS, "road_class")
#: the experiment's columns beside the sample's: each row's design, condition and slot (:data:`FLEET_SLOT` or the
#: index into the tilt grid)
EXPERIMENT_COLUMNS: tuple[str, ...] = ("design", "condition", "slot")


def _whole(name: str, value: Any, low: int) -> int:
    """``value`` if it is a whole number >= ``low``, else a :class:`DesignError` naming ``name``."""
    return check_value(name, value, low=low, whole=True, error=DesignError)


@dataclass(frozen=True)
class DesignExperiment:
    """The experiment's rows (:func:`design_experiment`).

    Attributes
    ----------
    tilts
        The tilt grid [degree] (:func:`tilt_grid`).
    conditions
        The operating conditions (:func:`conditions`).
    designs
        The designs (:func:`design_points`).
    samples
        The sample rows (:func:`design_samples`): the columns of :data:`bogie.fleet.sampling.sample.COLUMNS`, then
        ``design``, ``condition`` and ``slot``.
    """

    tilts: np.ndarray
    conditions: pd.DataFrame
    designs: pd.DataFrame
    samples: pd.DataFrame


@dataclass(frozen=True)
class DesignStudy:
    """A design study's rows, runs, analysis and sentences (:func:`study_designs`)."""

    experiment: DesignExperiment
    runs: pd.DataFrame
    analysis: DesignAnalysis
    guidance: list[str] = field(default_factory=list)


# ---- the experiment --------------------------------------------------------------------------------------------
def _rank(dist: Distribution, x: float) -> float:
    """The fleet rank F(x) in [0, 1] of value ``x`` under ``dist`` (its inverse CDF inverted on a fine grid)."""
    lo, hi = dist.support
    if hi <= lo:
        return 0.5
    u = np.linspace(0.0, 1.0, 20001)
    q = dist.ppf(np.clip(u, 1e-12, 1.0 - 1e-12))
    return float(np.interp(x, q, u))


def own_design(name: str) -> dict[str, float] | None:
    """The design of a group's base bogie when it is the user's bogie file (issue 45 Must 4): its own
    :data:`FACTORS` and :data:`HELD` [SI], to be weighed beside today's typical design and the best; None for a
    preset (its values are not a design anyone chose: the fleet's distributions replace them). The experiment's
    ``equaliser_arm`` sets every arm to one length; a file whose arms are not all one length keeps its own arms
    (``equaliser_arm`` NaN: :func:`bogie.fleet.sampling.sample.bogie_from_sample` leaves them as they are)."""
    if not is_bogie_file(name):
        return None
    b = base_bogie(name)
    arms = {*b.equaliser_front_arm, *b.equaliser_rear_arm}
    values = {f: float(getattr(b, f)) for f in (*FACTORS, *HELD) if f != "equaliser_arm"}
    return {**values, "equaliser_arm": float(arms.pop()) if len(arms) == 1 else math.nan}


def typical_design(fleet: Fleet) -> dict[str, float]:
    """Today's typical design: the median of each design factor's (and held parameter's) fleet distribution [SI].

    Parameters
    ----------
    fleet
        The fleet (:class:`bogie.fleet.Fleet`).

    Returns
    -------
    dict
        :data:`FACTORS` and :data:`HELD` -> the median [SI].
    """
    return {name: float(fleet.distributions[name].ppf(np.array([0.5]))[0]) for name in (*FACTORS, *HELD)}


def tilt_grid(fleet: Fleet, tilt_step_deg: float) -> np.ndarray:
    """The tilts of the tolerance grid [degree]: from level outward by ``tilt_step_deg`` [degree] to the bounds of
    the fleet's chassis tilt distribution, both ends included.

    Raises
    ------
    DesignError
        If the tilt distribution's range does not include level, or the step is not a finite number > 0.
    """
    step = tilt_step_deg
    check_value("tilt_step_deg", step, "degree", low=0.0, low_open=True, error=DesignError)
    low, high = (math.degrees(v) for v in fleet.distributions["chassis_tilt"].support)
    if not low <= 0.0 <= high:
        raise DesignError(
            f"fleet.distributions['chassis_tilt']: its range [{low:g}, {high:g}] degree must include level "
            "(0 degree): a design study measures the tilt tolerance outward from level"
        )
    up = np.arange(0.0, high - 1e-9, step) if high > 0.0 else np.zeros(0)
    down = -np.arange(step, -low - 1e-9, step) if low < 0.0 else np.zeros(0)
    ends = [v for v in (low, high) if v != 0.0]
    return np.unique(np.round(np.r_[down, up, ends, 0.0], 9))


def conditions(fleet: Fleet, n_conditions: int, seed: int) -> pd.DataFrame:
    """The operating conditions: a Latin hypercube over tilt, payload, each axle's tyre wear and the road class
    (:data:`CONDITION_DIMENSIONS`), mapped through the fleet's distributions, each with its own approach road.

    Parameters
    ----------
    fleet
        The fleet whose distributions the conditions are drawn from.
    n_conditions
        Number of conditions [-], at least 2.
    seed
        Master seed [-] (study ``design``: :func:`bogie.fleet.sampling.sample.design_seed`).

    Returns
    -------
    pandas.DataFrame
        ``condition`` [-], the dimensions [SI; ``chassis_tilt`` in rad], ``road_seed`` and ``sensor_seed`` [-].
    """
    n = _whole("n_conditions", n_conditions, 2)
    seed = _whole("seed", seed, 0)
    u = qmc.LatinHypercube(len(CONDITION_DIMENSIONS), rng=np.random.default_rng(design_seed(seed, "design"))).random(n)
    values: dict[str, Any] = {"condition": np.arange(n, dtype=np.int64)}
    for j, dim in enumerate(CONDITION_DIMENSIONS):
        dist = fleet.distributions["tyre_wear" if dim.startswith("tyre_wear_") else dim]
        values[dim] = dist.ppf(u[:, j])
    values["road_seed"] = np.array([road_seed(seed, "design", i) for i in range(n)], dtype=np.int64)
    values["sensor_seed"] = np.array([sensor_seed(seed, "design", i) for i in range(n)], dtype=np.int64)
    return pd.DataFrame(values)


def _space_filling(fleet: Fleet, k: int, seed: int) -> list[dict[str, float]]:
    """``k`` designs of a scrambled Sobol' sequence over the five factors' fleet distributions [SI]."""
    if k == 0:
        return []
    rng = np.random.default_rng(design_seed(seed, "design-points"))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*balance properties of Sobol.*", category=UserWarning)
        u = qmc.Sobol(len(FACTORS), scramble=True, rng=rng).random(k)
    return [{f: float(fleet.distributions[f].ppf(u[i : i + 1, j])[0]) for j, f in enumerate(FACTORS)} for i in range(k)]


def design_points(fleet: Fleet, settings: DesignSettings, seed: int) -> pd.DataFrame:
    """Every design studied, per group: ``typical``, the ``own`` design of a group whose base bogie is a bogie file
    (:func:`own_design`; always run, even if it equals another), the ``grid`` combinations, the ``space-filling``
    designs and the ``air`` reference; with each factor [SI] and its distance from the typical design in fleet
    ranks [-].

    The distance is sqrt(sum_f (F_f(x_f) - 1/2)^2) over the five factors, F_f the fleet's distribution of factor f:
    how far into the tails of today's fleet a design lies (0: the typical design; a design at a corner of the fleet's
    ranges: sqrt(5) / 2 = 1.12; an own design's arms of several lengths are left out of it). A grid design equal to
    the typical one is not run twice.

    Parameters
    ----------
    fleet
        The fleet: the factors' distributions.
    settings
        The grid, the groups and ``n_space_filling``.
    seed
        Master seed [-] (the Sobol' scrambling: study ``design-points``).

    Returns
    -------
    pandas.DataFrame
        ``design`` (``<group>-<kind>[-<i>]``), ``group``, ``kind``, ``suspension``, :data:`FACTORS`, :data:`HELD`
        [SI] and ``distance`` [-] (NaN for the air reference).
    """
    typ = typical_design(fleet)
    grid_names = list(settings.grid)
    combos = [
        dict(zip(grid_names, levels))
        for levels in np.array(np.meshgrid(*settings.grid.values(), indexing="ij")).reshape(len(grid_names), -1).T
    ]
    space = _space_filling(fleet, _whole("n_space_filling", settings.n_space_filling, 0), _whole("seed", seed, 0))
    rows = []
    for group in settings.groups:
        seen: set[tuple[float, ...]] = set()
        entries = [("typical", typ)]
        own = own_design(fleet.presets[group])
        if own is not None:
            entries.append(("own", own))
        entries += [(f"grid-{i:02d}", {**typ, **{k: float(v) for k, v in c.items()}}) for i, c in enumerate(combos)]
        entries += [(f"space-{i:02d}", {**typ, **p}) for i, p in enumerate(space)]
        for name, values in entries:
            key = tuple(round(values[f], 12) for f in FACTORS)
            if key in seen and name != "own":
                continue
            seen.add(key)
            ranks = [_rank(fleet.distributions[f], values[f]) for f in FACTORS if not math.isnan(values[f])]
            rows.append({
                "design": f"{group}-{name}", "group": group, "kind": name.split("-")[0], "suspension": "steel",
                **{f: values[f] for f in (*FACTORS, *HELD)},
                "distance": float(math.sqrt(sum((r - 0.5) ** 2 for r in ranks))),
            })  # fmt: skip
        rows.append({
            "design": f"{group}-air", "group": group, "kind": "air", "suspension": "air",
            **{f: typ[f] for f in (*FACTORS, *HELD)}, "distance": math.nan,
        })  # fmt: skip
    return pd.DataFrame(rows)


def design_samples(fleet: Fleet, designs: pd.DataFrame, conds: pd.DataFrame, tilts: np.ndarray) -> pd.DataFrame:
    """The sample rows of the experiment: each design at each condition's own tilt (slot :data:`FLEET_SLOT`) and at
    each tilt of ``tilts`` [degree] (slot = its index).

    Returns
    -------
    pandas.DataFrame
        The columns of :data:`bogie.fleet.sampling.sample.COLUMNS` (study ``design``; ``base_id`` is the condition),
        then ``design``, ``condition`` and ``slot`` [-]; design by design, condition by condition, own tilt first.
    """
    n_c, n_t = len(conds), len(tilts)
    per = n_c * (n_t + 1)
    d_idx = np.repeat(np.arange(len(designs)), per)
    c_idx = np.tile(np.repeat(np.arange(n_c), n_t + 1), len(designs))
    slot = np.tile(np.tile(np.r_[FLEET_SLOT, np.arange(n_t)], n_c), len(designs))
    sampled = conds["chassis_tilt"].to_numpy(dtype=float)
    tilt = np.where(slot == FLEET_SLOT, sampled[c_idx], np.radians(tilts)[np.maximum(slot, 0)])
    groups = designs["group"].to_numpy(dtype=object)[d_idx]
    values: dict[str, np.ndarray] = {f: designs[f].to_numpy(dtype=float)[d_idx] for f in (*FACTORS, *HELD)}
    values["chassis_tilt"] = tilt
    for c in ("payload_fraction", *TYRE_WEAR_COLUMNS, "road_class", "road_seed", "sensor_seed"):
        values[c] = conds[c].to_numpy()[c_idx]
    suspension = designs["suspension"].to_numpy(dtype=object)[d_idx]
    frame = study_frame(fleet, "design", groups, values, c_idx.astype(np.int64), suspension)
    frame["design"] = designs["design"].to_numpy(dtype=object)[d_idx]
    frame["condition"] = c_idx.astype(np.int64)
    frame["slot"] = slot.astype(np.int64)
    return frame


def design_experiment(fleet: Fleet, settings: DesignSettings, seed: int) -> DesignExperiment:
    """The experiment's tilt grid, conditions, designs and sample rows, from the fleet, the settings and the master
    seed [-]; ``len(designs) * n_conditions * (len(tilts) + 1)`` rows."""
    if not isinstance(settings, DesignSettings):
        raise DesignError(f"settings = {settings!r}: must be a bogie.fleet.DesignSettings")
    tilts = tilt_grid(fleet, settings.tilt_step_deg)
    conds = conditions(fleet, settings.n_conditions, seed)
    designs = design_points(fleet, settings, seed)
    return DesignExperiment(tilts, conds, designs, design_samples(fleet, designs, conds, tilts))


# ---- the runs --------------------------------------------------------------------------------------------------
def experiment_runs(experiment: DesignExperiment, runs: pd.DataFrame) -> pd.DataFrame:
    """The experiment's runs with each row's ``design``, ``condition`` and ``slot``, matched by ``sample_id``; a
    ``study`` column is dropped (the runs of one study)."""
    runs = runs.drop(columns=[c for c in ("study", *EXPERIMENT_COLUMNS) if c in runs.columns])
    keys = experiment.samples[["sample_id", *EXPERIMENT_COLUMNS]]
    return runs.merge(keys, on="sample_id", how="left", validate="1:1")


def weigh_designs(
    experiment: DesignExperiment,
    static: StaticProtocol,
    executor: Executor | None = None,
    chunk_rows: int = CHUNK_ROWS,
) -> pd.DataFrame:
    """Weigh the experiment's rows on the static weighbridge: its runs (:func:`experiment_runs`).

    Parameters
    ----------
    experiment
        :func:`design_experiment`.
    static
        The static weighbridge's settings.
    executor
        Where to weigh (:func:`bogie.fleet.weigh_fleet`): None in this process, or any
        :class:`concurrent.futures.Executor`; the runs are the same whatever the executor.
    chunk_rows
        Samples per task [-].
    """
    if not isinstance(static, StaticProtocol):
        raise DesignError(f"static = {static!r}: must be a bogie.fleet.StaticProtocol")
    runs = weigh_fleet(experiment.samples[list(COLUMNS)], {"static": static}, executor, chunk_rows)
    return experiment_runs(experiment, runs)


def study_designs(
    fleet: Fleet,
    settings: DesignSettings,
    seed: int,
    static: StaticProtocol,
    executor: Executor | None = None,
) -> DesignStudy:
    """The whole design study: the experiment's rows, weighed, analysed and put in words.

    Parameters
    ----------
    fleet
        The fleet whose distributions the conditions and the typical design come from.
    settings
        The experiment's settings.
    seed
        Master seed [-].
    static
        The static weighbridge's settings.
    executor
        Where to weigh: None in this process, or any :class:`concurrent.futures.Executor`.

    Returns
    -------
    DesignStudy
        The rows, the runs, :func:`~bogie.fleet.design.analysis.analyse_designs`'s tables and
        :func:`~bogie.fleet.design.analysis.guidance_sentences`.
    """
    experiment = design_experiment(fleet, settings, seed)
    runs = weigh_designs(experiment, static, executor)
    analysis = analyse_designs(
        runs, experiment.designs, experiment.tilts, settings.target_share, settings.confidence_level
    )
    text = guidance_sentences(analysis.designs, experiment.tilts, settings.target_share, dict(fleet.presets))
    return DesignStudy(experiment, runs, analysis, text)


def weigh_own_design(
    fleet: Fleet, path: str, settings: DesignSettings, seed: int, static: StaticProtocol,
    executor: Executor | None = None,
) -> DesignStudy:  # fmt: skip
    """A designer's bogie file weighed over ``fleet``'s conditions beside today's typical design, and nothing else
    (``python -m pipeline.own_design FILE``; the design study's own design, :func:`own_design`, in seconds):
    the two designs of the file's group (by its axle count) over the experiment's ``n_conditions`` conditions at
    their own tilts and on the tilt grid, seeded as the study is, so the figures are the study's for those two.

    Raises
    ------
    DesignError
        If ``path`` is not a bogie file, or a file of no group's axle count.
    """
    if not is_bogie_file(path):
        raise DesignError(f"path = {path!r}: must be a bogie file's path (.yaml), docs/bogie-file.md")
    n_axles = base_bogie(path).n_axles
    groups = [g for g, n in GROUP_AXLES.items() if n == n_axles]
    if not groups:
        raise DesignError(f"path = {path!r}: a bogie of {n_axles} axles is no axle group's ({dict(GROUP_AXLES)})")
    group = groups[0]
    mine = dataclasses.replace(fleet, presets={**fleet.presets, group: path})
    spec = dataclasses.replace(settings, groups=(group,), n_space_filling=0)
    tilts = tilt_grid(mine, spec.tilt_step_deg)
    conds = conditions(mine, spec.n_conditions, seed)
    designs = design_points(mine, spec, seed)
    designs = designs[designs["kind"].isin(("typical", "own"))].reset_index(drop=True)
    experiment = DesignExperiment(tilts, conds, designs, design_samples(mine, designs, conds, tilts))
    runs = weigh_designs(experiment, static, executor)
    analysis = analyse_designs(runs, designs, tilts, spec.target_share, spec.confidence_level)
    text = guidance_sentences(analysis.designs, tilts, spec.target_share, {group: path})
    return DesignStudy(experiment, runs, analysis, text)
