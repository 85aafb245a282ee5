"""The checks of a chunk's parsed vehicles (:mod:`bogie.weighings.readers`): the plausible ranges, the gross weight
against the axles at the file's resolution, the length against the wheelbase in the file's units, and the repeats
of earlier records by a hash of their key."""

from __future__ import annotations

import numpy as np
import pandas as pd

from bogie.weighings._records import (
    AXLE_LOAD_RANGE,
    DUPLICATE,
    GROSS_TOLERANCE,
    REL_TOL,
    SPACING_RANGE,
    SPEED_RANGE,
    _Reasons,
)
from bogie.weighings._stream import SeenStore, key_hashes
from bogie.weighings._tmg import POUND
from bogie.weighings.resolution import (
    ResidueCounts,
    detect_resolution,
)


def _residues(parsed: dict, ok: np.ndarray) -> ResidueCounts:
    """The residue counts of the axle loads of the ``ok`` records (:mod:`bogie.weighings.resolution`)."""
    base = parsed.get("weight_base", "kg")
    counts = ResidueCounts(parsed["load_step"] or 1.0, POUND if base == "lb" else 1.0, base)
    counts.add(parsed["loads"][ok])
    return counts


def _check_vehicles(parsed: dict, gross_kg: float | None = None) -> tuple[ResidueCounts, float | None]:
    """The plausibility checks, in their order, on every record not bad yet. Returns the residue counts of the loads
    that passed the checks before the gross weight's, and the weight step the gross-weight check allowed for:
    ``gross_kg``, or (None) the one these counts support."""
    reasons: _Reasons = parsed["reasons"]
    col = parsed["columns"]
    loads, spacings = parsed["loads"], parsed["spacings"]
    # each range's ends are in: a value derived from a field (an integer times its unit) is compared with a tolerance
    # of REL_TOL, so that a field written at an end (18.75 m as 1875 cm) is not lost to a float's last bit
    lo, hi = AXLE_LOAD_RANGE
    reasons.flag(_outside(loads, lo, hi).any(axis=1), f"implausible axle load (allowed {lo:g}-{hi:g} kg)")
    lo, hi = SPACING_RANGE
    reasons.flag(_outside(spacings, lo, hi).any(axis=1), f"implausible axle spacing (allowed {lo:g}-{hi:g} m)")
    lo, hi = SPEED_RANGE
    speed = col["speed"]
    reasons.flag(_outside(speed, lo, hi), f"implausible speed (allowed {lo * 3.6:g}-{hi * 3.6:g} km/h)")
    counts = _residues(parsed, reasons.ok)
    step = detect_resolution(counts).step_kg if gross_kg is None else gross_kg
    total = np.nansum(loads, axis=1)
    gross = col["gross_weight"]
    if not np.isnan(gross).all():
        # half a step of the gross weight's field and of each axle's, at the file's resolution if coarser
        load_half = max(step or 0.0, parsed["load_step"]) / 2
        gross_half = max(step or 0.0, parsed["gross_step"]) / 2
        slack = GROSS_TOLERANCE * total + gross_half + col["n_axles"] * load_half
        # a gross weight 2.2 times the axles' sum: the gross in pounds and the axles in kilograms (or a file of
        # the other edition); said as such, not as any other mismatch
        pounds = np.abs(gross - total / POUND) <= GROSS_TOLERANCE * total / POUND + gross_half
        reasons.flag(pounds & (np.abs(gross - total) > slack), "gross weight 2.2 times the sum of the axle loads: "
                     "pounds where kilograms are expected?")  # fmt: skip
        reasons.flag(np.abs(gross - total) > slack, "gross weight is not the sum of the axle loads")
    reasons.flag(_shorter_than_wheelbase(parsed), "length shorter than the wheelbase")
    return counts, step


def _outside(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``values`` outside [lo, hi], the ends in, to a relative :data:`REL_TOL` (NaN is never outside)."""
    return (values < lo - REL_TOL * abs(lo)) | (values > hi + REL_TOL * abs(hi))


def _shorter_than_wheelbase(parsed: dict) -> np.ndarray:
    """Records whose stated length is shorter than the sum of their axle spacings (a length of 0: not given).

    In a fixed-width format the two are compared as the integers the file holds, in the format's unit (every
    layout writes the length and the spacings in one unit): a length equal to the wheelbase to the unit is not
    shorter. Summing the spacings in metres in floating point lost 2.9 % of a real MON file's records (2.95 + 1.35 =
    4.300000000000001 > 4.3). Where the units differ, or the values are decimals (CSV), the comparison allows
    :data:`REL_TOL`."""
    length = parsed["columns"]["length"]
    if "length_units" in parsed:
        (length_int, length_unit), (spacing_int, spacing_unit) = parsed["length_units"], parsed["spacing_units"]
        if length_unit == spacing_unit:
            wheelbase = np.where(spacing_int > 0, spacing_int, 0).sum(axis=1)
            return (length_int > 0) & (length_int < wheelbase)
    wheelbase = np.nansum(parsed["spacings"], axis=1)
    return (length > 0) & (length < wheelbase * (1.0 - REL_TOL))


def _key_columns(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> dict[str, np.ndarray]:
    """The record columns a repeat shares with the record it repeats, but its axles: time, lane, direction, speed
    (and the station of a TMG file). The one definition of the key, with the axle loads and spacings
    (:func:`_repeat_key` exactly, :func:`_hashes` by hash)."""
    col = parsed["columns"]
    extra = parsed.get("extra", {})
    return {
        "t": stamps[rows].view(np.int64), "lane": col["lane"][rows], "dir": col["direction"][rows],
        "speed": col["speed"][rows], **({"station": extra["station"][rows]} if "station" in extra else {}),
    }  # fmt: skip


def _repeat_key(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> pd.DataFrame:
    """The key of ``rows`` as a table, to compare exactly: :func:`_key_columns`, the axle loads and spacings."""
    return pd.DataFrame({
        **_key_columns(parsed, stamps, rows),
        **{f"w{i}": parsed["loads"][rows, i] for i in range(parsed["loads"].shape[1])},
        **{f"s{i}": parsed["spacings"][rows, i] for i in range(parsed["spacings"].shape[1])},
    })  # fmt: skip


def _hashes(parsed: dict, stamps: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The 64-bit hashes of the repeat keys (:func:`_repeat_key`) of ``rows``, for the records of earlier chunks."""
    columns = list(_key_columns(parsed, stamps, rows).values())
    return key_hashes(columns, parsed["loads"][rows], parsed["spacings"][rows], parsed["columns"]["n_axles"][rows])


def _alike(parsed: dict, stamps: np.ndarray, seen: SeenStore | None) -> int:
    """How many good records are alike an earlier one (:func:`_repeat_key`; of an earlier chunk, by
    :func:`_hashes`): counted for a file of hourly time stamps, where two alike trucks in one hour are two
    vehicles."""
    good = np.flatnonzero(parsed["reasons"].ok)
    alike = np.zeros(len(good), bool)
    if len(good) >= 2:
        alike = _repeat_key(parsed, stamps, good).duplicated(keep="first").to_numpy()
    if seen is not None and len(good):
        hashes = _hashes(parsed, stamps, good)
        alike = alike | seen.add(stamps[good], hashes)
    return int(alike.sum())


def _flag_repeats(parsed: dict, stamps: np.ndarray, seen: SeenStore | None = None) -> None:
    """A good record equal to an earlier good one in time, lane, direction, speed, axle loads and spacings is bad:
    a WIM system does not weigh two vehicles in one lane at one instant (a record repeated by a copy or a retry)."""
    reasons: _Reasons = parsed["reasons"]
    everyone = np.flatnonzero(reasons.ok)
    repeat = np.zeros(len(reasons.code), bool)
    # only records that share their time with another can repeat one: compare the rest of the key for those only
    if len(everyone) >= 2:
        same_time = pd.Series(stamps[everyone].view(np.int64)).duplicated(keep=False).to_numpy()
        good = everyone[same_time]
        if len(good) >= 2:
            repeat[good[_repeat_key(parsed, stamps, good).duplicated(keep="first").to_numpy()]] = True
    if seen is not None and len(everyone):  # a repeat of a record of an earlier chunk, by its hash
        hashes = _hashes(parsed, stamps, everyone)
        # a repeat within the chunk has the hash of the record it repeats, added here too: adding every hash adds
        # the same set as adding the first of each only
        repeat[everyone[seen.add(stamps[everyone], hashes)]] = True
    reasons.flag(repeat, DUPLICATE)
