"""The protocols' accuracy at params.yaml's settings: a small fleet sample against its reference at a quarter of the
time step.

Issue 15 asks for the speed-ups to keep the results within a stated tolerance of a run at a quarter of the time step.
The reference here is the same protocol in fixed steps of dt / 4 (0.25 ms: its discretisation error is about a
sixteenth of a 1 ms run's); params.yaml's static protocol steps adaptively under ``step_tolerance_m`` and its WIM
pass in fixed steps of 1 ms, both with the first Newton correction of a step accepted unchecked where its measured
contraction allows (``docs/phases.md``). The sample: the first three tandem and the first three tri-axle bogies of
the 50-bogie fleet sample of ``bench/bench_protocol.py``, both protocols.

How the tolerance was set. On 1 December 2026 (the code before issue 15's changes) the 50-bogie sample of
``python -m bench.bench_protocol`` gave, fixed steps of 1 ms against dt / 4, at most: static 9.1 N in an axle load,
17 N in the group load, 0.005 points of max_deviation; WIM 130 N, 222 N and 0.082 points; the tolerances were set at
about twice those. On 2 December the wider study of ``python tools/accuracy_study.py`` (300 fleet bogies, both
protocols, and 150 samples of the Sobol' design, whose factors reach their ranges' ends together) found that code at
up to static 36.4 N, 30.2 N and 0.055 points (a chaotic stick-slip path of sample 83 of the design), WIM 114.9 N,
202.7 N and 0.153 points. The static tolerance is therefore what that code meets on the wider study: 40 N, 40 N and
0.06 points, in newtons of axle load (both wheels) and percentage points of max_deviation; the WIM one stands.
The code as issue 15 leaves it meets them on the same study: static 12.9 N, 30.5 N, 0.014 points (fleet and design
together); WIM 114.1 N, 201.5 N, 0.153 points (``docs/phases.md``, "Accuracy").
"""

import dataclasses
from pathlib import Path

import pytest

from bogie.fleet.constants import MAX_AXLES
from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.weigher import weigh
from pipeline.config import load_config
from pipeline.sample import sample_fleet

ROOT = Path(__file__).resolve().parents[2]
#: the reference runs at the protocol's time step divided by this, in fixed steps [-]
DT_DIVISOR = 4
#: largest |difference| from the dt / 4 reference: axle load [N], group load [N], max_deviation [points]
TOLERANCE = {
    "static": {"axle_load": 40.0, "group_load": 40.0, "max_deviation_points": 0.06},
    "wim": {"axle_load": 300.0, "group_load": 500.0, "max_deviation_points": 0.2},
}


def sample_rows() -> tuple[list[dict], object]:
    config = load_config(ROOT / "params.yaml")
    config = dataclasses.replace(config, fleet=dataclasses.replace(config.fleet, n_bogies=50))
    fleet = sample_fleet(config)
    chosen = [fleet[fleet["group"] == g].head(3) for g in ("tandem", "triaxle")]
    return [row for part in chosen for row in part.to_dict("records")], config


def reference_spec(spec):
    """The protocol's settings in fixed steps of a quarter of its time step."""
    fine = dataclasses.replace(spec, dt=spec.dt / DT_DIVISOR)
    return dataclasses.replace(fine, step_tolerance=None) if hasattr(fine, "step_tolerance") else fine


def differences(row: dict, reference: dict) -> dict[str, float]:
    """Largest |difference| of ``row`` from ``reference``: axle loads [N], group load [N], max_deviation [points]."""
    return {
        "axle_load": max(abs(row[f"axle_load_{i + 1}"] - reference[f"axle_load_{i + 1}"]) for i in range(MAX_AXLES)),
        "group_load": abs(row["group_load"] - reference["group_load"]),
        "max_deviation_points": 100.0 * abs(row["max_deviation"] - reference["max_deviation"]),
    }


@pytest.mark.parametrize("protocol", ["static", "wim"])
def test_the_protocol_at_its_settings_meets_the_tolerance_against_dt_over_4(protocol):
    records, config = sample_rows()
    spec = getattr(config.protocol, protocol)
    if protocol == "static":
        assert spec.step_tolerance is not None  # the default is the adaptive protocol this test is about
    worst = dict.fromkeys(TOLERANCE[protocol], 0.0)
    for record in records:
        bogie = bogie_from_sample(record)
        row = weigh(bogie, record, protocol, spec)
        reference = weigh(bogie, record, protocol, reference_spec(spec))
        assert row["status"] == "ok" and reference["status"] == "ok", (row["message"], reference["message"])
        for key, value in differences(row, reference).items():
            worst[key] = max(worst[key], value)
    for key, limit in TOLERANCE[protocol].items():
        assert worst[key] <= limit, f"{protocol}: {key} differs by {worst[key]:.4g} from dt / 4 (tolerance {limit})"
    # the tolerance is not vacuous: the protocol does differ from dt / 4, by more than round-off
    assert worst["axle_load"] > 0.01
