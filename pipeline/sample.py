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

import numpy as np
import pandas as pd

from bogie.fleet.sampling.sample import COLUMNS, VARIANTS
from bogie.fleet.sampling.sample import sample_fleet as fleet_sample
from bogie.fleet.sampling.sensitivity import sensitivity_design
from bogie.params import INHIBITORS
from pipeline.atomic import run_stage, stage_inputs
from pipeline.config import Config, ConfigError, load_config
from pipeline.config.view import BYTES_PER_RUN
from pipeline.resources import available_memory
from pipeline.schema import write_checksummed

STUDIES: tuple[str, ...] = ("fleet", "sensitivity", "ablation")


# ---- studies ---------------------------------------------------------------------------------------------------
def sample_fleet(config: Config) -> pd.DataFrame:
    """The fleet study of params.yaml: :func:`bogie.fleet.sample_fleet` of ``fleet.n_bogies`` bogies."""
    return fleet_sample(config.fleet_study, config.fleet.n_bogies, config.seed, config.fleet.sampling)


def sample_sensitivity(config: Config) -> pd.DataFrame:
    """The Sobol' sensitivity design of params.yaml: :func:`bogie.fleet.sensitivity_design` of ``sensitivity.factors``
    around ``sensitivity.group``'s base bogie, ``sensitivity.base_size`` base rows."""
    sens = config.sensitivity
    return sensitivity_design(config.fleet_study, sens.factors, sens.group, sens.base_size, config.seed)


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


#: memory one sampled bogie costs at the pipeline's peak [bytes]: validate's figure, declared once
#: (:data:`pipeline.config.view.BYTES_PER_RUN`; bench/README.md, ``bench_stage_memory``, measures the stages)
BYTES_PER_BOGIE = BYTES_PER_RUN


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
