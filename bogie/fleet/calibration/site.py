"""The WIM site in the calibration's observation model (issue 43 Must 2; ``docs/calibration.md``, "The site").

A survey's vehicles share what its one site does to them:

1. **Its calibration bias.** Every reading of the site is its force times ``1 + b`` (``b`` the quantity
   ``site_bias_pct`` / 100), whatever the vehicle: a fitted quantity under a sourced prior
   (:mod:`bogie.fleet.calibration.priors`), applied with the sensor's factors (:meth:`Table.reading_factors
   <bogie.fleet.calibration.table.Table.reading_factors>`).
2. **Its road.** One realisation of the approach road and the site (:class:`Site`: an ISO 8608 class and a seed),
   crossed by every vehicle of the survey, each at its own speed (:func:`bogie_speeds`): the spatial repeatability
   of dynamic loads (Cole and Cebon; Hodge 1989, TRRL RR214: mean impact factors 0.89-1.08 between sites).
3. **So the model's site is not the survey's.** The site the table is built on is one draw of the sites the survey
   could have been made at; the summaries' variance between sites enters the likelihood's covariance
   (:func:`bogie.fleet.calibration.posterior.site_covariance`).

Speeds in m/s. Seeds from the fleet's master seed and study (:mod:`bogie.fleet.sampling.seeds`): a bogie's speed and a
site's road do not depend on the other bogies or sites.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bogie.fleet.sampling.seeds import site_seed, speed_normal
from bogie.road import ISO8608_CLASSES
from bogie.settings import check_value

__all__ = ["SPEED_CLIP", "SPEED_SD_M_S", "Site", "bogie_speeds", "on_site", "site_of"]

#: sd of a heavy goods vehicle's speed over one WIM site about the WIM protocol's speed [m/s] (speed_m_s, 22 m/s).
#: DfT, Vehicle speed compliance statistics for Great Britain 2022, Table 1: 2 % of articulated HGVs over the 60 mph
#: motorway limit in free flow; DfT (HL3374, 2014): their mean 53 mph; a normal then has sd (60 - 53) / 2.054 =
#: 3.4 mph = 1.5 m/s. Assumed: normal (the 56 mph limiters cut its upper tail), and carried over to a site whose mean
#: is the protocol's speed (docs/calibration.md, "The site")
SPEED_SD_M_S = 1.5
#: a bogie's speed is drawn from a normal clipped at this many sd either side [-] (a convention: no lorry at twice
#: the speed limit)
SPEED_CLIP = 3.0


@dataclass(frozen=True)
class Site:
    """One WIM site's road: the ISO 8608 class ``road_class`` and the ``road_seed`` of its approach road's profile,
    the same for every vehicle of its survey (the site's smoothing and roughness are the WIM protocol's)."""

    road_class: str
    road_seed: int

    def __post_init__(self) -> None:
        if str(self.road_class).upper() not in ISO8608_CLASSES:
            allowed = ", ".join(ISO8608_CLASSES)
            raise ValueError(f"road_class = {self.road_class!r}: must be an ISO 8608 class, one of {allowed}")
        check_value("road_seed", self.road_seed, low=0, whole=True)


def site_of(seed: int, study: str, road_classes: Sequence[str], number: int = 0) -> Site:
    """WIM site ``number`` of a calibration (0: the table's own, 1, 2, ...: the other sites of the between-site
    covariance): its road's class is the ``number``-th of the calibration bogies' sampled classes ``road_classes``
    (cycled; so the sites' classes follow the fleet's distributions.road_class), its seed
    :func:`bogie.fleet.sampling.seeds.site_seed`."""
    if not len(road_classes):
        raise ValueError("road_classes: give the calibration bogies' road classes (one or more)")
    return Site(str(road_classes[number % len(road_classes)]), site_seed(seed, study, number))


def bogie_speeds(seed: int, study: str, sample_ids: Sequence[int], mean: float, sd: float = SPEED_SD_M_S) -> np.ndarray:
    """Each bogie's speed over the site [m/s]: ``mean + sd z``, ``z`` its own standard normal
    (:func:`bogie.fleet.sampling.seeds.speed_normal`) clipped to :data:`SPEED_CLIP`.

    Raises ``ValueError`` if ``mean`` is not positive, ``sd`` negative, or the slowest speed allowed not positive.
    """
    check_value("speed", mean, "m/s", low=0.0, low_open=True)
    check_value("speed_sd", sd, "m/s", low=0.0, high=mean / SPEED_CLIP, high_open=True,
                note=f"the slowest speed, mean - {SPEED_CLIP:g} sd, must be positive")  # fmt: skip
    z = np.array([speed_normal(seed, study, int(i)) for i in sample_ids], dtype=float)
    return float(mean) + float(sd) * np.clip(z, -SPEED_CLIP, SPEED_CLIP)


def on_site(sample: Mapping[str, Any], spec: Any, site: Site | None, speed: float | None) -> tuple[dict, Any]:
    """A WIM weighing's sample and settings at ``site``, at ``speed`` [m/s]: the sample's road replaced by the
    site's, the protocol's speed by the bogie's. ``site`` None: the sample's own road and the protocol's speed (each
    vehicle on a road of its own: no site shared)."""
    if site is None:
        return dict(sample), spec
    moved = {**sample, "road_class": site.road_class, "road_seed": int(site.road_seed)}
    return moved, (spec if speed is None else dataclasses.replace(spec, speed=float(speed)))
