"""The ``observed`` stage: an observed survey against the simulated fleet (pipeline.observed).

The simulated side is four fabricated bogies whose loads are chosen by hand; the observed side is the hand-written
tests/data/weighings/site.csv, whose statistics under a 15 t filter are worked out in tests/test_weighings_groups.py
and quoted in docs/weighings.md.
"""

import copy
import hashlib
import json
import math
import shutil
import tempfile
import typing
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from _flips import PLACES, flip

from bogie.fleet.weighing.weigher import result_row
from bogie.params import GRAVITY
from bogie.weighings.formats import FORMATS
from bogie.weighings.groups import POSITIONS
from pipeline.config import load_params, parse_config
from pipeline.config.schema import OBSERVED_FORMATS, Observed
from pipeline.observed import GROUPS_SCHEMA, SIMULATED_SCHEMA, main, simulated_readings, simulated_statistics
from pipeline.sample import sample_studies
from pipeline.schema import runs_frame, verified_table, write_runs_file

ROOT = Path(__file__).resolve().parents[2]
SITE = ROOT / "tests" / "data" / "weighings" / "site.csv"

#: (group, static loads, WIM loads or "failed") [kg]; every group is laden (>= 15 t) except bogie 1
BOGIES = [
    ("tandem", [9000, 8000], [9500, 7500]),
    ("tandem", [7000, 6000], "failed"),  # 13 t: below the filter
    ("triaxle", [8000, 8000, 8000], [12000, 0, 12000]),  # WIM: the middle wheels in the air
    ("triaxle", [9000, 8000, 7000], [10000, 8000, 6000]),
]


def raw_params(path=None, fmt="csv", position="all"):
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = len(BOGIES)
    raw["sensitivity"]["base_size"] = 2
    raw["ablation"]["n_bogies"] = 2
    raw["calibrate"] = None  # the stage under test is observed; a calibration of 4 bogies is not one
    raw["observed"].update(path=path, format=fmt, position=position)
    return raw


def fabricated_runs(raw):
    """The fleet's runs with the loads of :data:`BOGIES` (both sides, kg), through the protocol's result_row."""
    rows = []
    samples = sample_studies(parse_config(raw))["fleet"].to_dict("records")
    for sample, (group, static, wim) in zip(samples, BOGIES):
        n = len(static)
        sample.update(group=group, n_axles=n)
        for protocol, loads in (("static", static), ("wim", wim)):
            wheel = None if loads == "failed" else np.asarray(loads, dtype=float) * GRAVITY / 2.0
            row = result_row(protocol, n, wheel, 0.0)
            row.update(status="failed" if wheel is None else "ok", message="diverged" if wheel is None else "ok")
            rows.append({**sample, **row, "chassis_tilt_deg": np.degrees(sample["chassis_tilt"])})
    return runs_frame(rows)


def project(tmp_path, **params):
    raw = raw_params(**params)
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    part = tmp_path / "data" / "runs" / "study=fleet"
    part.mkdir(parents=True)
    write_runs_file(fabricated_runs(raw), part / "part-000000.parquet")
    return tmp_path


def args(root):
    return [
        "--params", str(root / "params.yaml"), "--runs", str(root / "data" / "runs"),
        "--out", str(root / "data" / "observed"), "--metrics", str(root / "metrics" / "observed.json"),
    ]  # fmt: skip


def metrics(root):
    return json.loads((root / "metrics" / "observed.json").read_text())


def test_the_tables_columns_are_the_librarys_each_with_a_type_and_a_unit():
    from bogie.fleet.weighing.observed import INEQUALITY_COLUMNS, SIMULATED_COLUMNS
    from bogie.weighings.groups import GROUP_TABLE_COLUMNS

    assert tuple(GROUPS_SCHEMA.names) == (*GROUP_TABLE_COLUMNS, *INEQUALITY_COLUMNS, "site")
    assert tuple(SIMULATED_SCHEMA.names) == SIMULATED_COLUMNS
    units = {f.name: f.metadata[b"unit"].decode() for f in (*GROUPS_SCHEMA, *SIMULATED_SCHEMA)}
    assert units["speed"] == "m/s" and units["axle_load_3"] == "kg" and units["spacing_2"] == "m"
    assert units["spread_pct"] == "%" and units["load_share_1"] == "-"


def test_the_schema_offers_the_formats_and_positions_of_the_readers():
    assert OBSERVED_FORMATS == ("auto", *FORMATS)
    # the group filter's keys are made from the library's declarations (bogie.weighings.settings.GROUP_FILTER)
    assert typing.get_args(Observed.model_fields["position"].annotation) == POSITIONS
    assert Observed.model_fields["min_group_load_t"].metadata[-1].le == 100.0  # 100 000 kg in the YAML's tonnes


def test_simulated_readings_leave_out_failed_airborne_and_light_groups_and_count_them(tmp_path):
    runs = fabricated_runs(raw_params())
    readings, counts = simulated_readings(runs, 15_000.0, "all")
    assert counts == {
        "static": {"n_runs": 4, "n_failed": 0, "n_airborne": 0, "n_light": 1, "n_position": 0, "n_kept": 3},
        "wim": {"n_runs": 4, "n_failed": 1, "n_airborne": 1, "n_light": 0, "n_position": 0, "n_kept": 2},
    }
    assert readings.columns.tolist() == SIMULATED_SCHEMA.names
    static = readings[readings["protocol"] == "static"].set_index("sample_id")
    assert static.loc[0, "group_load"] == pytest.approx(17_000.0, rel=1e-12)  # N back to kg
    assert np.isnan(static.loc[0, "axle_load_3"])  # a tandem has no third axle
    # bogie 3: loads 9, 8, 7 t: shares 9/8, 1, 7/8; spread 2000 kg, 25 % of the 8 t mean
    assert static.loc[3, ["load_share_1", "load_share_2", "load_share_3"]].tolist() == pytest.approx([1.125, 1, 0.875])
    assert static.loc[3, "spread_kg"] == pytest.approx(2000.0)
    assert static.loc[3, "spread_pct"] == pytest.approx(25.0)
    stats = simulated_statistics(readings, counts)
    # static tri-axles: 0 and 2000 kg spread; only bogie 3 is outside 5 % (2/9) and over 10 % (1.125)
    tri = stats["static"]["groups"]["triaxle"]
    assert (tri["n_groups"], tri["mean_spread_kg"], tri["share_outside_5pct"], tri["share_over_10pct"]) == (
        2, 1000.0, 0.5, 0.5,
    )  # fmt: skip
    # WIM: bogie 0 (9500, 7500: spread 2000 kg) and bogie 3 (10, 8, 6 t: spread 4000 kg, share 1.25)
    wim = stats["wim"]["groups"]
    assert (wim["tandem"]["n_groups"], wim["tandem"]["mean_spread_kg"]) == (1, 2000.0)
    assert (wim["triaxle"]["n_groups"], wim["triaxle"]["mean_spread_kg"], wim["triaxle"]["share_over_10pct"]) == (
        1, 4000.0, 1.0,
    )  # fmt: skip
    assert wim["triaxle"]["load_share_quantiles"]["axle_1"]["p50"] == 1.25


def test_without_a_path_the_stage_writes_the_simulated_side_and_an_empty_groups_table(tmp_path, capsys):
    root = project(tmp_path)
    assert main(args(root)) == 0
    assert "no observed survey given" in capsys.readouterr().out
    m = metrics(root)
    assert sorted(m) == ["filters", "observed", "reason", "simulated"]
    assert m["observed"] is None
    assert "observed.path is null" in m["reason"] and "docs/observed.md" in m["reason"]
    assert m["filters"] == {"min_group_load_t": 15.0, "group_spacing_m": 2.0, "position": "all"}
    assert m["simulated"]["static"]["groups"]["tandem"]["mean_spread_kg"] == 1000.0
    wim = raw_params()["protocol"]["wim"]
    model = m["simulated"]["wim_model"]
    assert model["sensor_error"] is (wim.get("sensor", "none") != "none")
    assert model["site_pavement"] is (wim.get("site_length_before_m", 0.0) + wim.get("site_length_after_m", 0.0) > 0)
    groups = pq.read_table(root / "data" / "observed" / "groups.parquet")
    assert groups.num_rows == 0
    assert groups.schema.equals(GROUPS_SCHEMA, check_metadata=False)
    assert groups.schema.field("group_load").metadata[b"unit"] == b"kg"
    assert groups.schema.field("speed").metadata[b"unit"] == b"m/s"
    assert pq.read_table(root / "data" / "observed" / "simulated.parquet").num_rows == 5
    assert sorted(p.name for p in (root / "data" / "observed").iterdir()) == [
        ".bogie-output",
        "groups.parquet",
        "simulated.parquet",
    ]
    assert [p.name for p in (root / "metrics").iterdir()] == ["observed.json"]


def test_with_a_path_the_observed_statistics_are_those_of_bogie_weighings(tmp_path, monkeypatch):
    root = project(tmp_path, path="observed/site.csv")
    (root / "observed").mkdir()
    shutil.copy(SITE, root / "observed" / "site.csv")
    scratch = tmp_path / "scratch"  # where the spilled groups and the groups file are written as the file streams
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    assert main(args(root)) == 0
    assert not list(scratch.iterdir())  # nothing left behind
    verified_table((root / "data" / "observed" / "groups.parquet").read_bytes(), "groups.parquet", "rerun")
    obs = metrics(root)["observed"]
    assert metrics(root)["reason"] is None
    assert (obs["path"], obs["format"]) == ("observed/site.csv", "csv")
    assert obs["sha256"] == hashlib.sha256(SITE.read_bytes()).hexdigest()
    assert obs["records"]["read"] == 5 and obs["records"]["skipped"] == 4
    assert sum(obs["records"]["skipped_by_reason"].values()) == 4
    # docs/weighings.md: two tandems (spreads 1000 and 0 kg, mean 500), two tri-axles (mean 1600 kg)
    tandem, tri = obs["groups"]["tandem"], obs["groups"]["triaxle"]
    assert (tandem["n_groups"], tandem["mean_spread_kg"], tandem["median_spread_pct"]) == (2, 500.0, 5.5556)
    assert (tandem["share_outside_5pct"], tandem["share_over_10pct"]) == (0.5, 0.0)
    assert (tri["n_groups"], tri["mean_spread_kg"], tri["share_over_10pct"]) == (2, 1600.0, 0.5)
    assert tandem["load_share_quantiles"]["axle_1"] == {
        "p05": 1.0028, "p25": 1.0139, "p50": 1.0278, "p75": 1.0417, "p95": 1.0528,
    }  # fmt: skip
    groups = pd.read_parquet(root / "data" / "observed" / "groups.parquet")
    assert len(groups) == 4 and set(groups["group"]) == {"tandem", "triaxle"}
    # line 3: a rigid truck's tandem of 9500 and 8500 kg: shares 19/18 and 17/18, spread 1000 kg
    row = groups[groups["line"] == 3].iloc[0]
    assert [row["load_share_1"], row["load_share_2"]] == pytest.approx([19 / 18, 17 / 18])
    assert row["spread_kg"] == 1000.0 and np.isnan(row["load_share_3"])


def test_a_drive_position_leaves_no_simulated_group_and_says_so(tmp_path):
    root = project(tmp_path, position="drive")
    assert main(args(root)) == 0
    sim = metrics(root)["simulated"]
    assert "semi-trailer groups only" in sim["position_note"]
    assert sim["static"]["runs"]["n_position"] == 3 and sim["static"]["runs"]["n_kept"] == 0
    assert sim["static"]["groups"]["triaxle"] == {
        "n_groups": 0, "mean_spread_kg": None, "median_spread_pct": None, "share_outside_5pct": None,
        "share_over_10pct": None, "load_share_quantiles": {},
    }  # fmt: skip


def test_a_missing_file_names_the_key_and_the_path_and_leaves_the_old_outputs(tmp_path, capsys):
    root = project(tmp_path)
    assert main(args(root)) == 0
    before = (root / "metrics" / "observed.json").read_bytes()
    params = yaml.safe_load((root / "params.yaml").read_text())
    params["observed"]["path"] = "observed/nowhere.mon"
    (root / "params.yaml").write_text(yaml.safe_dump(params, sort_keys=False))
    assert main(args(root)) == 2
    err = capsys.readouterr().err
    assert "observed.path = 'observed/nowhere.mon': no such file" in err
    assert str(root / "observed" / "nowhere.mon") in err
    assert (root / "metrics" / "observed.json").read_bytes() == before


def test_a_file_in_another_format_is_refused_with_the_readers_message(tmp_path, capsys):
    root = project(tmp_path, path="observed/site.csv", fmt="mon")
    (root / "observed").mkdir()
    shutil.copy(SITE, root / "observed" / "site.csv")
    assert main(args(root)) == 2
    assert "format mon" in capsys.readouterr().err


def test_the_outputs_are_byte_reproducible(tmp_path):
    root = project(tmp_path, path="observed/site.csv")
    (root / "observed").mkdir()
    shutil.copy(SITE, root / "observed" / "site.csv")
    outputs = [root / "metrics" / "observed.json", *(root / "data" / "observed" / n for n in
               ("groups.parquet", "simulated.parquet"))]  # fmt: skip
    assert main(args(root)) == 0
    first = [p.read_bytes() for p in outputs]
    assert main(args(root)) == 0
    assert [p.read_bytes() for p in outputs] == first


def test_validate_refuses_a_path_that_names_no_file_before_any_result_is_computed(tmp_path, capsys):
    from pipeline import validate

    root = project(tmp_path, path="observed/site.mon", fmt="mon")
    assert validate.main(["--params", str(root / "params.yaml"), "--out", str(root / "data" / "config.json")]) == 2
    assert "observed.path = 'observed/site.mon': no such file" in capsys.readouterr().err
    (root / "observed").mkdir()
    shutil.copy(ROOT / "tests" / "data" / "weighings" / "site.mon", root / "observed" / "site.mon")
    assert validate.main(["--params", str(root / "params.yaml"), "--out", str(root / "data" / "config.json")]) == 0
    assert json.loads((root / "data" / "config.json").read_text())["observed"]["path"] == "observed/site.mon"


def test_simulated_readings_are_read_at_the_observed_files_resolution_before_any_filter():
    # at a (deliberately coarse) 3000 kg step: static bogie 0 (9000, 8000) reads (9000, 9000), spread 0; bogie 3
    # (9000, 8000, 7000) reads (9000, 9000, 6000), spread 3000 kg; group loads are the sums of the readings
    readings, _ = simulated_readings(fabricated_runs(raw_params()), 15_000.0, "all", weight_step_kg=3000.0)
    static = readings[readings["protocol"] == "static"].set_index("sample_id")
    assert static.loc[0, ["axle_load_1", "axle_load_2"]].tolist() == [9000.0, 9000.0]
    assert (static.loc[0, "group_load"], static.loc[0, "spread_kg"]) == (18_000.0, 0.0)
    assert static.loc[3, ["axle_load_1", "axle_load_2", "axle_load_3"]].tolist() == [9000.0, 9000.0, 6000.0]
    assert (static.loc[3, "group_load"], static.loc[3, "spread_kg"]) == (24_000.0, 3000.0)


def test_format_auto_and_the_files_resolution_are_in_the_metrics(tmp_path):
    root = project(tmp_path, path="observed/site.csv", fmt="auto")
    (root / "observed").mkdir()
    shutil.copy(SITE, root / "observed" / "site.csv")
    assert main(args(root)) == 0
    obs = metrics(root)["observed"]
    assert (obs["format"], obs["format_asked"]) == ("csv", "auto")
    assert obs["records"]["weight_step_kg"] == 100.0  # site.csv: every load a whole 100 kg


# ---- a symlink in observed/ stays in observed/ (issue 28, item 3) -------------------------------------------------
SECRET = "BOGIE_TEST_SECRET=do-not-print-me"


def _linked_project(tmp_path, target, link="observed/site.csv"):
    """A project in tmp_path/project whose observed.path is a symlink to ``target``."""
    root = tmp_path / "project"
    root.mkdir()
    project(root, path=link)
    (root / "observed").mkdir(exist_ok=True)
    (root / link).symlink_to(target)
    return root


def _validate(root):
    from pipeline import validate

    return validate.main(["--params", str(root / "params.yaml"), "--out", str(root / "data" / "config.json")])


@pytest.mark.parametrize("stage", ["validate", "observed"])
def test_a_symlink_to_a_file_outside_the_project_is_refused_without_printing_it(tmp_path, capsys, stage):
    outside = tmp_path / "elsewhere" / "secret.csv"
    outside.parent.mkdir()
    outside.write_text(SECRET + "\n")
    root = _linked_project(tmp_path, outside)
    assert (_validate(root) if stage == "validate" else main(args(root))) == 2
    out, err = capsys.readouterr()
    for words in ("observed.path = 'observed/site.csv'", f"points to {outside}", f"{root}/observed", "observed/"):
        assert words in err, err
    assert "do-not-print-me" not in out + err
    assert not (root / "data" / "observed").exists() and not (root / "data" / "config.json").exists()


@pytest.mark.parametrize("stage", ["validate", "observed"])
def test_a_symlink_to_proc_self_environ_is_refused_without_printing_the_environment(tmp_path, capsys, monkeypatch,
                                                                                     stage):  # fmt: skip
    monkeypatch.setenv("BOGIE_TEST_SECRET", "do-not-print-me")
    root = _linked_project(tmp_path, "/proc/self/environ")
    assert (_validate(root) if stage == "validate" else main(args(root))) == 2
    out, err = capsys.readouterr()
    assert "observed.path = 'observed/site.csv' points to /proc/" in err and "outside the project's observed/" in err
    assert "do-not-print-me" not in out + err and "PATH=" not in out + err


def test_an_observed_directory_that_is_a_symlink_out_of_the_project_is_refused(tmp_path, capsys):
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    shutil.copy(SITE, outside / "site.csv")
    root = tmp_path / "project"
    root.mkdir()
    project(root, path="observed/site.csv")
    (root / "observed").symlink_to(outside, target_is_directory=True)
    assert main(args(root)) == 2
    assert f"points to {outside / 'site.csv'}, outside the project's observed/" in capsys.readouterr().err


def test_a_symlink_to_another_file_in_observed_is_read(tmp_path):
    root = tmp_path / "project"
    root.mkdir()
    project(root, path="observed/site.csv")
    (root / "observed" / "raw").mkdir(parents=True)
    shutil.copy(SITE, root / "observed" / "raw" / "2026-01.csv")
    (root / "observed" / "site.csv").symlink_to(Path("raw") / "2026-01.csv")
    assert _validate(root) == 0
    assert main(args(root)) == 0
    metrics = json.loads((root / "metrics" / "observed.json").read_text())
    assert metrics["observed"]["path"] == "observed/site.csv"
    assert metrics["observed"]["sha256"] == hashlib.sha256(SITE.read_bytes()).hexdigest()


@pytest.mark.parametrize("place", PLACES)
def test_a_runs_part_with_one_flipped_bit_is_refused_naming_it(tmp_path, capsys, place):
    # issue 28, item 4: the observed stage verifies the runs it reads (pipeline.survey.read_runs)
    root = project(tmp_path, path="observed/site.csv")
    (root / "observed").mkdir()
    shutil.copy(SITE, root / "observed" / "site.csv")
    damaged = root / "data" / "runs" / "study=fleet" / "part-000000.parquet"
    flip(damaged, place)
    assert main(args(root)) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"observed: {damaged} is damaged: its SHA-256 does not match") and "\n" not in err, err
    assert not (root / "data" / "observed").exists() and not (root / "metrics").exists()


def tmg_2001(station: str, hour: int, loads_t: list[float], spacings_m: list[float]) -> str:
    """A TMG 2001 "W" record (../shared/reference/tmg-weight-record.md: state 2-3, station 4-9, direction 10, lane
    11, yy mm dd hh 12-19, class 20-21, open 22-24, gross 25-28 in 100 kg, axles 29-30, then per axle its weight in
    100 kg (3 columns) and the spacing to the next in 0.1 m (3)), as tests/test_weighings_tmg.py types them."""
    weights = [round(10 * w) for w in loads_t]
    axles = "".join(f"{w:3d}{round(10 * s):3d}" for w, s in zip(weights, spacings_m)) + f"{weights[-1]:3d}"
    return f"W06{station}1126031{hour % 10}{hour // 10:02d} 9   {sum(weights):4d}{len(weights):2d}" + axles


def test_a_state_wide_file_puts_its_stations_side_by_side_and_flags_the_odd_one(tmp_path):
    # two stations of one TMG 2001 file, 30 trucks each: a steer axle of 5 t 4 m ahead of a tandem 1.3 m apart,
    # either 7.5 / 7.5 t (equal) or 9.0 / 6.5 t ((9.0 - 6.5) / 9.0 = 27.8 %: outside 5 % and over 10 %, spread
    # 2500 kg). Station 000101 has 6 unequal of 30, 000102 has 24: shares 0.2 and 0.8, mean spreads 500 and 2000 kg
    lines = []
    for station, unequal in (("000101", 6), ("000102", 24)):
        for k in range(30):
            tandem = [9.0, 6.5] if k < unequal else [7.5, 7.5]
            lines.append(tmg_2001(station, k % 24, [5.0, *tandem], [4.0, 1.3]))
    root = project(tmp_path, path="observed/state.dat", fmt="tmg2001", position="all")
    (root / "observed").mkdir()
    (root / "observed" / "state.dat").write_text("\n".join(lines) + "\n")
    assert main(args(root)) == 0
    obs = metrics(root)["observed"]
    assert obs["records"]["read"] == 60 and obs["groups"]["tandem"]["n_groups"] == 60
    assert set(obs["stations"]) == {"06-000101", "06-000102"}
    groups = pd.read_parquet(root / "data" / "observed" / "groups.parquet")  # each group's site as stations names it
    assert groups["site"].value_counts().to_dict() == {"06-000101": 30, "06-000102": 30}
    rows = {r["site"]: r for r in obs["sites"]}
    assert list(rows) == ["state.dat:06-000102", "state.dat:06-000101"]  # the most unequal sharing first
    a, b = rows["state.dat:06-000101"], rows["state.dat:06-000102"]
    assert (a["group"], a["n_groups"], a["n_outside_5pct"], a["n_over_10pct"]) == ("tandem", 30, 6, 6)
    assert (b["n_outside_5pct"], b["share_outside_5pct"], b["mean_spread_kg"], a["mean_spread_kg"]) == (
        24, 0.8, 2000.0, 500.0,
    )  # fmt: skip
    # the pooled two-proportion z test: p = 30 / 60 = 0.5, z = 0.6 / sqrt(0.25 x 2 / 30) = 4.648, two-sided p-value
    # erfc(z / sqrt 2) = 3.4e-6, under 0.05 / (2 x 2): both sites of the two that differ are flagged
    z = 0.6 / (0.25 * 2 / 30) ** 0.5
    assert a["p_outside_5pct"] == pytest.approx(math.erfc(z / 2**0.5), rel=1e-5) and a["p_outside_5pct"] < 0.0125
    assert a["disagrees"] and b["disagrees"] and not a["few"]
    # Wilson's 95 % interval of 6 of 30 holds 0.2 and lies within (0.08, 0.39) (its closed form: 0.0951-0.3857)
    assert 0.09 < a["share_outside_5pct_low"] < 0.2 < a["share_outside_5pct_high"] < 0.39
    # the observed page's words say the stations are pooled there and set side by side on the next page
    from pipeline.report import text

    words = " ".join(text.render("observed.j2", m=metrics(root), sizes=("tandem", "triaxle")))
    assert "The file holds 2 stations, pooled here; the next page sets them side by side." in words


def test_the_report_sets_the_sites_side_by_side(tmp_path):
    from pipeline.report.pages.observed import SITE_HEADER, site_table, sites_pages

    row = {"group": "tandem", "site": "state.dat:06-000101", "n_groups": 30, "share_outside_5pct": 0.2,
           "share_outside_5pct_low": 0.0951, "share_outside_5pct_high": 0.3857, "share_over_10pct": 0.2,
           "share_over_10pct_low": 0.0951, "share_over_10pct_high": 0.3857, "mean_spread_kg": 500.0, "few": False,
           "disagrees": True}  # fmt: skip
    assert site_table([row]) == [["tandem", "state.dat:06-000101", "30", "20.0 ( 9.5- 38.6)", "20.0 ( 9.5- 38.6)",
                                  "500", "disagrees"]]  # fmt: skip
    assert len(SITE_HEADER) == len(site_table([row])[0])
    observed = {"path": "observed/state.dat", "stations": {"06-000101": {}, "06-000102": {}}, "sites": [row]}
    pages = sites_pages(observed)
    assert len(pages) == 1 and pages[0].section == "Observed: the sites side by side"
    words = " ".join(t.get_text() for t in pages[0].figure.texts)
    assert "observed/state.dat holds 2 stations" in words and "1 site disagrees" in words
    assert sites_pages({"path": "observed/site.csv"}) == []  # one site: no page


def test_the_calibration_skips_a_file_of_several_stations_naming_them(tmp_path):
    # the calibration's site terms are one site's: pooling two stations would read as one site (issue 46 Must 2); the
    # stage catches SeveralSites and writes its skipped metrics with this reason (as for a folder of files:
    # tests/pipeline/test_observed_folder.py)
    from pipeline.calibrate import SeveralSites, observed_groups

    lines = [tmg_2001(station, k, [5.0, 7.5, 7.5], [4.0, 1.3]) for station in ("000101", "000102") for k in range(12)]
    path = tmp_path / "state.dat"
    path.write_text("\n".join(lines) + "\n")
    config = parse_config(raw_params(path="observed/state.dat", fmt="tmg2001", position="all"))
    with pytest.raises(SeveralSites, match=r"holds 2 stations \(06-000101, 06-000102\), each a WIM site.*"
                       r"the calibration is skipped"):  # fmt: skip
        observed_groups(path, config)
