"""The road stage's own pieces (issue 44): the simulated fleet's legal limits from its base bogies' spacing, and the
calibrated fleet's sharing factors from the calibrate stage's direct simulation, worked by hand."""

import json

import pandas as pd
import pytest

from pipeline.road import calibrated_wear, factors_table, fleet_limits


def test_the_simulated_fleet_is_judged_as_trailer_groups_at_its_base_bogies_spacing():
    # the presets are 1.31 m apart: a trailer tandem's 1.3-1.8 m band (18 t), a tri-axle over 1.3 m (24 t)
    assert fleet_limits({"tandem": "tandem_trrl", "triaxle": "triaxle_stage1"}) == (
        {"tandem": 18_000.0, "triaxle": 24_000.0}, 10_000.0)  # fmt: skip


def test_the_calibrated_fleets_sharing_factors_by_hand(tmp_path):
    # two steel tri-axles, 8,800 / 8,000 / 7,200 and 8,000 x 3 kg, and an air tri-axle shared equally: at k = 4 the
    # steel pair does (1.1^4 + 1 + 0.9^4 + 3) / 6 - 1 = 2.0 % more than equal sharing; the air group none
    table = tmp_path / "calibrated.csv"
    pd.DataFrame({
        "slot": [0, 1, 2], "group": "triaxle", "n_axles": 3, "suspension": ["steel", "steel", "air"],
        "tilt_deg": [1.0, 0.0, 1.0], "axle_load_1": [8800.0, 8000.0, 8000.0], "axle_load_2": 8000.0,
        "axle_load_3": [7200.0, 8000.0, 8000.0],
    }).to_csv(table, index=False)  # fmt: skip
    metrics = tmp_path / "calibration.json"
    metrics.write_text(json.dumps({"protocol": "wim"}))
    got = calibrated_wear(table, metrics, {"tandem": 18_000.0, "triaxle": 24_000.0}, 10_000.0, 3)
    assert got is not None and got[1] == "wim"
    wear = got[0].set_index("suspension")
    assert wear.loc["steel", "extra_wear_overall"] == pytest.approx((1.1**4 + 1 + 0.9**4 + 3) / 6 - 1, rel=1e-12)
    assert wear.loc["air", "extra_wear_overall"] == 0.0 and wear.loc["steel", "n_groups"] == 2
    empty = pd.DataFrame()
    simulated = wear.reset_index().assign(protocol="static")
    rows = factors_table(simulated, empty, "wim", got)
    calibrated = rows[rows["source"] == "calibrated"].set_index("suspension")
    assert set(calibrated["protocol"]) == {"wim"} and set(calibrated["position"]) == {"trailer"}
    assert calibrated.loc["steel", "factor_k4"] == pytest.approx(1.0 + wear.loc["steel", "extra_wear_overall"])
    # no calibration (the stage skipped: no table), no rows
    assert calibrated_wear(tmp_path / "none.csv", metrics, {}, 10_000.0, 3) is None
    assert "calibrated" not in set(factors_table(simulated, empty, "wim", None)["source"])


def test_the_road_page_says_the_calibrated_fleets_extra_wear_when_there_is_one():
    from pathlib import Path

    from pipeline.report import text
    from pipeline.report.pages.road import PROTOCOL_LABEL, SCENARIO_LABEL

    m = json.loads((Path(__file__).parents[2] / "metrics" / "road.json").read_text())
    entry = {"extra_wear_group_overall": 0.0123, "extra_wear_group_overall_low": 0.01,
             "extra_wear_group_overall_high": 0.015}  # fmt: skip
    m["calibrated"] = {"triaxle": {"steel": entry}}
    words = " ".join(
        " ".join(text.render("road.j2", m=m, protocol_label=PROTOCOL_LABEL, scenario=SCENARIO_LABEL)).split()
    )
    assert (
        "The calibrated fleet (at the posterior's medians, weighed as the survey was): steel tri-axles 1.2 %" in words
    )
    m["calibrated"] = None
    words = " ".join(text.render("road.j2", m=m, protocol_label=PROTOCOL_LABEL, scenario=SCENARIO_LABEL))
    assert "calibrated fleet" not in words
