"""The weighing protocols on the full model: the flags a reading carries."""

import math
from pathlib import Path

import numpy as np

from bogie.params import NO_STOP
from pipeline.config import load_config
from pipeline.protocol import weigh
from pipeline.sample import bogie_from_sample, sample_fleet

ROOT = Path(__file__).resolve().parents[2]


def tilted_triaxle(**changes):
    """A fleet tri-axle with a free bush and fixed contacts at 2 degrees nose up: its equalisers turn far."""
    config = load_config(ROOT / "params.yaml")
    fleet = sample_fleet(config)
    sample = fleet[fleet["group"] == "triaxle"].iloc[0].to_dict()
    sample.update(road_class="A")
    bogie = bogie_from_sample(sample).replace(
        bush_stiffness=0.0, contact_roll_radius=0.0, friction_coefficient=0.0, chassis_tilt=math.radians(2.0),
        **changes,
    )  # fmt: skip
    return bogie, sample, config


def test_a_reading_with_an_equaliser_on_its_stop_is_valid_and_flagged():
    bogie, sample, config = tilted_triaxle()
    row = weigh(bogie, sample, "static", config.protocol.static)
    assert row["status"] == "ok" and row["equaliser_on_stop"] is True
    free = weigh(bogie.replace(equaliser_stop=NO_STOP), sample, "static", config.protocol.static)
    assert free["status"] == "ok" and free["equaliser_on_stop"] is False
    # the stop holds the equaliser, so the loads part: the stopped group is the less equal one
    assert row["max_deviation"] > free["max_deviation"]
    assert not row["wheel_airborne"] and np.isfinite(row["axle_load_0"])


def test_a_level_bogie_reads_off_its_stops():
    bogie, sample, config = tilted_triaxle()
    row = weigh(bogie.replace(chassis_tilt=0.0), sample, "static", config.protocol.static)
    assert row["status"] == "ok" and row["equaliser_on_stop"] is False
