"""The weighing protocols on the full model: the flags a reading carries, and the result rows of a chunk."""

import math
from pathlib import Path

import numpy as np

from bogie import metrics
from bogie.fleet.constants import MAX_AXLES
from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.weigher import Outcome, result_rows, weigh
from bogie.params import NO_STOP
from pipeline.config import load_config
from pipeline.sample import sample_fleet

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
    assert not row["wheel_airborne"] and np.isfinite(row["axle_load_1"])


def test_a_level_bogie_reads_off_its_stops():
    bogie, sample, config = tilted_triaxle()
    row = weigh(bogie.replace(chassis_tilt=0.0), sample, "static", config.protocol.static)
    assert row["status"] == "ok" and row["equaliser_on_stop"] is False


def test_the_road_tables_are_the_protocols_roads_value_for_value():
    # the tables read the ISO 8608 grid's own heights and evaluate the blends only where they are neither 0 nor 1:
    # the same numbers as calling the approach road (and the WIM site road) at the table's distances
    import dataclasses

    from bogie.fleet.weighing import protocols as protocol

    config = load_config(ROOT / "params.yaml")
    fleet = sample_fleet(config)
    wim = config.protocol.wim
    wims = [wim, dataclasses.replace(wim, site_length_before=3.0, site_length_after=0.0),
            dataclasses.replace(wim, site_length_before=0.0, site_length_after=0.0)]  # fmt: skip
    for i in range(4):
        sample = fleet.iloc[i].to_dict()
        bogie = bogie_from_sample(sample)
        args = (bogie, sample["payload_fraction"], sample["road_class"], sample["road_seed"])
        approach = protocol._approach(sample["road_class"], sample["road_seed"], config.protocol.static.approach_length)
        checks = [(protocol.static_phases(*args, config.protocol.static)[1].road, approach)]
        for spec in wims:
            _, road, *_ = protocol._wim_route(bogie, sample["road_class"], sample["road_seed"], spec)
            checks.append((protocol.wim_phases(*args, spec)[0].road, road))  # fmt: skip
        for table, road in checks:
            x = (round(table.x0 / table.dx) + np.arange(len(table.heights))) * table.dx
            assert np.array_equal(table.heights, road(x))  # (off the road a 0 may carry the other sign)
            assert np.count_nonzero(table.heights) > 0.4 * len(table.heights)  # a real road, not an empty table


def test_weighings_that_share_a_cached_road_give_what_a_fresh_road_gives():
    # the ablation's variants of a bogie and the Sobol' design's samples share roads, and the protocols keep the
    # last road tables (issue 15): a weighing that finds its road cached, after others have run on it, must give the
    # row it gives on a freshly synthesised road, and nothing may write into a shared table
    from bogie.fleet.weighing import protocols as protocol

    config = load_config(ROOT / "params.yaml")
    fleet = sample_fleet(config)
    samples = [fleet.iloc[i].to_dict() for i in range(3)]
    for s in samples[1:]:  # three bogies on the first one's road
        s.update(road_class=samples[0]["road_class"], road_seed=samples[0]["road_seed"])
    specs = {"static": config.protocol.static, "wim": config.protocol.wim}

    def rows():
        return [weigh(bogie_from_sample(s), s, name, spec) for s in samples for name, spec in specs.items()]

    protocol._static_table.cache_clear()
    protocol._wim_table.cache_clear()
    shared = rows()  # the second and third bogies find the first one's tables
    assert protocol._static_table.cache_info().hits >= 2 and protocol._wim_table.cache_info().hits >= 2
    fresh = []
    for s in samples:
        for name, spec in specs.items():
            protocol._static_table.cache_clear()
            protocol._wim_table.cache_clear()
            fresh.append(weigh(bogie_from_sample(s), s, name, spec))
    assert all(r["status"] == "ok" for r in shared)
    for a, b in zip(shared, fresh):
        assert a.keys() == b.keys()
        for k in a:
            assert a[k] == b[k] or (isinstance(a[k], float) and math.isnan(a[k]) and math.isnan(b[k])), k
    bogie = bogie_from_sample(samples[0])
    args = (bogie, samples[0]["payload_fraction"], samples[0]["road_class"], samples[0]["road_seed"])
    for table in (
        protocol.static_phases(*args, specs["static"])[1].road,
        protocol.wim_phases(*args, specs["wim"])[0].road,
    ):
        assert not table.heights.flags.writeable


def test_a_chunks_result_rows_are_each_weighings_own_metrics_bit_for_bit():
    """result_rows computes a chunk's metrics in one numpy pass per group size: each row must hold what
    bogie.metrics gives for that weighing alone, to the last bit, and the hand-worked values of a simple one."""
    rng = np.random.default_rng(7)
    outcomes = []
    for k in range(40):
        n = 2 + k % 2
        loads = rng.uniform(2e4, 6e4, n)
        if k == 5:
            loads[1] = 0.0  # a wheel in the air over the sensor: a valid reading, flagged
        outcomes.append(Outcome("wim" if k % 3 else "static", n, loads, 1e-3 * k, k % 7 == 0))
    outcomes.insert(9, Outcome("static", 3, None, status="failed", message="no equilibrium"))
    outcomes.append(Outcome("static", 3, np.array([1e4, 2e4, 3e4])))
    rows = result_rows(outcomes)
    assert len(rows) == len(outcomes)
    for outcome, row in zip(outcomes, rows):
        assert (row["protocol"], row["n_axles"], row["status"]) == (outcome.protocol, outcome.n_axles, outcome.status)
        if outcome.wheel_loads is None:
            assert row["message"] == "no equilibrium" and math.isnan(row["p"]) and row["over_10pct"] is None
            continue
        n, w = outcome.n_axles, 2.0 * outcome.wheel_loads
        expected = {
            "group_load": w.sum(), "p": metrics.p(w / w.mean()), "p1": metrics.p1(w / w.mean()),
            "max_deviation": metrics.max_deviation(w), "spread": metrics.spread(w),
            "road_wear_factor": metrics.road_wear_factor(w), "chassis_pitch": outcome.pitch,
            **{f"axle_load_{i + 1}": w[i] if i < n else 0.0 for i in range(MAX_AXLES)},
            **{f"load_share_{i + 1}": metrics.lsc(w)[i] if i < n else 0.0 for i in range(MAX_AXLES)},
        }  # fmt: skip
        for column, value in expected.items():
            assert row[column] == float(value), column  # exact: the same arithmetic, row by row
        assert row["wheel_airborne"] is bool(w.min() <= 0.0) and row["equaliser_on_stop"] is outcome.on_stop
    # by hand: axle loads 20, 40, 60 kN (mean 40): max deviation 0.5, spread 40 kN, shares 0.5/1/1.5, p = sqrt(2)/2
    last = rows[-1]
    assert last["group_load"] == 1.2e5 and last["spread"] == 4e4 and last["max_deviation"] == 0.5
    assert [last[f"load_share_{i + 1}"] for i in range(3)] == [0.5, 1.0, 1.5]
    assert math.isclose(last["p"], math.sqrt(0.5**2 + 0.5**2), rel_tol=1e-15)
    assert last["outside_5pct"] is True and last["over_10pct"] is True and last["wheel_airborne"] is False
    assert rows[5]["wheel_airborne"] is True and rows[5]["status"] == "ok"  # the failed row went in at 9, after it
