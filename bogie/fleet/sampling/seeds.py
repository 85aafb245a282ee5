"""The seeds of a fleet study: every random draw (a study's design points, a row's road, WIM sensor and suspension)
from its own stream of the master seed, the study and the row (:mod:`bogie.fleet.sampling.sample`, "Seeds"), so that a
row's draws do not depend on the other rows, their order or the number of workers. :mod:`bogie.fleet.sampling.sample`
re-exports them."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

_STREAM_DESIGN = 0
_STREAM_ROAD = 1
_STREAM_SENSOR = 2
_STREAM_SUSPENSION = 3
_STREAM_SPEED = 4
_STREAM_SITE = 5


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
    """Seed of one bogie's WIM sensor errors (:func:`bogie.road.wim.sensor_factors`), like :func:`road_seed` [-].

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


def speed_normal(seed: int, study: str, sample_id: int) -> float:
    """One bogie's standard normal draw of its speed over a WIM site (:mod:`bogie.fleet.calibration.site`) [-]: a
    stream of its own, like :func:`suspension_draw`, so that the fleet's design and every other draw are as before."""
    return float(np.random.default_rng(_seed_sequence(seed, study, _STREAM_SPEED, sample_id)).standard_normal())


def site_seed(seed: int, study: str, site: int) -> int:
    """Seed of the approach road of WIM site number ``site`` of a calibration (0: the table's own; 1, 2, ...: the
    other sites of the between-site covariance, :mod:`bogie.fleet.calibration.site`) [-]."""
    return _seed_int(_seed_sequence(seed, study, _STREAM_SITE, site))


def suspensions(draws: np.ndarray, groups: np.ndarray, mix: Mapping[str, Mapping[str, float]]) -> np.ndarray:
    """``air`` where a bogie's draw is below its group's air share in ``mix`` (``fleet.suspension_mix``), else
    ``steel``."""
    share = np.array([mix[g]["air"] for g in groups], dtype=float)
    return np.where(np.asarray(draws, dtype=float) < share, "air", "steel").astype(object)


def design_seed(seed: int, study: str) -> int:
    """Seed of a study's uniform design (Latin hypercube, Sobol' scrambling, Saltelli) [-]."""
    return _seed_int(_seed_sequence(seed, study, _STREAM_DESIGN))
