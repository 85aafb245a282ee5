"""``bogie weighings``: the table, the JSON of issue 13 item 4, and the errors, on the hand-written files."""

import json
from pathlib import Path

import pandas as pd
import pytest

from bogie.cli import main
from bogie.weighings.legal import EU_SOURCE

DATA = Path(__file__).parent / "data" / "weighings"


def test_json_has_exactly_the_issues_shape_with_shares_as_fractions(capsys):
    assert main(["weighings", str(DATA / "site.mon"), "--format", "mon", "--min-group-load-t", "15", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"settings", "records", "positions", "groups", "road"}
    settings = out["settings"]
    assert (settings["format"], settings["format_asked"]) == ("mon", "mon")
    assert settings["filters"] == {"min_group_load_kg": 15000.0, "position": "all", "speed_kmh": None}
    assert settings["grouping"] == "spacing: consecutive axles at most 2 m apart"
    assert settings["legal_loads_kg"] == {"source": EU_SOURCE}  # the directive's by position and spacing
    assert settings["damage_exponents"] == {"overall": 4, "asphalt": 5, "subgrade": 7, "cemented": 12}
    assert settings["resolution"].startswith("weight resolution 100 kg (detected: 21 of 21 axle loads")
    resolution = out["records"].pop("resolution")
    assert out["records"] == {"read": 5, "skipped": 4, "weight_step_kg": 100.0}  # every load a whole 100 kg
    # the 5 good records' 21 loads (A 5, B 3, C 6, D 5, E 2 axles) all on 100 kg, of MON's 1 kg: the chance bound
    # is (1/100)^21, log10 -42.0
    assert resolution == {"step_kg": 100.0, "source": "detected", "detected_kg": 100.0, "unit_kg": 1.0,
                          "n_loads": 21, "on": 21, "below": 0, "above": 0, "chance_log10": -42.0,
                          "base": "kg"}  # fmt: skip
    # every group of the file before the filters (test_weighings_groups.py): A, D steer | single | tri-axle; B steer |
    # tandem; C steer | tandem | tri-axle; E steer | single
    assert out["positions"] == {
        "steer": {"single": 5, "tandem": 0, "triaxle": 0, "other": 0},
        "drive": {"single": 3, "tandem": 2, "triaxle": 0, "other": 0},
        "trailer": {"single": 0, "tandem": 0, "triaxle": 3, "other": 0},
    }
    assert set(out["groups"]) == {"tandem", "triaxle"}
    for entry in out["groups"].values():
        assert set(entry) == {"n_groups", "mean_spread_kg", "median_spread_pct", "share_outside_5pct",
                              "share_over_10pct", "load_share_quantiles"}  # fmt: skip
        assert 0.0 <= entry["share_outside_5pct"] <= 1.0 and 0.0 <= entry["share_over_10pct"] <= 1.0
    # the hand-worked tri-axles A and C (test_weighings_groups.py): 1600 kg, 20 %, all outside 5 %, half over 10 %
    tri = out["groups"]["triaxle"]
    assert (tri["n_groups"], tri["mean_spread_kg"], tri["share_outside_5pct"], tri["share_over_10pct"]) == (
        2, 1600.0, 1.0, 0.5)  # fmt: skip


def test_the_json_and_the_table_give_what_unequal_sharing_costs_the_road(tmp_path, capsys):
    # two 5-axle vehicles (steer | drive | tri-axle): tri-axles of 8000/8200/7800 kg and 8100 kg each
    path = tmp_path / "two.csv"
    path.write_text(
        "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,axle_load_3,axle_load_4,axle_load_5,"
        "spacing_1,spacing_2,spacing_3,spacing_4\n"
        "2026-01-05T06:00:00,80,1,5,6000,9000,8000,8200,7800,3.6,5.2,1.31,1.31\n"
        "2026-01-05T06:00:05,80,1,5,6100,9100,8100,8100,8100,3.6,5.2,1.31,1.31\n"
    )
    assert main(["weighings", str(path), "--json"]) == 0
    road = json.loads(capsys.readouterr().out)["road"]
    assert road["tandem"] == {"n_groups": 0}
    tri = road["triaxle"]
    # sum D / sum D_eq - 1 at k = 4, worked by hand: the standard axle cancels
    expected = (8000.0**4 + 8200.0**4 + 7800.0**4 + 3 * 8100.0**4) / (3 * 8000.0**4 + 3 * 8100.0**4) - 1.0
    assert tri["n_groups"] == 2 and tri["extra_wear_overall"] == pytest.approx(expected, abs=5e-5)
    assert tri["n_hidden"] == 0 and tri["share_hidden_overload"] == 0.0  # no axle over 10 t
    assert tri["extra_wear_cemented"] > tri["extra_wear_subgrade"] > tri["extra_wear_asphalt"] > expected
    assert main(["weighings", str(path)]) == 0
    table = capsys.readouterr().out
    assert "what unequal sharing costs the road" in table
    # the headline against Austroads' group count (the per-axle share times 3^-3 (181 / 80)^4 = 0.9705), the per-axle
    # share beside it
    group = expected * 3.0**-3 * (181.0 / 80.0) ** 4
    assert tri["extra_wear_group_overall"] == pytest.approx(group, abs=5e-5)
    assert f"triaxle      2 {100 * group:>10.2f} {100 * expected:>9.2f}" in table
    assert "an indicator, not an offence" in table
    # the sharing factors for pavement tools (issue 44 Must 5): 1 + the extra wear, per axle and against the guide
    out = tmp_path / "factors.csv"
    assert main(["weighings", str(path), "--sharing-factors", str(out)]) == 0
    capsys.readouterr()
    factors = pd.read_csv(out, comment="#")
    assert list(factors["group"]) == ["triaxle"] and factors.loc[0, "position"] == "all"
    assert factors.loc[0, "factor_k4"] == pytest.approx(1.0 + expected, rel=1e-5)
    assert factors.loc[0, "guide_factor_k4"] == pytest.approx(1.0 + group, rel=1e-5)
    assert main(["weighings", str(path), "--sharing-factors", str(tmp_path / "no" / "such.csv")]) == 2
    assert "--sharing-factors" in capsys.readouterr().err and not (tmp_path / "no").exists()


def test_the_legal_limits_go_by_the_groups_position_and_spacing_unless_stated(tmp_path, capsys):
    # three tractor-semi-trailers (steer | drive tandem | trailer tri-axle), worked by hand against 96/53/EC Annex I
    # (bogie.weighings.legal): 1. a drive tandem 1.35 m apart, 11,000 + 6,500 kg: within a motor tandem's 18 t and a
    # driving axle's 11.5 t; tri-axle 3 x 8,000 at 1.31 m (24 t band); 2. a drive tandem 1.0 m apart, 2 x 9,000: over
    # its 16 t; tri-axle 7,500 + 7,500 + 7,600 = 22,600 kg at 1.25 m: over its 21 t; 3. a tri-axle at 1.4 m of
    # 10,500 + 6,500 + 6,500 = 23,500 kg: within 24 t with an axle over 10 t (the indicator)
    path = tmp_path / "three.csv"
    header = ("timestamp,speed_kmh,lane,n_axles," + ",".join(f"axle_load_{i}" for i in range(1, 7)) + ","
              + ",".join(f"spacing_{i}" for i in range(1, 6)))  # fmt: skip
    path.write_text(
        header + "\n"
        "2026-01-05T06:00:00,80,1,6,6000,11000,6500,8000,8000,8000,3.2,1.35,5.0,1.31,1.31\n"
        "2026-01-05T06:00:05,80,1,6,6000,9000,9000,7500,7500,7600,3.2,1.0,5.0,1.25,1.25\n"
        "2026-01-05T06:00:09,80,1,6,6000,9000,8500,10500,6500,6500,3.2,1.35,5.0,1.4,1.4\n"
    )
    assert main(["weighings", str(path), "--json"]) == 0
    road = json.loads(capsys.readouterr().out)["road"]
    tandem, tri = road["tandem"], road["triaxle"]
    third = pytest.approx(1 / 3, abs=5e-5)  # the JSON's four decimals
    assert (tandem["n_groups"], tandem["n_hidden"], tandem["share_group_over"]) == (3, 0, third)
    assert (tri["n_groups"], tri["n_hidden"], tri["share_group_over"]) == (3, 1, third)
    # stated single limits (one for every position and spacing): the drive tandem's 11 t axle is over 10 t within
    # 18 t, the 18 t tandem at its limit is within it, the 22.6 t tri-axle within 24 t
    stated = ["--legal-axle-kg", "10000", "--legal-tandem-kg", "18000", "--legal-triaxle-kg", "24000"]
    assert main(["weighings", str(path), "--json", *stated]) == 0
    out = json.loads(capsys.readouterr().out)
    tandem, tri = out["road"]["tandem"], out["road"]["triaxle"]
    assert (tandem["n_hidden"], tandem["share_group_over"], tri["n_hidden"], tri["share_group_over"]) == (1, 0, 1, 0)
    assert out["settings"]["legal_loads_kg"] == {
        "tandem": 18_000.0, "triaxle": 24_000.0, "axle": 10_000.0, "source": "given by the caller"}  # fmt: skip
    # the table says which limits it judged by
    assert main(["weighings", str(path)]) == 0
    assert "within legal groups (96/53/EC's by each group's position and spacing)" in capsys.readouterr().out


def test_the_json_follows_the_filters(capsys):
    args = ["weighings", str(DATA / "site.castor"), "--format", "castor", "--json"]
    assert main([*args, "--min-group-load-t", "15", "--position", "drive"]) == 0
    drive = json.loads(capsys.readouterr().out)["groups"]
    assert (drive["tandem"]["n_groups"], drive["triaxle"]["n_groups"]) == (2, 0)
    # no load filter: D's unladen tri-axle (2000, 2100, 1900: spread 200 kg) joins -> mean (1200 + 2000 + 200) / 3
    assert main(args) == 0
    tri = json.loads(capsys.readouterr().out)["groups"]["triaxle"]
    assert tri["n_groups"] == 3 and tri["mean_spread_kg"] == pytest.approx(3400 / 3, abs=1e-4)
    # at 1 m no two axles form a group: no tandem, no tri-axle
    assert main([*args, "--group-spacing-m", "1.0"]) == 0
    none = json.loads(capsys.readouterr().out)["groups"]
    assert none["tandem"]["n_groups"] == none["triaxle"]["n_groups"] == 0


def test_the_table_names_the_skipped_lines_and_the_statistics_in_percent(capsys):
    assert main(["weighings", str(DATA / "site.ditis"), "--format", "ditis", "--min-group-load-t", "15"]) == 0
    out = capsys.readouterr().out
    assert "5 records read, 4 skipped" in out and "record too short for its stated axles: 1, line 9" in out
    table = [line.split() for line in out.splitlines() if line.startswith(("tandem ", "triaxle "))]
    rows = {row[0]: row for row in reversed(table)}  # the first rows are the statistics, then the quantiles
    # group, n, mean spread [kg], median spread [%], outside 5 % [%], over 10 % [%]
    assert rows["triaxle"][:6] == ["triaxle", "2", "1600", "20.0", "100.0", "50.0"]
    assert rows["tandem"][:6] == ["tandem", "2", "500", "5.6", "50.0", "0.0"]
    # then the load-share quantiles: the tri-axles' front axle, LSC 0.925 and 1.125 -> p05 0.935, p50 1.025
    assert ["triaxle", "1", "0.935", "0.975", "1.025", "1.075", "1.115"] in table


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--min-group-load-t", "-2"], "--min-group-load-t = -2.0 is out of range: must be in [0, 100] t"),
     (["--min-group-load-t", "heavy"], "--min-group-load-t = 'heavy' is not a number (text): must be in [0, 100] t"),
     (["--group-spacing-m", "9"], "--group-spacing-m = 9.0 is out of range: must be in [0.1, 5] m"),
     (["--position", "front"], "invalid choice: 'front'")],
)  # fmt: skip
def test_bad_arguments_name_the_parameter_value_range_and_unit(capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        main(["weighings", str(DATA / "site.mon"), "--format", "mon", *args])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_a_file_in_another_format_or_missing_is_an_error_not_a_traceback(capsys):
    assert main(["weighings", str(DATA / "site.mon"), "--format", "bedit"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bogie: error: ") and "(format bedit)" in err and "--format mon?" in err
    assert main(["weighings", str(DATA / "missing.mon"), "--format", "mon"]) == 2
    assert "missing.mon: No such file or directory" in capsys.readouterr().err


def test_format_auto_is_the_default_and_the_table_says_which_format_it_found(capsys):
    assert main(["weighings", str(DATA / "site.bedit")]) == 0
    assert "(format auto: bedit): 5 records read, 4 skipped" in capsys.readouterr().out
