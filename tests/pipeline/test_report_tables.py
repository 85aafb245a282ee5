"""The report's derived tables (pipeline.report.tables, the summary and Appendix C rows) and the survey's design
guidance table they draw from (bogie.fleet.design.table.design_table), on small hand-computed inputs."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bogie.fleet.design.table import design_table, wilson_interval
from pipeline.config import load_params, parse_config
from pipeline.report import tables
from pipeline.report.pages.appendix import failures_table
from pipeline.report.pages.front import summary_table, title_facts


# ---- runs ----------------------------------------------------------------------------------------------------------
def status_rows():
    rows = [
        ("ablation", 1, "tandem", "bush_stiffness", "static", "ok", "ok"),
        ("fleet", 3, "tandem", "baseline", "wim", "failed", "Newton did not converge at t = 1.234 s (step 12)"),
        ("fleet", 1, "tandem", "baseline", "static", "ok", "ok"),
        ("fleet", 7, "tandem", "baseline", "wim", "failed", "Newton did not converge at t = 2.5 s (step 3)"),
        ("fleet", 2, "triaxle", "baseline", "wim", "failed", "tyre lift-off"),
    ]
    columns = ["study", "sample_id", "group", "variant", "protocol", "status", "message"]
    return pd.DataFrame(rows, columns=columns)


def test_run_counts_per_study_in_pipeline_order_then_the_total():
    counts = tables.run_counts(status_rows())
    assert counts["study"].tolist() == ["fleet", "ablation", "all"]
    assert counts["n_runs"].tolist() == [4, 1, 5]
    assert counts["n_ok"].tolist() == [1, 1, 2]
    assert counts["n_failed"].tolist() == [3, 0, 3]


def test_title_facts_give_the_study_sizes_of_params_yaml():
    config = parse_config(load_params(Path(__file__).resolve().parents[2] / "params.yaml"))
    fleet = pd.DataFrame({"group": ["tandem", "triaxle", "triaxle"]})
    counts = tables.run_counts(status_rows())
    facts = dict(title_facts({"code_sha256": "c", "params_sha256": "p"}, config, fleet, counts))
    assert facts["Fleet"] == "3 bogies: 1 tandem, 2 tri-axle"
    # the baseline, each of the five inhibitors off alone, all five off
    assert facts["Ablation"] == "500 fleet bogies x 7 variants"
    assert facts["Runs"] == "2 succeeded, 3 failed, of 5"


def test_failed_runs_group_messages_that_differ_only_in_numbers():
    failed = tables.failed_runs(status_rows())
    assert len(failed) == 2
    newton = failed.iloc[0]
    assert (newton.study, newton.group, newton.n, newton.sample_ids) == ("fleet", "tandem", 2, "3 7")
    assert newton.kind == "Newton did not converge at t = # s (step #)"
    assert newton.message == "Newton did not converge at t = 1.234 s (step 12)"  # that of the lowest sample_id
    assert failed.iloc[1].sample_ids == "2"
    assert tables.failed_runs(status_rows().iloc[[0, 2]]).empty


def test_failures_table_shortens_long_id_lists_and_names_the_variant():
    failed = pd.DataFrame(
        [
            {"study": "fleet", "protocol": "wim", "group": "triaxle", "variant": "baseline", "n": 20,
             "sample_ids": " ".join(str(i) for i in range(20)), "message": "x " * 40},
            {"study": "ablation", "protocol": "static", "group": "tandem", "variant": "contact_roll_radius", "n": 1,
             "sample_ids": "5", "message": "m"},
        ]
    )  # fmt: skip
    rows = failures_table(failed)
    assert rows[0][:5] == ["fleet", "wim", "tri-axle", "–", "20"]
    assert rows[0][5].replace("\n", " ") == "0 1 2 3 4 5 6 7 8 9 10 11 ... (20 in all)"
    assert all(len(line) <= 24 for line in rows[0][5].split("\n"))
    assert all(len(line) <= 50 for line in rows[0][6].split("\n"))
    assert rows[1][3] == "contact roll\nradius" and rows[1][5] == "5"


# ---- summary -------------------------------------------------------------------------------------------------------
def test_summary_numbers_copy_the_metrics():
    headline = {"share_outside_5pct": 0.5, "share_over_10pct": 0.25, "mean_spread_kg": 100.0, "mean_spread_pct": 2.0}
    headline["rear_overload_share_nose_up"] = None
    survey = {"n_ok": 3, "static": {"tandem": {**headline, "n_ok": 3}}}
    sensitivity = {k: k for k in ("ranking", "ranking_measure", "reference_check", "ranking_other_measures")}
    sensitivity.update(sobol={"x": 1}, ablation={"static": {}}, extra="not copied")
    numbers = tables.summary_numbers(survey, sensitivity)
    assert numbers["survey"] == {"static": {"tandem": headline}}
    assert numbers["sobol"] == {"x": 1} and numbers["ranking"] == "ranking" and "extra" not in numbers


def test_summary_table_formats_indices_and_ablation_without_units():
    entry = {"mean_max_deviation": 0.0150, "share_outside_5pct": 0.25, "reduction": 0.0171, "reduction_low": 0.0161,
             "reduction_high": 0.0181}  # fmt: skip
    numbers = {
        "ranking": ["contact_roll_radius", "friction_coefficient"],
        "sobol": {"protocol": "static", "indices": {
            "contact_roll_radius": {"ST": 0.2449, "ST_conf": 0.05, "S1": 0.2, "S1_conf": 0.04},
            "friction_coefficient": {"ST": -0.001, "ST_conf": 0.004, "S1": -0.002, "S1_conf": 0.003}}},
        "ablation": {"static": {
            "baseline": {"mean_max_deviation": 0.0321, "share_outside_5pct": 0.625},
            "contact_roll_radius": entry,
            "friction_coefficient": {"mean_max_deviation": None, "share_outside_5pct": None, "reduction": None},
            "all": {**entry, "mean_max_deviation": 0.0012, "share_outside_5pct": 0.0}}},
    }  # fmt: skip
    header, rows = summary_table(numbers)
    assert len(header) == 6 == len(rows[0])
    assert rows[0] == [
        "1. contact roll radius", "0.24\n(0.19 to 0.29)", "0.20\n(0.16 to 0.24)", "1.50", "1.71\n(1.61 to 1.81)",
        "25.0"
    ]  # fmt: skip
    # indices under 0.01 get four decimals, so that two small, different ones do not both read 0.00
    assert rows[1] == [
        "2. spring-end friction coefficient", "-0.0010\n(-0.0050 to 0.0030)", "-0.0020\n(-0.0050 to 0.0010)", "n/a",
        "–", "n/a"
    ]  # fmt: skip
    assert rows[2] == ["all five removed", "", "", "0.12", "1.71\n(1.61 to 1.81)", "0.0"]
    assert rows[3] == ["none removed", "", "", "3.21", "", "62.5"]


def test_worse_without_lists_the_removals_whose_whole_interval_is_worse():
    from pipeline.report.tables import worse_without

    def entry(high):
        return {"reduction": high - 0.001, "reduction_low": high - 0.002, "reduction_high": high}

    numbers = {
        "ranking": ["contact_roll_radius", "friction_coefficient", "bush_damping"],
        "ablation": {
            "static": {"baseline": {}, "contact_roll_radius": entry(0.03), "friction_coefficient": entry(-0.001),
                       "bush_damping": entry(0.0005), "all": entry(0.05)},
            "wim": {"baseline": {}, "contact_roll_radius": entry(0.02), "friction_coefficient": entry(0.001),
                    "bush_damping": entry(-0.002), "all": entry(-0.01)},
        },
    }  # fmt: skip
    # an interval reaching zero (bush damping's static 0.0005) is no finding; "all" comes last
    assert worse_without(numbers) == {"static": ["friction_coefficient"], "wim": ["bush_damping", "all"]}
    for abl in numbers["ablation"].values():
        for v in ("friction_coefficient", "bush_damping", "all"):
            abl[v] = entry(0.01)
    assert worse_without(numbers) == {}


# ---- plot series ---------------------------------------------------------------------------------------------------
def test_plot_series_share_outside_each_tolerance_and_rear_heaviest_by_band():
    ok = pd.DataFrame({"group": "tandem", "protocol": "static", "pair_difference": [0.01, 0.06, 0.2]})
    tilt = pd.DataFrame(
        {"group": "tandem", "protocol": ["static", "static", "wim"], "tilt_deg_low": [0.0, 0.5, 0.0],
         "tilt_deg_high": [0.5, 1.0, 0.5], "rear_heaviest_share": [0.25, 0.75, 0.5]}
    )  # fmt: skip
    ablation = pd.DataFrame(
        {"group": ["all", "all", "tandem"], "protocol": "static", "variant": ["baseline", "bush_stiffness", "baseline"],
         "statistic": "mean_max_deviation", "value": [0.05, 0.04, 0.9]}
    )  # fmt: skip
    metrics = {"sobol": {"indices": {"bush_stiffness": {"S1": 0.1, "ST": 0.2}}}}
    series = tables.plot_series(metrics, ablation, ok, tilt)
    tol = series["tolerance.csv"].set_index("tolerance_pct")
    assert tol.loc[0.0, "tandem_static_pct"] == 100.0
    assert tol.loc[5.0, "tandem_static_pct"] == pytest.approx(66.667)
    assert tol.loc[10.0, "tandem_static_pct"] == pytest.approx(33.333)
    assert tol.loc[25.0, "tandem_static_pct"] == 0.0
    assert tol["triaxle_static_pct"].isna().all()
    assert series["tilt.csv"]["tilt_deg"].tolist() == [0.25, 0.75]
    assert series["tilt.csv"]["tandem_rear_heaviest_pct"].tolist() == [25.0, 75.0]
    assert series["ablation.csv"].set_index("variant")["static_mean_max_deviation_pct"].to_dict() == pytest.approx(
        {"none removed": 5.0, "bush stiffness": 4.0}
    )
    assert series["sobol.csv"].to_dict("records") == [{"factor": "bush stiffness", "S1": 0.1, "ST": 0.2}]


# ---- design guidance -----------------------------------------------------------------------------------------------
def test_wilson_interval_matches_the_formula():
    z = 1.959963984540054
    low, high = wilson_interval(np.array([5, 0, 0]), np.array([10, 10, 0]))
    half = z * math.sqrt(0.25 / 10 + z * z / 400) / (1 + z * z / 10)
    assert low[0] == pytest.approx(0.5 - half, abs=1e-12) and high[0] == pytest.approx(0.5 + half, abs=1e-12)
    assert low[0] == pytest.approx(0.2366, abs=1e-4)
    assert low[1] == 0.0 and high[1] == pytest.approx(z * z / 10 / (1 + z * z / 10), abs=1e-12)
    assert math.isnan(low[2]) and math.isnan(high[2])


def design_runs():
    """Four static tandem runs and one WIM run: bush 2, 5, 20, 2 N m/rad; arms 150, 150, 250, 250 mm."""
    return pd.DataFrame(
        {
            "protocol": ["static"] * 4 + ["wim"],
            "group": "tandem",
            "outside_5pct": [False, True, False, False, True],
            "bush_stiffness": [2.0, 5.0, 20.0, 2.0, 400.0],
            "equaliser_arm": [0.15, 0.15, 0.25, 0.25, 0.2],
            "friction_coefficient": [0.1, 0.2, 0.3, 0.4, 0.2],
            "contact_roll_radius": [0.01, 0.02, 0.03, 0.04, 0.02],
        }
    )


def test_design_table_bins_cells_and_single_parameters():
    table = design_table(design_runs())
    static = table[table["protocol"] == "static"]
    cells = static[static["kind"] == "cell"]
    assert len(cells) == 3 * 4  # bush 1-3-10-30 by four 25 mm arm bins from 150 to 250
    assert sorted(set(cells["x_low"])) == [1.0, 3.0, 10.0] and sorted(set(cells["x_high"])) == [3.0, 10.0, 30.0]
    assert sorted(set(cells["y_low"])) == [150.0, 175.0, 200.0, 225.0]
    filled = cells[cells["n"] > 0].set_index(["x_low", "y_low"])
    assert filled["n"].to_dict() == {(1.0, 150.0): 1, (1.0, 225.0): 1, (3.0, 150.0): 1, (10.0, 225.0): 1}
    assert filled["share"].to_dict() == {(1.0, 150.0): 1.0, (1.0, 225.0): 1.0, (3.0, 150.0): 0.0, (10.0, 225.0): 1.0}
    assert cells.loc[cells["n"] == 0, "share"].isna().all()
    bush = static[(static["kind"] == "bin") & (static["x"] == "bush_stiffness")]
    assert bush["n"].tolist() == [2, 1, 1] and bush["n_within"].tolist() == [2, 0, 1]
    assert bush["share"].tolist() == [1.0, 0.0, 1.0]
    low, high = wilson_interval(np.array([2]), np.array([2]))
    assert bush["share_low"].iloc[0] == pytest.approx(low[0]) and bush["share_high"].iloc[0] == 1.0
    assert set(bush["x_unit"]) == {"N m/rad"}
    arm = static[(static["kind"] == "bin") & (static["x"] == "equaliser_arm")]
    assert arm["n"].tolist() == [2, 0, 0, 2] and set(arm["x_unit"]) == {"mm"}
    # each protocol has its own edges
    wim = table[(table["protocol"] == "wim") & (table["x"] == "bush_stiffness") & (table["kind"] == "bin")]
    assert wim[["x_low", "x_high"]].values.tolist() == [[300.0, 1000.0]] and wim["n"].tolist() == [1]


def test_design_tables_select_a_protocol_for_the_page():
    grids, lines = tables.design_tables(design_table(design_runs()), "static")
    assert list(grids) == ["tandem"]
    assert grids["tandem"].columns.tolist() == ["x_low", "x_high", "y_low", "y_high", "n", "share"]
    assert [line.parameter for line in lines] == [
        "bush_stiffness", "equaliser_arm", "friction_coefficient", "contact_roll_radius"
    ]  # fmt: skip
    assert [line.log for line in lines] == [True, False, False, False]
    assert [line.label for line in lines[:2]] == ["bush stiffness [N m/rad]", "equaliser arm [mm]"]
    assert lines[0].bins["share"].tolist() == [1.0, 0.0, 1.0]
    assert tables.design_tables(design_table(design_runs()), "absent") == ({}, [])


def test_design_quotes_pick_the_cells_at_target_and_the_trends():
    grids, lines = tables.design_tables(design_table(design_runs()), "static")
    groups, trends = tables.design_quotes(grids, lines, target=0.95, min_cell=1)
    tandem = groups["tandem"]
    assert tandem["quoted"] == 4 and len(tandem["good"]) == 3
    assert (tandem["good"][0]["x_low"], tandem["good"][0]["y_low"]) == (1.0, 150.0)
    assert tandem["best"]["share"] == 1.0 and isinstance(tandem["best"]["n"], int)
    assert trends["bush stiffness"] == {"tandem": (1.0, 1.0)}
    assert trends["equaliser arm"] == {"tandem": (0.5, 1.0)}
    groups, trends = tables.design_quotes(grids, lines, target=0.95, min_cell=2)
    assert groups == {"tandem": None}
    assert trends["bush stiffness"] == {"tandem": (1.0, 1.0)} and "spring-end friction coefficient" not in trends


def test_distribution_text_of_params_entries():
    assert tables.distribution_text({"kind": "loguniform", "low": 1, "high": 3000}) == "loguniform 1-3000"
    assert (
        tables.distribution_text({"kind": "choice", "values": ["A", "B"], "weights": [0.7, 0.3]})
        == "choice A 0.7, B 0.3"
    )
    assert tables.distribution_text({"kind": "normal", "mean": 0.5, "sd": 0.25}) == "normal mean 0.5, sd 0.25"
    assert tables.distribution_text(None) == "not in params.yaml"
