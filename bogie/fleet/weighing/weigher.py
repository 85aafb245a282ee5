"""Weighing sampled bogies: each sample row by each protocol, one run row per weighing, never an exception.

:func:`weigh_fleet` weighs a table of samples (:func:`bogie.fleet.sample_fleet`) by the protocols given (a static
weighbridge, a WIM pass: their settings in :mod:`bogie.fleet.weighing.settings`, their simulation in
:mod:`bogie.fleet.weighing.protocols`) and returns the runs table (:mod:`bogie.fleet.weighing.runs`): one row per
(sample, protocol). A sample that is not a valid bogie or whose simulation fails is a row with ``status = "failed"``,
its reason in ``message`` and every result null; it is never dropped, and nothing raises for it. Every run is a pure
function of its sample row and protocol, so the table is the same whatever the executor, the number of workers or the
chunking.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from bogie import metrics
from bogie.air import AirBogie
from bogie.fleet.constants import MAX_AXLES, PAIR_TOLERANCE, PROTOCOLS, SHARE_TOLERANCE
from bogie.fleet.sampling.sample import COLUMNS, bogie_from_sample
from bogie.fleet.weighing.protocols import static_weighbridge, wim_pass
from bogie.fleet.weighing.runs import RESULT_COLUMNS, RUN_COLUMNS, runs_frame
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.params import GRAVITY, Bogie
from bogie.settings import check_value

__all__ = ["Outcome", "Protocols", "result_row", "result_rows", "weigh", "weigh_fleet", "weigh_rows", "weighing"]

#: (name, settings) of each protocol a sample is weighed by, in the order of its rows
Protocols = tuple[tuple[str, StaticProtocol | WimProtocol], ...]


def result_row(
    protocol: str, n_axles: int, wheel_loads: NDArray[np.float64] | None, pitch: float, on_stop: bool = False
) -> dict[str, Any]:
    """The result columns of one weighing (:data:`bogie.fleet.weighing.runs.RESULT_COLUMNS`) with ``protocol``.

    Axle loads [N] are twice the wheel loads (both sides); an axle the group does not have reads 0. With no
    ``wheel_loads`` (a failed weighing) every result is null: NaN for the numbers, None for the two flags.
    ``outside_5pct`` is (max W - min W) / max W > :data:`~bogie.fleet.constants.PAIR_TOLERANCE` (VSB 11) and
    ``over_10pct`` the largest load share n W / sum W above 1 + :data:`~bogie.fleet.constants.SHARE_TOLERANCE`.
    ``wheel_airborne``: some axle reads 0 N, its wheels in the air over their whole passage across the WIM sensor
    (the tyres are unilateral). A real WIM system records such a vehicle with a warning flag rather than dropping
    it; the row stays ``ok`` (the simulation succeeded) and the survey keeps it out of its statistics, counting it.
    ``equaliser_on_stop``: an equaliser bears on its bump stop while the protocol reads (a valid reading).
    The row also has ``status`` and ``message``, "ok" both (:func:`result_rows` of one :class:`Outcome`).
    """
    return result_rows([Outcome(protocol, int(n_axles), wheel_loads, pitch, on_stop)])[0]


@dataclass(frozen=True)
class Outcome:
    """What one weighing of :func:`weighing` gives: its protocol and group size, the reading of each wheel [N] (None
    if it failed), the chassis pitch [rad], whether an equaliser bore on its stop, and its status and message."""

    protocol: str
    n_axles: int
    wheel_loads: NDArray[np.float64] | None
    pitch: float = 0.0
    on_stop: bool = False
    status: str = "ok"
    message: str = "ok"


def result_rows(outcomes: Sequence[Outcome]) -> list[dict[str, Any]]:
    """:func:`result_row` of each weighing, with its ``status`` and ``message``: one numpy pass over the weighings
    of each group size instead of a dozen small numpy calls a weighing (issue 15: they cost a tenth of a ms a run).

    The same arithmetic as the :mod:`bogie.metrics` functions on each weighing alone (they reduce along the axles,
    the last axis, row by row), so every value is the one they give for that weighing by itself.
    """
    rows: list[dict[str, Any]] = []
    groups: dict[int, list[int]] = {}
    for k, o in enumerate(outcomes):
        row: dict[str, Any] = {"protocol": o.protocol, "n_axles": int(o.n_axles)}
        if o.wheel_loads is None:
            row.update(_NULL_RESULTS)
        else:
            groups.setdefault(int(o.n_axles), []).append(k)
        row.update(status=o.status, message=o.message)
        rows.append(row)
    for n, members in groups.items():
        loads = 2.0 * np.array([outcomes[k].wheel_loads for k in members], dtype=float).reshape(len(members), n)
        total = loads.sum(axis=-1)
        relative = loads / loads.mean(axis=-1, keepdims=True)
        heaviest, lightest = loads.max(axis=-1), loads.min(axis=-1)
        spread = metrics.spread(loads)
        share = metrics.lsc(loads)
        columns: dict[str, list] = {
            "group_load": total.tolist(),
            "p": metrics.p(relative).tolist(),
            "p1": metrics.p1(relative).tolist(),
            "max_deviation": metrics.max_deviation(loads).tolist(),
            "spread": spread.tolist(),
            "spread_kg": (spread / GRAVITY).tolist(),
            "road_wear_factor": metrics.road_wear_factor(loads).tolist(),
            "chassis_pitch": [float(outcomes[k].pitch) for k in members],
            "outside_5pct": ((heaviest - lightest) / heaviest > PAIR_TOLERANCE).tolist(),
            "over_10pct": (heaviest / (total / n) > 1.0 + SHARE_TOLERANCE).tolist(),
            "wheel_airborne": (lightest <= 0.0).tolist(),
            "equaliser_on_stop": [bool(outcomes[k].on_stop) for k in members],
        }
        for i in range(MAX_AXLES):
            columns[f"axle_load_{i + 1}"] = loads[:, i].tolist() if i < n else [0.0] * len(members)
            columns[f"load_share_{i + 1}"] = share[:, i].tolist() if i < n else [0.0] * len(members)
        names = list(columns)
        for k, values in zip(members, zip(*columns.values())):
            rows[k].update(zip(names, values))
    return rows


#: a failed weighing's results: NaN for the numbers, None for the flags
_NULL_RESULTS: dict[str, Any] = {c: None if RUN_COLUMNS[c] == "boolean" else math.nan for c in RESULT_COLUMNS}


def weighing(
    bogie: Bogie | AirBogie, sample: Mapping[str, Any], protocol: str, spec: StaticProtocol | WimProtocol
) -> Outcome:
    """Weigh one sampled bogie by ``protocol``: its reading, never an exception for a failed simulation (see the
    module text); :func:`result_rows` makes the run rows of many such weighings."""
    try:
        args = (bogie, float(sample["payload_fraction"]), str(sample["road_class"]), int(sample["road_seed"]), spec)
        if protocol == "static":
            run = static_weighbridge(*args)
        else:
            run = wim_pass(*args, sensor_seed=int(sample["sensor_seed"]))
        if not run.success:
            return Outcome(protocol, bogie.n_axles, None, status="failed", message=run.message)
        if run.reading is None or not np.all(np.isfinite(run.reading)):
            return Outcome(protocol, bogie.n_axles, None, status="failed", message="the reading is not finite")
        # a wheel in the air as it crosses a WIM sensor is a real reading (zero load), not a failure
        if np.sum(run.reading) <= 0.0:
            return Outcome(protocol, bogie.n_axles, None, status="failed",
                           message="the group carries no load at the reading")  # fmt: skip
        return Outcome(protocol, bogie.n_axles, run.reading, run.chassis_pitch, run.on_stop)
    except Exception as exc:  # noqa: BLE001 - any error of one bogie (MemoryError included) fails its row only
        return Outcome(protocol, bogie.n_axles, None, status="failed", message=f"{type(exc).__name__}: {exc}")


def weigh(
    bogie: Bogie | AirBogie, sample: Mapping[str, Any], protocol: str, spec: StaticProtocol | WimProtocol
) -> dict:
    """Weigh one sampled bogie by ``protocol``: its result columns (:func:`result_row`) with ``status`` and
    ``message``; never raises for a failed simulation (see the module text)."""
    return result_rows([weighing(bogie, sample, protocol, spec)])[0]


#: the numerical result columns: a successful row with a non-finite one is a failed run
_NUMBERS: tuple[str, ...] = tuple(c for c in RESULT_COLUMNS if RUN_COLUMNS[c] == "float64")


def weigh_rows(rows: Mapping[str, Sequence], protocols: Protocols) -> list[dict]:
    """Weigh every sample of ``rows`` (column name -> the samples' Python values) by every protocol: one dict of
    run columns per (sample, protocol). The result columns of the whole chunk come from one
    :func:`result_rows`."""
    names = list(rows)
    samples, outcomes = [], []
    for values in zip(*rows.values()):
        sample = dict(zip(names, values))
        try:
            bogie_ = bogie_from_sample(sample)
            invalid = None
        except (ValueError, TypeError) as exc:
            bogie_, invalid = None, f"invalid bogie: {type(exc).__name__}: {exc}"
        sample["chassis_tilt_deg"] = math.degrees(float(sample["chassis_tilt"]))
        for name, spec in protocols:
            if bogie_ is None:
                outcomes.append(Outcome(name, int(sample["n_axles"]), None, status="failed", message=invalid))
            else:
                outcomes.append(weighing(bogie_, sample, name, spec))
            samples.append(sample)
    out = []
    for sample, outcome, result in zip(samples, outcomes, result_rows(outcomes)):
        # math.isfinite: np.isfinite's ufunc call on each of the ~40 numbers cost a tenth of a ms a row
        bad = [c for c in _NUMBERS if not math.isfinite(result[c])] if result["status"] == "ok" else []
        if bad:
            # a successful row has no null: a non-finite metric is a failed run, not a number
            failed = Outcome(outcome.protocol, outcome.n_axles, None, status="failed",
                             message=f"non-finite result in {', '.join(bad)}")  # fmt: skip
            result = result_rows([failed])[0]
        out.append({**sample, **result})
    return out


#: samples weighed per task of an executor: enough to keep the task's overhead small, few enough to share the work
CHUNK_ROWS = 8


def _protocols(protocols: Mapping[str, StaticProtocol | WimProtocol]) -> Protocols:
    kinds = {"static": StaticProtocol, "wim": WimProtocol}
    if not protocols:
        raise ValueError(f"protocols: none given; allowed: {', '.join(PROTOCOLS)}, each with its settings")
    for name, spec in protocols.items():
        if name not in kinds:
            raise ValueError(f"protocols: {name!r} unknown; allowed: {', '.join(PROTOCOLS)}")
        if not isinstance(spec, kinds[name]):
            raise ValueError(f"protocols[{name!r}] = {spec!r}: must be a {kinds[name].__name__}")
    return tuple(protocols.items())


def weigh_fleet(
    samples: pd.DataFrame,
    protocols: Mapping[str, StaticProtocol | WimProtocol],
    executor: Executor | None = None,
    chunk_rows: int = CHUNK_ROWS,
) -> pd.DataFrame:
    """Weigh every sampled bogie by every protocol: the runs table.

    Parameters
    ----------
    samples
        Sample rows with the columns of :data:`bogie.fleet.sampling.sample.COLUMNS` (:func:`bogie.fleet.sample_fleet`).
    protocols
        Protocol name (``static``, ``wim``) -> its settings (:class:`~bogie.fleet.weighing.settings.StaticProtocol`,
        :class:`~bogie.fleet.weighing.settings.WimProtocol`); each sample's rows follow this order.
    executor
        Where to weigh: None in this process; any :class:`concurrent.futures.Executor` (a
        ``ProcessPoolExecutor``, a dask ``Client.get_executor()``) maps chunks of ``chunk_rows`` samples over its
        workers. The table is the same whatever the executor.
    chunk_rows
        Samples per task [-], at least 1.

    Returns
    -------
    pandas.DataFrame
        ``len(samples) * len(protocols)`` rows, sample by sample, with the columns and dtypes of
        :data:`bogie.fleet.weighing.runs.RUN_COLUMNS` (SI; ``chassis_tilt_deg`` in degrees). A sample that is not a
        valid bogie, or whose weighing fails, has rows with ``status = "failed"``, the reason in ``message`` and nulls
        in every result column.

    Raises
    ------
    ValueError
        If a protocol is unknown or its settings are not of its kind, a sample column is missing, or
        ``chunk_rows`` < 1.
    """
    pairs = _protocols(protocols)
    missing = [c for c in COLUMNS if c not in samples.columns and c != "study"]
    if missing:
        raise ValueError(
            f"samples: the columns {', '.join(missing)} are missing (see bogie.fleet.sampling.sample.COLUMNS)"
        )
    check_value("chunk_rows", chunk_rows, low=1, whole=True)
    # the columns' Python scalars, as to_dict("records") gives them, at a third of its cost
    columns = {c: samples[c].tolist() for c in samples.columns}
    chunks = [{c: v[i : i + chunk_rows] for c, v in columns.items()} for i in range(0, len(samples), chunk_rows)]
    task = functools.partial(weigh_rows, protocols=pairs)
    parts: Iterable[list[dict]] = map(task, chunks) if executor is None else executor.map(task, chunks)
    return runs_frame([row for part in parts for row in part])
