"""Both protocols reproduce stored result rows bit for bit (a faster weighing changes no result).

The rows in ``tests/data/protocol_identity/reference.json`` were written by ``make_reference.py`` beside it with the
protocols as issue 15 left them (phases in one compiled call, adaptive steps in the static protocol,
``docs/phases.md``): three tandem and three tri-axle bogies of the params.yaml fleet, each weighed by the static and
the WIM protocol (the WIM rows rewritten on 3 December 2026 for issue 30's sensor model; every row on 7 December
2026, when issue 43 Must 7 moved params.yaml's tilt distribution and so the bogies' sampled tilts). Floats are
stored as ``float.hex()`` and compared with ``==`` (NaN with NaN), every other field (flags, status, message) as
is. A change meant to change results rewrites the file on purpose.

Bits are defined on the machine that wrote the file (its CPU and library facts, ``tests/_fingerprint.py``, are stored
in it): on another, every float must agree within ``FOREIGN_RTOL`` of its scale (loads of the group load, the rest
of 1: shares, fractions, radians) and everything else exactly. Measured: numba compiling for Haswell with numpy's
AVX-512 loops disabled moved the rows by at most 6e-11 of their values, another CI machine by 1e-12.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from _fingerprint import describe, fingerprint

from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.weigher import weigh
from pipeline.config import load_config
from pipeline.sample import sample_fleet

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = json.loads((ROOT / "tests" / "data" / "protocol_identity" / "reference.json").read_text())
#: off the machine that wrote the rows: largest |difference| as a fraction of the field's scale
FOREIGN_RTOL = 1e-6
G = 9.80665  # [m/s^2], spread_kg = spread / g


@pytest.fixture(scope="module")
def fleet():
    config = load_config(ROOT / "params.yaml")
    return config, sample_fleet(config).to_dict("records")


def _decode(value):
    return float.fromhex(value["hex"]) if isinstance(value, dict) else value


def _scale(key: str, row: dict) -> float:
    """A field's scale: loads [N] the group load, spread_kg [kg] its mass, shares, fractions and radians 1."""
    if key in ("group_load", "spread") or key.startswith("axle_load_"):
        return abs(row["group_load"])
    if key == "spread_kg":
        return abs(row["group_load"]) / G
    return 1.0


def test_reference_covers_both_groups_and_protocols():
    seen = {(e["row"]["n_axles"], e["protocol"]) for e in REFERENCE["rows"]}
    assert seen == {(2, "static"), (3, "static"), (2, "wim"), (3, "wim")}
    assert all(e["row"]["status"] == "ok" for e in REFERENCE["rows"])
    assert set(REFERENCE["machine"]) == set(fingerprint())


@pytest.mark.parametrize("entry", REFERENCE["rows"], ids=lambda e: f"{e['protocol']}-{e['index']}")
def test_row_is_bit_identical(fleet, entry):
    config, records = fleet
    record = records[entry["index"]]
    row = weigh(bogie_from_sample(record), record, entry["protocol"], getattr(config.protocol, entry["protocol"]))
    expected = {key: _decode(value) for key, value in entry["row"].items()}
    assert row.keys() == expected.keys()
    for key, want in expected.items():
        got = row[key]
        if isinstance(want, float):
            assert isinstance(got, float), key
            if math.isnan(want) or math.isnan(got) or REFERENCE.get("machine") == fingerprint():
                assert got == want or (math.isnan(got) and math.isnan(want)), (key, got.hex(), want.hex())
            else:
                allowed = FOREIGN_RTOL * _scale(key, expected)
                assert abs(got - want) <= allowed, (
                    f"{key}: {got!r} against {want!r}, allowed {allowed:.3g} off the machine that wrote the rows "
                    f"({describe(REFERENCE.get('machine', {}), fingerprint())})"
                )
        else:
            assert got == want and type(got) is type(want), (key, got, want)
