"""What acting would save (bogie.fleet.road), on a design experiment made by hand."""

import math

import numpy as np
import pandas as pd
import pytest

from bogie.fleet.road import design_savings, fleet_wear, scenario_runs
from bogie.params import GRAVITY

G = GRAVITY
TILTS = [-1.0, 0.0, 1.0]  # the tilt grid [degree]: slots 0, 1, 2


def run(design, condition, slot, loads_kg, tilt_deg, status="ok"):
    n = len(loads_kg)
    loads = [w * G for w in loads_kg] + [0.0] * (3 - n)
    return {
        "design": design, "condition": condition, "slot": slot, "group": "triaxle", "n_axles": n, "status": status,
        "chassis_tilt_deg": tilt_deg, "axle_load_1": loads[0], "axle_load_2": loads[1], "axle_load_3": loads[2],
    }  # fmt: skip


def experiment():
    """Two conditions at tilts +1.5 and 0.2 degrees; the typical design is unequal, the best and the air group equal;
    the typical design's grid runs at -1, 0, +1 degree of condition 0 differ so that the held tilt can be told."""
    rows = [
        run("triaxle-typical", 0, -1, [8800.0, 8000.0, 7200.0], 1.5),  # 4.0 % extra at k = 4
        run("triaxle-typical", 1, -1, [8400.0, 8000.0, 7600.0], 0.2),
        run("triaxle-typical", 0, 0, [7600.0, 8000.0, 8400.0], -1.0),
        run("triaxle-typical", 0, 1, [8000.0, 8000.0, 8000.0], 0.0),
        run("triaxle-typical", 0, 2, [8400.0, 8000.0, 7600.0], 1.0),
        run("triaxle-grid-01", 0, -1, [8000.0, 8000.0, 8000.0], 1.5),
        run("triaxle-grid-01", 1, -1, [8000.0, 8000.0, 8000.0], 0.2),
        run("triaxle-air", 0, -1, [8000.0, 8000.0, 8000.0], 1.5),
        run("triaxle-air", 1, -1, [8000.0, 8000.0, 8000.0], 0.2, status="failed"),
    ]
    designs = pd.DataFrame({
        "design": ["triaxle-grid-01", "triaxle-typical", "triaxle-air"], "group": "triaxle",
        "kind": ["grid", "typical", "air"], "tilt_tolerance_nose_up_deg": [2.0, 1.0, 2.0],
        "tilt_tolerance_nose_down_deg": [2.0, 0.5, 2.0],
    })  # fmt: skip
    return pd.DataFrame(rows), designs


def extra4(loads):
    w = np.asarray(loads) / np.mean(loads)
    return np.mean(w**4) - 1.0


def test_tilt_held_reads_the_grid_run_inside_the_tolerance_and_keeps_a_tilt_already_inside():
    runs, designs = experiment()
    held = scenario_runs(runs, designs, TILTS)
    held = held[held["scenario"] == "tilt_held"].set_index("condition")
    # condition 0 at +1.5 degrees is outside the band [-0.5, +1.0]: read at the grid's +1.0 (slot 2)
    assert held.loc[0, "slot"] == 2 and held.loc[0, "held_tilt_deg"] == 1.0
    # condition 1 at +0.2 degrees is inside: its own run
    assert held.loc[1, "slot"] == -1 and held.loc[1, "held_tilt_deg"] == 0.2


def test_savings_are_the_typical_designs_extra_wear_minus_the_scenarios_paired_over_conditions():
    runs, designs = experiment()
    table = design_savings(runs, designs, TILTS, {"triaxle": 24_000.0}, 10_000.0, resamples=50, seed=1)
    table = table.set_index("scenario")
    # the typical design over both conditions: sum D / sum D_eq - 1 with equal group loads (24 t each)
    typical = (np.mean(np.r_[1.1, 1.0, 0.9] ** 4) + np.mean(np.r_[1.05, 1.0, 0.95] ** 4)) / 2 - 1.0
    best = table.loc["best"]
    assert best["n_conditions"] == 2 and best["n_failed"] == 0
    assert best["extra_wear_overall_typical"] == pytest.approx(typical, rel=1e-12)
    assert best["extra_wear_overall"] == pytest.approx(0.0, abs=1e-14)
    assert best["saved_wear_overall"] == pytest.approx(typical, rel=1e-12)
    # the air group failed at condition 1: one pair left, condition 0's 4.0 %
    air = table.loc["air"]
    assert (air["n_conditions"], air["n_failed"]) == (1, 1)
    assert air["saved_wear_overall"] == pytest.approx(extra4([8800, 8000, 7200]), rel=1e-12)
    # held: condition 0 read at +1 degree (8400/8000/7600), condition 1 as it was: the saving is condition 0's change
    held = table.loc["tilt_held"]
    after = (np.mean(np.r_[1.05, 1.0, 0.95] ** 4) * 2) / 2 - 1.0
    assert held["extra_wear_overall"] == pytest.approx(after, rel=1e-12)
    assert held["saved_wear_overall"] == pytest.approx(typical - after, rel=1e-12)
    assert held["held_tilt_deg_max"] == 1.0
    assert best["saved_wear_overall_low"] <= best["saved_wear_overall"] <= best["saved_wear_overall_high"]


def test_fleet_wear_keeps_laden_groups_and_counts_a_failed_run():
    rows = [
        {"protocol": "static", "group": "triaxle", "suspension": "steel", "n_axles": 3, "status": "ok",
         "axle_load_1": 8800 * G, "axle_load_2": 8000 * G, "axle_load_3": 7200 * G, "group_load": 24000 * G},
        {"protocol": "static", "group": "triaxle", "suspension": "steel", "n_axles": 3, "status": "ok",
         "axle_load_1": 5000 * G, "axle_load_2": 4000 * G, "axle_load_3": 3000 * G, "group_load": 12000 * G},
        {"protocol": "static", "group": "triaxle", "suspension": "steel", "n_axles": 3, "status": "failed",
         "axle_load_1": math.nan, "axle_load_2": math.nan, "axle_load_3": math.nan, "group_load": math.nan},
    ]  # fmt: skip
    table = fleet_wear(pd.DataFrame(rows), {"triaxle": 24_000.0}, 10_000.0, 15_000.0, resamples=20)
    [row] = table.to_dict("records")
    # the 12 t group is not laden (left out, not counted); the failed run is counted
    assert (row["n_groups"], row["n_failed"]) == (1, 1)
    assert row["extra_wear_overall"] == pytest.approx(extra4([8800, 8000, 7200]), rel=1e-12)
