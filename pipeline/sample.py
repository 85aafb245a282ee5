"""DVC stage ``sample``: the fleet, the Sobol' sensitivity design and the switch-off ablation -> data/samples/.

``python -m pipeline.sample`` reads params.yaml and writes one Parquet table per study
(``data/samples/fleet.parquet``, ``sensitivity.parquet``, ``ablation.parquet``), one row per bogie, every
parameter in SI. Every study is a uniform design of the unit hypercube mapped through the distributions' inverse
CDFs, so the fleet and the sensitivity design share exactly the same marginals.

Seeds: every random stream is a :class:`numpy.random.SeedSequence` of the master ``seed`` with the spawn key
(study, stream[, sample_id]), so each study, each stream and each bogie's road is independent of the others and
of row order, chunking and the number of workers.
"""

from __future__ import annotations

import argparse
import functools
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from bogie import air
from bogie.air import AirBogie
from bogie.params import (
    GRAVITY,
    INHIBITORS,
    Bogie,
    design_spring_loads,
    equaliser_arm_changes,
    preset,
    preset_fields,
    with_equaliser_arms,
)
from pipeline.atomic import atomic_file, io_error
from pipeline.config import Config, ConfigError, load_config
from pipeline.constants import GROUP_AXLES, MAX_AXLES
from pipeline.distributions import Choice
from pipeline.resources import available_memory

STUDIES: tuple[str, ...] = ("fleet", "sensitivity", "ablation")

#: ablation variants: the baseline, each inhibitor switched off alone, and all five off
VARIANTS: tuple[str, ...] = ("baseline", *INHIBITORS, "all")

#: radius of gyration of the sprung mass about its centre of gravity in pitch [m]
PITCH_RADIUS_OF_GYRATION = 3.5

TYRE_WEAR_COLUMNS: tuple[str, ...] = tuple(f"tyre_wear_{i}" for i in range(MAX_AXLES))

#: the sampled quantities with one value per bogie, in the order of the fleet design's dimensions
_SCALARS: tuple[str, ...] = (
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
_FLEET_DIMENSIONS: tuple[str, ...] = ("group", *_SCALARS, *TYRE_WEAR_COLUMNS, "road_class")

#: column -> dtype of every study table, in order; units in the README of data/samples
COLUMNS: dict[str, str] = {
    "sample_id": "int64",  # row index within the study [-]
    "base_id": "int64",  # fleet: sample_id; ablation: the fleet sample_id; sensitivity: Saltelli base row [-]
    "study": "str",
    "group": "str",  # tandem | triaxle
    "n_axles": "int64",
    "preset": "str",  # bogie.params preset of the group
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

_STREAM_DESIGN = 0
_STREAM_ROAD = 1
_STREAM_SENSOR = 2
_STREAM_SUSPENSION = 3


# ---- seeds -----------------------------------------------------------------------------------------------------
def _study_code(study: str) -> int:
    # the name's bytes, not hash(): Python salts str hashes per process
    return int.from_bytes(study.encode("utf-8"), "big")


def _seed_sequence(seed: int, study: str, stream: int, *ids: int) -> np.random.SeedSequence:
    return np.random.SeedSequence(seed, spawn_key=(_study_code(study), stream, *ids))


def _seed_int(sequence: np.random.SeedSequence) -> int:
    # 63 bits: a non-negative int64, what Parquet stores and every numpy generator accepts
    return int(sequence.generate_state(1, np.uint64)[0] >> np.uint64(1))


def road_seed(seed: int, study: str, sample_id: int) -> int:
    """Seed of one bogie's random approach road, from the master seed, the study and the sample id.

    Parameters
    ----------
    seed
        Master seed of params.yaml [-].
    study
        Study name.
    sample_id
        Row index within the study [-].

    Returns
    -------
    int
        A non-negative int64, the same whatever the row order or chunking.
    """
    return _seed_int(_seed_sequence(seed, study, _STREAM_ROAD, sample_id))


def sensor_seed(seed: int, study: str, sample_id: int) -> int:
    """Seed of one bogie's WIM sensor errors (:func:`bogie.wim.axle_errors`), like :func:`road_seed` [-].

    A stream of its own, so the sensor's errors are independent of the road's profile; per bogie and kept by the
    ablation's variants, so a variant and its baseline read with the same errors (common random numbers).
    """
    return _seed_int(_seed_sequence(seed, study, _STREAM_SENSOR, sample_id))


def suspension_draw(seed: int, study: str, sample_id: int) -> float:
    """One bogie's uniform draw in [0, 1) that sets its suspension: air if below its group's air share [-].

    A stream of its own, outside the fleet's design, so that a fleet with no air share is the fleet of before
    (the design's dimensions and draws unchanged), and a bogie keeps its draw whatever the share: raising the air
    share turns steel groups into air ones and never the other way (common random numbers for ``calibrate``).
    """
    return float(np.random.default_rng(_seed_sequence(seed, study, _STREAM_SUSPENSION, sample_id)).random())


def suspensions(draws: np.ndarray, groups: np.ndarray, mix: Mapping[str, Mapping[str, float]]) -> np.ndarray:
    """``air`` where a bogie's draw is below its group's air share in ``mix`` (``fleet.suspension_mix``), else
    ``steel``."""
    share = np.array([mix[g]["air"] for g in groups], dtype=float)
    return np.where(np.asarray(draws, dtype=float) < share, "air", "steel").astype(object)


def design_seed(seed: int, study: str) -> int:
    """Seed of a study's uniform design (Latin hypercube, Sobol' scrambling, Saltelli) [-]."""
    return _seed_int(_seed_sequence(seed, study, _STREAM_DESIGN))


# ---- the design bogie ------------------------------------------------------------------------------------------
def design_bogie(preset_name: str, legal_group_load: float) -> Bogie:
    """The preset with the sprung mass that makes its fully laden design load the legal group load.

    Per side: (sprung weight on the bogie) + n m_axle g = legal_group_load / 2. The sprung weight on the bogie,
    m g x_cg / x_b (:func:`bogie.params.design_spring_loads`), is linear in the payload mass m, so one evaluation on
    the preset gives the exact m. The pitch inertia is m (x_cg^2 + r^2) with r = :data:`PITCH_RADIUS_OF_GYRATION`.

    Parameters
    ----------
    preset_name
        Name of a bogie.params preset.
    legal_group_load
        Legal load of the axle group, both sides together [N].

    Returns
    -------
    Bogie
        The preset with ``payload_mass`` [kg] and ``chassis_pitch_inertia`` [kg m^2] set.
    """
    base = preset(preset_name)
    weight_per_kg = sum(design_spring_loads(base)) / base.payload_mass  # [N/kg]
    unsprung_weight = base.n_axles * base.axle_mass * GRAVITY
    payload = (0.5 * legal_group_load - unsprung_weight) / weight_per_kg
    return base.replace(
        payload_mass=payload,
        chassis_pitch_inertia=payload * (base.payload_cg_x**2 + PITCH_RADIUS_OF_GYRATION**2),
    )


#: each preset's fields (:func:`bogie.params.preset_fields`) gathered once per process: a copy costs a tenth of that
_preset_fields = functools.cache(preset_fields)


def bogie_from_sample(row: Mapping[str, Any]) -> Bogie | AirBogie:
    """The bogie of one sample row: its group's preset with the sampled parameters and the design payload.

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
        design = preset(
            str(row["preset"]),
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
    fields = dict(_preset_fields(str(row["preset"])))  # the values are immutable: a shallow copy is a new bogie's
    fields.update(changes)
    # a longer arm on the same axle layout shortens the springs beside it; the design loads stay equal
    fields.update(equaliser_arm_changes(fields, float(row["equaliser_arm"])))
    try:
        return Bogie(**fields)
    except ValueError:
        pass  # the steps raise the error they always raised (the first of several, say)
    bogie = preset(str(row["preset"]), **changes)
    return with_equaliser_arms(bogie, float(row["equaliser_arm"]))


# ---- studies ---------------------------------------------------------------------------------------------------
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


def _frame(
    config: Config,
    study: str,
    groups: np.ndarray,
    values: dict[str, np.ndarray],
    base_id: np.ndarray,
    suspension: np.ndarray | None = None,
) -> pd.DataFrame:
    """Assemble a study table from per-row groups and sampled values, adding the group constants and seeds.

    ``suspension``: each row's, all ``steel`` by default."""
    n = len(groups)
    suspension = np.full(n, "steel", dtype=object) if suspension is None else suspension
    fleet = config.fleet
    design = {g: design_bogie(fleet.presets[g], fleet.legal_group_load[g]) for g in GROUP_AXLES}
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


def sample_fleet(config: Config) -> pd.DataFrame:
    """The fleet study: ``fleet.n_bogies`` bogies from one Latin hypercube or scrambled Sobol' design.

    Every dimension of the design, including the axle group (a choice weighted by ``fleet.axle_mix``) and each
    axle's tyre wear, is mapped through its distribution's inverse CDF, so the stratification of the design carries
    over to every marginal.

    Parameters
    ----------
    config
        The validated parameters.

    Returns
    -------
    pandas.DataFrame
        One row per bogie with the columns of :data:`COLUMNS`, SI.
    """
    n = config.fleet.n_bogies
    u = _unit_design(n, len(_FLEET_DIMENSIONS), config.fleet.sampling, design_seed(config.seed, "fleet"))
    mix = config.fleet.axle_mix
    values: dict[str, np.ndarray] = {}
    for j, dim in enumerate(_FLEET_DIMENSIONS):
        if dim == "group":
            dist = Choice(values=tuple(mix), weights=tuple(mix.values()))
        elif dim.startswith("tyre_wear_"):
            dist = config.distributions["tyre_wear"]
        else:
            dist = config.distributions[dim]
        values[dim] = dist.ppf(u[:, j])
    values["road_seed"] = np.array([road_seed(config.seed, "fleet", i) for i in range(n)], dtype=np.int64)
    values["sensor_seed"] = np.array([sensor_seed(config.seed, "fleet", i) for i in range(n)], dtype=np.int64)
    groups = values.pop("group")
    draws = np.array([suspension_draw(config.seed, "fleet", i) for i in range(n)])
    kinds = suspensions(draws, groups, config.fleet.suspension_mix)
    return _frame(config, "fleet", groups, values, np.arange(n), kinds)


def sensitivity_problem(config: Config) -> dict[str, Any]:
    """The SALib problem of the sensitivity design, over the unit hypercube.

    One variable per factor, except tyre wear, which has one variable per axle of ``sensitivity.group`` (named
    ``tyre_wear_<i>``) gathered in the SALib group ``tyre_wear``. Pass the same dict to
    ``SALib.analyze.sobol.analyze`` with ``calc_second_order=False``.

    Parameters
    ----------
    config
        The validated parameters.

    Returns
    -------
    dict
        ``num_vars``, ``names``, ``bounds`` (all [0, 1]) and ``groups`` (one per factor, in the order of
        ``sensitivity.factors``). A new dict at every call: SALib adds keys to the one it is given.
    """
    n_axles = GROUP_AXLES[config.sensitivity.group]
    names: list[str] = []
    groups: list[str] = []
    for factor in config.sensitivity.factors:
        members = list(TYRE_WEAR_COLUMNS[:n_axles]) if factor == "tyre_wear" else [factor]
        names += members
        groups += [factor] * len(members)
    return {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names), "groups": groups}


def sample_sensitivity(config: Config) -> pd.DataFrame:
    """The Sobol' sensitivity design: SALib's Saltelli sampling of the factors, N (G + 2) rows.

    The base bogie is the group's preset; each factor is mapped from SALib's unit design through the same
    distribution as in the fleet, and every other quantity is held at its distribution's median. All rows share one
    approach road, ``road_seed(seed, "sensitivity", 0)``: the road is a non-factor too, and a road per row would add
    variance that no factor explains. So do the WIM sensor's errors, ``sensor_seed(seed, "sensitivity", 0)``.

    Parameters
    ----------
    config
        The validated parameters.

    Returns
    -------
    pandas.DataFrame
        Rows in SALib's order (``sample_id``), the columns of :data:`COLUMNS`, SI; ``base_id`` is the Saltelli
        base row a row belongs to.
    """
    from SALib.sample import sobol  # here, as scipy.stats in _unit_design

    sens = config.sensitivity
    problem = sensitivity_problem(config)
    u = sobol.sample(
        problem, sens.base_size, calc_second_order=False, scramble=True, seed=design_seed(config.seed, "sensitivity")
    )
    n = len(u)
    n_groups = len(sens.factors)
    values: dict[str, np.ndarray] = {}
    for name in (*_SCALARS, "road_class"):
        values[name] = np.full(
            n, config.distributions[name].quantile(0.5), dtype=object if name == "road_class" else float
        )
    for c in TYRE_WEAR_COLUMNS:
        values[c] = np.full(n, config.distributions["tyre_wear"].quantile(0.5))
    for j, name in enumerate(problem["names"]):
        dist = config.distributions["tyre_wear" if name.startswith("tyre_wear_") else name]
        values[name] = dist.ppf(u[:, j])
    values["road_seed"] = np.full(n, road_seed(config.seed, "sensitivity", 0), dtype=np.int64)
    values["sensor_seed"] = np.full(n, sensor_seed(config.seed, "sensitivity", 0), dtype=np.int64)
    groups = np.full(n, sens.group, dtype=object)
    return _frame(config, "sensitivity", groups, values, np.arange(n) // (n_groups + 2))


def sample_ablation(config: Config, fleet: pd.DataFrame) -> pd.DataFrame:
    """The switch-off ablation: the first ``ablation.n_bogies`` steel fleet bogies, each as the variants of
    :data:`VARIANTS` (the inhibitors are the steel groups'; an air-sprung group has none to remove).

    A variant differs from its baseline only in the inhibitor(s) set to the ideal value of
    :data:`bogie.params.INHIBITORS`; it keeps the fleet bogie's road seed and WIM sensor seed, so the baseline rows
    equal the fleet rows and every variant crosses the same road and reads with the same sensor errors as its
    baseline (common random numbers: a variant's difference is the inhibitor's alone).

    Parameters
    ----------
    config
        The validated parameters.
    fleet
        The fleet study (:func:`sample_fleet`).

    Returns
    -------
    pandas.DataFrame
        ``len(VARIANTS)`` consecutive rows per fleet bogie, ``base_id`` its fleet ``sample_id``.
    """
    steel = fleet[fleet["suspension"] == "steel"]
    if len(steel) < config.ablation.n_bogies:
        raise ConfigError(
            "ablation.n_bogies",
            f"ablation.n_bogies = {config.ablation.n_bogies}: the fleet has only {len(steel)} steel-equalised "
            "bogies (fleet.suspension_mix), and the ablation removes the steel groups' inhibitors; allowed: at most "
            f"{len(steel)} [-]",
        )
    base = steel.iloc[: config.ablation.n_bogies]
    frame = base.loc[base.index.repeat(len(VARIANTS))].reset_index(drop=True)
    variant = np.tile(np.array(VARIANTS, dtype=object), len(base))
    for name, ideal in INHIBITORS.items():
        frame.loc[(variant == name) | (variant == "all"), name] = ideal
    frame["sample_id"] = np.arange(len(frame), dtype=np.int64)
    frame["study"] = "ablation"
    frame["variant"] = variant
    return frame.astype(COLUMNS)


def sample_studies(config: Config) -> dict[str, pd.DataFrame]:
    """Every study table, by study name (:data:`STUDIES`)."""
    fleet = sample_fleet(config)
    return {"fleet": fleet, "sensitivity": sample_sensitivity(config), "ablation": sample_ablation(config, fleet)}


# ---- output ----------------------------------------------------------------------------------------------------
def write_parquet_atomic(frame: pd.DataFrame, path: str | Path) -> None:
    """Write ``frame`` to ``path`` through a temporary file in the same directory, so no reader sees half a file."""
    with atomic_file(path) as tmp:
        frame.to_parquet(tmp, index=False)


#: memory one sampled bogie costs at the pipeline's peak: its sample row and design point (about 0.6 KiB with
#: pandas' overheads) and, in the survey, its runs under every protocol with their derived columns (about 1 KiB
#: each) [bytes]
BYTES_PER_BOGIE = 3 * 1024


def memory_needed(config: Config) -> int:
    """The memory [bytes] the studies of ``config`` need at the pipeline's peak (:data:`BYTES_PER_BOGIE`)."""
    sensitivity = config.sensitivity.base_size * (len(config.sensitivity.factors) + 2)
    rows = config.fleet.n_bogies + sensitivity + len(VARIANTS) * config.ablation.n_bogies
    return rows * BYTES_PER_BOGIE


def check_memory(config: Config, available: int | None) -> None:
    """Refuse studies that would not fit in ``available`` memory [bytes] (None: unknown, no check).

    Raises
    ------
    ConfigError
        Naming ``fleet.n_bogies``, the memory the studies need and what is available.
    """
    need = memory_needed(config)
    if available is not None and need > available:
        raise ConfigError(
            "fleet.n_bogies",
            f"fleet.n_bogies = {config.fleet.n_bogies}: the studies ({config.fleet.n_bogies:,} fleet, "
            f"{config.ablation.n_bogies:,} x {len(VARIANTS)} ablation and the Sobol' design) need about "
            f"{need / 2**30:,.1f} GiB at the pipeline's peak, more than the {available / 2**30:,.1f} GiB available "
            "on this machine: lower fleet.n_bogies, or run on a larger machine",
        )


def main(argv: list[str] | None = None) -> int:
    """Run the stage: validate params.yaml, sample every study, then write them all."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.sample", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--out", default="data/samples", help="output directory (default: data/samples)")
    args = parser.parse_args(argv)
    try:
        config = load_config(args.params)
        check_memory(config, available_memory())
    except (ConfigError, OSError, yaml.YAMLError) as exc:
        print(f"sample: {args.params}: {exc}", file=sys.stderr)
        return 2
    # everything is sampled before anything is written: a failure leaves the previous outputs untouched
    try:
        frames = sample_studies(config)
    except ConfigError as exc:
        print(f"sample: {args.params}: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        for study, frame in frames.items():
            write_parquet_atomic(frame, out / f"{study}.parquet")
    except OSError as exc:
        print(io_error("sample", exc), file=sys.stderr)
        return 2
    counts = ", ".join(f"{study} {len(frame)}" for study, frame in frames.items())
    print(f"sample: wrote {counts} rows to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
