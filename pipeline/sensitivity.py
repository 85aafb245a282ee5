"""DVC stage ``sensitivity``: Sobol' indices and the switch-off ablation -> data/sensitivity/, metrics/sensitivity.json.

``python -m pipeline.sensitivity`` reads the runs of the ``sensitivity`` study (SALib's Saltelli design over the
five inhibitors, chassis tilt and tyre wear, see :func:`bogie.fleet.sensitivity_design`) and of the
``ablation`` study (fleet bogies with each inhibitor switched off), and writes:

- first-order and total Sobol' indices with bootstrap confidence intervals of the inequality measures
  (:data:`SOBOL_MEASURES`) under ``sensitivity.protocol``, and the ranking of the five inhibitors by the total
  index of ``max_deviation``;
- the ablation: the fleet's mean inequality and tolerance exceedance for each variant, and what removing each
  inhibitor buys against the baseline, with paired bootstrap intervals over bogies.

Failed runs of the Sobol' design: Saltelli's estimators are means over the base rows, each of which needs all
G + 2 runs of its block (A, the G cross rows, B). A block with a failed run is dropped whole; the indices are then
the same estimators over the remaining blocks. No value is imputed, since an invented output would enter the
variance being apportioned. If more than :data:`MAX_DROPPED_FRACTION` of the blocks are lost the stage refuses,
naming the failed runs: the failures would then cut a region out of the factor space and bias the indices. The
method and its caveats: ``docs/sensitivity.md``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from SALib.analyze import sobol
from SALib.util import extract_group_names

from bogie.fleet.sampling.sample import TYRE_WEAR_COLUMNS, design_seed
from bogie.fleet.sampling.sensitivity import sensitivity_problem
from bogie.fleet.weighing.survey import AXLE_LOAD_COLUMNS
from bogie.rounding import json_number
from pipeline.ablation import (
    INHIBITOR_NAMES,
    SensitivityDataError,
    ablation_effects,
    ablation_metrics,
    ablation_pairs,
)
from pipeline.atomic import run_stage, stage_inputs
from pipeline.config import Config, load_config
from pipeline.survey import read_runs, write_outputs

#: inequality measures (result columns) whose Sobol' indices are computed
SOBOL_MEASURES: tuple[str, ...] = ("max_deviation", "p1", "road_wear_factor")
#: the measure whose total index ranks the inhibitors
RANKING_MEASURE = "max_deviation"
#: most Saltelli blocks that failed runs may remove before the Sobol' analysis refuses [-]
MAX_DROPPED_FRACTION = 0.05


def bootstrap_seed(seed: int, name: str) -> int:
    """A positive seed for one bootstrap stream, from the master seed (SALib treats a seed of 0 as none)."""
    return max(1, design_seed(seed, name))


# ---- Sobol' ------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SaltelliOutputs:
    """The outputs of a Saltelli design in SALib's order, after dropping the blocks with a failed run.

    Attributes
    ----------
    outputs
        Measure -> outputs Y of the kept blocks, in SALib's row order.
    base_size
        Base rows N of the design [-].
    n_blocks
        Base rows (blocks of G + 2 runs) kept [-].
    excluded
        The failed runs: ``sample_id``, ``base_id``, ``message``; their blocks are dropped.
    """

    outputs: dict[str, np.ndarray]
    base_size: int
    n_blocks: int
    excluded: pd.DataFrame


def _ids_text(ids: Sequence[int], limit: int = 20) -> str:
    shown = ", ".join(str(int(i)) for i in ids[:limit])
    return shown + (f", ... ({len(ids)} in all)" if len(ids) > limit else "")


def protocol_runs(runs: pd.DataFrame, protocol: str) -> pd.DataFrame:
    """The runs of one protocol; a clear error if there are none."""
    chosen = runs[runs["protocol"] == protocol]
    if chosen.empty:
        present = ", ".join(sorted(runs["protocol"].astype(str).unique())) or "none"
        raise SensitivityDataError(f"no sensitivity runs under protocol {protocol!r} (the runs have: {present})")
    return chosen


def check_saltelli_order(frame: pd.DataFrame, problem: Mapping[str, Any]) -> None:
    """Check that rows sorted by ``sample_id`` are SALib's Saltelli blocks (without second order).

    In each block of G + 2 rows, row k + 1 must equal row 0 (matrix A) except in the columns of group k, which
    must equal the last row (matrix B). The sampled values are deterministic functions of SALib's unit values, so
    the check is exact.

    Raises
    ------
    SensitivityDataError
        Naming the first block that breaks the pattern.
    """
    names = list(problem["names"])
    groups = list(problem.get("groups") or names)
    group_names, n_groups = extract_group_names(problem)
    step = n_groups + 2
    x = frame[names].to_numpy(dtype=float).reshape(-1, step, len(names))
    a, b = x[:, :1, :], x[:, -1:, :]
    member = np.array([[g == name for g in groups] for name in group_names])  # (G, D)
    expected = np.where(member[None, :, :], b, a)
    bad = np.any(x[:, 1:-1, :] != expected, axis=(1, 2))
    if bad.any():
        block = int(np.argmax(bad))
        raise SensitivityDataError(
            f"the runs sorted by sample_id are not in SALib's Saltelli order: block {block} (sample_id "
            f"{block * step}-{block * step + step - 1}) does not cross A and B group by group over "
            f"{', '.join(group_names)}; were the runs made from this params.yaml's sensitivity design?"
        )


def _complete_design(runs: pd.DataFrame, base_size: int, step: int) -> pd.DataFrame:
    """The runs sorted by ``sample_id``, checked to be each of the design's N (G + 2) runs once, in their blocks."""
    n_rows = base_size * step
    duplicated = runs["sample_id"][runs["sample_id"].duplicated()].unique()
    if len(duplicated):
        raise SensitivityDataError(f"the sensitivity runs hold sample_id {_ids_text(sorted(duplicated))} twice")
    frame = runs.sort_values("sample_id").reset_index(drop=True)
    ids = frame["sample_id"].to_numpy()
    missing = np.setdiff1d(np.arange(n_rows), ids)
    if len(missing):
        raise SensitivityDataError(
            f"the sensitivity design has {n_rows} runs (base size {base_size} x {step}) but {len(missing)} are "
            f"missing: sample_id {_ids_text(missing)}; rerun the simulate stage"
        )
    if len(ids) != n_rows:
        raise SensitivityDataError(
            f"the sensitivity runs have {len(ids)} rows, sample_id up to {ids.max()}, but the design has {n_rows} "
            f"(base size {base_size} x {step}); were they made from this params.yaml?"
        )
    if not np.array_equal(frame["base_id"].to_numpy(), ids // step):
        raise SensitivityDataError(f"the sensitivity runs' base_id is not sample_id // {step} (G + 2 = {step})")
    return frame


def saltelli_outputs(
    runs: pd.DataFrame,
    problem: Mapping[str, Any],
    base_size: int,
    measures: Sequence[str] = SOBOL_MEASURES,
    max_dropped_fraction: float = MAX_DROPPED_FRACTION,
) -> SaltelliOutputs:
    """The outputs Y of a Saltelli design from its runs (one protocol), checked and in SALib's order.

    Parameters
    ----------
    runs
        Runs of the sensitivity study under one protocol, any row order, failed rows included.
    problem
        The SALib problem of the design (:func:`bogie.fleet.sensitivity_problem`).
    base_size
        Base size N of the design [-].
    measures
        Result columns to return.
    max_dropped_fraction
        Largest fraction of blocks that failed runs may remove [-].

    Raises
    ------
    SensitivityDataError
        If a run is missing or duplicated, the rows are not the design's Saltelli blocks, or failed runs remove
        more than ``max_dropped_fraction`` of the blocks (the message names the failed sample ids).
    """
    _, n_groups = extract_group_names(problem)
    step = n_groups + 2
    n_rows = base_size * step
    frame = _complete_design(runs, base_size, step)
    check_saltelli_order(frame, problem)
    failed = frame[frame["status"] != "ok"]
    dropped = np.unique(failed["base_id"].to_numpy())
    if len(dropped) > max_dropped_fraction * base_size:
        messages = failed["message"].value_counts().head(3)
        reasons = "; ".join(f"{n} x {m!r}" for m, n in messages.items())
        raise SensitivityDataError(
            f"{len(failed)} of {n_rows} sensitivity runs failed (sample_id {_ids_text(failed['sample_id'].tolist())}"
            f"; {reasons}), which removes {len(dropped)} of {base_size} Saltelli blocks, more than "
            f"{max_dropped_fraction:.0%}: the Sobol' indices would describe only the region where the model "
            "converges. Fix the failures (or raise the base size) before ranking the factors"
        )
    kept = frame[~frame["base_id"].isin(dropped)]
    outputs = {m: kept[m].to_numpy(dtype=float) for m in measures}
    excluded = failed[["sample_id", "base_id", "message"]].reset_index(drop=True)
    return SaltelliOutputs(outputs, base_size, base_size - len(dropped), excluded)


def sobol_indices(
    problem: Mapping[str, Any], y: np.ndarray, num_resamples: int, conf_level: float, seed: int
) -> pd.DataFrame:
    """First-order and total Sobol' indices of one output, with bootstrap confidence intervals (SALib).

    Parameters
    ----------
    problem
        The SALib problem, with groups; indices are per group.
    y
        Outputs in SALib's Saltelli order without second order, N (G + 2) values.
    num_resamples
        Bootstrap resamples [-].
    conf_level
        Confidence level [-].
    seed
        Positive seed of the bootstrap.

    Returns
    -------
    pandas.DataFrame
        One row per factor (group): ``S1``, ``S1_conf`` (half-width of SALib's normal-approximation interval,
        ``z sd`` of the bootstrap), ``S1_low``, ``S1_high``, and the same for ``ST``.

    Raises
    ------
    SensitivityDataError
        If an output is not finite or the outputs do not vary (the indices are then undefined).

    Notes
    -----
    SALib's estimators without second order: the first-order index by Saltelli et al. (2010, Table 2 (b)), the
    total index by Jansen (1999) as given there (Table 2 (f)), each over the N blocks of G + 2 runs.

    References
    ----------
    A. Saltelli, P. Annoni, I. Azzini, F. Campolongo, M. Ratto, S. Tarantola, "Variance based sensitivity analysis
    of model output. Design and estimator for the total sensitivity index", Computer Physics Communications 181(2),
    259-270, 2010.
    M. J. W. Jansen, "Analysis of variance designs for model output", Computer Physics Communications 117(1-2),
    35-43, 1999.
    """
    if seed <= 0:
        raise ValueError(f"seed = {seed}: must be a positive integer (SALib ignores a seed of 0)")
    y = np.asarray(y, dtype=float)
    if not np.all(np.isfinite(y)):
        raise SensitivityDataError(f"{int(np.sum(~np.isfinite(y)))} outputs are not finite")
    if np.ptp(y) == 0.0:
        raise SensitivityDataError(f"the output is constant ({y[0]:g}) over the design: no variance to apportion")
    result = sobol.analyze(
        dict(problem), y, calc_second_order=False, num_resamples=num_resamples, conf_level=conf_level, seed=seed
    )
    names, _ = extract_group_names(problem)
    table = pd.DataFrame({"factor": names})
    for index in ("S1", "ST"):
        table[index] = np.asarray(result[index], dtype=float)
        table[f"{index}_conf"] = np.asarray(result[f"{index}_conf"], dtype=float)
        table[f"{index}_low"] = table[index] - table[f"{index}_conf"]
        table[f"{index}_high"] = table[index] + table[f"{index}_conf"]
    return table


def sobol_table(
    design: SaltelliOutputs, problem: Mapping[str, Any], num_resamples: int, conf_level: float, seed: int
) -> pd.DataFrame:
    """:func:`sobol_indices` of every measure of ``design``, stacked with a ``measure`` column."""
    tables = [
        sobol_indices(problem, y, num_resamples, conf_level, seed).assign(measure=measure, n_blocks=design.n_blocks)
        for measure, y in design.outputs.items()
    ]
    table = pd.concat(tables, ignore_index=True)
    return table[["measure", *[c for c in table.columns if c != "measure"]]]


def rank_inhibitors(indices: pd.DataFrame, inhibitors: Sequence[str] = INHIBITOR_NAMES) -> pd.DataFrame:
    """The inhibitors ordered by total index, largest first, with ``rank`` (1 = most influential).

    Parameters
    ----------
    indices
        One measure's table from :func:`sobol_indices`.
    inhibitors
        Factors to rank.
    """
    table = indices[indices["factor"].isin(inhibitors)].sort_values("ST", ascending=False, kind="stable")
    return table.assign(rank=np.arange(1, len(table) + 1)).reset_index(drop=True)


def reference_check(ranking: pd.DataFrame) -> dict[str, bool | None]:
    """The reference's conclusion, friction below bush stiffness and contact movement, against a ranking.

    Returns
    -------
    dict
        ``agrees``: friction's total index is below both point estimates; ``resolved``: the upper end of its
        interval is below the lower ends of both, so the bootstrap separates them. Both None when the design
        leaves out one of the three factors.
    """
    row = ranking.set_index("factor")
    if not {"friction_coefficient", "bush_stiffness", "contact_roll_radius"} <= set(row.index):
        return {"agrees": None, "resolved": None}
    friction, others = row.loc["friction_coefficient"], row.loc[["bush_stiffness", "contact_roll_radius"]]
    return {
        "agrees": bool((friction["ST"] < others["ST"]).all()),
        "resolved": bool((friction["ST_high"] < others["ST_low"]).all()),
    }


# ---- the stage -----------------------------------------------------------------------------------------------------
def sensitivity_metrics(
    indices: pd.DataFrame, design: SaltelliOutputs, effects: pd.DataFrame, config: Config
) -> dict[str, Any]:
    """The small dict of metrics/sensitivity.json (see ``docs/outputs.md``), rounded for ``dvc metrics show``."""
    sens = config.sensitivity
    main_indices = indices[indices["measure"] == RANKING_MEASURE]
    ranking = rank_inhibitors(main_indices)
    metrics: dict[str, Any] = {
        "ranking": ranking["factor"].tolist(),
        "rank": {row.factor: int(row.rank) for row in ranking.itertuples()},
        "ranking_measure": f"total Sobol index ST of {RANKING_MEASURE} ({sens.protocol}, {sens.group})",
        "reference_check": {
            "claim": "friction_coefficient below bush_stiffness and contact_roll_radius",
            **reference_check(ranking),
        },
        "sobol": {
            "measure": RANKING_MEASURE,
            "protocol": sens.protocol,
            "group": sens.group,
            "base_size": sens.base_size,
            "n_blocks": design.n_blocks,
            "n_failed": len(design.excluded),
            "confidence_level": sens.confidence_level,
            "bootstrap_resamples": sens.bootstrap_resamples,
            "indices": {
                row.factor: {k: json_number(getattr(row, k), 4) for k in ("ST", "ST_conf", "S1", "S1_conf")}
                for row in main_indices.itertuples()
            },
        },  # fmt: skip
        "ranking_other_measures": {
            m: rank_inhibitors(indices[indices["measure"] == m])["factor"].tolist()
            for m in indices["measure"].unique()
            if m != RANKING_MEASURE
        },
    }
    metrics["ablation"] = ablation_metrics(effects)
    return metrics


def main(argv: list[str] | None = None) -> int:
    """Run the stage: read the sensitivity and ablation runs, analyse, write data/sensitivity/ and the metrics."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.sensitivity", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--out", default="data/sensitivity", help="output directory (default: data/sensitivity)")
    parser.add_argument(
        "--metrics", default="metrics/sensitivity.json", help="metrics file (default: metrics/sensitivity.json)"
    )
    args = parser.parse_args(argv)
    return run_stage("sensitivity", parser, args, lambda own: _stage(args, own), files=["metrics"], dirs=["out"])


def _stage(args: argparse.Namespace, own: Sequence[Path]) -> int:
    """The stage's work while it owns its outputs: read, compute, write; the exit code."""
    with stage_inputs("sensitivity"):
        config = load_config(args.params)
        sens = config.sensitivity
        problem = sensitivity_problem(sens.factors, sens.group)
        base = ["sample_id", "base_id", "protocol", "status", "message"]
        runs = read_runs(args.runs, "sensitivity", [*base, *problem["names"], *SOBOL_MEASURES])
        loads = ["n_axles", "chassis_tilt", *TYRE_WEAR_COLUMNS, *AXLE_LOAD_COLUMNS, "max_deviation", "p1"]
        ablation = read_runs(args.runs, "ablation", [*base, "group", "variant", *loads])
        design = saltelli_outputs(protocol_runs(runs, sens.protocol), problem, sens.base_size)
        seed = bootstrap_seed(config.seed, "sensitivity_bootstrap")
        indices = sobol_table(design, problem, sens.bootstrap_resamples, sens.confidence_level, seed)
        pairs = ablation_pairs(ablation)
    seed = bootstrap_seed(config.seed, "ablation_bootstrap")
    effects = ablation_effects(pairs, sens.bootstrap_resamples, sens.confidence_level, seed)
    metrics = sensitivity_metrics(indices, design, effects, config)
    tables = {
        "sobol_indices.csv": indices,
        "sobol_excluded.csv": design.excluded,
        "ablation.csv": effects,
        "ablation_pairs.parquet": pairs,
    }
    write_outputs(tables, args.out, metrics, args.metrics, stage="sensitivity", own=own)
    print(f"sensitivity: ranking by {metrics['ranking_measure']}: {' > '.join(metrics['ranking'])}; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
