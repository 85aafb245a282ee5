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
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.constants import GROUP_AXLES
from bogie.fleet.sampling.sample import (
    COLUMNS,
    SCALAR_QUANTITIES,
    TYRE_WEAR_COLUMNS,
    VARIANTS,
    design_seed,
    road_seed,
    sensor_seed,
    study_frame,
)
from bogie.fleet.sampling.sample import sample_fleet as fleet_sample
from bogie.params import INHIBITORS
from pipeline.atomic import run_stage, stage_inputs
from pipeline.config import Config, ConfigError, load_config
from pipeline.resources import available_memory
from pipeline.schema import write_checksummed

STUDIES: tuple[str, ...] = ("fleet", "sensitivity", "ablation")


# ---- studies ---------------------------------------------------------------------------------------------------
def sample_fleet(config: Config) -> pd.DataFrame:
    """The fleet study of params.yaml: :func:`bogie.fleet.sample_fleet` of ``fleet.n_bogies`` bogies."""
    return fleet_sample(config.fleet_study, config.fleet.n_bogies, config.seed, config.fleet.sampling)


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
    from SALib.sample import sobol  # here: the simulate stage's workers need none of it

    sens = config.sensitivity
    problem = sensitivity_problem(config)
    u = sobol.sample(
        problem, sens.base_size, calc_second_order=False, scramble=True, seed=design_seed(config.seed, "sensitivity")
    )
    n = len(u)
    n_groups = len(sens.factors)
    values: dict[str, np.ndarray] = {}
    for name in (*SCALAR_QUANTITIES, "road_class"):
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
    return study_frame(config.fleet_study, "sensitivity", groups, values, np.arange(n) // (n_groups + 2))


def sample_ablation(config: Config, fleet: pd.DataFrame) -> pd.DataFrame:
    """The switch-off ablation: the first ``ablation.n_bogies`` steel fleet bogies (all of them when the fleet has
    fewer: the size follows the fleet), each as the variants of :data:`VARIANTS` (the inhibitors are the steel
    groups'; an air-sprung group has none to remove).

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
    if len(steel) == 0:
        raise ConfigError(
            "fleet.suspension_mix",
            f"fleet.suspension_mix = {dict(config.fleet.suspension_mix)}: the fleet of {len(fleet)} bogies has no "
            "steel-equalised bogie, and the ablation removes the steel groups' inhibitors; allowed: a steel share "
            "above 0 in some group [-]",
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
    """Write ``frame`` to ``path`` through a temporary file in the same directory, so no reader sees half a file, with
    a part file's checksums (:func:`pipeline.schema.write_checksummed`): simulate and the report verify them."""
    write_checksummed(frame, path)


#: memory one sampled bogie costs at the pipeline's peak: its sample row and design point (about 0.6 KiB with
#: pandas' overheads) and, in the survey, its runs under every protocol with their derived columns (about 1 KiB
#: each) [bytes]
BYTES_PER_BOGIE = 3 * 1024


def memory_needed(config: Config) -> int:
    """The memory [bytes] the studies of ``config`` need at the pipeline's peak (:data:`BYTES_PER_BOGIE`)."""
    sensitivity = config.sensitivity.base_size * (len(config.sensitivity.factors) + 2)
    ablation = min(config.ablation.n_bogies, config.fleet.n_bogies)
    rows = config.fleet.n_bogies + sensitivity + len(VARIANTS) * ablation
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
            f"{min(config.ablation.n_bogies, config.fleet.n_bogies):,} x {len(VARIANTS)} ablation and the Sobol' "
            "design) need about "
            f"{need / 2**30:,.1f} GiB at the pipeline's peak, more than the {available / 2**30:,.1f} GiB available "
            "on this machine: lower fleet.n_bogies, or run on a larger machine",
        )


def main(argv: list[str] | None = None) -> int:
    """Run the stage: validate params.yaml, sample every study, then write them all."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.sample", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--out", default="data/samples", help="output directory (default: data/samples)")
    args = parser.parse_args(argv)
    return run_stage("sample", parser, args, lambda own: _stage(args))


def _stage(args: argparse.Namespace) -> int:
    """Sample every study, then write them all; the exit code (errors: :func:`pipeline.atomic.run_stage`'s)."""
    # everything is sampled before anything is written: a failure leaves the previous outputs untouched
    with stage_inputs("sample", prefix=f"{args.params}: "):
        config = load_config(args.params)
        check_memory(config, available_memory())
        frames = sample_studies(config)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for study, frame in frames.items():
        write_parquet_atomic(frame, out / f"{study}.parquet")
    counts = ", ".join(f"{study} {len(frame)}" for study, frame in frames.items())
    print(f"sample: wrote {counts} rows to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
