"""The protocols' accuracy at params.yaml's time step: a small fleet sample against its dt / 4 reference.

Issue 15 asks for every speed-up to keep the results within a stated tolerance of a run at a quarter of the time
step; this is that tolerance, and the test that the code meets it. The sample: the first three tandem and the first
three tri-axle bogies of the 50-bogie fleet sample of ``bench/bench_protocol.py``, both protocols, params.yaml's
settings (dt = 1 ms), each against the same weighing at dt / 4 (0.25 ms).

How the tolerance was set: on the whole 50-bogie sample (``python -m bench.bench_protocol``, 1 December 2026, the
code before any of issue 15's optimisations) the largest differences from dt / 4 were, static: 9.1 N in an axle load,
17 N in the group load, 0.005 points in max_deviation; WIM: 130 N, 222 N and 0.082 points. The tolerances below are
about twice those (the margin for a sample of bogies the 50 did not cover), in newtons of axle load (both wheels) and
in percentage points of max_deviation. On the six bogies here today's code gives at most (static) 3.2 N, 8.8 N,
0.001 points and (WIM) 75 N, 155 N, 0.031 points.
"""

import dataclasses
from pathlib import Path

import pytest

from pipeline.config import load_config
from pipeline.constants import MAX_AXLES
from pipeline.protocol import weigh
from pipeline.sample import bogie_from_sample, sample_fleet

ROOT = Path(__file__).resolve().parents[2]
#: the reference runs at the protocol's time step divided by this [-]
DT_DIVISOR = 4
#: largest |difference| from the dt / 4 reference: axle load [N], group load [N], max_deviation [points]
TOLERANCE = {
    "static": {"axle_load": 20.0, "group_load": 40.0, "max_deviation_points": 0.01},
    "wim": {"axle_load": 300.0, "group_load": 500.0, "max_deviation_points": 0.2},
}


def sample_rows() -> tuple[list[dict], object]:
    config = load_config(ROOT / "params.yaml")
    config = dataclasses.replace(config, fleet=dataclasses.replace(config.fleet, n_bogies=50))
    fleet = sample_fleet(config)
    chosen = [fleet[fleet["group"] == g].head(3) for g in ("tandem", "triaxle")]
    return [row for part in chosen for row in part.to_dict("records")], config


def differences(row: dict, reference: dict) -> dict[str, float]:
    """Largest |difference| of ``row`` from ``reference``: axle loads [N], group load [N], max_deviation [points]."""
    return {
        "axle_load": max(abs(row[f"axle_load_{i}"] - reference[f"axle_load_{i}"]) for i in range(MAX_AXLES)),
        "group_load": abs(row["group_load"] - reference["group_load"]),
        "max_deviation_points": 100.0 * abs(row["max_deviation"] - reference["max_deviation"]),
    }


@pytest.mark.parametrize("protocol", ["static", "wim"])
def test_the_protocol_at_its_time_step_meets_the_tolerance_against_dt_over_4(protocol):
    records, config = sample_rows()
    spec = getattr(config.protocol, protocol)
    fine = dataclasses.replace(spec, dt=spec.dt / DT_DIVISOR)
    worst = dict.fromkeys(TOLERANCE[protocol], 0.0)
    for record in records:
        bogie = bogie_from_sample(record)
        row = weigh(bogie, record, protocol, spec)
        reference = weigh(bogie, record, protocol, fine)
        assert row["status"] == "ok" and reference["status"] == "ok", (row["message"], reference["message"])
        for key, value in differences(row, reference).items():
            worst[key] = max(worst[key], value)
    for key, limit in TOLERANCE[protocol].items():
        assert worst[key] <= limit, f"{protocol}: {key} differs by {worst[key]:.4g} from dt / 4 (tolerance {limit})"
    # the tolerance is not vacuous: dt = 1 ms does differ from dt / 4, by more than round-off
    assert worst["axle_load"] > 0.01
