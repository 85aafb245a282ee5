"""The ``survey`` stage: roadside-survey statistics of the fleet runs (pipeline.survey), on fabricated runs."""

import copy
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml
from _flips import PLACES, flip

from bogie.fleet.weighing.survey import (
    band,
    distribution_stats,
    failure_table,
    histograms,
    inequality_columns,
    legal_limits,
    run_counts,
    split_failed,
    static_vs_wim,
    survey_tables,
    tilt_table,
    wear_table,
    wim_class,
)
from bogie.fleet.weighing.weigher import result_row
from bogie.params import GRAVITY
from pipeline.config import load_params, parse_config
from pipeline.sample import sample_studies, write_parquet_atomic
from pipeline.schema import RUNS_SCHEMA, checksummed_content, read_runs_file, runs_frame, write_runs_file
from pipeline.survey import RunsError, headline_metrics, main, read_runs, write_outputs

ROOT = Path(__file__).resolve().parents[2]
TONNE = 1000.0 * GRAVITY  # [N]
LEGAL_GROUP = {"tandem": 18.0 * TONNE, "triaxle": 24.0 * TONNE}


def run(sample_id, loads, protocol="static", tilt_deg=0.0, wear_mm=(0.0, 0.0, 0.0), status="ok", message="ok"):
    """One fabricated run row: axle loads [N] through the protocol's own result_row, plus the sample columns."""
    n = len(loads)
    wheel = None if status != "ok" else np.asarray(loads, dtype=float) / 2.0
    row = result_row(protocol, n, wheel, 0.0)
    row.update(status=status, message=message)
    row.update(
        sample_id=sample_id,
        base_id=sample_id,
        group="tandem" if n == 2 else "triaxle",
        chassis_tilt=math.radians(tilt_deg),
        **{f"tyre_wear_{i + 1}": w / 1000.0 for i, w in enumerate(wear_mm)},
    )
    return row


def frame(rows):
    return pd.DataFrame(rows)


def derived(rows):
    ok, _ = split_failed(frame(rows))
    return inequality_columns(ok)


# ---- tolerances, spread ------------------------------------------------------------------------------------------
def tolerance_fleet():
    """10 tri-axles: 1 outside both tolerances, 2 outside 5 % only, 7 inside both."""
    rows = [run(0, [100e3, 80e3, 60e3])]  # (max-min)/max = 0.4, max LSC = 1.25
    rows += [run(i, [80e3, 80e3, 73.6e3]) for i in (1, 2)]  # (max-min)/max = 0.08, max LSC = 1.027
    rows += [run(i, [80e3, 79e3, 80e3]) for i in range(3, 10)]  # 0.0125
    return rows


def test_shares_outside_the_5_and_10_percent_tolerances_count_exactly_those_groups():
    ok = derived(tolerance_fleet())
    assert ok["outside_5pct"].tolist() == [True, True, True] + [False] * 7
    assert ok["over_10pct"].tolist() == [True] + [False] * 9
    tables = survey_tables(frame(tolerance_fleet()), 10 * TONNE, LEGAL_GROUP)
    summary = tables["summary"].iloc[0]
    assert summary["share_outside_5pct"] == pytest.approx(0.3)
    assert summary["share_over_10pct"] == pytest.approx(0.1)


def test_spread_in_percent_of_the_mean_and_in_kg():
    ok = derived([run(0, [100e3, 80e3, 60e3]), run(1, [50e3, 40e3])])
    assert ok["spread_pct"].tolist() == pytest.approx([50.0, 100.0 * 10e3 / 45e3])
    assert ok["spread_kg"].tolist() == pytest.approx([40e3 / GRAVITY, 10e3 / GRAVITY])
    assert ok["pair_difference"].tolist() == pytest.approx([0.4, 0.2])
    assert ok["max_load_share"].tolist() == pytest.approx([1.25, 50 / 45])


def test_distribution_stats_match_numpy_and_skip_the_missing_third_axle_of_tandems():
    rng = np.random.default_rng(1)
    rows = [run(i, 80e3 * (1 + 0.1 * rng.standard_normal(3))) for i in range(40)]
    rows += [run(100 + i, 80e3 * (1 + 0.1 * rng.standard_normal(2))) for i in range(30)]
    ok = derived(rows)
    stats = distribution_stats(ok).set_index(["quantity", "group"])
    tri = ok[ok["group"] == "triaxle"]
    row = stats.loc[("load_share_2", "triaxle")]
    assert row["n"] == 40
    assert row["mean"] == pytest.approx(tri["load_share_2"].mean())
    assert row["sd"] == pytest.approx(tri["load_share_2"].std())
    assert row[["p05", "p25", "p50", "p75", "p95"]].tolist() == pytest.approx(
        np.percentile(tri["load_share_2"], [5, 25, 50, 75, 95])
    )
    assert ("load_share_3", "tandem") not in stats.index
    assert ("road_wear_factor", "tandem") in stats.index
    # load shares of each group average to 1 (LSC sums to n)
    shares = stats.xs("triaxle", level="group").loc[["load_share_1", "load_share_2", "load_share_3"], "mean"]
    assert shares.sum() == pytest.approx(3.0)


def test_histograms_share_edges_across_groups_and_count_every_row():
    rng = np.random.default_rng(2)
    rows = [run(i, 80e3 * (1 + 0.1 * rng.standard_normal(3))) for i in range(25)]
    rows += [run(100 + i, 80e3 * (1 + 0.1 * rng.standard_normal(2)), "wim") for i in range(15)]
    hist = histograms(derived(rows), bins=7)
    spread = hist[hist["quantity"] == "spread_pct"]
    per = spread.groupby(["protocol", "group"])
    assert per["count"].sum().to_dict() == {("static", "triaxle"): 25, ("wim", "tandem"): 15}
    edges = [tuple(sub["bin_low"]) for _, sub in per]
    assert edges[0] == edges[1] and len(edges[0]) == 7


# ---- tilt and tyre wear -------------------------------------------------------------------------------------------
def test_band_is_left_closed_and_puts_an_edge_that_went_through_radians_in_the_upper_band():
    tilt = np.degrees(np.radians([0.5, -0.5, 0.0, 0.49, -0.01, 1.99, -2.0]))
    low, high = band(tilt, 0.5)
    assert low.tolist() == [0.5, -0.5, 0.0, 0.0, -0.5, 1.5, -2.0]
    assert (high - low).tolist() == pytest.approx([0.5] * 7)


def test_tilt_table_assigns_rows_to_bins_and_finds_the_rear_overload_nose_up():
    rows = [
        run(0, [70e3, 80e3, 90e3], tilt_deg=0.75),  # rear heaviest
        run(1, [75e3, 80e3, 85e3], tilt_deg=0.5),  # rear heaviest, on the 0.5 edge
        run(2, [85e3, 80e3, 75e3], tilt_deg=0.99),  # front heaviest
        run(3, [90e3, 80e3, 70e3], tilt_deg=-0.75),  # nose down: front heaviest
        run(4, [80e3, 80e3, 80e3], tilt_deg=0.1),  # level: tie goes to the front
    ]
    table = tilt_table(derived(rows)).set_index("tilt_deg_bin")
    assert table["n"].to_dict() == {"[-1, -0.5)": 1, "[0, 0.5)": 1, "[0.5, 1)": 3}
    assert table.loc["[0.5, 1)", "rear_heaviest_share"] == pytest.approx(2 / 3)
    assert table.loc["[-1, -0.5)", "rear_heaviest_share"] == 0.0
    assert table.loc["[0.5, 1)", "mean_load_share_3"] == pytest.approx(np.mean([90 / 80, 85 / 80, 75 / 80]))
    assert table.loc["[0.5, 1)", "tilt_deg_low"] == 0.5
    summary = survey_tables(frame(rows), 10 * TONNE, LEGAL_GROUP)["summary"].iloc[0]
    # nose up beyond 0.5 degree: rows 0 and 2 (row 1 sits on 0.5, not above)
    assert summary["rear_overload_share_nose_up"] == pytest.approx(0.5)
    assert summary["n_nose_up"] == 2


def test_tilt_table_leaves_the_tandems_third_axle_empty():
    table = tilt_table(derived([run(0, [40e3, 50e3], tilt_deg=1.2)]))
    assert math.isnan(table["mean_load_share_3"].iloc[0])
    assert table["rear_heaviest_share"].iloc[0] == 1.0


def test_wear_bands_use_the_difference_between_the_groups_own_tyres():
    rows = [
        run(0, [80e3, 80e3, 70e3], wear_mm=(0.0, 3.0, 1.0)),  # 3 mm -> [2, 4), outside 5 %
        run(1, [80e3, 80e3, 80e3], wear_mm=(5.0, 5.5, 5.0)),  # 0.5 mm -> [0, 2)
        run(2, [40e3, 40e3], wear_mm=(1.0, 1.0, 10.0)),  # the tandem has no third tyre: 0 mm
    ]
    ok = derived(rows)
    assert ok["wear_diff_mm"].tolist() == pytest.approx([3.0, 0.5, 0.0])
    table = wear_table(ok).set_index(["group", "wear_diff_mm_bin"])
    assert table.loc[("triaxle", "[2, 4)"), "share_outside_5pct"] == 1.0
    assert table.loc[("triaxle", "[0, 2)"), "mean_max_deviation"] == 0.0
    assert table.loc[("tandem", "[0, 2)"), "n"] == 1


# ---- static against WIM ------------------------------------------------------------------------------------------
def test_static_and_wim_are_paired_by_sample_id_whatever_the_row_order():
    static = [run(i, [80e3 - 1e3 * i, 80e3, 80e3 + 1e3 * i]) for i in range(6)]
    wim = [run(i, [80e3 - 3e3 * i, 80e3, 80e3 + 3e3 * i], "wim") for i in range(6)]
    wim[4] = run(4, [0, 0, 0], "wim", status="failed", message="Newton failed")
    rows = wim[::-1] + static[::2] + static[1::2]
    pairs, summary = static_vs_wim(derived(rows))
    assert pairs["sample_id"].tolist() == [0, 1, 2, 3, 5]
    # max deviation i 1e3 / 80e3 static, three times that by WIM
    expected = np.array([0, 1, 2, 3, 5]) * 2e3 / 80e3
    assert pairs["dynamic_excess"].to_numpy() == pytest.approx(expected)
    assert pairs["load_share_3_diff"].to_numpy() == pytest.approx(expected)
    row = summary.iloc[0]
    assert row["n_pairs"] == 5
    assert row["mean_dynamic_excess"] == pytest.approx(expected.mean())
    assert row["corr_max_deviation"] == pytest.approx(1.0)
    assert row["share_wim_worse"] == pytest.approx(4 / 5)


def test_static_vs_wim_is_empty_with_one_protocol():
    pairs, summary = static_vs_wim(derived([run(0, [40e3, 50e3])]))
    assert pairs.empty and summary.empty


def test_the_wim_class_holds_the_readings_against_the_static_weighings_of_the_same_bogies():
    # four tri-axles read -3 %, 0, +3 % (each group exact); a tandem read +12 % on both axles
    static = [run(i, [80e3, 80e3, 80e3]) for i in range(4)] + [run(9, [90e3, 90e3])]
    wim = [run(i, [80e3 * 0.97, 80e3, 80e3 * 1.03], "wim") for i in range(4)] + [run(9, [90e3 * 1.12] * 2, "wim")]
    table = wim_class(derived(wim[::-1] + static)).set_index(["group", "criterion"])
    assert table.loc[("triaxle", "group"), "n"] == 4 and table.loc[("triaxle", "axle_of_group"), "n"] == 12
    assert table.loc[("triaxle", "group"), "class_reached"] == "A(5)"  # every error within +-7 % and +-10 %
    # the tandem: +12 % is outside A(5)'s 7 % (group) and 10 % (axle), outside B+(7)'s 10 % (group), inside B(10)'s 13 %
    tandem = table.loc["tandem"]
    assert tandem.loc["group", "share_within_B+(7)"] == 0.0 and tandem.loc["group", "share_within_B(10)"] == 1.0
    assert tandem.loc["axle_of_group", "mean_error_pct"] == pytest.approx(12.0)
    assert tandem.loc["group", "class_reached"] == "B(10)"
    # all five groups: 4 of 5 groups within 7 % and 12 of 14 axles within 10 %, short of 0.95, so B(10) again
    assert table.loc[("all", "group"), "share_within_A(5)"] == pytest.approx(0.8)
    assert table.loc[("all", "axle_of_group"), "share_within_A(5)"] == pytest.approx(12 / 14)
    assert table.loc[("all", "group"), "class_reached"] == "B(10)"
    assert wim_class(derived(static)).empty  # one protocol: nothing to hold against


# ---- legal limits, failures, counts -----------------------------------------------------------------------------
def test_axle_over_its_limit_while_the_group_is_legal():
    rows = [
        run(0, [10.5 * TONNE, 7.0 * TONNE]),  # group 17.5 t legal, axle over: counted
        run(1, [10.5 * TONNE, 8.0 * TONNE]),  # group 18.5 t over: not counted
        run(2, [9.0 * TONNE, 9.0 * TONNE]),  # both legal
        run(3, [10.0 * TONNE, 8.0 * TONNE]),  # exactly at both limits: legal
    ]
    table = legal_limits(derived(rows), 10 * TONNE, LEGAL_GROUP).iloc[0]
    assert (table["n"], table["n_axle_over"], table["n_group_over"], table["n_axle_over_group_legal"]) == (4, 2, 1, 1)
    assert table["frac_axle_over_group_legal"] == pytest.approx(0.25)


def test_failed_rows_are_excluded_from_statistics_but_counted_with_their_messages():
    good = tolerance_fleet()
    failed = [
        run(20, [0, 0, 0], status="failed", message="Newton failed at t = 1.2 s"),
        run(21, [0, 0, 0], status="failed", message="Newton failed at t = 1.2 s"),
        run(22, [0, 0, 0], status="failed", message="wheel off the ground"),
    ]
    clean = survey_tables(frame(good), 10 * TONNE, LEGAL_GROUP)
    mixed = survey_tables(frame(good + failed), 10 * TONNE, LEGAL_GROUP)
    pd.testing.assert_frame_equal(mixed["distributions"], clean["distributions"])
    pd.testing.assert_frame_equal(mixed["tilt"], clean["tilt"])
    counts = run_counts(frame(good + failed)).iloc[0]
    assert (counts["n_runs"], counts["n_ok"], counts["n_failed"]) == (13, 10, 3)
    summary = mixed["summary"].iloc[0]
    assert summary["n_failed"] == 3 and summary["share_outside_5pct"] == pytest.approx(0.3)
    fails = failure_table(frame(good + failed))
    assert fails[["message", "n_failed", "example_sample_ids"]].values.tolist() == [
        ["Newton failed at t = 1.2 s", 2, "20 21"],
        ["wheel off the ground", 1, "22"],
    ]


def test_a_protocol_and_group_where_every_run_failed_still_has_its_counts():
    rows = tolerance_fleet() + [run(50, [0, 0], "wim", status="failed", message="diverged")]
    tables = survey_tables(frame(rows), 10 * TONNE, LEGAL_GROUP)
    metrics = headline_metrics(tables)
    assert metrics["wim"]["tandem"]["n_failed"] == 1 and metrics["wim"]["tandem"]["n_ok"] == 0
    assert metrics["wim"]["tandem"]["share_outside_5pct"] is None
    json.dumps(metrics, allow_nan=False)


# ---- JSON ------------------------------------------------------------------------------------------------------------
def test_headline_metrics_keys_and_rounding():
    rng = np.random.default_rng(3)
    rows = []
    for i in range(30):
        tilt = rng.uniform(-2, 2)
        shares = 1 + 0.04 * tilt * np.array([-1.0, 0.0, 1.0]) + 0.01 * rng.standard_normal(3)
        rows += [run(i, 80e3 * shares, tilt_deg=tilt), run(i, 80e3 * shares * (1 + 0.02 * rng.random(3)), "wim")]
    metrics = headline_metrics(survey_tables(frame(rows), 10 * TONNE, LEGAL_GROUP))
    expected = {
        "n_runs", "n_ok", "n_failed", "n_airborne", "static", "wim", "static_vs_wim", "by_suspension", "wim_class",
    }  # fmt: skip
    assert set(metrics) == expected
    entry = metrics["static"]["triaxle"]
    assert set(entry) == {
        "share_outside_5pct", "share_over_10pct", "mean_max_deviation", "mean_spread_pct", "mean_spread_kg",
        "mean_road_wear_factor", "rear_overload_share_nose_up", "frac_axle_over_group_legal", "n_ok", "n_failed",
        "n_airborne", "share_on_stop",
    }  # fmt: skip
    assert entry["rear_overload_share_nose_up"] == 1.0  # the fabricated shares rise towards the rear when nose up
    assert round(entry["mean_spread_kg"], 1) == entry["mean_spread_kg"]
    assert round(entry["mean_spread_pct"], 2) == entry["mean_spread_pct"]
    assert round(entry["mean_road_wear_factor"], 4) == entry["mean_road_wear_factor"]
    assert set(metrics["static_vs_wim"]["triaxle"]) == {"mean_dynamic_excess", "corr_max_deviation", "n_pairs"}
    assert (metrics["n_runs"], metrics["n_ok"]) == (60, 60)
    assert len(json.dumps(metrics)) < 4000


def test_the_suspension_table_splits_the_survey_into_steel_and_air_groups():
    # 6 steel tri-axles 10 % apart front to rear (outside 5 %), 4 air ones equal (inside), one air one failed
    steel = [run(i, [76e3, 80e3, 84e3]) for i in range(6)]
    air = [run(6 + i, [80e3, 80e3, 80e3]) for i in range(4)] + [run(10, [80e3] * 3, status="failed", message="x")]
    rows = [{**r, "suspension": "steel"} for r in steel] + [{**r, "suspension": "air"} for r in air]
    tables = survey_tables(frame(rows), 10 * TONNE, LEGAL_GROUP)
    table = tables["by_suspension"].set_index("suspension")
    assert table.loc["steel", "share_outside_5pct"] == 1.0 and table.loc["air", "share_outside_5pct"] == 0.0
    assert table.loc["steel", "mean_spread_kg"] == pytest.approx(8e3 / GRAVITY)
    assert table.loc["air", "mean_spread_kg"] == 0.0
    assert (table.loc["air", "n_runs"], table.loc["air", "n_ok"], table.loc["air", "n_failed"]) == (5, 4, 1)
    # the survey itself (both kinds together, as a WIM file sees them): 6 of 10 readings outside
    summary = tables["summary"].set_index("group")
    assert summary.loc["triaxle", "share_outside_5pct"] == pytest.approx(0.6)
    metrics = headline_metrics(tables)["by_suspension"]["static"]["triaxle"]
    assert metrics["air"]["n_failed"] == 1 and metrics["steel"]["share_over_10pct"] == 0.0


# ---- the stage ------------------------------------------------------------------------------------------------------
def small_raw():
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 40
    raw["sensitivity"]["base_size"] = 2
    raw["ablation"]["n_bogies"] = 4
    return raw


def fabricated_runs(samples: pd.DataFrame) -> pd.DataFrame:
    """Runs of a sample table without the solver: loads rise towards the rear with nose-up tilt (as measured)."""
    rows = []
    for sample in samples.to_dict("records"):
        n = sample["n_axles"]
        slope = 2.0 * sample["chassis_tilt"] * (np.arange(n) - (n - 1) / 2)  # [-], 0.07 per degree
        wheel = sample["payload_fraction"] * sample["legal_group_load"] / (2 * n) * (1 + slope)
        for protocol in ("static", "wim"):
            failed = protocol == "wim" and sample["sample_id"] == 3
            row = result_row(protocol, n, None if failed else wheel * (1.03 if protocol == "wim" else 1.0), 0.0)
            row.update(status="failed" if failed else "ok", message="diverged" if failed else "ok")
            rows.append({**sample, **row, "chassis_tilt_deg": math.degrees(sample["chassis_tilt"])})
    return runs_frame(rows)


@pytest.fixture()
def stage_dir(tmp_path):
    raw = small_raw()
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    fleet = sample_studies(parse_config(raw))["fleet"]
    part = tmp_path / "data" / "runs" / "study=fleet"
    part.mkdir(parents=True)
    runs = fabricated_runs(fleet)
    write_runs_file(runs.iloc[:50], part / "part-000000.parquet")
    write_runs_file(runs.iloc[50:], part / "part-000001.parquet")
    return tmp_path


def stage_args(root):
    return [
        "--params", str(root / "params.yaml"), "--runs", str(root / "data" / "runs"),
        "--out", str(root / "data" / "survey"), "--metrics", str(root / "metrics" / "survey.json"),
    ]  # fmt: skip


def test_stage_writes_every_table_and_the_metrics(stage_dir):
    assert main(stage_args(stage_dir)) == 0
    out = stage_dir / "data" / "survey"
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["summary.csv", "by_suspension.csv", "counts.csv", "failures.csv", "distributions.csv", "histograms.csv",
         "tilt.csv", "tyre_wear.csv", "static_vs_wim.csv", "static_vs_wim_pairs.parquet", "legal.csv", "wim_class.csv",
         "design_guidance.csv", ".bogie-output"]
    )  # fmt: skip
    metrics = json.loads((stage_dir / "metrics" / "survey.json").read_text())
    assert (metrics["n_runs"], metrics["n_failed"]) == (80, 1)
    runs = read_runs(stage_dir / "data" / "runs", "fleet")
    group = runs.loc[runs["sample_id"] == 3, "group"].iloc[0]
    assert metrics["wim"][group]["n_failed"] == 1
    counts = pd.read_csv(out / "counts.csv")
    assert counts["n_runs"].sum() == 80
    # nothing temporary left behind
    assert sorted(p.name for p in (stage_dir / "data").iterdir()) == ["runs", "survey"]
    assert [p.name for p in (stage_dir / "metrics").iterdir()] == ["survey.json"]


def test_stage_with_no_fleet_runs_fails_clearly_and_leaves_old_outputs(stage_dir, capsys):
    assert main(stage_args(stage_dir)) == 0
    before = (stage_dir / "metrics" / "survey.json").read_text()
    for part in (stage_dir / "data" / "runs" / "study=fleet").iterdir():
        part.rename(stage_dir / part.name)
    assert main(stage_args(stage_dir)) == 2
    assert "no runs of study 'fleet'" in capsys.readouterr().err
    assert (stage_dir / "metrics" / "survey.json").read_text() == before
    assert (stage_dir / "data" / "survey" / "summary.csv").exists()


def test_read_runs_refuses_files_of_another_schema_and_rows_that_break_the_null_rule(stage_dir):
    runs_dir = stage_dir / "data" / "runs"
    first = sorted((runs_dir / "study=fleet").iterdir())[0]  # holds the failed run of sample 3
    frame = pd.read_parquet(first)
    # each file with its checksums (pipeline.schema.checksummed_content): these faults are in what the writer wrote
    first.write_bytes(checksummed_content(pa.Table.from_pandas(frame.drop(columns="max_deviation"))))
    with pytest.raises(RunsError, match=r"part-000000.parquet is not a runs file of this version: max_deviation miss"):
        read_runs(runs_dir, "fleet")
    # a successful row with a null result: refused, never averaged over
    ok = frame.index[frame["status"] == "ok"][:3]
    frame.loc[ok, "max_deviation"] = np.nan
    first.write_bytes(checksummed_content(pa.Table.from_pandas(frame, schema=RUNS_SCHEMA, preserve_index=False)))
    with pytest.raises(RunsError, match=r"max_deviation null in 3 successful rows"):
        read_runs(runs_dir, "fleet")
    # a failed row with a number in it: a made-up result, refused
    frame.loc[ok, "max_deviation"] = 0.1
    failed = frame.index[frame["status"] == "failed"]
    assert len(failed)
    frame.loc[failed, "spread_kg"] = 0.0
    first.write_bytes(checksummed_content(pa.Table.from_pandas(frame, schema=RUNS_SCHEMA, preserve_index=False)))
    with pytest.raises(RunsError, match=rf"spread_kg set in {len(failed)} failed rows \(must be null\)"):
        read_runs(runs_dir, "fleet")


def test_an_error_while_writing_leaves_the_old_outputs_and_no_temporary_files(tmp_path):
    good = {"a.csv": pd.DataFrame({"x": [1.0]})}
    write_outputs(good, tmp_path / "out", {"v": 1}, tmp_path / "m" / "metrics.json")
    bad = {"a.csv": pd.DataFrame({"x": [2.0]}), "b.parquet": pd.DataFrame({"x": [1, "mixed"]})}
    with pytest.raises(Exception, match="(?i)conversion|convert|type"):
        write_outputs(bad, tmp_path / "out", {"v": 2}, tmp_path / "m" / "metrics.json")
    assert pd.read_csv(tmp_path / "out" / "a.csv")["x"].tolist() == [1.0]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [".bogie-output", "a.csv"]
    assert json.loads((tmp_path / "m" / "metrics.json").read_text()) == {"v": 1}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m", "out"]
    assert [p.name for p in (tmp_path / "m").iterdir()] == ["metrics.json"]
    with pytest.raises(ValueError):  # NaN is not JSON: refused before anything is replaced
        write_outputs(good, tmp_path / "out", {"v": math.nan}, tmp_path / "m" / "metrics.json")
    assert json.loads((tmp_path / "m" / "metrics.json").read_text()) == {"v": 1}


def test_the_stage_refuses_an_incomplete_runs_dataset(stage_dir, capsys):
    second = sorted((stage_dir / "data" / "runs" / "study=fleet").iterdir())[1]
    frame = pd.read_parquet(second)
    write_runs_file(frame.iloc[:-3], second)  # an interrupted simulate: the last three runs never written
    assert main(stage_args(stage_dir)) == 2
    err = capsys.readouterr().err
    assert "the fleet runs are incomplete: 3 of 80 (sample, protocol) runs missing" in err
    assert not (stage_dir / "metrics" / "survey.json").exists()


def test_a_reading_with_a_wheel_in_the_air_is_counted_and_kept_out_of_the_statistics():
    # 9 WIM readings within 2 %, and one tri-axle read 25 kN / 0 / 0: its wheels were off the road over the sensor
    rows = [run(i, [80e3, 80.5e3, 81e3], "wim") for i in range(9)] + [run(9, [25e3, 0.0, 0.0], "wim")]
    assert [r["wheel_airborne"] for r in rows] == [False] * 9 + [True]
    assert rows[-1]["max_deviation"] == pytest.approx(2.0)  # what an unflagged reading would add to the mean
    tables = survey_tables(frame(rows), 10 * TONNE, LEGAL_GROUP)
    summary = tables["summary"].iloc[0]
    assert (summary["n_ok"], summary["n_airborne"]) == (10, 1)
    assert summary["share_outside_5pct"] == 0.0  # the nine real readings, all within 5 %
    assert summary["mean_max_deviation"] == pytest.approx(0.5 / 80.5)  # |W - mean| / mean of the nine
    assert headline_metrics(tables)["n_airborne"] == 1


# ---- the fleet's WIM readings as a file of records (issue 27 Must 6) ---------------------------------------------
def export_dir(stage_dir, fmt):
    raw = yaml.safe_load((stage_dir / "params.yaml").read_text())
    raw["survey"] = {"export_format": fmt}
    (stage_dir / "params.yaml").write_text(yaml.safe_dump(raw))
    fleet = sample_studies(parse_config(raw))["fleet"]
    (stage_dir / "data" / "samples").mkdir(parents=True, exist_ok=True)
    write_parquet_atomic(fleet, stage_dir / "data" / "samples" / "fleet.parquet")  # as the sample stage writes it
    return fleet, [*stage_args(stage_dir), "--samples", str(stage_dir / "data" / "samples")]


@pytest.mark.parametrize(("fmt", "step_kg", "step_m"), [("mon", 1.0, 1e-3), ("castor", 100.0, 0.1), ("csv", 0.0, 0.0)])
def test_the_fleets_wim_readings_are_written_as_records_that_read_back_at_the_formats_resolution(
    stage_dir, fmt, step_kg, step_m
):
    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.weighings.readers import read_weighings

    fleet, argv = export_dir(stage_dir, fmt)
    assert main(argv) == 0
    metrics = json.loads((stage_dir / "metrics" / "survey.json").read_text())
    # 40 bogies, the WIM run of sample 3 failed (fabricated_runs): 39 records
    assert metrics["export"] == {
        "format": fmt, "file": f"fleet_wim.{fmt}", "n_readings": 40, "n_failed": 1, "n_airborne": 0, "n_written": 39,
    }  # fmt: skip
    read = read_weighings(stage_dir / "data" / "survey" / f"fleet_wim.{fmt}", fmt)
    assert (read.n_read, read.n_skipped) == (39, 0)
    runs = read_runs(stage_dir / "data" / "runs", "fleet")
    wim = runs[(runs["protocol"] == "wim") & (runs["status"] == "ok")].sort_values("sample_id")
    by_id = fleet.set_index("sample_id")

    def at(x, step):
        return np.round(np.asarray(x, float) / step) * step if step else np.asarray(x, float)

    for k, (row, got) in enumerate(zip(wim.to_dict("records"), read.vehicles.to_dict("records"))):
        n = row["n_axles"]
        assert got["n_axles"] == n
        loads = [row[f"axle_load_{i + 1}"] / GRAVITY for i in range(n)]
        assert [got[f"axle_load_{i + 1}"] for i in range(n)] == pytest.approx(at(loads, step_kg), abs=1e-6)
        spacings = np.diff(bogie_from_sample(by_id.loc[row["sample_id"]].to_dict()).axle_x)
        assert [got[f"spacing_{i + 1}"] for i in range(n - 1)] == pytest.approx(at(spacings, step_m), abs=1e-9)
        assert got["timestamp"] == pd.Timestamp("2026-01-01") + pd.Timedelta(seconds=10 * k)


def test_an_export_without_wim_readings_is_refused_in_validation():
    from pipeline.config import ConfigError

    raw = small_raw()
    raw["survey"] = {"export_format": "mon"}
    raw["protocol"]["run"] = ["static"]
    raw["sensitivity"]["protocol"] = "static"
    with pytest.raises(ConfigError, match=r"survey.export_format.*needs WIM readings to export"):
        parse_config(raw)


@pytest.mark.parametrize("place", PLACES)
def test_a_part_with_one_flipped_bit_is_refused_naming_the_file_not_averaged(stage_dir, capsys, place):
    # issue 28, item 4: a flip in a data page changed mean_max_deviation without a word; one in the statistics or the
    # footer's metadata changes no number but is damage all the same, and the same check sees every byte
    damaged = stage_dir / "data" / "runs" / "study=fleet" / "part-000001.parquet"
    flip(damaged, place)
    assert main(stage_args(stage_dir)) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"survey: {damaged} is damaged: its SHA-256 does not match") and "\n" not in err, err
    assert "rerun the simulate stage" in err
    assert not (stage_dir / "metrics" / "survey.json").exists()


def test_a_part_without_the_checksum_is_refused_and_every_written_part_verifies(stage_dir, capsys):
    first, second = sorted((stage_dir / "data" / "runs" / "study=fleet").iterdir())
    for path in (first, second):  # what write_runs_file writes verifies and reads back as pandas reads it
        pd.testing.assert_frame_equal(read_runs_file(path).to_pandas(), pd.read_parquet(path))
    pq.write_table(pq.read_table(second).replace_schema_metadata({}), second)  # a Parquet file from elsewhere
    assert main(stage_args(stage_dir)) == 2
    err = capsys.readouterr().err
    assert f"{second} carries no checksum (metadata key bogie.runs.sha256)" in err
