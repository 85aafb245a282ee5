"""The design stage: tolerances and shares against hand-worked answers, common random numbers, bad input, a run.

The analysis tests feed :func:`bogie.fleet.design.analysis.analyse_designs` runs whose axle loads are linear in tilt
with known slopes, so the share within 5 % against tilt, and the tolerance where it falls below the target, are worked
out by hand:
a tandem with loads W0 = 1 + a t, W1 = 1 - a t is within 5 % while (W0 - W1) / max = 2 a |t| / (1 + a |t|) <= 0.05,
that is |t| <= 0.05 / (1.95 a).
"""

import copy
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from bogie.fleet.design import analysis as A
from bogie.fleet.design import experiment as L
from pipeline import design as D
from pipeline.config import ConfigError, parse_config

ROOT = Path(__file__).resolve().parents[2]


def raw_params(**design):
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["execution"]["n_jobs"] = 2
    raw["execution"]["chunk_size"] = 16
    raw["design"].update(design)
    return raw


def limit(a):
    """The largest |tilt| [degree] at which loads 1 +- a t stay within 5 %."""
    return 0.05 / (1.95 * a)


# ---- the tolerance and the share, by hand ------------------------------------------------------------------------
def test_tolerance_is_where_the_share_first_falls_below_the_target_on_each_side():
    fine = np.round(np.arange(-2.0, 2.0 + 1e-9, 0.01), 6)
    share = np.where((fine >= -0.4) & (fine <= 0.6), 1.0, 0.5)
    share[fine > 1.2] = 1.0  # a recovery beyond a gap does not extend the tolerance: it must hold all the way
    assert A.tilt_tolerance(fine, share, 0.95) == (0.6, 0.4, 1.0)
    only_up = np.where((fine >= 0.0) & (fine <= 0.3), 1.0, 0.5)
    up, down, _ = A.tilt_tolerance(fine, only_up, 0.95)
    assert (up, down) == (0.3, 0.0) and math.copysign(1.0, down) == 1.0  # no nose-down tolerance reads 0, not -0
    level_fails = np.where(np.abs(fine) < 0.2, 0.9, 1.0)
    assert A.tilt_tolerance(fine, level_fails, 0.95) == (None, None, 0.9)


def test_tilt_grid_steps_outward_from_level_and_keeps_the_ends():
    raw = raw_params(tilt_step_deg=0.75)
    config = parse_config(raw)
    tilts = L.tilt_grid(config.fleet_study, config.design.tilt_step_deg)
    np.testing.assert_allclose(tilts, [-2.0, -1.5, -0.75, 0.0, 0.75, 1.5, 2.0])
    raw["distributions"]["chassis_tilt_deg"] = {"kind": "uniform", "low": 0.5, "high": 2.0}
    # refused by the schema, before any stage runs (pipeline.config.rules)
    with pytest.raises(ConfigError, match="chassis_tilt_deg.*must include level"):
        parse_config(raw)


def test_pareto_front_keeps_the_designs_nothing_beats_on_share_and_distance():
    share = np.array([0.5, 0.8, 0.7, 0.8, 0.95])
    distance = np.array([0.0, 0.3, 0.2, 0.5, 0.9])
    # 3 is beaten by 1 (same share, nearer); every other is best at its distance
    assert A.pareto_front(share, distance).tolist() == [True, True, True, False, True]


def _runs(slopes, tilts, fleet_tilts, design="tandem-typical", failed=()):
    """Runs of one tandem design: loads 1 +- a t [N] at each grid tilt and at each condition's own tilt."""
    rows = []
    for c, a in enumerate(slopes):
        for slot, t in [(A.FLEET_SLOT, fleet_tilts[c]), *enumerate(tilts)]:
            w0, w1 = 1e4 * (1 + a * t), 1e4 * (1 - a * t)
            bad = (c, slot) in failed
            rows.append({
                "design": design, "condition": c, "slot": slot, "status": "failed" if bad else "ok",
                "chassis_tilt": math.radians(t), "axle_load_1": np.nan if bad else w0,
                "axle_load_2": np.nan if bad else w1,
                "outside_5pct": None if bad else bool((max(w0, w1) - min(w0, w1)) / max(w0, w1) > 0.05),
                "over_10pct": None if bad else bool(max(w0, w1) / (0.5 * (w0 + w1)) > 1.10),
                "max_deviation": np.nan if bad else abs(a * t),
            })  # fmt: skip
    return pd.DataFrame(rows)


def _designs(name="tandem-typical"):
    return pd.DataFrame([{
        "design": name, "group": "tandem", "kind": "typical", "suspension": "steel", "bush_stiffness": 50.0,
        "equaliser_arm": 0.2, "contact_roll_radius": 0.06, "friction_coefficient": 0.25, "spring_friction_band": 2e3,
        "bush_damping": 17.0, "spring_friction_decay": 0.005, "distance": 0.0,
    }])  # fmt: skip


def test_analysis_recovers_the_hand_worked_tolerance_and_shares():
    tilts = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    slopes = [0.02] * 19 + [0.1]  # 19 conditions within 5 % to 1.282 degree, one only to 0.256 degree
    fleet_tilts = [0.1] * 10 + [0.5] * 9 + [0.5]
    a = A.analyse_designs(_runs(slopes, tilts, fleet_tilts), _designs(), tilts, 0.95, 0.95)
    row = a.designs.iloc[0]
    # the share is 20/20 to 0.256, 19/20 = 0.95 to 1.282, then 0: the tolerance ends at 1.28 (0.01 steps) both ways
    assert row["tilt_tolerance_nose_up_deg"] == pytest.approx(math.floor(100 * limit(0.02)) / 100)
    assert row["tilt_tolerance_nose_down_deg"] == pytest.approx(math.floor(100 * limit(0.02)) / 100)
    assert row["share_within_5pct_at_tolerance"] == pytest.approx(0.95)
    # at their own tilts: the condition of slope 0.1 at 0.5 degree is outside (0.5 > 0.256), the others inside
    assert row["within_5pct"] == 19 and row["share_within_5pct"] == pytest.approx(0.95)
    assert row["share_within_5pct_low"] < 0.95 < row["share_within_5pct_high"]
    assert row["share_within_10pct"] == 1.0
    # loads linear in tilt are interpolated exactly
    check = a.check
    assert len(check) == 20
    np.testing.assert_allclose(check["max_deviation_interpolated"], check["max_deviation_direct"], atol=1e-12)


def test_a_failed_run_is_counted_and_leaves_its_condition_out_not_read_as_zero():
    tilts = np.array([-1.0, 0.0, 1.0])
    slopes = [0.02] * 9 + [0.1]
    runs = _runs(slopes, tilts, [0.2] * 10, failed={(9, 1), (8, A.FLEET_SLOT)})
    a = A.analyse_designs(runs, _designs(), tilts, 0.95, 0.95)
    row = a.designs.iloc[0]
    assert row["n_failed"] == 2
    assert row["n_conditions"] == 9  # the failed run at its own tilt is not a sample
    assert row["n_curve_conditions"] == 9  # the condition with a failed grid run leaves the curve
    # without the steep condition every remaining one holds to 1 degree (limit 1.28 beyond the grid's end)
    assert row["tilt_tolerance_nose_up_deg"] == pytest.approx(1.0)


# ---- the experiment's samples: common random numbers -------------------------------------------------------------
def test_every_design_runs_over_the_same_conditions_and_tilts():
    config = parse_config(raw_params(n_conditions=5, n_space_filling=2, grid={"bush_stiffness": [1.0, 3000.0]}))
    exp = D.experiment(config)
    tilts, designs, conds, samples = exp.tilts, exp.designs, exp.conditions, exp.samples
    assert len(samples) == len(designs) * 5 * (len(tilts) + 1)
    assert set(designs["kind"]) == {"typical", "grid", "space", "air"}
    per = samples.groupby("design")
    for column in ("payload_fraction", "tyre_wear_1", "tyre_wear_2", "road_class", "road_seed", "chassis_tilt"):
        first = None
        for _, rows in per:
            values = rows.sort_values(["condition", "slot"])[column].tolist()
            first = values if first is None else first
            assert values == first, column
    own = samples[samples["slot"] == A.FLEET_SLOT].drop_duplicates("condition").sort_values("condition")
    np.testing.assert_array_equal(own["chassis_tilt"].to_numpy(), conds["chassis_tilt"].to_numpy())
    grid = samples[samples["slot"] >= 0]
    np.testing.assert_allclose(np.degrees(grid["chassis_tilt"]), tilts[grid["slot"]])
    typical = designs[designs["kind"] == "typical"].iloc[0]
    assert typical["distance"] == pytest.approx(0.0, abs=1e-3)
    free = designs[(designs["kind"] == "grid") & (designs["bush_stiffness"] == 1.0)].iloc[0]
    assert free["distance"] == pytest.approx(0.5, abs=1e-3)  # rank 0 of the bush, every other factor at its median


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"grid": {"bush_damping": [1.0]}}, r"grid\.bush_damping.*not a design factor.*allowed: bush_stiffness"),
        ({"grid": {"contact_roll_radius_mm": [0.0, 900.0]}}, r"grid\.contact_roll_radius_mm\[1\].*900.*mm"),
        ({"grid": {"bush_stiffness": [1.0, 1.0]}}, r"grid\.bush_stiffness.*twice"),
        ({"n_conditions": 1}, r"n_conditions"),
        ({"target_share": 1.5}, r"target_share"),
    ],
)
def test_bad_design_parameters_name_the_key_and_the_allowed_values(change, message):
    raw = raw_params()
    raw["design"] = {**copy.deepcopy(raw["design"]), **change}
    with pytest.raises(ConfigError, match=message):
        parse_config(raw)


# ---- the stage ------------------------------------------------------------------------------------------------------
def test_the_stage_writes_best_designs_first_with_exactly_the_issue_keys(tmp_path):
    raw = raw_params(groups=["tandem"], n_conditions=3, tilt_step_deg=1.0, n_space_filling=0,
                     grid={"bush_stiffness": [1.0, 3000.0], "contact_roll_radius_mm": [0.0, 120.0]})  # fmt: skip
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    args = ["--params", str(tmp_path / "params.yaml"), "--runs", str(tmp_path / "runs"),
            "--out", str(tmp_path / "design"), "--metrics", str(tmp_path / "design.json")]  # fmt: skip
    assert D.main(args) == 0
    m = json.loads((tmp_path / "design.json").read_text())
    assert len(m["designs"]) == 5  # typical + 4 grid designs; the air reference apart
    assert all(list(d) == list(D.DESIGN_KEYS) for d in m["designs"])
    assert m["failed"] == 0 and m["runs"] == 6 * 3 * 6
    table = pd.read_csv(tmp_path / "design" / "designs.csv")
    steel = table[table["suspension"] == "steel"]
    # best first: the Pareto front leads, and no design after it beats a front design on share at a smaller distance
    assert steel["pareto"].iloc[0]
    n_front = int(steel["pareto"].sum())
    assert steel["pareto"].iloc[:n_front].all() and not steel["pareto"].iloc[n_front:].any()
    # the reference's first inhibitor: with fixed contact points a free bearing shares the load better than a
    # stiff bush over the same conditions
    fixed = steel[steel["contact_roll_radius"] == 0.0].set_index("bush_stiffness")
    assert fixed.loc[1.0, "mean_max_deviation"] < fixed.loc[3000.0, "mean_max_deviation"]
    assert m["air"]["tandem"]["group"] == "tandem"
    assert m["guidance"] and all(isinstance(s, str) for s in m["guidance"])
    # a rerun with nothing changed computes nothing and rewrites the same bytes
    before = (tmp_path / "design.json").read_bytes()
    assert D.main(args) == 0
    assert (tmp_path / "design.json").read_bytes() == before


def test_a_null_design_section_skips_the_stage_with_one_line(tmp_path, capsys):
    raw = raw_params()
    raw["design"] = None
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    args = ["--params", str(tmp_path / "params.yaml"), "--runs", str(tmp_path / "runs"),
            "--out", str(tmp_path / "design"), "--metrics", str(tmp_path / "design.json")]  # fmt: skip
    assert D.main(args) == 0
    assert "design: skipped" in capsys.readouterr().out
    assert json.loads((tmp_path / "design.json").read_text())["designs"] == []


# ---- one executor (issue 29) ---------------------------------------------------------------------------------------
def test_the_design_runs_on_a_local_dask_cluster_are_the_runs_on_this_machine(tmp_path):
    from dask.distributed import LocalCluster

    from pipeline.schema import read_runs_frame

    config = parse_config(raw_params(groups=["tandem"], n_conditions=2, tilt_step_deg=2.0, n_space_filling=0,
                                     grid={"bush_stiffness": [1.0, 3000.0]}))  # fmt: skip
    quiet = lambda text: None  # noqa: E731
    here, _, here_metrics = D.run(config, tmp_path / "loky", quiet)
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        execution = dataclasses.replace(config.execution, backend="dask", dask_scheduler=cluster.scheduler_address)
        there, _, there_metrics = D.run(dataclasses.replace(config, execution=execution), tmp_path / "dask", quiet)
    runs = read_runs_frame(tmp_path / "loky", "design")
    assert len(runs) == 4 * 2 * 4 and (runs["status"] == "ok").all()  # typical, 2 grid, air x 2 conditions x 4 tilts
    # the same runs, bit for bit, whoever computed them; so the same tables and metrics
    pd.testing.assert_frame_equal(read_runs_frame(tmp_path / "dask", "design"), runs, check_exact=True)
    for name in ("designs", "curves", "check"):
        pd.testing.assert_frame_equal(getattr(there, name), getattr(here, name), check_exact=True)
    assert there_metrics == here_metrics
    # the library's own weighing of the same rows (bogie.fleet.weigh_designs) gives the stage's analysis
    exp = D.experiment(config)
    spec = config.design
    mine = A.analyse_designs(L.weigh_designs(exp, config.protocol.static), exp.designs, exp.tilts, spec.target_share,
                             spec.confidence_level)  # fmt: skip
    for name in ("designs", "curves", "check"):
        pd.testing.assert_frame_equal(getattr(mine, name), getattr(here, name), check_exact=True)
