"""A fleet of trailer axle groups as a table of samples: one row per bogie, every parameter in SI.

:class:`Fleet` says what varies between the bogies and how (one distribution per sampled quantity, the share of
each axle group and suspension, each group's preset and legal load); :func:`sample_fleet` draws ``n_bogies`` of them
from one seeded Latin hypercube or scrambled Sobol' design of the unit hypercube, each dimension mapped through its
distribution's inverse CDF, so the design's stratification carries over to every marginal; :func:`bogie_from_sample`
turns a row back into the bogie it describes. The rows are what :func:`bogie.fleet.weigh_fleet` weighs.

Seeds: every random stream is a :class:`numpy.random.SeedSequence` of the master ``seed`` with the spawn key
(study, stream[, sample_id]), so each study, each stream and each bogie's road is independent of the others and
of row order, chunking and the number of workers.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie import air
from bogie.air import AirBogie
from bogie.bogie_file import base_bogie, base_fields, is_bogie_file
from bogie.fleet.constants import GROUP_AXLES, MAX_AXLES, SUSPENSIONS
from bogie.fleet.sampling.distributions import Choice, Distribution
from bogie.fleet.sampling.seeds import (
    design_seed,
    road_seed,
    sensor_seed,
    suspension_draw,
    suspensions,
)
from bogie.params import (
    GRAVITY,
    INHIBITORS,
    Bogie,
    design_spring_loads,
    equaliser_arm_changes,
    with_equaliser_arms,
)
from bogie.presets import PRESETS
from bogie.road import ISO8608_CLASSES
from bogie.settings import MapSetting, Setting, declared, documented, map_setting, setting

__all__ = [
    "COLUMNS", "FLEET_QUANTITIES", "SAMPLINGS", "SAMPLING_SETTINGS", "SCALAR_QUANTITIES", "TYRE_WEAR_COLUMNS",
    "VARIANTS", "Fleet", "FleetError", "bogie_from_sample", "design_bogie", "design_seed", "road_seed", "sample_fleet",
    "sensor_seed", "study_frame", "suspension_draw", "suspensions",
]  # fmt: skip

#: ablation variants: the baseline, each inhibitor switched off alone, and all five off
VARIANTS: tuple[str, ...] = ("baseline", *INHIBITORS, "all")

#: radius of gyration of the sprung mass about its centre of gravity in pitch [m]
PITCH_RADIUS_OF_GYRATION = 3.5

TYRE_WEAR_COLUMNS: tuple[str, ...] = tuple(f"tyre_wear_{i + 1}" for i in range(MAX_AXLES))

#: the sampled quantities with one value per bogie, in the order of the fleet design's dimensions
SCALAR_QUANTITIES: tuple[str, ...] = (
    "bush_stiffness",
    "bush_damping",
    "friction_coefficient",
    "contact_roll_radius",
    "chassis_tilt",
    "payload_fraction",
    "equaliser_arm",
    "spring_friction_band",
    "spring_friction_decay",
)

#: dimensions of the fleet design, in order; the order is part of the design (changing it changes the draws)
_FLEET_DIMENSIONS: tuple[str, ...] = ("group", *SCALAR_QUANTITIES, *TYRE_WEAR_COLUMNS, "road_class")

#: column -> dtype of every study table, in order; units in the README of data/samples
COLUMNS: dict[str, str] = {
    "sample_id": "int64",  # row index within the study [-]
    "base_id": "int64",  # fleet: sample_id; ablation: the fleet sample_id; sensitivity: Saltelli base row [-]
    "study": "str",
    "group": "str",  # tandem | triaxle
    "n_axles": "int64",
    "preset": "str",  # base bogie of the group: a bogie.params preset's name or a bogie file's path
    "variant": "str",  # baseline, or the inhibitor switched off (ablation)
    "suspension": "str",  # steel (leaf springs, equalisers) | air (connected air springs: bogie.air)
    "bush_stiffness": "float64",  # [N m/rad]
    "bush_damping": "float64",  # [N m s/rad]
    "friction_coefficient": "float64",  # [-]
    "contact_roll_radius": "float64",  # [m]
    **{c: "float64" for c in TYRE_WEAR_COLUMNS},  # [m], 0 for an axle the group does not have
    "chassis_tilt": "float64",  # nose up positive [rad]
    "payload_fraction": "float64",  # of the legal group load [-]
    "equaliser_arm": "float64",  # length of every equaliser arm, axle spacing kept [m]
    "spring_friction_band": "float64",  # interleaf friction band of every leaf spring, half-width [N]
    "spring_friction_decay": "float64",  # its decay length [m]
    "road_class": "str",  # ISO 8608 class
    "road_seed": "int64",  # seed of the approach road's random profile [-]
    "sensor_seed": "int64",  # seed of the WIM sensor's errors on the axle readings [-]
    "legal_group_load": "float64",  # both sides [N]
    "payload_mass": "float64",  # sprung mass per side of the fully laden design bogie [kg]
    "chassis_pitch_inertia": "float64",  # [kg m^2]
}

#: the quantities a :class:`Fleet` gives a distribution of, SI: ``bush_stiffness`` [N m/rad], ``bush_damping``
#: [N m s/rad], ``friction_coefficient`` [-], ``contact_roll_radius`` [m], ``chassis_tilt`` (nose up +) [rad],
#: ``payload_fraction`` (of the legal group load) [-], ``equaliser_arm`` [m], ``spring_friction_band`` (half-width)
#: [N], ``spring_friction_decay`` [m], ``tyre_wear`` (loss of tyre radius, drawn per axle) [m] and ``road_class``
#: (ISO 8608 class of the approach road, a :class:`~bogie.fleet.sampling.distributions.Choice` of labels)
FLEET_QUANTITIES: tuple[str, ...] = (*SCALAR_QUANTITIES, "tyre_wear", "road_class")

#: the uniform designs of the unit hypercube: Latin hypercube, scrambled Sobol' (scipy.stats.qmc)
SAMPLINGS: tuple[str, ...] = ("lhs", "sobol")
#: :func:`sample_fleet`'s arguments other than the fleet, declared once (:mod:`bogie.settings`): params.yaml's
#: ``fleet.n_bogies`` and ``fleet.sampling`` are built from these
SAMPLING_SETTINGS: dict[str, Setting] = {
    "n_bogies": Setting("-", "Number of bogies.", low=1, whole=True),
    "sampling": Setting(
        "-", "``lhs`` (Latin hypercube) or ``sobol`` (scrambled Sobol'), both from scipy.stats.qmc.", choices=SAMPLINGS
    ),
    "seed": Setting("-", "Master seed: the design, each bogie's road, WIM sensor errors and suspension draw.", low=0,
                    whole=True),
}  # fmt: skip
#: a fraction of a mix [-]
_FRACTION = Setting("-", "A fraction.", low=0.0, high=1.0)


class FleetError(ValueError):
    """A fleet that cannot be sampled: the message names the argument, its value and what is allowed."""


def _fractions(name: str, mix: Mapping[str, Any], spec: MapSetting) -> dict[str, float]:
    """A mix checked by its declaration (keys among ``spec.keys``, each fraction in [0, 1], summing to 1), as floats."""
    spec.check(name, mix, FleetError)
    return {str(k): float(v) for k, v in mix.items()}


def _all_steel() -> dict[str, dict[str, float]]:
    return {g: {"steel": 1.0, "air": 0.0} for g in GROUP_AXLES}


#: a group's suspension mix: the fractions of steel-equalised and air-sprung groups [-]
_SUSPENSION_SHARES = MapSetting(
    "-", "One axle group's fractions of steel-equalised and air-sprung groups, summing to 1.", SUSPENSIONS, _FRACTION,
    total=1.0,
)  # fmt: skip


@documented
@dataclass(frozen=True)
class Fleet:
    """What varies between the bogies of a fleet, and how: the input of :func:`sample_fleet`.

    Parameters
    ----------
    distributions
        Quantity name -> its distribution, in SI units: every name of :data:`FLEET_QUANTITIES`, each a
        :class:`~bogie.fleet.sampling.distributions.Distribution` (``road_class`` a ``Choice`` of ISO 8608 labels). A
        sample outside a quantity's physical range (:mod:`bogie.params`) is not refused here: its weighings are
        rows with ``status = "failed"`` and the reason.
    """

    # every field but the distributions declared once here, its unit, range and doc as data (bogie.settings): the
    # docstring's other parameters and params.yaml's fleet: keys are made from these
    distributions: Mapping[str, Distribution]
    axle_mix: Mapping[str, float] = map_setting(
        unit="-", doc="Fraction of the fleet in each axle group, summing to 1.", keys=GROUP_AXLES, entry=_FRACTION,
        total=1.0,
    )  # fmt: skip
    presets: Mapping[str, str] = map_setting(
        unit="-", keys=GROUP_AXLES,
        doc="Each group's base bogie, with the group's number of axles: a bogie.presets.PRESETS name or the path of a "
        "bogie file (bogie.bogie_file.load_bogie, docs/bogie-file.md; relative to the working directory, which must be "
        "the same for every process that rebuilds a bogie from a sample row), held as given in the sample rows' preset "
        "column.",
    )  # fmt: skip
    legal_group_load: Mapping[str, float] = map_setting(
        unit="N", keys=GROUP_AXLES, entry=Setting("N", "A group's legal load.", low=0.0, low_open=True),
        doc="Legal load of each group, both sides together: its design payload (design_bogie).",
    )  # fmt: skip
    legal_axle_load: float | None = setting(
        None, unit="N", low=0.0, low_open=True,
        doc="Legal load of a single axle, both sides together (the survey's over-limit counts); None: no limit given.",
    )  # fmt: skip
    suspension_mix: Mapping[str, Mapping[str, float]] = map_setting(
        unit="-", keys=GROUP_AXLES, entry=_SUSPENSION_SHARES, default_factory=_all_steel,
        doc="Per axle group, the fraction of its groups of each suspension (steel: leaf springs and equalisers, air: "
        "connected air springs, bogie.air), summing to 1. Default: every group steel, the bogies the reference's "
        "inhibitors belong to.",
    )  # fmt: skip

    def __post_init__(self) -> None:
        missing = [q for q in FLEET_QUANTITIES if q not in self.distributions]
        unknown = [q for q in self.distributions if q not in FLEET_QUANTITIES]
        if missing or unknown:
            raise FleetError(
                f"distributions: {'missing ' + ', '.join(missing) if missing else ''}"
                f"{'; ' if missing and unknown else ''}{'unknown ' + ', '.join(unknown) if unknown else ''}; "
                f"needed: one distribution of each of {', '.join(FLEET_QUANTITIES)} (SI units)"
            )
        for name, dist in self.distributions.items():
            if not isinstance(dist, Distribution):
                raise FleetError(f"distributions[{name!r}] = {dist!r}: must be a bogie.fleet distribution")
        road = self.distributions["road_class"]
        classes = road.values if isinstance(road, Choice) else (getattr(road, "value", None),)
        if not all(c in ISO8608_CLASSES for c in classes):
            raise FleetError(
                f"distributions['road_class'] = {road!r}: must be a Choice or Constant of ISO 8608 classes "
                f"({', '.join(ISO8608_CLASSES)})"
            )
        specs = declared(Fleet)
        mix = _fractions("axle_mix", self.axle_mix, specs["axle_mix"])
        # the groups in a fixed order, fewest axles first: the order is part of the design
        object.__setattr__(self, "axle_mix", {g: mix[g] for g in GROUP_AXLES if g in mix})
        for name, table in (("presets", self.presets), ("legal_group_load", self.legal_group_load)):
            lacking = [g for g in self.axle_mix if g not in table]
            if lacking:
                raise FleetError(f"{name} = {dict(table)!r}: a value is needed for {', '.join(lacking)}")
        for name in ("presets", "legal_group_load", "legal_axle_load"):
            specs[name].check(name, getattr(self, name), FleetError)
        for g in self.axle_mix:
            _check_preset(g, self.presets[g])
        if g_missing := [g for g in self.axle_mix if g not in self.suspension_mix]:
            raise FleetError(f"suspension_mix = {dict(self.suspension_mix)!r}: a mix is needed for {g_missing[0]}")
        specs["suspension_mix"].check("suspension_mix", self.suspension_mix, FleetError)
        suspension = {g: {str(k): float(v) for k, v in self.suspension_mix[g].items()} for g in self.axle_mix}
        for shares in suspension.values():
            shares.setdefault("air", 0.0)
        object.__setattr__(self, "suspension_mix", suspension)


def _check_preset(group: str, name: str) -> None:
    """A group's preset: a preset's name or a readable bogie file with the group's number of axles."""
    if name not in PRESETS and not is_bogie_file(name):
        raise FleetError(
            f"presets[{group!r}] = {name!r}: must be one of {', '.join(PRESETS)} or a bogie file's path (.yaml)"
        )
    try:
        n_axles = base_bogie(name).n_axles
    except ValueError as exc:
        raise FleetError(f"presets[{group!r}] = {name!r}: {exc}") from None
    if n_axles != GROUP_AXLES[group]:
        raise FleetError(
            f"presets[{group!r}] = {name!r} has {n_axles} axles but a {group} has {GROUP_AXLES[group]} [-]"
        )


# ---- the design bogie ------------------------------------------------------------------------------------------
def design_bogie(preset_name: str, legal_group_load: float) -> Bogie:
    """The base bogie (a preset or a bogie file) with the sprung mass that makes its fully laden design load the legal
    group load.

    Per side: (sprung weight on the bogie) + n m_axle g = legal_group_load / 2. The sprung weight on the bogie,
    m g x_cg / x_b (:func:`bogie.params.design_spring_loads`), is linear in the payload mass m, so one evaluation on
    the preset gives the exact m. The pitch inertia is m (x_cg^2 + r^2) with r = :data:`PITCH_RADIUS_OF_GYRATION`.

    Parameters
    ----------
    preset_name
        Name of a bogie.params preset, or a bogie file's path (:func:`bogie.bogie_file.base_bogie`).
    legal_group_load
        Legal load of the axle group, both sides together [N].

    Returns
    -------
    Bogie
        The base bogie with ``payload_mass`` [kg] and ``chassis_pitch_inertia`` [kg m^2] set (a file's own two are
        replaced, as a preset's are).
    """
    base = base_bogie(preset_name)
    weight_per_kg = sum(design_spring_loads(base)) / base.payload_mass  # [N/kg]
    unsprung_weight = base.n_axles * base.axle_mass * GRAVITY
    payload = (0.5 * legal_group_load - unsprung_weight) / weight_per_kg
    return base.replace(
        payload_mass=payload,
        chassis_pitch_inertia=payload * (base.payload_cg_x**2 + PITCH_RADIUS_OF_GYRATION**2),
    )


#: each base bogie's fields (:func:`bogie.bogie_file.base_fields`: a preset's, or a file's read once) gathered once per
#: process: a copy costs a tenth of that
_base_fields = functools.cache(base_fields)
#: each base bogie once per process (a file read once): the air path's and the error path's start
_base_bogie = functools.cache(base_bogie)


def bogie_from_sample(row: Mapping[str, Any]) -> Bogie | AirBogie:
    """The bogie of one sample row: its group's base bogie (the ``preset`` column: a preset's name or a bogie file's
    path) with the sampled parameters and the design payload.

    A row whose ``suspension`` is ``air`` gives the air-sprung group on the same trailer
    (:func:`bogie.air.from_steel` of the steel design bogie): its own tilt, tyre wear, payload and pitch inertia;
    the steel-only parameters (bush, friction, contact, springs' band, equaliser arm) do not apply to it.

    Parameters
    ----------
    row
        One row of a study table (a dict or a pandas Series) with the columns of :data:`COLUMNS`.

    Returns
    -------
    Bogie
        The validated bogie. ``payload_fraction`` is not applied: the protocol applies it as a load factor.
    """
    n_axles = int(row["n_axles"])
    if str(row.get("suspension", "steel")) == "air":
        design = _base_bogie(str(row["preset"])).replace(
            payload_mass=float(row["payload_mass"]),
            chassis_pitch_inertia=float(row["chassis_pitch_inertia"]),
        )
        return air.from_steel(
            design,
            tyre_wear=tuple(float(row[c]) for c in TYRE_WEAR_COLUMNS[:n_axles]),
            chassis_tilt=float(row["chassis_tilt"]),
        )
    changes = dict(
        bush_stiffness=float(row["bush_stiffness"]),
        bush_damping=float(row["bush_damping"]),
        friction_coefficient=float(row["friction_coefficient"]),
        contact_roll_radius=float(row["contact_roll_radius"]),
        spring_friction_band=float(row["spring_friction_band"]),
        spring_friction_decay=float(row["spring_friction_decay"]),
        tyre_wear=tuple(float(row[c]) for c in TYRE_WEAR_COLUMNS[:n_axles]),
        chassis_tilt=float(row["chassis_tilt"]),
        payload_mass=float(row["payload_mass"]),
        chassis_pitch_inertia=float(row["chassis_pitch_inertia"]),
    )
    # the preset with the changes and the arms in one validation (issue 15: preset, changes and arms validated
    # one after another took a tenth of a weighing's Python); the same fields as the steps below
    fields = dict(_base_fields(str(row["preset"])))  # the values are immutable: a shallow copy is a new bogie's
    fields.update(changes)
    # a longer arm on the same axle layout shortens the springs beside it; the design loads stay equal. NaN: the
    # base bogie's own arms (a designer's file with arms of several lengths, bogie.fleet.design.experiment.own_design)
    arm = float(row["equaliser_arm"])
    if not math.isnan(arm):
        fields.update(equaliser_arm_changes(fields, arm))
    try:
        return Bogie(**fields)
    except ValueError:
        pass  # the steps raise the error they always raised (the first of several, say)
    bogie = _base_bogie(str(row["preset"])).replace(**changes)
    return bogie if math.isnan(arm) else with_equaliser_arms(bogie, arm)


# ---- the fleet ------------------------------------------------------------------------------------------------
def _unit_design(n: int, d: int, method: str, seed: int) -> np.ndarray:
    """``n`` points of a seeded, scrambled design of the d-dimensional unit hypercube [0, 1)^d."""
    from scipy.stats import qmc  # here: scipy.stats takes half a second to import, and the simulate stage's workers
    # import this module for bogie_from_sample only

    rng = np.random.default_rng(seed)
    if method == "lhs":
        return qmc.LatinHypercube(d, rng=rng).random(n)
    with warnings.catch_warnings():
        # the first n points of a scrambled Sobol' sequence are still a low-discrepancy design; they only lose
        # the exact balance of a power of 2, which nothing here relies on
        warnings.filterwarnings("ignore", message=".*balance properties of Sobol.*", category=UserWarning)
        return qmc.Sobol(d, scramble=True, rng=rng).random(n)


def study_frame(
    fleet: Fleet,
    study: str,
    groups: np.ndarray,
    values: dict[str, np.ndarray],
    base_id: np.ndarray,
    suspension: np.ndarray | None = None,
) -> pd.DataFrame:
    """Assemble a study table from per-row groups and sampled values, adding the group constants.

    Parameters
    ----------
    fleet
        The fleet: each group's preset and legal load.
    study
        The study's name (the ``study`` column).
    groups
        Each row's axle group.
    values
        Column name -> each row's value, SI: every sampled quantity of :data:`COLUMNS` (each axle's tyre wear,
        ``road_seed``, ``sensor_seed`` included).
    base_id
        Each row's base row [-].
    suspension
        Each row's suspension, all ``steel`` by default.

    Returns
    -------
    pandas.DataFrame
        The columns of :data:`COLUMNS` in order, with their dtypes.
    """
    n = len(groups)
    suspension = np.full(n, "steel", dtype=object) if suspension is None else suspension
    design = {g: design_bogie(fleet.presets[g], fleet.legal_group_load[g]) for g in dict.fromkeys(groups.tolist())}
    n_axles = np.array([GROUP_AXLES[g] for g in groups], dtype=np.int64)
    columns: dict[str, Any] = {
        **values,
        "sample_id": np.arange(n, dtype=np.int64),
        "base_id": base_id,
        "study": np.full(n, study, dtype=object),
        "group": groups,
        "n_axles": n_axles,
        "preset": np.array([fleet.presets[g] for g in groups], dtype=object),
        "variant": np.full(n, "baseline", dtype=object),
        "suspension": suspension,
        "legal_group_load": np.array([fleet.legal_group_load[g] for g in groups], dtype=float),
        "payload_mass": np.array([design[g].payload_mass for g in groups], dtype=float),
        "chassis_pitch_inertia": np.array([design[g].chassis_pitch_inertia for g in groups], dtype=float),
    }
    for i, c in enumerate(TYRE_WEAR_COLUMNS):
        # an axle the group does not have wears nothing: 0.0 keeps the table free of NaN
        columns[c] = np.where(n_axles > i, values[c], 0.0)
    return pd.DataFrame({c: columns[c] for c in COLUMNS}).astype(COLUMNS)


def sample_fleet(fleet: Fleet, n_bogies: int, seed: int, sampling: str = "lhs") -> pd.DataFrame:
    """A sampled fleet: ``n_bogies`` bogies from one Latin hypercube or scrambled Sobol' design.

    Every dimension of the design, including the axle group (a choice weighted by ``fleet.axle_mix``) and each
    axle's tyre wear, is mapped through its distribution's inverse CDF, so the stratification of the design carries
    over to every marginal.

    Parameters
    ----------
    fleet
        What varies between the bogies and how (:class:`Fleet`).
    n_bogies
        Number of bogies [-], at least 1.
    seed
        Master seed [-]: the design, each bogie's road, WIM sensor errors and suspension draw come from it
        (:func:`road_seed`, :func:`sensor_seed`, :func:`suspension_draw`), the same whatever the row order.
    sampling
        ``lhs`` (Latin hypercube) or ``sobol`` (scrambled Sobol'), both from :mod:`scipy.stats.qmc`.

    Returns
    -------
    pandas.DataFrame
        One row per bogie with the columns of :data:`COLUMNS`, SI.
    """
    for name, value in (("n_bogies", n_bogies), ("sampling", sampling), ("seed", seed)):
        SAMPLING_SETTINGS[name].check(name, value, FleetError)
    n = int(n_bogies)
    u = _unit_design(n, len(_FLEET_DIMENSIONS), sampling, design_seed(seed, "fleet"))
    mix = fleet.axle_mix
    values: dict[str, np.ndarray] = {}
    for j, dim in enumerate(_FLEET_DIMENSIONS):
        if dim == "group":
            dist = Choice(values=tuple(mix), weights=tuple(mix.values()))
        elif dim.startswith("tyre_wear_"):
            dist = fleet.distributions["tyre_wear"]
        else:
            dist = fleet.distributions[dim]
        values[dim] = dist.ppf(u[:, j])
    values["road_seed"] = np.array([road_seed(seed, "fleet", i) for i in range(n)], dtype=np.int64)
    values["sensor_seed"] = np.array([sensor_seed(seed, "fleet", i) for i in range(n)], dtype=np.int64)
    groups = values.pop("group")
    draws = np.array([suspension_draw(seed, "fleet", i) for i in range(n)])
    kinds = suspensions(draws, groups, fleet.suspension_mix)
    return study_frame(fleet, "fleet", groups, values, np.arange(n), kinds)
