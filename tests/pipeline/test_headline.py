"""The headline metrics: a few figures taken from the stages' metrics, checked on a hand-made pair of files."""

import json

import pandas as pd
from _flips import flip
from test_observed import fabricated_runs, raw_params

from pipeline.headline import headline, main
from pipeline.schema import write_runs_file

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
    assert "ranking" not in out  # a 90-character string took the width of dvc exp show (issue 45 Must 2)
    st = [k for k in out if k.startswith("ST_")]  # the ranking is the order of the inhibitors' indices
    assert st == ["ST_contact_roll_radius", "ST_bush_stiffness", "ST_friction_coefficient", "ST_bush_damping",
                  "ST_chassis_tilt"]  # fmt: skip
    assert (out["ST_contact_roll_radius"], out["ST_chassis_tilt"]) == (0.24, 0.78)
    assert out["outside_5pct_static_triaxle"] == 0.75 and out["spread_kg_wim_tandem"] == 1219.6
    assert "outside_5pct_wim_triaxle" not in out  # not in the metrics: left out, not invented
    assert (out["runs"], out["failed"]) == (5, 2)
    assert len(out) == 5 + 3 + 3 + 2
    road = {"simulated": {"static": {"triaxle": {"steel": {"extra_wear_overall": 0.0447}},
                                     "tandem": {"air": {"extra_wear_overall": 0.001}}}}}  # fmt: skip
    out = headline(SURVEY, SENSITIVITY, status, road)
    # the steel groups' figure only; the air-only tandem and the missing WIM side are left out
    assert out["extra_wear_static_triaxle"] == 0.0447 and len(out) == 5 + 3 + 3 + 1 + 2
    assert list(out)[-3:] == ["extra_wear_static_triaxle", "runs", "failed"]


def test_stage_writes_the_file(tmp_path):
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "survey.json").write_text(json.dumps(SURVEY))
    (tmp_path / "m" / "sensitivity.json").write_text(json.dumps(SENSITIVITY))
    runs = tmp_path / "runs" / "study=fleet"
    runs.mkdir(parents=True)
    write_runs_file(fabricated_runs(raw_params()), runs / "part-00000.parquet")  # 8 runs, one failed
    out = tmp_path / "m" / "headline.json"
    assert main(["--metrics", str(tmp_path / "m"), "--runs", str(tmp_path / "runs"), "--out", str(out)]) == 0
    assert (json.loads(out.read_text())["runs"], json.loads(out.read_text())["failed"]) == (8, 1)
    assert main(["--metrics", str(tmp_path / "missing"), "--out", str(out)]) == 2


def test_stage_refuses_a_part_with_a_flipped_bit_in_its_footer(tmp_path, capsys):
    # issue 28, item 4: the headline counts runs; a damaged part is refused, not counted
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "survey.json").write_text(json.dumps(SURVEY))
    (tmp_path / "m" / "sensitivity.json").write_text(json.dumps(SENSITIVITY))
    part = tmp_path / "runs" / "study=fleet" / "part-00000.parquet"
    part.parent.mkdir(parents=True)
    write_runs_file(fabricated_runs(raw_params()), part)
    flip(part, "footer metadata")
    out = tmp_path / "m" / "headline.json"
    assert main(["--metrics", str(tmp_path / "m"), "--runs", str(tmp_path / "runs"), "--out", str(out)]) == 2
    assert f"headline: {part} is damaged: its SHA-256 does not match" in capsys.readouterr().err
    assert not out.exists()
