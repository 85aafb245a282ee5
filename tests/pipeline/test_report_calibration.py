"""The report's calibration pages (pipeline.report.pages.calibration) from outputs shaped as ``calibrate`` writes them.

The outputs are made here, small and with numbers chosen to format distinctly (no simulation): metrics/calibration.json
and the tables of data/calibration, written to a temporary directory and read back as the report reads them.
"""

import json
from types import SimpleNamespace

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from test_report import figure_text  # the same "every string on a page" as the other report tests

from pipeline.report import build
from pipeline.report.inputs import NO_CALIBRATION, calibration_inputs, skipped_calibration
from pipeline.report.layout import TEXT_BOTTOM
from pipeline.report.pages import calibration
from pipeline.report.style import STYLE
from pipeline.survey import RunsError

FITTED = {
    "chassis_tilt_mean_deg": {"value": 0.7671, "low": 0.5123, "high": 1.4557, "bounds": [-1.0, 1.5]},
    "chassis_tilt_sd_deg": {"value": 0.4057, "low": 0.2088, "high": 0.6906, "bounds": [0.1, 1.5]},
    "air_share": {"value": 0.4156, "low": None, "high": None, "bounds": [0.0, 1.0]},
}
FIXED = {"site_iri_m_km": 1.5, "sensor_error_pct": 2.25}
#: the prior-free minimum of the distance beside the fitted (posterior) values, a diagnostic (issue 43 Must 1); the
#: third quantity has none (an older stage's metrics: "-")
PRIOR_FREE = {
    "chassis_tilt_mean_deg": {"value": 1.49, "low": 0.91, "high": 1.5, "bounds": [-1.0, 1.5]},
    "chassis_tilt_sd_deg": {"value": 0.18, "low": 0.1, "high": 0.52, "bounds": [0.1, 1.5]},
}
#: the posterior of two of the fitted quantities (an older stage's metrics have none: the third shows "-")
POSTERIOR = {
    "chassis_tilt_mean_deg": {"median": 0.7412, "low": 0.4871, "high": 1.1023, "share_at_low": 0.0,
                              "share_at_high": 0.0, "piled": None},
    "chassis_tilt_sd_deg": {"median": 0.3377, "low": 0.1052, "high": 0.5811, "share_at_low": 0.31,
                            "share_at_high": 0.0, "piled": "low"},
}  # fmt: skip


def stats(n, spread, share, quantiles):
    """A ``groups`` entry of one size: statistics and the load-share quantiles of each axle."""
    return {
        "n_groups": n, "mean_spread_kg": spread, "median_spread_pct": spread / 100.0, "share_outside_5pct": share,
        "share_over_10pct": share / 4,
        "load_share_quantiles": {
            f"axle_{i + 1}": {k: c + d for k, d in zip(("p05", "p25", "p50", "p75", "p95"), (-.1, -.03, 0, .03, .1))}
            for i, c in enumerate(quantiles)
        },
    }  # fmt: skip


def groups(scale):
    return {
        "tandem": stats(20, 429.6 * scale, 0.4, (0.99, 1.01)),
        "triaxle": stats(107, 981.87 * scale, 0.7757, (0.97, 1.0, 1.03)),
    }


def fitted_metrics(held=True):
    """metrics/calibration.json of a fit, shaped as pipeline.calibrate.run writes it."""
    held_out = {"fit_on": "even records", "held_out": "odd records"}
    if held:
        held_out.update(
            fitted={q: e["value"] for q, e in FITTED.items()}, distance_fit_half=2.21837, distance_held_out=2.32483,
            distance_halves=2.71184, groups=groups(1.1), calibrated_groups=groups(0.9),
        )  # fmt: skip
    else:
        held_out.update(reason="too few odd records", groups=None)
    return {
        "skipped": False,
        "protocol": "wim",
        "method": "differential evolution on the energy distance",
        "fitted": FITTED,
        "fixed": FIXED,
        "confidence_level": 0.9,
        "bootstrap_resamples": 4,
        "distance": 4.49106,
        "distance_direct": 7.07898,
        "prior_free_minimum": {"note": "a diagnostic", "fitted": PRIOR_FREE, "at_bounds": {}, "distance": 4.1},
        "sizes_fitted": ["tandem", "triaxle"],
        "evaluations": 512,
        "trade_offs": [{"quantities": ["chassis_tilt_mean_deg", "chassis_tilt_sd_deg"], "correlation": 0.973}],
        "table": {
            "n_bogies": 40,
            "tilts_deg": [-1.0, 0.0, 1.0],
            "site_iri_levels_m_km": [1.0, 2.0],
            "n_weighings": 480,
            "n_failed": 0,
        },  # fmt: skip
        "observed": {"groups": groups(1.0)},
        "calibrated": {"groups": groups(0.8)},
        "held_out": held_out,
        "ablation": {},
        "posterior": {
            "method": "random-walk Metropolis",
            "credible_level": 0.9,
            "draws": 3000,
            "acceptance": 0.2871,
            "quantities": POSTERIOR,
            "priors": {"chassis_tilt_mean_deg": "normal(mean 0, sd 0.6): a source", "chassis_tilt_sd_deg": "half"},
        },  # fmt: skip
    }


def fitted_tables(names=tuple(FITTED)):
    """The tables of data/calibration of a fit of ``names``."""
    x = np.linspace(-1.0, 1.5, 7)
    y = np.linspace(0.1, 1.5, 6)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    valley = pd.DataFrame({
        "quantity_x": names[0], "x": xx.ravel(), "quantity_y": names[1] if len(names) > 1 else names[0],
        "y": yy.ravel(), "distance": 4.5 + (xx.ravel() - 0.77) ** 2 + 3 * (yy.ravel() - 0.41) ** 2,
    }) if len(names) > 1 else pd.DataFrame(columns=["quantity_x", "x", "quantity_y", "y", "distance"])  # fmt: skip
    profiles = pd.concat(
        pd.DataFrame({"quantity": q, "value": v, "distance": 4.5 + (v - FITTED[q]["value"]) ** 2})
        for q in names
        for v in [np.linspace(*FITTED[q]["bounds"], 9)]
    )
    boot = pd.DataFrame({"resample": range(3), **{q: FITTED[q]["value"] + np.r_[-0.1, 0.0, 0.1] for q in names},
                         "distance": [5.0, 4.8, 5.2]})  # fmt: skip
    ablation = pd.DataFrame({
        "variant": ["baseline", "baseline", "bush_stiffness", "bush_stiffness", "friction_coefficient", "all", "all"],
        "group": ["tandem", "triaxle", "tandem", "triaxle", "triaxle", "tandem", "triaxle"],
        "n_groups": [1, 11, 1, 11, 11, 2, 10],
        "mean_max_deviation_pct": [0.01, 11.83, 1.78, 11.45, 14.24, 3.41, 14.17],
        "share_outside_5pct": [0.0, 0.91, 0.0, 0.91, 0.91, 1.0, 0.8],
        "buys_points": [0.0, 0.0, -1.77, 0.38, -2.41, -3.40, -2.34],
    })  # fmt: skip
    calibrated = pd.DataFrame({
        "slot": [0, 1], "group": ["triaxle", "tandem"], "n_axles": [3, 2], "suspension": ["steel", "air"],
        "tilt_deg": [1.16, 0.94], "axle_load_1": [4137.0, 6604.0], "axle_load_2": [5737.1, 6813.8],
        "axle_load_3": [6425.2, np.nan],
    })  # fmt: skip
    return {"bootstrap.csv": boot, "valley.csv": valley, "profiles.csv": profiles, "calibrated.csv": calibrated,
            "ablation.csv": ablation}  # fmt: skip


def written(tmp_path, metrics, tables):
    """``metrics`` and ``tables`` written as the stage writes them, and read back as the report reads them."""
    out, metrics_file = tmp_path / "data" / "calibration", tmp_path / "metrics" / "calibration.json"
    out.mkdir(parents=True)
    metrics_file.parent.mkdir()
    metrics_file.write_text(json.dumps(metrics, indent=2))
    for name, frame in tables.items():
        frame.to_csv(out / name, index=False, float_format="%.6g")
    if not tables:
        (out / "README.txt").write_text(f"calibration skipped: {metrics['reason']}\n")
    return calibration_inputs(out, metrics_file)


def pages_of(tables, metrics, survey=True):
    """The calibration pages of ``tables`` and ``metrics``; ``survey``: whether an observed survey was given."""
    observed = {"observed": {"path": "observed/site.mon"} if survey else None}
    ctx = SimpleNamespace(
        inputs=SimpleNamespace(calibration=tables, calibration_metrics=metrics, observed_metrics=observed)
    )
    with matplotlib.rc_context(STYLE):
        return calibration.page(ctx)


def table_cells(fig):
    """The rows of the (first) table drawn on a page, header first."""
    [table] = [t for ax in fig.get_axes() for t in ax.tables][:1]
    cells = table.get_celld()
    n_rows, n_cols = max(r for r, _ in cells) + 1, max(c for _, c in cells) + 1
    return [[cells[r, c].get_text().get_text() for c in range(n_cols)] for r in range(n_rows)]


def tables_of(fig):
    return [t for ax in fig.get_axes() for t in ax.tables]


def assert_text_above_the_footer(fig):
    FigureCanvasAgg(fig)
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    height = fig.bbox.height
    for t in fig.texts:
        if t.get_text().strip():
            assert t.get_window_extent(renderer).y0 / height >= TEXT_BOTTOM - 1e-3, t.get_text()[:60]


# ---- inputs -------------------------------------------------------------------------------------------------------
def test_a_missing_metrics_file_reads_as_skipped_with_a_reason(tmp_path):
    tables, metrics = calibration_inputs(tmp_path / "data" / "calibration", tmp_path / "metrics" / "calibration.json")
    assert tables == {} and metrics == skipped_calibration(NO_CALIBRATION)
    assert "calibrate stage has not run" in metrics["reason"]


def test_a_skipped_calibration_needs_no_tables_and_a_fit_needs_them_all(tmp_path):
    tables, metrics = written(tmp_path / "skip", skipped_calibration("no observed survey given"), {})
    assert tables == {} and metrics["reason"] == "no observed survey given"
    some = fitted_tables()
    del some["valley.csv"]
    with pytest.raises(RunsError, match="valley.csv"):
        written(tmp_path / "fit", fitted_metrics(), some)


def test_the_calibration_pages_follow_the_observed_page():
    names = [name for name, _ in build.PAGES]
    assert names.index("calibration") == names.index("observed against simulated") + 1
    assert ("calibration", calibration.page) in build.PAGES


# ---- the pages ----------------------------------------------------------------------------------------------------
def test_skipped_with_a_survey_gives_one_page_that_says_why_and_without_one_none(tmp_path):
    reason = "calibrate is null in params.yaml"
    tables, metrics = written(tmp_path, skipped_calibration(reason), {})
    assert pages_of(tables, metrics, survey=False) == []  # the observed page says what a survey brings
    [(section, name, fig)] = pages_of(tables, metrics)
    assert (section, name) == ("Calibration", "")
    assert not fig.get_axes()
    page = figure_text(fig)
    assert f"The calibrate stage was skipped: {reason}." in page
    for words in ("observed.path: observed/site.mon", "observed.kind: weighbridge", "calibrate section",
                  "calibrate.fit", "docs/calibration.md"):  # fmt: skip
        assert words in page, words
    assert_text_above_the_footer(fig)


def test_a_fit_gives_the_fit_page_and_the_checks_page(tmp_path):
    tables, metrics = written(tmp_path, fitted_metrics(), fitted_tables())
    pages = pages_of(tables, metrics)
    assert [(p.section, p.name) for p in pages] == [
        ("Calibration: the fit", "calibration_fit"),
        ("Calibration: observed against calibrated, held out, ablation", "calibration_checks"),
    ]
    for _, _, fig in pages:
        for ax in fig.get_axes():
            if ax.get_visible() and ax.axison and not ax.tables:
                assert ax.has_data(), ax.get_title()
                assert ax.get_ylabel() or ax.get_label() == "<colorbar>", ax.get_title()
        assert_text_above_the_footer(fig)


def test_the_fit_table_gives_the_metrics_numbers(tmp_path):
    tables, metrics = written(tmp_path, fitted_metrics(), fitted_tables())
    fig = pages_of(tables, metrics)[0].figure
    header, *rows = table_cells(fig)
    assert header == list(calibration.FIT_HEADER)
    by_label = {row[0]: row for row in rows}
    assert len(rows) == len(FITTED) + len(FIXED)
    for q, e in metrics["fitted"].items():
        row = by_label[calibration.quantity_label(q)]
        assert row[1] == "fitted"
        assert float(row[2]) == e["value"]
        if e["low"] is None:
            assert row[3] == "none"
        else:
            low, high = row[3].split(" to ")
            assert (float(low), float(high)) == (e["low"], e["high"])
        p = PRIOR_FREE.get(q)
        if p is None:
            assert row[4] == "-"
        else:
            assert row[4] == f"{p['value']:g} ({p['low']:g} to {p['high']:g})"
        assert [float(b) for b in row[5].split(" to ")] == e["bounds"]
    for q, v in metrics["fixed"].items():
        row = by_label[calibration.quantity_label(q)]
        assert row[1] == "fixed" and float(row[2]) == v
    page = figure_text(fig)
    reached = f"Distance reached: {metrics['distance']:g} at the posterior medians (4.1 at the prior-free minimum), "
    assert reached + "through the table" in page
    assert f"simulated directly: {metrics['distance_direct']:g}" in page
    assert "chassis tilt, centre and chassis tilt, spread (sd): +0.97" in page
    flat = " ".join(page.split())
    assert "Posterior: 3000 draws (29 % accepted)" in flat and "90 % credible interval" in flat
    assert "chassis tilt, centre normal(mean 0, sd 0.6); chassis tilt, spread (sd) half." in flat


def test_the_checks_page_gives_each_sides_statistics_and_the_held_out_distances(tmp_path):
    tables, metrics = written(tmp_path, fitted_metrics(), fitted_tables())
    fig = pages_of(tables, metrics)[1].figure
    header, *rows = table_cells(fig)
    assert len(rows) == 2 * len(calibration.CHECK_SIDES)
    where = {label: path for label, path, _ in calibration.CHECK_SIDES}
    for row in rows:
        size = {"tandem": "tandem", "tri-axle": "triaxle"}[row[0]]
        entry = metrics
        for key in where[row[1]]:
            entry = entry[key]
        entry = entry[size]
        assert int(row[2]) == entry["n_groups"]
        assert row[3] == f"{100 * entry['share_outside_5pct']:.1f}"
        assert row[4] == f"{100 * entry['share_over_10pct']:.1f}"
        assert row[5] == f"{entry['mean_spread_kg']:.0f}"
    page = figure_text(fig)
    h = metrics["held_out"]
    for key in ("distance_fit_half", "distance_held_out", "distance_halves"):
        assert f"{h[key]:g}" in page, key
    legends = [t.get_text() for ax in fig.get_axes() if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert "observed, 107 groups" in legends and "tri-axle (11 steel groups, 11.83 % with all present)" in legends


def test_a_single_fitted_quantity_and_no_held_out_check_still_give_both_pages(tmp_path):
    metrics = fitted_metrics(held=False)
    metrics["fitted"] = {"air_share": FITTED["air_share"]}
    metrics["trade_offs"] = []
    tables, metrics = written(tmp_path, metrics, fitted_tables(("air_share",)))
    fit, check = pages_of(tables, metrics)
    assert "None: no two fitted quantities" in figure_text(fit.figure)
    assert "No held-out check: too few odd records." in figure_text(check.figure)
    rows = table_cells(check.figure)[1:]
    assert [r[2] for r in rows if r[1].startswith("held-out")] == ["0"] * 4
    for page in (fit, check):
        assert_text_above_the_footer(page.figure)


def test_a_fit_at_a_bound_is_said_in_words_on_the_fit_page_and_nothing_is_said_without_one(tmp_path):
    metrics = fitted_metrics()
    page = figure_text(pages_of(*written(tmp_path / "a", metrics, fitted_tables()))[0].figure)
    assert "At a bound" not in page  # the metrics of a fit without one (and of an older stage: no key)
    # the posterior (the fitted values) piled at the spread's lower bound, its median near the air share's upper one;
    # the prior-free minimum (the diagnostic) at the tilt mean's upper bound, where the posterior is not
    metrics["at_bounds"] = {
        "chassis_tilt_sd_deg": {"bound": "low", "value": 0.1, "limit": 0.1, "share_of_posterior": 0.31},
        "air_share": {"bound": "high", "value": 0.99, "limit": 1.0, "share_of_posterior": 0.05},
    }
    metrics["prior_free_minimum"]["at_bounds"] = {
        "chassis_tilt_mean_deg": {"bound": "high", "value": 1.49, "limit": 1.5, "share_of_refits": 0.25},
    }
    tables, read = written(tmp_path / "b", metrics, fitted_tables())
    fig = pages_of(tables, read)[0].figure
    page = " ".join(figure_text(fig).split())
    assert "At a bound: a finding about the model, not a value of the fleet" in page
    spread = calibration.quantity_label("chassis_tilt_sd_deg", False)
    assert (f"{spread}: posterior median 0.1, at its lower bound 0.1; 31 % of the posterior's draws lie within 2 % "
            "of the range from it.") in page  # fmt: skip
    assert f"{calibration.quantity_label('air_share', False)}: posterior median 0.99, near its upper bound 1;" in page
    mean = calibration.quantity_label("chassis_tilt_mean_deg", False)
    assert (f"{mean}, prior-free minimum (the diagnostic): 1.49, at its upper bound 1.5, as are 25 % of the bootstrap "
            "refits; the posterior, with its prior, is not piled there.") in page  # fmt: skip
    assert_text_above_the_footer(fig)


def attribution_metrics():
    """metrics/calibration.json's ``attribution`` for two of the four groups (numbers chosen to format distinctly;
    the Shapley shares add up to as observed - at rest, the one-at-a-time shares with the interaction too)."""

    def share(v, lo, hi):
        return {"share_outside_5pct": {"value": v, "low": lo, "high": hi},
                "share_over_10pct": {"value": v / 2, "low": lo / 2, "high": hi / 2},
                "mean_spread_pct": {"value": 10 * v, "low": 10 * lo, "high": 10 * hi}}  # fmt: skip

    def stats(outside):
        return {"share_outside_5pct": outside, "share_over_10pct": outside / 3, "mean_spread_pct": 40 * outside}

    return {
        "triaxle/steel": {"n_groups": 21, "n_dropped": 0, "as_observed": stats(0.81), "at_rest": stats(0.29),
                          "total": share(0.52, 0.4, 0.63),
                          "shapley": {"resolution": share(0.0, -0.01, 0.01), "sensor": share(0.08, 0.01, 0.16),
                                      "tilt": share(0.36, 0.25, 0.47), "dynamics": share(0.08, -0.03, 0.19)},
                          "one_at_a_time": {"resolution": share(0.0, -0.01, 0.01), "sensor": share(0.05, -0.02, 0.12),
                                            "tilt": share(0.33, 0.21, 0.46), "dynamics": share(-0.07, -0.15, 0.02)},
                          "interaction": share(0.21, 0.09, 0.34)},
        "tandem/air": {"n_groups": 7, "n_dropped": 1, "as_observed": stats(0.43), "at_rest": stats(0.0),
                       "total": share(0.43, 0.14, 0.71),
                       "shapley": {"resolution": share(0.0, 0.0, 0.0), "sensor": share(0.29, 0.0, 0.57),
                                   "tilt": share(0.0, 0.0, 0.0), "dynamics": share(0.14, 0.0, 0.29)},
                       "one_at_a_time": {"resolution": share(0.0, 0.0, 0.0), "sensor": share(0.43, 0.14, 0.71),
                                         "tilt": share(0.0, 0.0, 0.0), "dynamics": share(0.14, 0.0, 0.29)},
                       "interaction": share(-0.14, -0.29, 0.0)},
    }  # fmt: skip


def test_the_attribution_gives_a_page_of_each_causes_share_with_its_interval(tmp_path):
    metrics = fitted_metrics()
    assert [p.name for p in pages_of(*written(tmp_path / "a", metrics, fitted_tables()))][-1] == "calibration_checks"
    metrics["attribution"] = attribution_metrics()
    tables, read = written(tmp_path / "b", metrics, fitted_tables())
    pages = pages_of(tables, read)
    assert (pages[-1].section, pages[-1].name) == ("Calibration: what the WIM shows, by cause", "calibration_causes")
    fig = pages[-1].figure
    header, *rows = table_cells(fig)
    assert header == list(calibration.CAUSE_HEADER)
    # tri-axles first, as the bars; outside 5 % in % of groups: each cause's Shapley share above its interval and at
    # rest, below each cause's one-at-a-time share and the interaction beside them
    assert [[" ".join(cell.split()) for cell in row] for row in rows] == [
        ["tri-axle, steel", "21", "81", "Shapley", "+0 (-1 to +1)", "+8 (+1 to +16)", "+36 (+25 to +47)",
         "+8 (-3 to +19)", "-", "29"],
        ["", "", "", "one at a time", "+0 (-1 to +1)", "+5 (-2 to +12)", "+33 (+21 to +46)", "-7 (-15 to +2)",
         "+21 (+9 to +34)", ""],
        ["tandem, air", "7", "43", "Shapley", "+0 (+0 to +0)", "+29 (+0 to +57)", "+0 (+0 to +0)", "+14 (+0 to +29)",
         "-", "0"],
        ["", "", "", "one at a time", "+0 (+0 to +0)", "+43 (+14 to +71)", "+0 (+0 to +0)", "+14 (+0 to +29)",
         "-14 (-29 to +0)", ""],
    ]  # fmt: skip
    bars = [ax for ax in fig.get_axes() if not ax.tables and ax.get_visible() and ax.axison]
    assert [ax.get_ylabel() for ax in bars] == [label for _, label, _ in calibration.CAUSE_STATS]
    assert all(ax.has_data() for ax in bars)
    page = " ".join(figure_text(fig).split())
    assert "the four shares add up exactly to as observed minus at rest" in page
    assert "what switching that one cause off removes" in page and "90 % interval from a paired bootstrap" in page
    assert_text_above_the_footer(fig)


def test_a_half_fit_whose_posterior_is_piled_is_said_not_to_validate_that_fleet(tmp_path):
    metrics = fitted_metrics()
    page = " ".join(figure_text(pages_of(*written(tmp_path / "a", metrics, fitted_tables()))[1].figure).split())
    assert "posterior is piled" not in page
    metrics["held_out"]["posterior_piled"] = {"air_share": "high"}
    fig = pages_of(*written(tmp_path / "b", metrics, fitted_tables()))[1].figure
    page = " ".join(figure_text(fig).split())
    assert "The half fit's posterior is piled against a bound for air_share: a held-out match" in page
    assert_text_above_the_footer(fig)


def test_the_fit_page_says_whether_the_table_is_faithful_within_the_sampling_floor(tmp_path):
    metrics = fitted_metrics()
    metrics["table_faithful"] = {"gap": 2.58792, "floor": 2.71184, "faithful": True}
    page = " ".join(figure_text(pages_of(*written(tmp_path / "a", metrics, fitted_tables()))[0].figure).split())
    assert "simulated directly: 7.07898: within the sampling floor 2.71184 of the table's" in page
    assert "misstates" not in page
    metrics["table_faithful"] = {"gap": 2.9, "floor": 1.2, "faithful": False}
    page = " ".join(figure_text(pages_of(*written(tmp_path / "b", metrics, fitted_tables()))[0].figure).split())
    assert "NOT within the sampling floor 1.2 of the table's" in page and "misstates the fleet it fits" in page


def test_the_checks_page_offers_the_fitted_values_to_the_fleet_study(tmp_path):
    metrics = fitted_metrics()
    metrics["fleet_study"] = {
        "set": {"fleet.suspension_mix.triaxle.air": 0.4156}, "not_settable": ["contact_roll_radius_mean_mm"],
        "command": "dvc exp run -S fleet.suspension_mix.triaxle.air=0.4156",
    }  # fmt: skip
    fig = pages_of(*written(tmp_path, metrics, fitted_tables()))[1].figure
    page = " ".join(figure_text(fig).split())
    assert "The calibrated fleet in the fleet study" in page
    assert "dvc exp run -S fleet.suspension_mix.triaxle.air=0.4156 (contact_roll_radius_mean_mm have no" in page
    assert_text_above_the_footer(fig)


def test_the_fit_table_gives_each_quantitys_rhat_and_ess_and_the_page_says_an_unconverged_posterior(tmp_path):
    # issue 43 Must 5: R-hat; bulk/tail ESS in the fit table's last column ("-" where the metrics have none, as an
    # older stage's), and the advice in words when the posterior did not converge
    metrics = fitted_metrics()
    post = metrics["posterior"]
    quantities = post["quantities"]
    quantities["chassis_tilt_mean_deg"].update(rhat=1.0031, ess_bulk=2234.7, ess_tail=1876.2)
    quantities["chassis_tilt_sd_deg"].update(rhat=1.0712, ess_bulk=61.4, ess_tail=None)
    advice = ("unconverged (thresholds: R-hat < 1.01, bulk and tail ESS >= 400; Vehtari et al. 2021): "
              "chassis_tilt_sd_deg short; raise posterior_draws (params.yaml calibrate.posterior_draws) from 3000 "
              "to 20000")  # fmt: skip
    post.update(chains=4, converged=False, advice=advice,
                thresholds={"rhat_below": 1.01, "ess_bulk_and_tail_at_least": 400.0, "source": "Vehtari"})  # fmt: skip
    fig = pages_of(*written(tmp_path / "a", metrics, fitted_tables()))[0].figure
    header, *rows = table_cells(fig)
    assert header[-1] == "R-hat; ESS\nbulk/tail"
    cell = {row[0]: row[-1] for row in rows}
    label = calibration.quantity_label
    assert cell[label("chassis_tilt_mean_deg")] == "1.003; 2235/1876"
    assert cell[label("chassis_tilt_sd_deg")] == "1.071; 61/n/a"
    assert cell[label("air_share")] == "-" and cell[label("site_iri_m_km")] == "-"  # no posterior; fixed
    page = " ".join(figure_text(fig).split())
    assert "4 chains, the first from the prior-free minimum, the others from points drawn within the bounds" in page
    assert "converged when R-hat is below 1.01 and both are at least 400, which NOT every quantity is" in page
    assert "The posterior has not converged: its medians and intervals are provisional" in page
    assert f"The posterior is {advice}." in page
    assert_text_above_the_footer(fig)
    post.update(converged=True, advice=None)
    page = " ".join(figure_text(pages_of(*written(tmp_path / "b", metrics, fitted_tables()))[0].figure).split())
    assert "both are at least 400, as every quantity is." in page and "has not converged" not in page


def test_the_fit_page_says_the_sites_share_the_prior_sensitivity_and_a_sensor_above_four_percent(tmp_path):
    # issue 43 Musts 2, 4 and 6, as calibrate writes them (bogie.fleet.calibration.checks)
    metrics = fitted_metrics()
    metrics["posterior"].update(covariance_sites=16, covariance_shares={"survey": 0.2, "table": 0.3,
                                                                        "between_sites": 0.5})  # fmt: skip
    sentence = ("With the chassis tilt's prior sd halved and doubled, chassis_tilt_mean_deg moves from 0.741 to 0.52 "
                "and 0.93 degree (0.71 of its interval): the answer depends on the tilt prior; the survey does not pin "
                "it, the prior does, so read it with the prior's source (docs/calibration.md).")  # fmt: skip
    metrics["prior_sensitivity"] = {"depends": True, "sentence": sentence}
    finding = (
        "the per-axle sensor error is fitted at 4.7 %, above the 4 % RMS a strip sensor's whole error reaches "
        "against an instrumented vehicle (Cebon and Winkler 1991): it is per-axle scatter the model lacks"
    )
    metrics["sensor_per_axle"] = {"value": 4.7, "low": 4.0, "high": 5.3, "bound_pct": 4.0, "exceeds": True,
                                  "finding": finding}  # fmt: skip
    fig = pages_of(*written(tmp_path / "a", metrics, fitted_tables()))[0].figure
    page = " ".join(figure_text(fig).split())
    assert "and between WIM sites, the calibration bogies weighed on 16 other sites' roads (50 % of the" in page
    assert f"Prior sensitivity: {sentence}" in page
    assert "The sensor's per-axle error is above what a strip sensor reaches" in page
    assert f"In words: {finding}." in page and "interval [4, 5.3] %" in page
    assert_text_above_the_footer(fig)
    # within a strip sensor's error, and no sites: nothing said of either
    metrics["sensor_per_axle"].update(value=2.1, exceeds=False, finding=None)
    metrics["posterior"].update(covariance_sites=0, covariance_shares=None)
    page = " ".join(figure_text(pages_of(*written(tmp_path / "b", metrics, fitted_tables()))[0].figure).split())
    assert "strip sensor reaches" not in page and "between WIM sites" not in page


def test_the_checks_page_gives_what_the_posterior_predicts_with_the_mean_group_load(tmp_path):
    metrics = fitted_metrics()
    entry = {"median": 0.5, "low": 0.4, "high": 0.6}
    metrics["calibrated"]["posterior_predictive"] = {
        "draws": 8, "credible_level": 0.9,
        "triaxle": {"share_outside_5pct": entry, "mean_spread_kg": {"median": 981.6, "low": 900.2, "high": 1050.0},
                    "mean_group_load_kg": {"median": 20140.0, "low": 19220.0, "high": 21060.0}},
    }  # fmt: skip
    fig = pages_of(*written(tmp_path, metrics, fitted_tables()))[1].figure
    page = " ".join(figure_text(fig).split())
    assert "What the posterior predicts (the calibration fleet simulated at 8 posterior draws" in page
    assert ("tri-axles outside 5 % 50.0 % (40.0 to 60.0), mean spread 982 kg (900 to 1050), mean group load 20.1 t "
            "(19.2 to 21.1, the site's bias included).") in page  # fmt: skip
    assert_text_above_the_footer(fig)


def test_no_calibration_page_has_a_layout_fault(tmp_path):
    # issue 45 Must 3: the fit, checks and causes pages (pipeline.report.faults), on the metrics made by hand here
    from pipeline.report.faults import layout_faults

    metrics = fitted_metrics()
    metrics["attribution"] = attribution_metrics()
    pages = pages_of(*written(tmp_path, metrics, fitted_tables()))
    with matplotlib.rc_context(STYLE):
        faults = [(p.name, f) for p in pages for f in layout_faults(p.figure)]
    assert not faults
