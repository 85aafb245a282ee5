"""What the WIM shows, by cause: on the calibrated fleet, how much of the inequality the readings show comes from
the file's resolution, the sensor, the chassis tilt and the dynamics, and how much is the suspension's own at rest
(``docs/calibration.md``, issue 30 Must 6; Shapley shares, issue 43 Must 3).

Paired runs: the calibration bogies of the calibrated fleet (their fitted tilts, suspensions and inhibitor
distributions) weighed four ways with common random numbers: by WIM at their tilt and level, statically at their
tilt and level. The tilt and the dynamics choose the weighing; the sensor (times its factors) and the resolution
(rounded to the file's step, after the sensor) are post-processing of its readings. So every on/off combination of
the four causes, 2^4 = 16 (:data:`COMBINATIONS`), comes from the four weighings. Six have names:

| scenario | causes on | readings |
|---|---|---|
| ``as_observed`` | all | WIM at the fitted tilt, times the sensor's factors, read at the file's resolution |
| ``no_resolution`` | all but resolution | the same, not rounded |
| ``no_sensor`` | all but sensor | WIM at the fitted tilt, read at the resolution, no sensor error |
| ``no_tilt`` | all but tilt | WIM with the chassis level, with the sensor's error, at the resolution |
| ``no_dynamics`` | all but dynamics | static at the fitted tilt, with the sensor's error, at the resolution |
| ``at_rest`` | none | the static weighing with the chassis level, exact: the suspension mechanics alone |

and the ten others ``with_<the causes on>``. With v(S) a statistic of the readings with the causes in S on, a
cause's **Shapley share** (:func:`shapley_shares`) is its step v(S + i) - v(S) averaged over every order of
switching the causes on: the four add up exactly to the **total** ``as_observed - at_rest``. Beside them the
**one-at-a-time share** ``as_observed - no_<cause>`` (:func:`one_at_a_time_shares`, the attribution before issue 43)
and the **interaction**, the total less the one-at-a-time shares. The groups compared are the same in every
combination: those ``as_observed`` keeps (laden, every wheel read) and that every combination weighed. The shares
are linear in the statistic, a mean over the groups: computed per group and averaged. Intervals: a paired bootstrap
over the groups, one resample of the groups for every combination and share, so each resample's Shapley shares add
up to its total too.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from bogie.fleet.calibration.problem import SIZES, CalibrationError, Mapper, Table
from bogie.fleet.calibration.table import bogie_tilts, moved_samples, protocol_spec, weigh_readings
from bogie.fleet.weighing.settings import StaticProtocol
from bogie.intervals import percentile_interval
from bogie.rounding import json_number
from bogie.weighings.stats import at_resolution, group_inequality

__all__ = [
    "CAUSES", "COMBINATIONS", "SCENARIOS", "STATISTICS", "Estimate", "GroupAttribution", "attribute_loads",
    "attribution", "combination_loads", "combination_name", "one_at_a_time_shares", "scenario_loads",
    "shapley_shares",
]  # fmt: skip

#: the causes, and the named scenario with each switched off (the others on)
CAUSES: dict[str, str] = {
    "resolution": "no_resolution", "sensor": "no_sensor", "tilt": "no_tilt", "dynamics": "no_dynamics",
}  # fmt: skip
#: the named scenarios: all on, each cause off alone, all off
SCENARIOS: tuple[str, ...] = ("as_observed", *CAUSES.values(), "at_rest")
#: every on/off combination of the causes (the set of those on), in the order of the table: all on, then one off
#: (in the order of CAUSES), two off, three off, all off
COMBINATIONS: tuple[frozenset[str], ...] = tuple(
    frozenset(CAUSES) - frozenset(off) for r in range(len(CAUSES) + 1) for off in itertools.combinations(CAUSES, r)
)
#: the statistics attributed: share of groups outside 5 % (VSB 11) [-], share with an axle over 10 % of its equal
#: share [-], mean spread (max - min) / mean [%]
STATISTICS: tuple[str, ...] = ("share_outside_5pct", "share_over_10pct", "mean_spread_pct")


def combination_name(on: Sequence[str] | frozenset[str]) -> str:
    """A combination's name, given the causes on: a scenario of :data:`SCENARIOS` (all on, one off, none on), else
    ``with_`` and the causes on joined by ``+`` in the order of :data:`CAUSES` (``with_sensor+tilt``)."""
    on = frozenset(on)
    if not on <= set(CAUSES):
        raise CalibrationError(f"causes {sorted(on - set(CAUSES))}: must be of {', '.join(CAUSES)}")
    off = [c for c in CAUSES if c not in on]
    if not off:
        return "as_observed"
    if not on:
        return "at_rest"
    if len(off) == 1:
        return CAUSES[off[0]]
    return "with_" + "+".join(c for c in CAUSES if c in on)


# ---- the arithmetic of the shares ---------------------------------------------------------------------------------
def _by_bitmask(values: Mapping[frozenset[str], Any] | Sequence[Any] | np.ndarray, causes: tuple[str, ...]):
    """``values`` as an array whose first axis is the combination's bitmask (bit ``b`` set: ``causes[b]`` on)."""
    n = len(causes)
    if n == 0 or len(set(causes)) != n:
        raise ValueError(f"causes = {causes!r}: must be one or more distinct names")
    if isinstance(values, Mapping):
        keys = [frozenset(c for b, c in enumerate(causes) if mask >> b & 1) for mask in range(1 << n)]
        missing = [sorted(k) for k in keys if k not in values]
        if missing:
            raise ValueError(f"values: no entry for the combinations {missing} (keys: frozensets of the causes on)")
        return np.stack([np.asarray(values[k], dtype=float) for k in keys])
    v = np.asarray(values, dtype=float)
    if v.ndim < 1 or v.shape[0] != (1 << n):
        raise ValueError(f"values: {v.shape[0] if v.ndim else 0} entries; {len(causes)} causes make {1 << n}")
    return v


def _plain(x: np.ndarray) -> Any:
    return float(x) if np.ndim(x) == 0 else x


def shapley_shares(
    values: Mapping[frozenset[str], Any] | Sequence[Any] | np.ndarray, causes: Sequence[str]
) -> dict[str, Any]:
    """Each cause's Shapley share of ``v(all) - v(none)``: ``φ_i = Σ_{S ∌ i} |S|! (n - |S| - 1)! / n! [v(S ∪ {i}) -
    v(S)]``, its step averaged over every order of switching the causes on; the shares add up to ``v(all) -
    v(none)`` (``docs/calibration.md``).

    ``values``: v of every combination, a mapping from the frozenset of the causes on to a number (or an array: the
    shares are taken element-wise), or an array whose first axis, of length 2^n, is the bitmask of the causes on
    (bit ``b``: ``causes[b]``). Returns cause -> share (a float, or an array of v's other axes)."""
    causes = tuple(causes)
    v, n = _by_bitmask(values, causes), len(causes)
    weight = [math.factorial(s) * math.factorial(n - s - 1) / math.factorial(n) for s in range(n)]
    shares = {}
    for b, cause in enumerate(causes):
        bit = 1 << b
        steps = [weight[mask.bit_count()] * (v[mask | bit] - v[mask]) for mask in range(1 << n) if not mask & bit]
        shares[cause] = _plain(np.sum(steps, axis=0))
    return shares


def one_at_a_time_shares(
    values: Mapping[frozenset[str], Any] | Sequence[Any] | np.ndarray, causes: Sequence[str]
) -> dict[str, Any]:
    """Each cause's one-at-a-time share ``v(all) - v(all without it)``, what switching it alone off removes (the
    arguments as :func:`shapley_shares`'s). They need not add up to ``v(all) - v(none)``: the rest is the
    interaction."""
    causes = tuple(causes)
    v, full = _by_bitmask(values, causes), (1 << len(causes)) - 1
    return {cause: _plain(v[full] - v[full ^ (1 << b)]) for b, cause in enumerate(causes)}


# ---- the loads of every combination --------------------------------------------------------------------------------
def combination_loads(
    weighed: Mapping[str, np.ndarray], factors: np.ndarray, weight_step_kg: float | None
) -> dict[frozenset[str], np.ndarray]:
    """Every combination's loads [kg] (:data:`COMBINATIONS` -> (n, 3)) from the four weighings ``weighed``
    (``wim``, ``wim_level``, ``static``, ``static_level``): the tilt on reads the tilted weighing, the dynamics on
    the WIM's; the sensor on multiplies by its ``factors``, then the resolution on rounds to ``weight_step_kg``."""
    loads = {}
    for on in COMBINATIONS:
        w = weighed[("wim" if "dynamics" in on else "static") + ("" if "tilt" in on else "_level")]
        w = w * factors if "sensor" in on else w
        loads[on] = at_resolution(w, weight_step_kg) if "resolution" in on else w
    return loads


def scenario_loads(
    table: Table, values: Mapping[str, float], static: StaticProtocol, weight_step_kg: float | None,
    executor: Executor | Mapper | None = None,
) -> tuple[dict[frozenset[str], np.ndarray], np.ndarray]:  # fmt: skip
    """Every combination's loads [kg] of the calibrated fleet (:data:`COMBINATIONS` -> (n, 3),
    :func:`combination_loads`), and each bogie's suspension (``steel``/``air``). Four direct weighings of the
    calibration bogies (WIM and static, tilted and level)."""
    if table.protocol != "wim":
        raise CalibrationError("attribution: the table must be a WIM calibration's (it splits the WIM's readings)")
    if not isinstance(static, StaticProtocol):
        raise CalibrationError(f"static = {static!r}: must be a StaticProtocol (the weighing without dynamics)")
    tilt = np.radians(bogie_tilts(table, values))
    kinds = np.where(table.air_u < values["air_share"], "air", "steel")
    rows = moved_samples(table, values).to_dict("records")
    wim = protocol_spec(table, values["site_iri_m_km"])
    weighed = {}
    for name, protocol, spec, level in (
        ("wim", "wim", wim, False), ("wim_level", "wim", wim, True), ("static", "static", static, False),
        ("static_level", "static", static, True),
    ):  # fmt: skip
        tasks = [
            table.task(i, {**row, "suspension": kinds[i], "chassis_tilt": 0.0 if level else float(tilt[i])}, spec,
                       protocol)
            for i, row in enumerate(rows)
        ]  # fmt: skip
        weighed[name] = weigh_readings(tasks, executor)
    factors = table.reading_factors(values)
    return combination_loads(weighed, factors, weight_step_kg), kinds


# ---- the attribution ----------------------------------------------------------------------------------------------
def _statistics(loads: np.ndarray, n: int) -> np.ndarray:
    """Per group: outside 5 %, over 10 %, spread [%] (columns of :data:`STATISTICS`)."""
    ineq = group_inequality(loads, np.full(len(loads), n))
    return np.column_stack([ineq["outside_5pct"], ineq["over_10pct"], ineq["spread_pct"]]).astype(float)


@dataclass(frozen=True)
class Estimate:
    """A quantity of the attribution, unrounded: ``value`` (statistics,), the mean over the groups, and ``boot``
    (resamples, statistics), the same over each bootstrap resample of the groups."""

    value: np.ndarray
    boot: np.ndarray

    @classmethod
    def of(cls, per_group: np.ndarray, idx: np.ndarray) -> Estimate:
        """From the quantity of each group (groups, statistics) and the resamples' group indices (resamples,
        groups)."""
        return cls(per_group.mean(axis=0), per_group[idx].mean(axis=1))

    def entry(self, j: int, confidence_level: float) -> dict[str, float | None]:
        """Statistic ``j``'s value and percentile interval, for JSON."""
        low, high = percentile_interval(self.boot[:, j], confidence_level)
        return {"value": json_number(self.value[j]), "low": json_number(low), "high": json_number(high)}


@dataclass(frozen=True)
class GroupAttribution:
    """One size and suspension's attribution, unrounded: ``means`` (16, statistics), each combination's statistics
    in the order of :data:`COMBINATIONS`; ``total`` (as observed - at rest), each cause's ``shapley`` and
    ``one_at_a_time`` share, and the ``interaction`` (total - the one-at-a-time shares)."""

    n_groups: int
    n_dropped: int
    means: np.ndarray
    total: Estimate
    shapley: dict[str, Estimate]
    one_at_a_time: dict[str, Estimate]
    interaction: Estimate


def _group_attribution(per: np.ndarray, idx: np.ndarray, dropped: int) -> GroupAttribution:
    """From each combination's per-group statistics ``per`` (16 in COMBINATIONS' order, groups, statistics)."""
    causes = tuple(CAUSES)
    by_mask = {on: per[i] for i, on in enumerate(COMBINATIONS)}
    total = per[0] - per[-1]
    shapley = shapley_shares(by_mask, causes)
    single = one_at_a_time_shares(by_mask, causes)
    interaction = total - np.sum([single[c] for c in causes], axis=0)
    return GroupAttribution(
        per.shape[1], dropped, per.mean(axis=1), Estimate.of(total, idx),
        {c: Estimate.of(shapley[c], idx) for c in causes}, {c: Estimate.of(single[c], idx) for c in causes},
        Estimate.of(interaction, idx),
    )  # fmt: skip


def attribute_loads(
    loads: Mapping[frozenset[str], np.ndarray], kinds: np.ndarray, size: np.ndarray, min_group_load_kg: float,
    seed: int = 0, resamples: int = 200,
) -> dict[str, GroupAttribution]:  # fmt: skip
    """The attribution of every combination's ``loads`` [kg] (:data:`COMBINATIONS` -> (n, 3), e.g.
    :func:`scenario_loads`), per ``size/suspension`` of the bogies' ``size`` and ``kinds``, unrounded; groups kept
    if ``as_observed`` reads them laden (every wheel read, at least ``min_group_load_kg``) and every combination
    weighed them. ``seed``, ``resamples``: the paired bootstrap's (spawn key 4; one resample of the groups for
    every combination and share)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(4,)))
    out = {}
    for group, n in SIZES.items():
        for kind in ("steel", "air"):
            sel = (size == group) & (kinds == kind)
            obs = loads[COMBINATIONS[0]][sel, :n]
            laden = np.all(np.isfinite(obs) & (obs > 0.0), axis=1) & (np.nansum(obs, axis=1) >= min_group_load_kg)
            ok = laden.copy()
            for on in COMBINATIONS:
                w = loads[on][sel, :n]
                ok &= np.all(np.isfinite(w) & (w > 0.0), axis=1)
            if not ok.any():
                continue
            per = np.stack([_statistics(loads[on][sel, :n][ok], n) for on in COMBINATIONS])
            idx = rng.integers(0, int(ok.sum()), size=(max(resamples, 2), int(ok.sum())))
            out[f"{group}/{kind}"] = _group_attribution(per, idx, int((laden & ~ok).sum()))
    return out


def attribution(
    table: Table, values: Mapping[str, float], min_group_load_kg: float, static: StaticProtocol,
    weight_step_kg: float | None = None, executor: Executor | Mapper | None = None, seed: int = 0,
    resamples: int = 200, confidence_level: float = 0.9,
) -> tuple[pd.DataFrame, dict[str, Any]]:  # fmt: skip
    """The attribution of the calibrated fleet's WIM inequality to its causes.

    Parameters
    ----------
    table, values
        The calibration's table (a WIM one) and the calibrated fleet's values (every quantity).
    min_group_load_kg
        The survey's smallest group load [kg], applied to the ``as_observed`` readings.
    static
        The static weighing's settings: the readings without dynamics.
    weight_step_kg
        The observed file's resolution [kg] (None: whole numbers as they are).
    executor
        Where the weighings run.
    seed, resamples, confidence_level
        The paired bootstrap's seed, resamples (>= 2) and the intervals' confidence level (0, 1).

    Returns
    -------
    table : DataFrame
        One row per combination (:data:`COMBINATIONS`), size and suspension: ``scenario``
        (:func:`combination_name`), ``group``, ``suspension``, whether each cause of :data:`CAUSES` is on,
        ``n_groups`` and each of :data:`STATISTICS`.
    metrics : dict
        Per ``size/suspension``: ``n_groups``, ``n_dropped`` (weighed in one combination but not another),
        ``as_observed`` and ``at_rest`` statistics, and each statistic's ``value`` with its interval ``low``,
        ``high`` under ``total``, ``shapley.<cause>``, ``one_at_a_time.<cause>`` and ``interaction``
        (``docs/calibration.md``).
    """
    loads, kinds = scenario_loads(table, values, static, weight_step_kg, executor)
    by_group = attribute_loads(loads, kinds, table.size, min_group_load_kg, seed, resamples)
    return _table(by_group), {key: _metrics_of(att, confidence_level) for key, att in by_group.items()}


def _table(by_group: Mapping[str, GroupAttribution]) -> pd.DataFrame:
    """The statistics of every combination, per size and suspension."""
    rows = []
    for key, att in by_group.items():
        group, kind = key.split("/")
        for on, means in zip(COMBINATIONS, att.means, strict=True):
            rows.append({"scenario": combination_name(on), "group": group, "suspension": kind,
                         **{c: c in on for c in CAUSES}, "n_groups": att.n_groups,
                         **dict(zip(STATISTICS, means, strict=True))})  # fmt: skip
    return pd.DataFrame(rows, columns=["scenario", "group", "suspension", *CAUSES, "n_groups", *STATISTICS])


def _metrics_of(att: GroupAttribution, confidence_level: float) -> dict[str, Any]:
    """One size and suspension's attribution for JSON, rounded."""

    def entries(estimate: Estimate) -> dict[str, dict[str, float | None]]:
        return {s: estimate.entry(j, confidence_level) for j, s in enumerate(STATISTICS)}

    return {
        "n_groups": att.n_groups, "n_dropped": att.n_dropped,
        "as_observed": {s: json_number(att.means[0, j]) for j, s in enumerate(STATISTICS)},
        "at_rest": {s: json_number(att.means[-1, j]) for j, s in enumerate(STATISTICS)},
        "total": entries(att.total),
        "shapley": {c: entries(e) for c, e in att.shapley.items()},
        "one_at_a_time": {c: entries(e) for c, e in att.one_at_a_time.items()},
        "interaction": entries(att.interaction),
    }  # fmt: skip
