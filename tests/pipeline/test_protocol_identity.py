"""Both protocols reproduce stored result rows bit for bit (a faster weighing changes no result).

The rows in ``tests/data/protocol_identity/reference.json`` were written by ``make_reference.py`` beside it with the
protocols as issue 15 left them (phases in one compiled call, adaptive steps in the static protocol,
``docs/phases.md``): three tandem and three tri-axle bogies of the params.yaml fleet, each weighed by the static and
the WIM protocol. Floats are stored as ``float.hex()`` and compared with ``==`` (NaN with NaN), every other field
(flags, status, message) as is. A change meant to change results rewrites the file on purpose.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from pipeline.config import load_config
from pipeline.protocol import weigh
from pipeline.sample import bogie_from_sample, sample_fleet

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = json.loads((ROOT / "tests" / "data" / "protocol_identity" / "reference.json").read_text())


@pytest.fixture(scope="module")
def fleet():
    config = load_config(ROOT / "params.yaml")
    return config, sample_fleet(config).to_dict("records")


def _decode(value):
    return float.fromhex(value["hex"]) if isinstance(value, dict) else value


def test_reference_covers_both_groups_and_protocols():
    seen = {(e["row"]["n_axles"], e["protocol"]) for e in REFERENCE["rows"]}
    assert seen == {(2, "static"), (3, "static"), (2, "wim"), (3, "wim")}
    assert all(e["row"]["status"] == "ok" for e in REFERENCE["rows"])


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
            assert got == want or (math.isnan(got) and math.isnan(want)), (key, got.hex(), want.hex())
        else:
            assert got == want and type(got) is type(want), (key, got, want)
