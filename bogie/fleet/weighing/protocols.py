"""How one sampled bogie is weighed: a static weighbridge and a weigh-in-motion (WIM) pass.

``static``: the empty trailer (a quarter of the design payload weight: chassis and body) is loaded to its
payload fraction on level ground, crawls at walking pace over a few metres of random road (ISO 8608, the sample's
class and seed) onto a level weighbridge, stops and settles; the axle loads are the mean over the last half
second. The load history and the approach leave friction forces locked in, as on a real weighbridge.

``wim``: the laden trailer passes at road speed over the random approach road and a WIM site at its end: the road
made smoother over the site's length before and after the sensor (:class:`bogie.road.wim.SiteRoad`), a sensor that reads
each tyre's force averaged over its passage across the sensor's weighing length (:func:`bogie.road.wim.sensor_reading`),
and the sensor's own error, a factor common to the pass's axles and each axle's own, drawn from the sample's
``sensor_seed`` (:func:`bogie.road.wim.sensor_factors`). With no site, a point sensor and sensor ``none`` this is the
instantaneous wheel force on the sampled road. Sources and the effect of each part: ``docs/wim-site.md``.

Both run the full non-linear model: :mod:`bogie.steel.nonlinear` for a steel-equalised group, :mod:`bogie.air.dynamics`
for an air-sprung one (:class:`bogie.air.AirBogie`: the same loading, roads, site, sensor and readings; its bags
start levelled and equalised, its valve and pipe work throughout). One side of the bogie is modelled; axle loads are
twice the wheel loads (both sides alike). :func:`weigh` returns one flat row of results, never raises for a
failed simulation: the row then has ``status = "failed"`` and the solver's message, and its results are null
(:mod:`pipeline.schema`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.air import AirBogie
from bogie.air import dynamics as air_dynamics
from bogie.fleet.constants import READ_TIME, TARE_FRACTION
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.params import Bogie
from bogie.road import ISO8608_CLASSES, ISO8608Profile, wim
from bogie.steel import nonlinear
from bogie.steel import phases as phases_mod

#: length over which the random approach road blends into the level weighbridge or starts from level [m]
BLEND_LENGTH = 1.0
#: random approach roads are generated this much longer than needed [m]
ROAD_MARGIN = 20.0


@dataclass(frozen=True)
class ApproachRoad:
    """A random ISO 8608 road of ``length`` [m] that starts and ends level (cosine blends of BLEND_LENGTH)."""

    profile: ISO8608Profile
    length: float

    def taper(self, x: ArrayLike) -> NDArray[np.float64]:
        """The blend [-]: 0 off the road, rising to 1 over its first BLEND_LENGTH and falling over its last."""
        xx = np.asarray(x, dtype=float)
        ramp_in = np.clip(xx / BLEND_LENGTH, 0.0, 1.0)
        ramp_out = np.clip((self.length - xx) / BLEND_LENGTH, 0.0, 1.0)
        ramp = np.minimum(ramp_in, ramp_out)
        if ramp.ndim == 0:
            return 0.5 * (1.0 - numerics.cos(np.pi * ramp))
        # 0.5 (1 - cos 0) is exactly 0 and 0.5 (1 - cos pi) exactly 1: the cosine only over the blends (issue 15:
        # it took a tenth of a pass's road), the same taper value for value
        taper = np.ones_like(ramp)
        taper[ramp <= 0.0] = 0.0
        blend = ~((ramp <= 0.0) | (ramp >= 1.0))
        taper[blend] = 0.5 * (1.0 - numerics.cos(np.pi * ramp[blend]))
        return taper

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        xx = np.asarray(x, dtype=float)
        return self.profile(np.clip(xx, 0.0, self.profile.length)) * self.taper(xx)

    def table(self, x_from: float, x_to: float) -> phases_mod.RoadTable:
        """This road at the profile's grid points that cover [x_from, x_to] [m].

        The grid's own heights times the blend, without interpolating (the road is 0 where the blend is, off the
        road, whatever height the periodic grid has there); the same values as a call at those distances. The blend
        is evaluated only where it is neither 0 nor 1 (:func:`_blended`).
        """
        dx = self.profile.grid_spacing
        k0, k1 = math.floor(x_from / dx), math.ceil(x_to / dx)
        heights = self.profile.grid_heights(k0, k1)
        if self.length < 2.0 * BLEND_LENGTH + 2.0 * dx:  # the two blends meet: the taper's own arithmetic
            return phases_mod.RoadTable(k0 * dx, dx, heights * self.taper(np.arange(k0, k1 + 1) * dx))
        blends = ((0.0, BLEND_LENGTH, lambda x: x / BLEND_LENGTH),
                  (self.length - BLEND_LENGTH, self.length, lambda x: (self.length - x) / BLEND_LENGTH))  # fmt: skip
        return phases_mod.RoadTable(k0 * dx, dx, heights * _zoned(k0, k1, dx, blends, lambda b: b))


def _zoned(
    k0: int, k1: int, dx: float, blends: tuple[tuple[float, float, Any], ...], weight: Any
) -> NDArray[np.float64]:
    """A cosine-blended weight at the distances k dx, k = k0 .. k1 [m]: ``weight(b)`` of the blend
    b = (1 - cos(pi r)) / 2, r the ramp clipped to [0, 1] that ``ramp(x)`` gives over each blend interval (start,
    end, ramp) [m], b = 0 before the first interval and after the last and 1 between. The cosine only over the
    intervals (and a point either side): the arithmetic of :meth:`ApproachRoad.taper` and
    :meth:`bogie.road.wim.SiteRoad.site_weight`, value for value, on a table of thousands of points at the cost of a few
    hundred."""
    n = k1 - k0 + 1

    def index(x: float) -> int:
        return min(n, max(0, math.floor(x / dx) - k0))

    b = np.zeros(n)
    b[index(blends[0][1]) : index(blends[-1][0]) + 1] = 1.0
    for start, end, ramp in blends:
        lo, hi = index(start - dx), min(n, index(end + dx) + 1)
        if hi > lo:
            r = np.clip(ramp((k0 + np.arange(lo, hi)) * dx), 0.0, 1.0)
            b[lo:hi] = 0.5 * (1.0 - numerics.cos(np.pi * r))
    return weight(b)


def _approach(road_class: str, seed: int, length: float) -> ApproachRoad:
    profile = ISO8608Profile(road_class, length=max(50.0, length + ROAD_MARGIN), seed=int(seed))
    return ApproachRoad(profile, length)


def _simulate(bogie: AirBogie, inputs: nonlinear.Inputs, initial: Any = None) -> Any:
    """An air-sprung group's time simulation over ``inputs`` from ``initial`` (None: at rest at the first row)."""
    return air_dynamics.simulate(bogie, inputs, initial=initial)


@dataclass(frozen=True)
class Weighing:
    """What one weighing gives.

    Attributes
    ----------
    status, message
        "ok" and "ok", or "failed" and the solver's message (the readings are then None).
    reading
        Each wheel's load as the protocol reads it [N] (WIM: with the sensor's error).
    reading_error_free
        WIM: each tyre's force averaged over its passage across the sensor, before the sensor's error [N]; static:
        the same as ``reading``.
    on_stop
        An equaliser bore on its bump stop while the protocol read.
    chassis_pitch
        Chassis pitch at the end [rad], nose up positive.
    run
        A steel group's run of :func:`bogie.steel.phases.run`: each phase's work (steps, force evaluations, ...) and, if
        asked for, the history of the wheel loads; None for an air-sprung group, which :mod:`bogie.air.dynamics`
        steps.
    """

    status: str
    message: str
    reading: NDArray[np.float64] | None = None
    reading_error_free: NDArray[np.float64] | None = None
    on_stop: bool = False
    chassis_pitch: float = math.nan
    run: phases_mod.PhasesRun | None = None

    @property
    def success(self) -> bool:
        """True if the weighing ran to its reading."""
        return self.status == "ok"


#: share of ``StaticProtocol.step_tolerance`` (the crawl's) that the load ramp and the settle take: the ramp's slips
#: and hysteresis lock in with little to reset them, and the settle's reading averages its slow pitch oscillation,
#: whose phase error accumulates over the run (docs/phases.md, "Tolerances")
RAMP_TOLERANCE_SHARE = 1.0 / 3.0
SETTLE_TOLERANCE_SHARE = 0.2
#: the front axle starts this far before the random road of the static protocol [m]
STATIC_LEAD = 0.5


#: road tables kept per process, most recent first: a table is a pure function of the road's class and seed, the
#: protocol's geometry and the group's length, and the default study weighs many bogies on one road (the ablation's
#: seven variants of a fleet bogie share its roads, consecutive in a chunk; the Sobol' design runs all its samples on
#: one road), where synthesising the ISO 8608 profile (an inverse FFT of 16,384 points) and tabulating it was about
#: a tenth of a weighing. Fleet bogies each have their own road and miss; a miss costs what the table always cost.
#: Four covers a bogie's static and WIM tables and the design stage's conditions (each a run of consecutive samples
#: on one road); a table is up to 130 kB, so more would only hold memory
ROAD_TABLE_CACHE = 4


def _read_only(table: phases_mod.RoadTable) -> phases_mod.RoadTable:
    """``table`` with its heights made read-only: a cached table is shared by every weighing on its road."""
    table.heights.flags.writeable = False
    return table


def _crawl_distance(approach_length: float, group_length: float) -> float:
    """How far the static protocol's front axle crawls [m]: from :data:`STATIC_LEAD` before the approach road to
    half a metre onto the weighbridge with the whole group."""
    return STATIC_LEAD + approach_length + group_length + 0.5


@functools.lru_cache(maxsize=ROAD_TABLE_CACHE)
def _static_table(road_class: str, road_seed: int, approach_length: float, group_length: float) -> phases_mod.RoadTable:
    """The static protocol's crawl road: the approach road at its grid points from the rear axle's start to the
    front axle's stop (:meth:`ApproachRoad.table`); cached (:data:`ROAD_TABLE_CACHE`), read-only."""
    road = _approach(road_class, road_seed, approach_length)
    distance = _crawl_distance(approach_length, group_length)
    return _read_only(road.table(-STATIC_LEAD - group_length, distance - STATIC_LEAD))


def static_phases(
    bogie: Bogie, payload_fraction: float, road_class: str, road_seed: int, spec: StaticProtocol
) -> list[phases_mod.Phase]:
    """The static protocol's phases (:mod:`bogie.steel.phases`): the load ramp from the tare, the crawl over the
    approach road onto the weighbridge, the settle with its reading over the last :data:`READ_TIME`."""
    dt = spec.dt
    group_length = bogie.axle_x[-1] - bogie.axle_x[0]
    distance = _crawl_distance(spec.approach_length, group_length)
    table = _static_table(road_class, road_seed, spec.approach_length, group_length)
    tol = spec.step_tolerance

    def share(k: float) -> float | None:
        return None if tol is None else k * tol

    settle = phases_mod.MeanReading(spec.settle_time - READ_TIME, spec.settle_time)
    return [
        phases_mod.Phase(spec.load_time, (TARE_FRACTION, payload_fraction), dt=dt,
                         tolerance=share(RAMP_TOLERANCE_SHARE), name="load ramp"),
        phases_mod.Phase(distance / spec.crawl_speed, payload_fraction, road=table, speed=spec.crawl_speed,
                         front_axle_start=-STATIC_LEAD, dt=dt, tolerance=share(1.0), name="crawl"),
        phases_mod.Phase(spec.settle_time, payload_fraction, dt=dt, tolerance=share(SETTLE_TOLERANCE_SHARE),
                         reading=settle, name="settle"),
    ]  # fmt: skip


def static_weighbridge(
    bogie: Bogie | AirBogie,
    payload_fraction: float,
    road_class: str,
    road_seed: int,
    spec: StaticProtocol,
    history: bool = False,
) -> Weighing:
    """Run the static protocol; the reading is each wheel's mean load over the last :data:`READ_TIME` [N].

    ``history``: keep a steel group's wheel loads at every step in ``Weighing.run`` (:func:`bogie.steel.phases.run`).
    """
    if isinstance(bogie, AirBogie):
        return _air_static(bogie, payload_fraction, road_class, road_seed, spec)
    run = phases_mod.run(bogie, static_phases(bogie, payload_fraction, road_class, road_seed, spec), history=history)
    if not run.success:
        return Weighing("failed", run.message, run=run)
    settled = run.phases[-1]
    assert run.final_state is not None and settled.reading is not None
    return Weighing("ok", "ok", settled.reading, settled.reading, settled.on_stop, float(run.final_state.u[0]), run)


def _air_static(
    bogie: AirBogie, payload_fraction: float, road_class: str, road_seed: int, spec: StaticProtocol
) -> Weighing:
    """The static protocol of an air-sprung group (:mod:`bogie.air.dynamics`, fixed steps of ``spec.dt``)."""
    dt = spec.dt
    group_length = bogie.axle_x[-1] - bogie.axle_x[0]
    load = nonlinear.load_ramp(bogie, TARE_FRACTION, payload_fraction, spec.load_time, dt)
    loaded = _simulate(bogie, load)
    if not loaded.success:
        return Weighing("failed", loaded.message)
    road = _approach(road_class, road_seed, spec.approach_length)
    distance = _crawl_distance(spec.approach_length, group_length)
    crawl = nonlinear.road_inputs(
        bogie, road, spec.crawl_speed, distance / spec.crawl_speed, dt, -STATIC_LEAD, load_factor=payload_fraction
    )
    crawled = _simulate(bogie, crawl, initial=loaded.final_state)
    if not crawled.success:
        return Weighing("failed", crawled.message)
    settled = _simulate(bogie, nonlinear.hold(bogie, spec.settle_time, dt, load_factor=payload_fraction),
                        initial=crawled.final_state)  # fmt: skip
    if not settled.success:
        return Weighing("failed", settled.message)
    window = settled.t >= settled.t[-1] - READ_TIME
    reading = np.mean(settled.wheel_loads[window], axis=0)
    return Weighing("ok", "ok", reading, reading, False, float(settled.extras["chassis_pitch"][-1]))


def wim_site(road: ApproachRoad, road_class: str, spec: WimProtocol) -> wim.SiteRoad:
    """The approach road with the WIM site of ``spec`` around the sensor, at ``spec.approach_length`` [m].

    The site's heights are the sampled road's scaled by r = sqrt(G_site / G_road)
    (:class:`bogie.road.wim.SiteRoad`), G_site the ISO 8608 G_d(n0) of the site's IRI
    (:func:`bogie.road.wim.gd_n0_for_iri`) and G_road that of the sampled class: above 1 on a road smoother than the
    site (no cap: the site has its own roughness on every road, docs/wim-site.md).
    """
    scale = math.sqrt(wim.gd_n0_for_iri(spec.site_iri) / ISO8608_CLASSES[road_class.upper()])
    return wim.SiteRoad(road, spec.approach_length, spec.site_length_before, spec.site_length_after, scale)


def _wim_route(
    bogie: Bogie | AirBogie, road_class: str, road_seed: int, spec: WimProtocol
) -> tuple[ApproachRoad, wim.SiteRoad, float, float, float, float]:
    """The WIM pass's approach road, that road with the site, the pass's duration [s], and the sensor's passage:
    the time the front tyre's patch centre is over the sensor [s], half the time a patch takes to cross it,
    (S + L) / 2v, and half the time of full overlap, |S - L| / 2v [s]."""
    return _route(bogie.axle_x[-1] - bogie.axle_x[0], road_class, road_seed, spec)


def _route(
    group_length: float, road_class: str, road_seed: int, spec: WimProtocol
) -> tuple[ApproachRoad, wim.SiteRoad, float, float, float, float]:
    """:func:`_wim_route` for a group of ``group_length`` [m], front to rear axle."""
    approach = _approach(road_class, road_seed, spec.approach_length + group_length + 5.0)
    # the site lies on the random road (WIM sites are on ordinary road, made smooth), not on the level run-out
    road = wim_site(approach, road_class, spec)
    sensor = spec.approach_length
    half = 0.5 * (spec.sensor_length + spec.contact_length) / spec.speed
    flat = 0.5 * abs(spec.sensor_length - spec.contact_length) / spec.speed
    duration = (sensor + group_length) / spec.speed + half + 0.05
    return approach, road, duration, sensor / spec.speed, half, flat


@functools.lru_cache(maxsize=ROAD_TABLE_CACHE)
def _wim_table(
    road_class: str, road_seed: int, spec: WimProtocol, group_length: float
) -> tuple[phases_mod.RoadTable, float, float, float, float]:
    """The WIM pass's road (the approach road with the site's smoothing, at its grid points over the pass) and
    :func:`_wim_route`'s duration and sensor passage; cached (:data:`ROAD_TABLE_CACHE`), the table read-only."""
    approach, road, duration, crossing, half, flat = _route(group_length, road_class, road_seed, spec)
    table = approach.table(-group_length, spec.speed * duration)
    # the site's smoothing on the approach's table: the same heights as the site road's at those distances
    if road.before > 0.0 or road.after > 0.0:
        blend = wim.SITE_BLEND_LENGTH
        start, end = road.sensor - road.before, road.sensor + road.after
        blends = ((start - blend, start, lambda x: 1.0 - (road.sensor - road.before - x) / blend),
                  (end, end + blend, lambda x: 1.0 - (x - road.sensor - road.after) / blend))  # fmt: skip
        k0 = round(table.x0 / table.dx)
        smoothing = _zoned(k0, k0 + len(table.heights) - 1, table.dx, blends, lambda b: 1.0 - (1.0 - road.scale) * b)
        table = phases_mod.RoadTable(table.x0, table.dx, table.heights * smoothing)
    return _read_only(table), duration, crossing, half, flat


def wim_phases(
    bogie: Bogie, payload_fraction: float, road_class: str, road_seed: int, spec: WimProtocol
) -> list[phases_mod.Phase]:
    """The WIM protocol's one phase (:mod:`bogie.steel.phases`): the pass over the approach road and the site at fixed
    steps of ``spec.dt``, with the sensor's reading of each tyre's passage."""
    group_length = bogie.axle_x[-1] - bogie.axle_x[0]
    table, duration, crossing, half, flat = _wim_table(road_class, road_seed, spec, group_length)
    reading = phases_mod.SensorReading(crossing, half, flat)
    return [
        phases_mod.Phase(duration, payload_fraction, road=table, speed=spec.speed, dt=spec.dt, reading=reading,
                         name="WIM pass")
    ]  # fmt: skip


def wim_pass(
    bogie: Bogie | AirBogie,
    payload_fraction: float,
    road_class: str,
    road_seed: int,
    spec: WimProtocol,
    sensor_seed: int | None = None,
    history: bool = False,
) -> Weighing:
    """Run the WIM protocol; the reading is each wheel's load read by the sensor [N].

    ``reading_error_free`` is the same before the sensor's error, each tyre's force averaged over its passage across
    the sensor (:func:`bogie.road.wim.sensor_reading`). ``sensor_seed`` seeds the sensor's errors
    (:func:`bogie.road.wim.sensor_factors`: a part common to the pass's axles and each axle's own, of the sizes
    ``spec`` gives); it may be None only for an error-free sensor. ``history``: as :func:`static_weighbridge`.
    """
    if spec.error_free:
        factors = np.ones(bogie.n_axles)
    elif sensor_seed is None:
        raise ValueError(f"sensor {spec.sensor} needs a sensor_seed (a non-negative integer)")
    else:
        factors = wim.sensor_factors(spec.vehicle_error_sd, spec.axle_error_sd, sensor_seed, bogie.n_axles)
    if isinstance(bogie, AirBogie):
        weighing = _air_wim(bogie, payload_fraction, road_class, road_seed, spec)
    else:
        run = phases_mod.run(bogie, wim_phases(bogie, payload_fraction, road_class, road_seed, spec), history=history)
        if not run.success:
            return Weighing("failed", run.message, run=run)
        passed = run.phases[-1]
        assert run.final_state is not None and passed.reading is not None
        weighing = Weighing("ok", "ok", passed.reading, passed.reading, passed.on_stop, float(run.final_state.u[0]),
                            run)  # fmt: skip
    if not weighing.success or weighing.reading_error_free is None:
        return weighing
    return dataclasses.replace(weighing, reading=weighing.reading_error_free * factors)


def _air_wim(bogie: AirBogie, payload_fraction: float, road_class: str, road_seed: int, spec: WimProtocol) -> Weighing:
    """The WIM pass of an air-sprung group (:mod:`bogie.air.dynamics`, fixed steps of ``spec.dt``), error free."""
    _, road, duration, crossing, half, _ = _wim_route(bogie, road_class, road_seed, spec)
    inputs = nonlinear.road_inputs(bogie, road, spec.speed, duration, spec.dt, 0.0, load_factor=payload_fraction)
    run = _simulate(bogie, inputs)  # at rest at the first row: the bags levelled and equalised
    if not run.success:
        return Weighing("failed", run.message)
    centres = crossing + (np.asarray(bogie.axle_x) - bogie.axle_x[0]) / spec.speed
    passage = np.array([
        wim.sensor_reading(run.t, run.wheel_loads[:, i], centres[i], spec.speed, spec.sensor_length,
                           spec.contact_length)
        for i in range(bogie.n_axles)
    ])  # fmt: skip
    return Weighing("ok", "ok", passage, passage, False, float(run.extras["chassis_pitch"][-1]))
