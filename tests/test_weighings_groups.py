"""bogie.weighings.groups and .survey: axle groups of the hand-written vehicles (see test_weighings_readers.py),
their labels, the filters, and the statistics of an observed survey worked out by hand."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bogie.weighings.groups import axle_groups, filter_groups
from bogie.weighings.readers import read_weighings
from bogie.weighings.survey import observed_survey

DATA = Path(__file__).parent / "data" / "weighings"


@pytest.fixture(scope="module")
def groups():
    return axle_groups(read_weighings(DATA / "site.mon", "mon").vehicles)


def test_groups_sizes_and_positions_at_2_m(groups):
    # A: 3.6 | 5.2 | 1.31 1.31 -> steer single, drive single, trailer tri-axle (3 groups)
    # B: 4.2 | 1.35 -> steer single, drive tandem (2 groups: no trailer)
    # C: 3.8 | 1.35 | 6.0 | 1.31 1.31 -> steer, drive tandem, trailer tri-axle
    # D: as A (unladen); E: 2.6 -> steer single, drive single
    by_vehicle = groups.groupby("line")
    assert by_vehicle["group"].apply(list).tolist() == [
        ["other", "other", "triaxle"], ["other", "tandem"], ["other", "tandem", "triaxle"],
        ["other", "other", "triaxle"], ["other", "other"],
    ]  # fmt: skip
    assert by_vehicle["position"].apply(list).tolist() == [
        ["steer", "drive", "trailer"], ["steer", "drive"], ["steer", "drive", "trailer"],
        ["steer", "drive", "trailer"], ["steer", "drive"],
    ]  # fmt: skip
    # group loads: A's tri-axle 7400 + 8000 + 8600 = 24 000 kg, C's tandem 18 000, D's tri-axle 6000
    assert groups["group_load"].tolist() == [6500, 9000, 24000, 6000, 18000, 7000, 18000, 24000, 5000, 6000, 6000,
                                             1200, 1100]  # fmt: skip
    tri = groups.iloc[2]
    assert (tri["first_axle"], tri["axle_load_1"], tri["axle_load_3"], tri["spacing_2"]) == (3, 7400, 8600, 1.31)
    # the MON file's own count of groups agrees with the 2 m rule here
    assert groups.groupby("line")["vehicle_groups"].first().tolist() == [3, 2, 3, 3, 2]


def test_a_wider_group_spacing_joins_axles_and_a_narrower_one_splits_them(groups):
    vehicles = read_weighings(DATA / "site.mon", "mon").vehicles
    # at 1.0 m no spacing qualifies: every axle a group of its own, 5 + 3 + 6 + 5 + 2 = 21
    assert len(axle_groups(vehicles, 1.0)) == 21
    # at 4.0 m A's 3.6 m joins steer and drive: (steer + drive) [2], tri-axle -> 2 groups, no trailer
    wide = axle_groups(vehicles, 4.0)
    assert wide[wide["line"] == 1][["group", "position"]].values.tolist() == [["tandem", "steer"],
                                                                              ["triaxle", "drive"]]  # fmt: skip


def test_every_group_after_the_second_is_a_trailer_group_a_b_doubles_lead_trailer_too():
    # C made a B-double: steer | tandem drive | tri-axle lead trailer | tri-axle rear trailer (issue 27: before, the
    # lead trailer was labelled a drive group, as only a vehicle's last group was a trailer group)
    vehicles = read_weighings(DATA / "site.mon", "mon").vehicles
    c = vehicles.iloc[[2]].copy()
    assert int(c["n_axles"].iloc[0]) == 6
    c["n_axles"] = 9
    for i, load in enumerate([6000, 9000, 9000, 8000, 8000, 8000, 7000, 7000, 7000]):
        c[f"axle_load_{i + 1}"] = load
    for i, spacing in enumerate([3.8, 1.35, 5.0, 1.31, 1.31, 6.5, 1.31, 1.31]):
        c[f"spacing_{i + 1}"] = spacing
    wide = axle_groups(c)
    assert wide["group"].tolist() == ["other", "tandem", "triaxle", "triaxle"]
    assert wide["position"].tolist() == ["steer", "drive", "trailer", "trailer"]
    assert wide["group_load"].tolist() == [6000, 18000, 24000, 21000]


def test_filters_on_group_load_position_and_speed(groups):
    laden = filter_groups(groups, min_group_load_kg=15_000)
    # >= 15 000 kg: A's and C's tri-axles (24 t), B's and C's tandems (18 t); D's tri-axle (6 t) left out
    assert laden[["line", "group"]].values.tolist() == [[1, "triaxle"], [2, "tandem"], [4, "tandem"],
                                                        [4, "triaxle"]]  # fmt: skip
    assert filter_groups(groups, min_group_load_kg=15_000, position="trailer")["line"].tolist() == [1, 4]
    assert filter_groups(groups, min_group_load_kg=15_000, position="drive")["group"].tolist() == ["tandem", "tandem"]
    # MON speeds 82.08, 74.88, 87.84, 90, 100.08 km/h: 80-90 keeps A, C and D
    assert sorted(set(filter_groups(groups, speed_kmh=(80, 90))["line"])) == [1, 4, 6]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"min_group_load_kg": -1.0}, r"min_group_load_kg = -1.0 is out of range: must be in \[0, 100000\] kg"),
     ({"position": "front"}, r"position = 'front' is unknown: must be one of all, steer, drive, trailer"),
     ({"speed_kmh": (90, 80)}, r"speed_kmh highest = 80 is out of range: must be in \[90, 160\] km/h")],
)  # fmt: skip
def test_bad_filters_are_refused_naming_the_parameter_value_range_and_unit(groups, kwargs, message):
    with pytest.raises(ValueError, match=message):
        filter_groups(groups, **kwargs)


def test_a_group_spacing_out_of_range_is_refused():
    with pytest.raises(ValueError, match=r"group_spacing_m = 0.0 is out of range: must be in \(0, 5\] m"):
        axle_groups(pd.DataFrame(), 0.0)


def test_observed_survey_statistics_by_hand():
    survey = observed_survey(DATA / "site.csv", "csv", min_group_load_kg=15_000)
    out = survey.to_dict()
    assert out["records"].pop("resolution")["source"] == "detected"
    assert out["records"] == {"read": 5, "skipped": 4, "weight_step_kg": 100.0}  # every load a whole 100 kg
    tandem, tri = out["groups"]["tandem"], out["groups"]["triaxle"]
    # tandems B (9500, 8500) and C (9000, 9000): spreads 1000 and 0 kg -> mean 500 kg;
    # spread over the mean axle load 1000/9000 = 11.11 % and 0 % -> median 5.556 %;
    # (max - min)/max = 0.105 > 0.05 for B only -> 0.5; LSC 1.056, 1.0 -> none over 1.10
    assert tandem == {
        "n_groups": 2, "mean_spread_kg": 500.0, "median_spread_pct": 5.5556, "share_outside_5pct": 0.5,
        "share_over_10pct": 0.0,
        # front axle LSC 9500/9000 = 1.0556 and 1.0: p50 1.0278, p05 1.0 + 0.05 x 0.0556 = 1.0028
        "load_share_quantiles": {
            "axle_1": {"p05": 1.0028, "p25": 1.0139, "p50": 1.0278, "p75": 1.0417, "p95": 1.0528},
            "axle_2": {"p05": 0.9472, "p25": 0.9583, "p50": 0.9722, "p75": 0.9861, "p95": 0.9972},
        },
    }  # fmt: skip
    # tri-axles A (7400, 8000, 8600) and C (9000, 7000, 8000), both 24 t, mean axle 8000 kg:
    # spreads 1200 and 2000 kg -> mean 1600; 15 % and 25 % -> median 20 %; 0.140 and 0.222 > 0.05 -> 1.0;
    # largest LSC 1.075 and 1.125 -> C over 1.10 -> 0.5; front LSC 0.925 and 1.125 -> p50 1.025
    assert (tri["n_groups"], tri["mean_spread_kg"], tri["median_spread_pct"]) == (2, 1600.0, 20.0)
    assert (tri["share_outside_5pct"], tri["share_over_10pct"]) == (1.0, 0.5)
    assert tri["load_share_quantiles"]["axle_1"]["p50"] == 1.025
    assert tri["load_share_quantiles"]["axle_3"]["p50"] == pytest.approx((1.075 + 1.0) / 2)


def test_every_format_gives_the_same_survey_of_the_same_vehicles():
    ref = observed_survey(DATA / "site.csv", "csv", min_group_load_kg=15_000).to_dict()
    assert ref["records"].pop("resolution")["unit_kg"] == 1.0
    assert ref.pop("settings")["format"] == "csv"
    for fmt in ("mon", "castor", "bedit", "ditis"):
        out = observed_survey(DATA / f"site.{fmt}", fmt, min_group_load_kg=15_000).to_dict()
        # the same 100 kg, detected in kilograms (CSV, MON) or the kg/100 formats' own unit
        resolution = out["records"].pop("resolution")
        assert out.pop("settings")["format"] == fmt
        assert (resolution["step_kg"], resolution["source"]) == (
            (100.0, "detected") if fmt == "mon" else (100.0, "format")
        ), fmt
        assert out == ref, fmt


def test_a_filter_that_leaves_no_tandem_gives_an_empty_entry_not_an_error():
    out = observed_survey(DATA / "site.mon", "mon", min_group_load_kg=15_000, position="trailer").to_dict()
    assert out["groups"]["tandem"] == {
        "n_groups": 0, "mean_spread_kg": None, "median_spread_pct": None, "share_outside_5pct": None,
        "share_over_10pct": None, "load_share_quantiles": {},
    }  # fmt: skip
    assert out["groups"]["triaxle"]["n_groups"] == 2
    none = observed_survey(DATA / "site.mon", "mon", min_group_load_kg=99_000).to_dict()
    assert none["groups"]["triaxle"]["n_groups"] == 0


def test_the_bulk_grouping_is_the_per_vehicle_rule_on_random_vehicles():
    # the rule written plainly, vehicle by vehicle: a group ends after a spacing wider than the threshold
    rng = np.random.default_rng(27)
    n = rng.integers(2, 9, 300)
    width = int(n.max())
    loads = np.where(np.arange(width) < n[:, None], rng.uniform(1000, 11000, (300, width)).round(), np.nan)
    gaps = np.where(np.arange(width - 1) < n[:, None] - 1, rng.choice([1.3, 1.4, 1.9, 2.0, 2.1, 3.6, 6.0],
                                                                        (300, width - 1)), np.nan)  # fmt: skip
    vehicles = pd.DataFrame({
        "line": np.arange(300) + 1, "timestamp": pd.Timestamp("2026-01-01"), "speed": 22.0, "lane": 1, "n_axles": n,
        **{f"axle_load_{i + 1}": loads[:, i] for i in range(width)},
        **{f"spacing_{i + 1}": gaps[:, i] for i in range(width - 1)},
    })  # fmt: skip
    got = axle_groups(vehicles, 2.0)
    expected = []
    for v in range(300):
        first = 0
        for i in range(1, int(n[v]) + 1):
            if i == n[v] or gaps[v, i - 1] > 2.0:
                expected.append((v + 1, first + 1, i - first, float(loads[v, first:i].sum())))
                first = i
    assert list(zip(got["line"], got["first_axle"], got["n_axles"], got["group_load"])) == expected
    for row in got.itertuples():
        v, a, k = row.line - 1, row.first_axle - 1, row.n_axles
        shown = [getattr(row, f"axle_load_{i + 1}") for i in range(3)]
        if k <= 3:  # a tandem's or tri-axle's loads front first, NaN past them
            assert shown[:k] == list(loads[v, a : a + k]) and all(np.isnan(shown[k:]))
        else:  # a group of more than three: no loads in the three columns
            assert all(np.isnan(shown))
        assert row.position == ("steer", "drive", "trailer")[min(row.group_index - 1, 2)]
