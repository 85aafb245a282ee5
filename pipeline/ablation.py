"""The switch-off ablation: fleet bogies with each inhibitor removed, paired with themselves as they are.

Part of the ``sensitivity`` stage (:mod:`pipeline.sensitivity`): the fleet's mean inequality and tolerance
exceedance for each variant, and what removing each inhibitor buys against the baseline, with paired percentile
bootstrap intervals over bogies (``scipy.stats.bootstrap``). Method and caveats: ``docs/sensitivity.md``.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from bogie.fleet.sampling.sample import VARIANTS
from bogie.fleet.weighing.survey import inequality_columns
from bogie.params import INHIBITORS
from bogie.rounding import json_number
from pipeline.survey import RunsError

__all__ = [
    "ABLATION_STATISTICS",
    "EFFECT_COLUMNS",
    "INHIBITOR_NAMES",
    "SensitivityDataError",
    "ablation_effects",
    "ablation_metrics",
    "ablation_pairs",
]

#: the five inhibitors (the reference's four and the leaf-spring hysteresis), each switched off in one variant
INHIBITOR_NAMES: tuple[str, ...] = tuple(INHIBITORS)
#: ablation statistic -> per-bogie column it averages
ABLATION_STATISTICS: dict[str, str] = {
    "mean_max_deviation": "max_deviation",
    "mean_p1": "p1",
    "share_outside_5pct": "outside_5pct",
    "share_over_10pct": "over_10pct",
}


#: columns of :func:`ablation_effects` after the keys and counts
EFFECT_COLUMNS: tuple[str, ...] = (
    "baseline", "value", "difference", "difference_low", "difference_high", "reduction", "reduction_low",
    "reduction_high", "relative_reduction", "relative_reduction_low", "relative_reduction_high",
)  # fmt: skip


class SensitivityDataError(RunsError):
    """The runs cannot give a trustworthy Sobol' analysis or ablation (missing, failed or misordered rows)."""


def ablation_pairs(runs: pd.DataFrame) -> pd.DataFrame:
    """Each ablation variant paired with its baseline bogie (same ``base_id`` and protocol).

    Parameters
    ----------
    runs
        Runs of the ablation study, failed rows included.

    Returns
    -------
    pandas.DataFrame
        One row per protocol, bogie and variant (the baseline included): ``ok`` (variant and baseline succeeded
        and neither reading has a wheel in the air), ``airborne`` (either reading has an axle at 0 N over the WIM
        sensor: a record a WIM system flags, left out like a failure but counted apart), and ``max_deviation``,
        ``p1`` (of the loads over their mean) [-], ``outside_5pct``, ``over_10pct`` of the variant and of the
        baseline (suffix ``_baseline``); NaN for a failed run.

    Raises
    ------
    SensitivityDataError
        If a bogie lacks a variant or has one twice under a protocol.
    """
    counts = runs.groupby(["protocol", "base_id", "variant"], observed=True).size()
    complete = counts.unstack("variant").reindex(columns=list(VARIANTS))
    bad = complete[(complete != 1).any(axis=1)]
    if len(bad):
        (protocol, base_id), row = bad.index[0], bad.iloc[0]
        wrong = ", ".join(f"{v} x {int(n) if n == n else 0}" for v, n in row.items() if n != 1)
        raise SensitivityDataError(
            f"{len(bad)} ablation bogies lack a variant or have one twice, e.g. base_id {base_id} under {protocol}:"
            f" {wrong}; every bogie needs each of {', '.join(VARIANTS)} once"
        )
    frame = runs.reset_index(drop=True)
    airborne = (
        frame["wheel_airborne"].fillna(False).astype(bool)
        if "wheel_airborne" in frame
        else pd.Series(False, index=frame.index)
    )
    ok = (frame["status"] == "ok") & ~airborne
    values = ["max_deviation", "p1", "outside_5pct", "over_10pct"]
    flags = inequality_columns(frame[ok])[["outside_5pct", "over_10pct"]].astype(float)
    frame = frame.assign(outside_5pct=np.nan, over_10pct=np.nan)
    frame.loc[ok, ["outside_5pct", "over_10pct"]] = flags.to_numpy()
    frame.loc[~ok, ["max_deviation", "p1"]] = np.nan
    frame["airborne"] = airborne.to_numpy()
    keys = ["protocol", "base_id"]
    base = frame.loc[frame["variant"] == "baseline", [*keys, *values, "airborne"]]
    pairs = frame[[*keys, "group", "variant", *values, "airborne"]].merge(base, on=keys, suffixes=("", "_baseline"))
    pairs["ok"] = pairs[values[0]].notna() & pairs[f"{values[0]}_baseline"].notna()
    pairs["airborne"] = pairs["airborne"] | pairs.pop("airborne_baseline")
    pairs["variant"] = pd.Categorical(pairs["variant"], categories=list(VARIANTS))
    return pairs.sort_values(["protocol", "variant", "base_id"]).reset_index(drop=True)


def ablation_effects(pairs: pd.DataFrame, num_resamples: int, conf_level: float, seed: int) -> pd.DataFrame:
    """Fleet mean inequality of each ablation variant and its paired difference from the baseline.

    For each protocol, group (``all`` and each axle group), variant and statistic of :data:`ABLATION_STATISTICS`,
    over the bogies whose variant and baseline both succeeded: the baseline and variant means, the mean paired
    difference (variant minus baseline) with a percentile bootstrap interval over bogies, the reduction (minus the
    difference, what removing the inhibitor buys) and the relative reduction (over the baseline mean, its interval
    from the same resamples: a ratio of resampled means).

    Parameters
    ----------
    pairs
        :func:`ablation_pairs`.
    num_resamples
        Bootstrap resamples [-].
    conf_level
        Confidence level of the intervals [-].
    seed
        Seed of the bootstrap.

    Notes
    -----
    Every statistic of one protocol, group and variant is resampled with the same draws of bogies (common random
    numbers: the intervals of the four statistics describe the same resamples); the next variant draws anew from
    the one generator seeded with ``seed``.

    References
    ----------
    B. Efron, R. J. Tibshirani, *An Introduction to the Bootstrap*, Chapman & Hall, 1993, ch. 13 (percentile
    intervals).
    """
    rng = np.random.default_rng(seed)
    rows = []
    scopes = [("all", pairs)] + [(g, sub) for g, sub in pairs.groupby("group", observed=True)]
    for group, scope in scopes:
        for (protocol, variant), sub in scope.groupby(["protocol", "variant"], observed=True):
            good = sub[sub["ok"]]
            n = len(good)
            state = _PairedDraws(rng, n, num_resamples)
            for statistic, column in ABLATION_STATISTICS.items():
                row = {"protocol": protocol, "group": group, "variant": variant, "statistic": statistic}
                n_airborne = int(sub["airborne"].sum()) if "airborne" in sub else 0
                row.update(n_pairs=n, n_failed=len(sub) - n - n_airborne, n_airborne=n_airborne)
                value, baseline = good[column].to_numpy(float), good[f"{column}_baseline"].to_numpy(float)
                row.update(_paired_effect(value, baseline, state, conf_level))
                rows.append(row)
            state.advance()
    return pd.DataFrame(rows)


class _PairedDraws:
    """One set of bootstrap draws of ``n`` bogies, replayed for every statistic by :func:`scipy.stats.bootstrap`.

    scipy draws its resample indices as ``integers(0, n, (n_resamples, n))`` from the generator it is given; a
    generator restored to the same state gives every statistic the same draws, and :meth:`advance` moves the
    shared generator past them.
    """

    def __init__(self, rng: np.random.Generator, n: int, num_resamples: int) -> None:
        self.rng, self.n, self.num_resamples = rng, n, num_resamples
        self.state = rng.bit_generator.state

    def generator(self) -> np.random.Generator:
        replay = np.random.Generator(type(self.rng.bit_generator)())
        replay.bit_generator.state = self.state
        return replay

    def advance(self) -> None:
        if self.n:
            self.rng.integers(0, self.n, size=(self.num_resamples, self.n))


def _difference(value: np.ndarray, baseline: np.ndarray, axis: int = -1) -> np.ndarray:
    return (value - baseline).mean(axis=axis)


def _relative_reduction(value: np.ndarray, baseline: np.ndarray, axis: int = -1) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return 1.0 - value.mean(axis=axis) / baseline.mean(axis=axis)


def _percentile_bootstrap(
    statistic, value: np.ndarray, baseline: np.ndarray, draws: _PairedDraws, conf_level: float
) -> tuple[float, float]:
    """Paired percentile bootstrap interval of ``statistic(value, baseline)``; NaN if a resample is not finite."""
    if len(value) < 2:  # scipy needs two observations; one pair has no sampling distribution to speak of
        return np.nan, np.nan
    result = stats.bootstrap(  # numerics-ok: percentile method: integer resampling, means, np.percentile
        (value, baseline), statistic, n_resamples=draws.num_resamples, paired=True, vectorized=True,
        confidence_level=conf_level, method="percentile", rng=draws.generator(),
    )  # fmt: skip
    if not np.all(np.isfinite(result.bootstrap_distribution)):
        return np.nan, np.nan
    return float(result.confidence_interval.low), float(result.confidence_interval.high)


def _paired_effect(value: np.ndarray, baseline: np.ndarray, draws: _PairedDraws, conf_level: float) -> dict:
    if draws.n == 0:
        return dict.fromkeys(EFFECT_COLUMNS, np.nan)
    with warnings.catch_warnings():
        # a statistic that is constant over the resamples (e.g. no group over 10 % in any variant) is a
        # degenerate, zero-width interval, which is the right answer here
        warnings.simplefilter("ignore", stats.DegenerateDataWarning)  # numerics-ok: a warning class
        diff_low, diff_high = _percentile_bootstrap(_difference, value, baseline, draws, conf_level)
        rel_low, rel_high = _percentile_bootstrap(_relative_reduction, value, baseline, draws, conf_level)
    base_mean = baseline.mean()
    # a baseline with no inequality (e.g. no group over 10 %) has no relative reduction: NaN
    point = 1.0 - value.mean() / base_mean if base_mean != 0 else np.nan
    difference = float(np.mean(value - baseline))
    return {
        "baseline": float(base_mean), "value": float(value.mean()), "difference": difference,
        "difference_low": diff_low, "difference_high": diff_high, "reduction": 0.0 - difference,
        "reduction_low": 0.0 - diff_high, "reduction_high": 0.0 - diff_low, "relative_reduction": float(point),
        "relative_reduction_low": rel_low, "relative_reduction_high": rel_high,
    }  # fmt: skip


def ablation_metrics(effects: pd.DataFrame) -> dict[str, Any]:
    """The ablation part of metrics/sensitivity.json: per protocol, the fleet baseline and each variant's gain."""
    fleet = effects[effects["group"] == "all"].set_index(["protocol", "variant", "statistic"]).sort_index()
    summary: dict[str, Any] = {}
    for protocol in fleet.index.unique("protocol"):
        entry: dict[str, Any] = {}
        base = fleet.loc[(protocol, "baseline")]
        entry["baseline"] = {s: json_number(base.loc[s, "value"], 4) for s in ABLATION_STATISTICS}
        entry["baseline"]["n_bogies"] = int(base["n_pairs"].iloc[0])
        for variant in VARIANTS[1:]:
            dev, out5 = (
                fleet.loc[(protocol, variant, "mean_max_deviation")],
                fleet.loc[(protocol, variant, "share_outside_5pct")],
            )
            entry[variant] = {
                "mean_max_deviation": json_number(dev["value"], 4), "reduction": json_number(dev["reduction"], 4),
                "reduction_low": json_number(dev["reduction_low"], 4),
                "reduction_high": json_number(dev["reduction_high"], 4),
                "relative_reduction": json_number(dev["relative_reduction"], 3),
                "share_outside_5pct": json_number(out5["value"], 4), "n_failed": int(dev["n_failed"]),
                "n_airborne": int(dev["n_airborne"]),
            }  # fmt: skip
        singles = {v: entry[v]["reduction"] for v in INHIBITOR_NAMES if entry[v]["reduction"] is not None}
        entry["largest_single_gain"] = max(singles, key=singles.get) if singles else None
        summary[protocol] = entry
    return summary
