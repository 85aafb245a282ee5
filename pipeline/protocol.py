"""How one sampled bogie is weighed: a static weighbridge and a weigh-in-motion (WIM) pass.

``static``: the empty trailer (a quarter of the design payload weight: chassis and body) is loaded to its
payload fraction on level ground, crawls at walking pace over a few metres of random road (ISO 8608, the sample's
class and seed) onto a level weighbridge, stops and settles; the axle loads are the mean over the last half
second. The load history and the approach leave friction forces locked in, as on a real weighbridge.

``wim``: the laden trailer passes at road speed over the random approach road and a WIM site at its end: the road
made smoother over the site's length before and after the sensor (:class:`bogie.wim.SiteRoad`), a sensor that reads
each tyre's force averaged over its passage across the sensor's weighing length (:func:`bogie.wim.sensor_reading`),
and a random error on each axle reading from the sensor's COST 323 accuracy class, drawn from the sample's
``sensor_seed`` (:func:`bogie.wim.axle_errors`). With no site, a point sensor and class ``none`` this is the
instantaneous wheel force on the sampled road. Sources and the effect of each part: ``docs/wim-site.md``.

Both run the full non-linear model: :mod:`bogie.nonlinear` for a steel-equalised group, :mod:`bogie.air_dynamics`
for an air-sprung one (:class:`bogie.air.AirBogie`: the same loading, roads, site, sensor and readings; its bags
start levelled and equalised, its valve and pipe work throughout). One side of the bogie is modelled; axle loads are
twice the wheel loads (both sides alike). :func:`weigh` returns one flat row of results, never raises for a
failed simulation: the row then has ``status = "failed"`` and the solver's message, and its results are null
(:mod:`pipeline.schema`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import air_dynamics, metrics, nonlinear, wim
from bogie.air import AirBogie
from bogie.params import GRAVITY, Bogie
from bogie.road import ISO8608_CLASSES, ISO8608Profile
from pipeline.config import StaticProtocol, WimProtocol
from pipeline.constants import MAX_AXLES, PAIR_TOLERANCE, READ_TIME, SHARE_TOLERANCE, TARE_FRACTION
from pipeline.schema import RESULT_COLUMNS

#: length over which the random approach road blends into the level weighbridge or starts from level [m]
BLEND_LENGTH = 1.0
#: random approach roads are generated this much longer than needed [m]
ROAD_MARGIN = 20.0


@dataclass(frozen=True)
class ApproachRoad:
    """A random ISO 8608 road of ``length`` [m] that starts and ends level (cosine blends of BLEND_LENGTH)."""

    profile: ISO8608Profile
    length: float

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        xx = np.asarray(x, dtype=float)
        ramp_in = np.clip(xx / BLEND_LENGTH, 0.0, 1.0)
        ramp_out = np.clip((self.length - xx) / BLEND_LENGTH, 0.0, 1.0)
        ramp = np.minimum(ramp_in, ramp_out)
        if ramp.ndim == 0:
            taper = 0.5 * (1.0 - np.cos(np.pi * ramp))
        else:
            # 0.5 (1 - cos 0) is exactly 0 and 0.5 (1 - cos pi) exactly 1: the cosine only over the blends (issue 15:
            # it took a tenth of a pass's road), the same taper value for value
            taper = np.ones_like(ramp)
            taper[ramp <= 0.0] = 0.0
            blend = ~((ramp <= 0.0) | (ramp >= 1.0))
            taper[blend] = 0.5 * (1.0 - np.cos(np.pi * ramp[blend]))
        return self.profile(np.clip(xx, 0.0, self.profile.length)) * taper


def _approach(road_class: str, seed: int, length: float) -> ApproachRoad:
    profile = ISO8608Profile(road_class, length=max(50.0, length + ROAD_MARGIN), seed=int(seed))
    return ApproachRoad(profile, length)


def _simulate(bogie: Bogie | AirBogie, inputs: nonlinear.Inputs, initial: Any = None) -> Any:
    """The group's time simulation over ``inputs`` from ``initial`` (None: at rest at the first input row)."""
    if isinstance(bogie, AirBogie):
        return air_dynamics.simulate(bogie, inputs, initial=initial)
    return nonlinear.simulate(bogie, inputs, initial=initial)


def static_weighbridge(
    bogie: Bogie | AirBogie, payload_fraction: float, road_class: str, road_seed: int, spec: StaticProtocol
) -> nonlinear.NonlinearResult:
    """Run the static protocol; the result's ``extras["reading"]`` holds the weighbridge's wheel loads [N]."""
    dt = spec.dt
    lead = 0.5  # the front axle starts this far before the random road [m]
    group_length = bogie.axle_x[-1] - bogie.axle_x[0]
    load = nonlinear.load_ramp(bogie, TARE_FRACTION, payload_fraction, spec.load_time, dt)
    loaded = _simulate(bogie, load)
    if not loaded.success:
        return loaded
    road = _approach(road_class, road_seed, spec.approach_length)
    distance = lead + spec.approach_length + group_length + 0.5
    crawl = nonlinear.road_inputs(
        bogie, road, spec.crawl_speed, distance / spec.crawl_speed, dt, -lead, load_factor=payload_fraction
    )
    crawled = _simulate(bogie, crawl, initial=loaded.final_state)
    if not crawled.success:
        return crawled
    settle = nonlinear.hold(bogie, spec.settle_time, dt, load_factor=payload_fraction)
    settled = _simulate(bogie, settle, initial=crawled.final_state)
    if settled.success:
        window = settled.t >= settled.t[-1] - READ_TIME
        settled.extras["reading"] = np.mean(settled.wheel_loads[window], axis=0)
        settled.extras["on_stop"] = _on_stop(settled, window)
    return settled


def wim_site(road: ApproachRoad, road_class: str, spec: WimProtocol) -> wim.SiteRoad:
    """The approach road with the WIM site of ``spec`` around the sensor, at ``spec.approach_length`` [m].

    The site's heights are the sampled road's scaled by r = min(1, sqrt(G_site / G_road)) (:class:`bogie.wim.SiteRoad`),
    G_site the ISO 8608 G_d(n0) of the site's IRI (:func:`bogie.wim.gd_n0_for_iri`) and G_road that of the
    sampled class.
    """
    scale = min(1.0, math.sqrt(wim.gd_n0_for_iri(spec.site_iri) / ISO8608_CLASSES[road_class.upper()]))
    return wim.SiteRoad(road, spec.approach_length, spec.site_before, spec.site_after, scale)


def wim_pass(
    bogie: Bogie | AirBogie,
    payload_fraction: float,
    road_class: str,
    road_seed: int,
    spec: WimProtocol,
    sensor_seed: int | None = None,
) -> nonlinear.NonlinearResult:
    """Run the WIM protocol; ``extras["reading"]`` holds each wheel's load read by the sensor [N].

    ``extras["reading_error_free"]`` is the same before the sensor's error, each tyre's force averaged over its
    passage across the sensor (:func:`bogie.wim.sensor_reading`). ``sensor_seed`` seeds the errors of
    ``spec.accuracy_class``; it may be None only for class ``none``.
    """
    dt = spec.dt
    group_length = bogie.axle_x[-1] - bogie.axle_x[0]
    road = wim_site(_approach(road_class, road_seed, spec.approach_length + group_length + 5.0), road_class, spec)
    # the site lies on the random road (WIM sites are on ordinary road, made smooth), not on the level run-out
    sensor = spec.approach_length
    half = 0.5 * (spec.sensor_length + spec.contact_length) / spec.speed  # half a tyre's passage over it [s]
    duration = (sensor + group_length) / spec.speed + half + 0.05
    inputs = nonlinear.road_inputs(bogie, road, spec.speed, duration, dt, 0.0, load_factor=payload_fraction)
    # at rest at the first row: a steel group with its friction relaxed, an air group levelled and equalised
    state = None if isinstance(bogie, AirBogie) else nonlinear.equilibrium(bogie, inputs.drive_row(bogie, 0))
    run = _simulate(bogie, inputs, initial=state)
    if run.success:
        crossing = (sensor + (np.asarray(bogie.axle_x) - bogie.axle_x[0])) / spec.speed
        passage = [
            wim.sensor_reading(run.t, run.wheel_loads[:, i], crossing[i], spec.speed, spec.sensor_length,
                               spec.contact_length)
            for i in range(bogie.n_axles)
        ]  # fmt: skip
        run.extras["reading_error_free"] = np.array(passage)
        if spec.accuracy_class == "none":
            error = np.zeros(bogie.n_axles)
        elif sensor_seed is None:
            raise ValueError(f"accuracy_class {spec.accuracy_class} needs a sensor_seed (a non-negative integer)")
        else:
            error = wim.axle_errors(spec.accuracy_class, spec.confidence_level, sensor_seed, bogie.n_axles)
        run.extras["reading"] = run.extras["reading_error_free"] * (1.0 + error)
        window = (run.t >= crossing[0] - half - 0.5 * dt) & (run.t <= crossing[-1] + half + 0.5 * dt)
        run.extras["on_stop"] = _on_stop(run, window)
    return run


def _on_stop(run: nonlinear.NonlinearResult, window: NDArray[np.bool_]) -> bool:
    """Whether an equaliser bears on its bump stop (a non-zero stop moment) at any step of ``window``; an
    air-sprung group has no equaliser (False)."""
    if "stop_moment" not in run.extras:
        return False
    moment = np.asarray(run.extras["stop_moment"])
    return bool(np.any(moment[window] != 0.0))


def result_row(
    protocol: str, n_axles: int, wheel_loads: NDArray[np.float64] | None, pitch: float, on_stop: bool = False
) -> dict[str, Any]:
    """The result columns of one weighing (:data:`pipeline.schema.RESULT_COLUMNS`) with ``protocol``.

    Axle loads [N] are twice the wheel loads (both sides); an axle the group does not have reads 0. With no
    ``wheel_loads`` (a failed weighing) every result is null: NaN for the numbers, None for the two flags.
    ``outside_5pct`` is (max W - min W) / max W > :data:`~pipeline.constants.PAIR_TOLERANCE` (VSB 11) and
    ``over_10pct`` the largest load share n W / sum W above 1 + :data:`~pipeline.constants.SHARE_TOLERANCE`.
    ``wheel_airborne``: some axle reads 0 N, its wheels in the air over their whole passage across the WIM sensor
    (the tyres are unilateral). A real WIM system records such a vehicle with a warning flag rather than dropping
    it; the row stays ``ok`` (the simulation succeeded) and the survey keeps it out of its statistics, counting it.
    ``equaliser_on_stop``: an equaliser bears on its bump stop while the protocol reads (a valid reading).
    """
    row: dict[str, Any] = {"protocol": protocol, "n_axles": int(n_axles)}
    if wheel_loads is None:
        row.update(dict.fromkeys(RESULT_COLUMNS, math.nan))
        row.update(outside_5pct=None, over_10pct=None, wheel_airborne=None, equaliser_on_stop=None)
        return row
    loads = 2.0 * np.asarray(wheel_loads, dtype=float)
    axle = np.zeros(MAX_AXLES)
    share = np.zeros(MAX_AXLES)
    axle[:n_axles] = loads
    share[:n_axles] = metrics.lsc(loads)
    heaviest, lightest = float(loads.max()), float(loads.min())
    row.update(
        group_load=float(loads.sum()),
        p=float(metrics.p(loads / loads.mean())),
        p1=float(metrics.p1(loads / loads.mean())),
        max_deviation=float(metrics.max_deviation(loads)),
        spread=float(metrics.spread(loads)),
        spread_kg=float(metrics.spread(loads) / GRAVITY),
        road_wear_factor=float(metrics.road_wear_factor(loads)),
        chassis_pitch=float(pitch),
        outside_5pct=bool((heaviest - lightest) / heaviest > PAIR_TOLERANCE),
        over_10pct=bool(heaviest / (loads.sum() / n_axles) > 1.0 + SHARE_TOLERANCE),
        wheel_airborne=bool(lightest <= 0.0),
        equaliser_on_stop=bool(on_stop),
    )
    for i in range(MAX_AXLES):
        row[f"axle_load_{i}"] = float(axle[i])
        row[f"load_share_{i}"] = float(share[i])
    return row


def weigh(
    bogie: Bogie | AirBogie, sample: Mapping[str, Any], protocol: str, spec: StaticProtocol | WimProtocol
) -> dict:
    """Weigh one sampled bogie by ``protocol``; never raises for a failed simulation (see the module text)."""
    status, message = "ok", "ok"
    reading = None
    pitch = 0.0
    on_stop = False
    try:
        args = (bogie, float(sample["payload_fraction"]), str(sample["road_class"]), int(sample["road_seed"]), spec)
        if protocol == "static":
            run = static_weighbridge(*args)
        else:
            run = wim_pass(*args, sensor_seed=int(sample["sensor_seed"]))
        if run.success and np.all(np.isfinite(run.extras["reading"])):
            reading = run.extras["reading"]
            pitch = float(run.extras["chassis_pitch"][-1])
            on_stop = bool(run.extras["on_stop"])
            # a wheel in the air as it crosses a WIM sensor is a real reading (zero load), not a failure
            if np.sum(reading) <= 0.0:
                status, message = "failed", "the group carries no load at the reading"
                reading = None
        else:
            status, message = "failed", run.message
    except Exception as exc:  # noqa: BLE001 - any error of one bogie (MemoryError included) fails its row only
        status, message = "failed", f"{type(exc).__name__}: {exc}"
        reading = None
    row = result_row(protocol, bogie.n_axles, reading, pitch, on_stop)
    row.update(status=status, message=message)
    return row
