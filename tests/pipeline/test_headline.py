"""The headline metrics: a few figures taken from the stages' metrics, checked on a hand-made pair of files."""

import json

import pandas as pd

from pipeline.headline import headline, main

SURVEY = {
    "static": {"tandem": {"share_outside_5pct": 0.4, "mean_spread_kg": 371.4},
               "triaxle": {"share_outside_5pct": 0.75, "mean_spread_kg": 1065.6}},
    "wim": {"tandem": {"share_outside_5pct": 0.7, "mean_spread_kg": 1219.6}},
}  # fmt: skip
SENSITIVITY = {
    "ranking": ["contact_roll_radius", "bush_stiffness", "friction_coefficient", "bush_damping"],
    "sobol": {"indices": {"contact_roll_radius": {"ST": 0.24}, "bush_stiffness": {"ST": 0.03},
                          "friction_coefficient": {"ST": 0.015}, "bush_damping": {"ST": 0.0},
                          "chassis_tilt": {"ST": 0.78}}},
}  # fmt: skip


def test_headline_takes_each_figure_from_its_metric_and_counts_failures():
    status = pd.Series(["ok", "failed", "ok", "ok", "failed"])
    out = headline(SURVEY, SENSITIVITY, status)
    assert out["ranking"] == "contact_roll_radius > bush_stiffness > friction_coefficient > bush_damping"
    assert (out["ST_contact_roll_radius"], out["ST_chassis_tilt"]) == (0.24, 0.78)
    assert out["outside_5pct_static_triaxle"] == 0.75 and out["spread_kg_wim_tandem"] == 1219.6
    assert "outside_5pct_wim_triaxle" not in out  # not in the metrics: left out, not invented
    assert (out["runs"], out["failed"]) == (5, 2)
    assert len(out) == 1 + 5 + 3 + 3 + 2


def test_stage_writes_the_file(tmp_path):
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "survey.json").write_text(json.dumps(SURVEY))
    (tmp_path / "m" / "sensitivity.json").write_text(json.dumps(SENSITIVITY))
    runs = tmp_path / "runs" / "study=fleet"
    runs.mkdir(parents=True)
    pd.DataFrame({"status": ["ok", "failed"]}).to_parquet(runs / "part-00000.parquet")
    out = tmp_path / "m" / "headline.json"
    assert main(["--metrics", str(tmp_path / "m"), "--runs", str(tmp_path / "runs"), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["failed"] == 1
    assert main(["--metrics", str(tmp_path / "missing"), "--out", str(out)]) == 2
