"""The ``sensitivity`` stage: Sobol' indices, inhibitor ranking and ablation (pipeline.sensitivity)."""

import copy
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from _flips import PLACES, flip
from SALib.sample import sobol as sobol_sample
from SALib.test_functions import Ishigami

from bogie.fleet.sampling.sample import VARIANTS
from bogie.fleet.sampling.sensitivity import sensitivity_problem
from bogie.fleet.weighing.weigher import result_row
from pipeline.ablation import SensitivityDataError, ablation_effects, ablation_pairs
from pipeline.config import load_params, parse_config
from pipeline.sample import sample_studies
from pipeline.schema import RESULT_COLUMNS, write_runs_file
from pipeline.sensitivity import (
    bootstrap_seed,
    main,
    rank_inhibitors,
    reference_check,
    saltelli_outputs,
    sobol_indices,
    sobol_table,
)

ROOT = Path(__file__).resolve().parents[2]
BASE_SIZE = 256
#: variance share of each factor in the additive test model (S1 = ST = share for an additive model)
SHARES = {
    "bush_stiffness": 0.30,
    "contact_roll_radius": 0.20,
    "chassis_tilt": 0.18,
    "spring_friction_band": 0.12,
    "tyre_wear": 0.10,
    "friction_coefficient": 0.08,
    "bush_damping": 0.02,
}
LOG_FACTORS = ("bush_stiffness", "bush_damping")  # log-uniform: additive in their logarithm


def small_raw():
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 12
    raw["sensitivity"]["base_size"] = BASE_SIZE
    raw["sensitivity"]["bootstrap_resamples"] = 200
    raw["ablation"]["n_bogies"] = 12
    return raw


def design_problem(config):
    """The SALib problem of the config's sensitivity design (:func:`bogie.fleet.sensitivity_problem`)."""
    return sensitivity_problem(config.sensitivity.factors, config.sensitivity.group)


@pytest.fixture(scope="module")
def config():
    return parse_config(small_raw())


@pytest.fixture(scope="module")
def studies(config):
    return sample_studies(config)


def _term(name, x):
    return np.log(x) if name in LOG_FACTORS else x


def additive_coefficients(config):
    """Coefficients that give each factor its variance share in SHARES (total variance 1), from the marginals."""
    u = (np.arange(200_000) + 0.5) / 200_000
    coef = {}
    for name, share in SHARES.items():
        var = np.var(_term(name, config.distributions[name].ppf(u)))
        # tyre wear is one group of three independent axles, each with a third of the share
        coef[name] = math.sqrt(share / (3 if name == "tyre_wear" else 1) / var)
    return coef


def additive_output(frame, coef):
    y = np.zeros(len(frame))
    for name, c in coef.items():
        columns = [f"tyre_wear_{i + 1}" for i in range(3)] if name == "tyre_wear" else [name]
        for col in columns:
            y += c * _term(name, frame[col].to_numpy())
    return y


@pytest.fixture(scope="module")
def sens_runs(config, studies):
    """Fabricated sensitivity runs: every measure an additive model of the factors (known indices)."""
    frame = studies["sensitivity"].drop(columns="study").copy()
    y = additive_output(frame, additive_coefficients(config))
    frame["protocol"] = "static"
    frame["status"] = "ok"
    frame["message"] = "ok"
    frame["max_deviation"] = 0.05 + 0.01 * y
    frame["p1"] = 800.0 + 100.0 * y
    frame["road_wear_factor"] = 1.0 + 0.001 * y**2  # not additive: only run through, not checked
    return frame.sample(frac=1.0, random_state=0)  # the analysis must not rely on row order


# ---- SALib wiring -------------------------------------------------------------------------------------------------
def test_ishigami_indices_match_the_closed_form_within_the_bootstrap_interval():
    problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-math.pi, math.pi]] * 3}
    x = sobol_sample.sample(problem, 2048, calc_second_order=False, seed=7)
    table = sobol_indices(problem, Ishigami.evaluate(x), 200, 0.95, seed=11).set_index("factor")
    a, b = 7.0, 0.1
    v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * math.pi**8 * (1 / 18 - 1 / 50)
    var = v1 + v2 + v13
    s1 = {"x1": v1 / var, "x2": v2 / var, "x3": 0.0}
    st = {"x1": (v1 + v13) / var, "x2": v2 / var, "x3": v13 / var}
    for f in s1:
        assert table.loc[f, "S1_low"] - 0.01 <= s1[f] <= table.loc[f, "S1_high"] + 0.01, f
        assert table.loc[f, "ST_low"] - 0.01 <= st[f] <= table.loc[f, "ST_high"] + 0.01, f
        assert 0 < table.loc[f, "ST_conf"] < 0.1


def test_the_design_path_recovers_an_additive_models_indices_ranking_and_groups(config, sens_runs):
    problem = design_problem(config)
    design = saltelli_outputs(sens_runs, problem, BASE_SIZE)
    assert design.n_blocks == BASE_SIZE and design.excluded.empty
    table = sobol_table(design, problem, 200, 0.95, seed=5)
    idx = table[table["measure"] == "max_deviation"].set_index("factor")
    # one index per factor: the three tyre wear columns are one group
    assert list(idx.index) == list(config.sensitivity.factors)
    for name, share in SHARES.items():
        for index in ("S1", "ST"):
            assert abs(idx.loc[name, index] - share) <= max(idx.loc[name, f"{index}_conf"], 0.01) + 0.02, (name, index)
    # p1 is an affine map of the same output: the indices do not change
    p1 = table[table["measure"] == "p1"].set_index("factor")
    assert p1["ST"].to_numpy() == pytest.approx(idx["ST"].to_numpy(), abs=1e-9)
    ranking = rank_inhibitors(idx.reset_index())
    assert ranking["factor"].tolist() == [
        "bush_stiffness",
        "contact_roll_radius",
        "spring_friction_band",
        "friction_coefficient",
        "bush_damping",
    ]
    assert ranking["rank"].tolist() == [1, 2, 3, 4, 5]
    assert reference_check(ranking) == {"agrees": True, "resolved": True}


def test_reference_check_tells_an_unresolved_ranking_from_a_resolved_one():
    def table(st, conf):
        names = ["bush_stiffness", "contact_roll_radius", "friction_coefficient", "bush_damping"]
        return rank_inhibitors(pd.DataFrame({"factor": names, "ST": st, "ST_low": np.subtract(st, conf),
                                             "ST_high": np.add(st, conf)}))  # fmt: skip

    assert reference_check(table([0.4, 0.3, 0.2, 0.1], 0.02)) == {"agrees": True, "resolved": True}
    assert reference_check(table([0.4, 0.3, 0.25, 0.1], 0.04)) == {"agrees": True, "resolved": False}
    assert reference_check(table([0.4, 0.1, 0.3, 0.05], 0.01)) == {"agrees": False, "resolved": False}
    assert table([0.1, 0.3, 0.2, 0.4], 0.0)["factor"].tolist()[0] == "bush_damping"
    # a design without friction cannot check the claim
    without = table([0.4, 0.3, 0.2, 0.1], 0.0)
    assert reference_check(without[without["factor"] != "friction_coefficient"]) == {"agrees": None, "resolved": None}


# ---- failed and missing data --------------------------------------------------------------------------------------
def test_failed_runs_drop_their_whole_saltelli_block_and_are_listed(config, sens_runs):
    problem = design_problem(config)
    runs = sens_runs.copy()
    bad = runs["sample_id"].isin([19, 20, 901])  # blocks 2 (two runs) and 100 of G + 2 = 9 runs each
    runs.loc[bad, ["status", "message", "max_deviation", "p1", "road_wear_factor"]] = ["failed", "diverged", 0, 0, 0]
    design = saltelli_outputs(runs, problem, BASE_SIZE)
    assert design.n_blocks == BASE_SIZE - 2
    assert design.excluded["sample_id"].tolist() == [19, 20, 901]
    assert design.excluded["base_id"].tolist() == [2, 2, 100]
    ordered = sens_runs.sort_values("sample_id")
    kept = ordered[~ordered["base_id"].isin([2, 100])]
    assert design.outputs["max_deviation"] == pytest.approx(kept["max_deviation"].to_numpy())
    idx = sobol_indices(problem, design.outputs["max_deviation"], 100, 0.95, seed=3).set_index("factor")
    assert abs(idx.loc["bush_stiffness", "ST"] - SHARES["bush_stiffness"]) < 0.05


def test_too_many_failures_refuse_with_their_count_and_ids(config, sens_runs):
    runs = sens_runs.copy()
    failed_ids = np.arange(20) * 9 * 5  # the first run of every fifth block of 9: 20 blocks of 256, 7.8 % > 5 %
    runs.loc[runs["sample_id"].isin(failed_ids), ["status", "message"]] = ["failed", "Newton failed at t = 2 s"]
    with pytest.raises(SensitivityDataError, match=r"20 of 2304 sensitivity runs failed \(sample_id 0, 45, 90") as e:
        saltelli_outputs(runs, design_problem(config), BASE_SIZE)
    assert "20 x 'Newton failed at t = 2 s'" in str(e.value) and "more than 5%" in str(e.value)


def test_missing_duplicated_or_foreign_runs_are_refused(config, sens_runs):
    problem = design_problem(config)
    with pytest.raises(SensitivityDataError, match=r"1 are missing: sample_id 33;"):
        saltelli_outputs(sens_runs[sens_runs["sample_id"] != 33], problem, BASE_SIZE)
    with pytest.raises(SensitivityDataError, match="sample_id 5 twice"):
        saltelli_outputs(pd.concat([sens_runs, sens_runs[sens_runs["sample_id"] == 5]]), problem, BASE_SIZE)
    with pytest.raises(SensitivityDataError, match="2304 rows.*design has 1152"):  # 256 x 9 runs, 128 x 9
        saltelli_outputs(sens_runs, problem, BASE_SIZE // 2)


def test_rows_out_of_saltelli_order_are_refused(config, sens_runs):
    runs = sens_runs.sort_values("sample_id").reset_index(drop=True)
    # swap the factor values of two rows of block 3 (AB_1 and AB_2), keeping their ids: no longer Saltelli's cross
    names = design_problem(config)["names"]
    runs.loc[[28, 29], names] = runs.loc[[29, 28], names].to_numpy()
    with pytest.raises(SensitivityDataError, match=r"not in SALib's Saltelli order: block 3 \(sample_id 27-35\)"):
        saltelli_outputs(runs, design_problem(config), BASE_SIZE)


def test_a_constant_or_non_finite_output_has_no_indices(config):
    problem = design_problem(config)
    n = 4 * (len(config.sensitivity.factors) + 2)
    with pytest.raises(SensitivityDataError, match="constant"):
        sobol_indices(problem, np.full(n, 0.02), 10, 0.95, seed=1)
    with pytest.raises(SensitivityDataError, match="not finite"):
        sobol_indices(problem, np.r_[np.nan, np.ones(n - 1)], 10, 0.95, seed=1)
    with pytest.raises(ValueError, match="positive"):
        sobol_indices(problem, np.arange(n, dtype=float), 10, 0.95, seed=0)


# ---- ablation -----------------------------------------------------------------------------------------------------
#: known effect of each variant on max_deviation d of every bogie (variant - baseline); "all" is the sum of the five
EFFECT = {"baseline": 0.0, "bush_stiffness": -0.02, "bush_damping": 0.0, "contact_roll_radius": -0.015,
          "friction_coefficient": -0.005, "spring_friction_band": -0.0025, "all": -0.0425}  # fmt: skip


WHEEL_LOAD = 40e3  # mean wheel load of the fabricated ablation bogies [N]


def ablation_runs(n_bogies=60, noise=0.0, seed=0, n_axles=None):
    """Ablation runs with axle loads 2 W (1 - d, 1, 1 + d) (tandem: 2 W (1 - d, 1 + d)): max_deviation d.

    A tri-axle is outside 5 % iff 2 d / (1 + d) > 0.05, d > 0.02564. ``n_axles`` gives each bogie's axle count.
    """
    rng = np.random.default_rng(seed)
    rows = []
    for base_id in range(n_bogies):
        n = 3 if n_axles is None else int(n_axles[base_id])
        d0 = 0.045 + 0.01 * (base_id % 5)  # 0.045 .. 0.085
        for k, variant in enumerate(VARIANTS):
            d = d0 + EFFECT[variant] + (noise * rng.standard_normal() if variant == "bush_stiffness" else 0.0)
            shape = [1 - d, 1, 1 + d] if n == 3 else [1 - d, 1 + d]
            for protocol in ("static", "wim"):
                row = result_row(protocol, n, WHEEL_LOAD * np.array(shape), 0.0)
                row.update(status="ok", message="ok")
                group = "triaxle" if n == 3 else "tandem"
                row.update(
                    sample_id=len(VARIANTS) * base_id + k,
                    base_id=base_id,
                    group=group,
                    variant=variant,
                    chassis_tilt=0.0,
                )
                row.update(tyre_wear_1=0.0, tyre_wear_2=0.0, tyre_wear_3=0.0)
                rows.append(row)
    return pd.DataFrame(rows)


def effects_of(runs, resamples=300):
    table = ablation_effects(ablation_pairs(runs), resamples, 0.95, seed=9)
    return table.set_index(["protocol", "group", "variant", "statistic"])


def test_ablation_recovers_known_paired_effects_with_exact_intervals_when_they_are_constant():
    effects = effects_of(ablation_runs())
    base_mean = np.mean([0.045 + 0.01 * (i % 5) for i in range(60)])
    for variant, effect in EFFECT.items():
        row = effects.loc[("static", "all", variant, "mean_max_deviation")]
        assert row["baseline"] == pytest.approx(base_mean)
        assert row["difference"] == pytest.approx(effect)
        assert row[["difference_low", "difference_high"]].tolist() == pytest.approx([effect, effect])
        assert row["reduction"] == pytest.approx(-effect)
        assert row["relative_reduction"] == pytest.approx(-effect / base_mean)
        assert row["n_pairs"] == 60 and row["n_failed"] == 0
    # p1 of the loads over their mean, (1 - d, 1, 1 + d), is d sqrt(2/3)
    p1 = effects.loc[("wim", "triaxle", "all", "mean_p1")]
    assert p1["difference"] == pytest.approx(-0.0425 * math.sqrt(2 / 3))
    # with every inhibitor off d is 0.0025..0.0425: only d = 0.0325, 0.0425 stay outside 5 % (2 of 5)
    out5 = effects.loc[("static", "all", "all", "share_outside_5pct")]
    assert (out5["baseline"], out5["value"], out5["reduction"]) == pytest.approx((1.0, 0.4, 0.6))
    out10 = effects.loc[("static", "all", "baseline", "share_over_10pct")]
    assert out10["value"] == 0.0 and math.isnan(out10["relative_reduction"])


def test_ablation_bootstrap_interval_covers_the_effect_with_the_width_of_a_mean():
    noise = 0.01
    effects = effects_of(ablation_runs(n_bogies=200, noise=noise, seed=4), resamples=1000)
    row = effects.loc[("static", "all", "bush_stiffness", "mean_max_deviation")]
    assert row["difference_low"] < -0.02 < row["difference_high"]
    width = row["difference_high"] - row["difference_low"]
    assert width == pytest.approx(2 * 1.96 * noise / math.sqrt(200), rel=0.2)
    assert row["relative_reduction_low"] < row["relative_reduction"] < row["relative_reduction_high"]


def test_ablation_intervals_are_the_percentile_bootstrap_of_one_shared_draw_per_variant():
    """scipy's paired percentile bootstrap gives the intervals of the explicit resampling it replaced.

    The explicit form: one generator seeded once; for each scope, protocol and variant one matrix of bogie draws
    shared by every statistic; the 2.5 and 97.5 percentiles of the resampled paired difference and of the ratio of
    resampled means.
    """
    runs = ablation_runs(n_bogies=40, noise=0.01, seed=7)
    pairs = ablation_pairs(runs)
    resamples = 250
    table = ablation_effects(pairs, resamples, 0.95, seed=11).set_index(["protocol", "group", "variant", "statistic"])
    rng = np.random.default_rng(11)
    scopes = [("all", pairs)] + [(g, sub) for g, sub in pairs.groupby("group", observed=True)]
    checked = 0
    for group, scope in scopes:
        for (protocol, variant), sub in scope.groupby(["protocol", "variant"], observed=True):
            good = sub[sub["ok"]]
            draw = rng.integers(0, len(good), size=(resamples, len(good)))
            value = good["max_deviation"].to_numpy(float)
            base = good["max_deviation_baseline"].to_numpy(float)
            row = table.loc[(protocol, group, variant, "mean_max_deviation")]
            diff = np.percentile((value - base)[draw].mean(axis=1), [2.5, 97.5])
            ratio = np.percentile(1.0 - value[draw].mean(axis=1) / base[draw].mean(axis=1), [2.5, 97.5])
            assert row[["difference_low", "difference_high"]].tolist() == pytest.approx(diff, rel=1e-12, abs=1e-15)
            assert row[["relative_reduction_low", "relative_reduction_high"]].tolist() == pytest.approx(
                ratio, rel=1e-12, abs=1e-15
            )
            checked += 1
    assert checked == 2 * 2 * len(VARIANTS)  # scopes "all" and "triaxle" (every bogie a tri-axle), two protocols


def test_ablation_excludes_a_failed_run_from_its_pairs_only_and_counts_it():
    runs = ablation_runs()
    hit = (runs["base_id"] == 3) & (runs["variant"] == "friction_coefficient") & (runs["protocol"] == "static")
    runs.loc[hit, ["status", "message", "max_deviation", "p1"]] = ["failed", "diverged", 0.0, 0.0]
    effects = effects_of(runs)
    friction = effects.loc[("static", "all", "friction_coefficient", "mean_max_deviation")]
    assert (friction["n_pairs"], friction["n_failed"]) == (59, 1)
    assert friction["difference"] == pytest.approx(-0.005)
    assert effects.loc[("static", "all", "bush_damping", "mean_max_deviation"), "n_pairs"] == 60
    assert effects.loc[("wim", "all", "friction_coefficient", "mean_max_deviation"), "n_pairs"] == 60
    runs.loc[(runs["base_id"] == 4) & (runs["variant"] == "baseline"), "status"] = "failed"
    assert effects_of(runs).loc[("static", "all", "all", "mean_max_deviation"), "n_pairs"] == 59


def test_ablation_leaves_out_a_wim_reading_with_a_wheel_in_the_air_and_counts_it_apart_from_failures():
    # a WIM record with an axle at 0 N is flagged by the site, as the survey does: its pair is left out of the
    # effects and counted as airborne, not as failed; a baseline in the air takes every variant's pair with it
    runs = ablation_runs()
    assert "wheel_airborne" in runs and not runs["wheel_airborne"].any()
    hit = (runs["base_id"] == 3) & (runs["variant"] == "contact_roll_radius") & (runs["protocol"] == "wim")
    runs.loc[hit, "wheel_airborne"] = True
    base = (runs["base_id"] == 5) & (runs["variant"] == "baseline") & (runs["protocol"] == "wim")
    runs.loc[base, "wheel_airborne"] = True
    effects = effects_of(runs)
    contact = effects.loc[("wim", "all", "contact_roll_radius", "mean_max_deviation")]
    assert (contact["n_pairs"], contact["n_failed"], contact["n_airborne"]) == (58, 0, 2)
    friction = effects.loc[("wim", "all", "friction_coefficient", "mean_max_deviation")]
    assert (friction["n_pairs"], friction["n_failed"], friction["n_airborne"]) == (59, 0, 1)
    static = effects.loc[("static", "all", "bush_damping", "mean_max_deviation")]
    assert (static["n_pairs"], static["n_airborne"]) == (60, 0)
    # the effect over the other pairs is unchanged: the synthetic effect is the same for every bogie
    assert contact["difference"] == pytest.approx(EFFECT["contact_roll_radius"])


def test_an_incomplete_ablation_is_refused():
    runs = ablation_runs(n_bogies=5)
    drop = (runs["base_id"] == 2) & (runs["variant"] == "bush_damping") & (runs["protocol"] == "wim")
    with pytest.raises(SensitivityDataError, match=r"base_id 2 under wim: bush_damping x 0"):
        ablation_pairs(runs[~drop])


# ---- the stage ----------------------------------------------------------------------------------------------------
def write_runs(root, study, frame):
    part = root / "data" / "runs" / f"study={study}"
    part.mkdir(parents=True, exist_ok=True)
    frame = frame.assign(chassis_tilt_deg=np.degrees(frame["chassis_tilt"]))
    # results the stage does not read: equal axle loads, so the file is a complete row of the runs schema
    filler = result_row("static", 3, np.full(3, 1e4), 0.0)
    frame = frame.assign(**{c: filler[c] for c in RESULT_COLUMNS if c not in frame.columns})
    write_runs_file(frame, part / "part-000000.parquet")


def stage_args(root):
    return [
        "--params", str(root / "params.yaml"), "--runs", str(root / "data" / "runs"),
        "--out", str(root / "data" / "sensitivity"), "--metrics", str(root / "metrics" / "s.json"),
    ]  # fmt: skip


def ablation_study_runs(config, studies):
    """The ablation sample table with fabricated results of the known effects (EFFECT) attached."""
    ablation = studies["ablation"].drop(columns="study")
    n_axles = ablation.groupby("base_id")["n_axles"].first().to_numpy()
    fabricated = ablation_runs(n_bogies=config.ablation.n_bogies, n_axles=n_axles)
    columns = ["protocol", "status", "message", *RESULT_COLUMNS]
    return ablation.merge(fabricated[["sample_id", *columns]], on="sample_id")


def test_stage_writes_indices_ablation_and_a_ranking_json(tmp_path, config, studies, sens_runs):
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(small_raw()))
    write_runs(tmp_path, "sensitivity", sens_runs)
    write_runs(tmp_path, "ablation", ablation_study_runs(config, studies))
    assert main(stage_args(tmp_path)) == 0
    metrics = json.loads((tmp_path / "metrics" / "s.json").read_text())
    assert metrics["ranking"] == [
        "bush_stiffness",
        "contact_roll_radius",
        "spring_friction_band",
        "friction_coefficient",
        "bush_damping",
    ]
    assert metrics["rank"]["friction_coefficient"] == 4
    assert metrics["reference_check"]["agrees"] is True
    assert set(metrics["sobol"]["indices"]) == set(config.sensitivity.factors)
    assert set(metrics["sobol"]["indices"]["chassis_tilt"]) == {"ST", "ST_conf", "S1", "S1_conf"}
    assert metrics["sobol"]["n_failed"] == 0 and metrics["sobol"]["n_blocks"] == BASE_SIZE
    assert "max_deviation" in metrics["ranking_measure"]
    static = metrics["ablation"]["static"]
    assert static["largest_single_gain"] == "bush_stiffness"
    assert static["all"]["reduction"] == pytest.approx(0.0425, abs=1e-4)
    assert static["baseline"]["n_bogies"] == config.ablation.n_bogies
    out = tmp_path / "data" / "sensitivity"
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["sobol_indices.csv", "sobol_excluded.csv", "ablation.csv", "ablation_pairs.parquet", ".bogie-output"]
    )
    assert len(pd.read_csv(out / "sobol_indices.csv")) == 3 * len(config.sensitivity.factors)
    # small enough for `dvc metrics show`: an inhibitor costs about 600 characters (its ranking and rank entries,
    # its indices, its ablation entry under each protocol), so the bound of 4000 with four is 4600 with five
    assert len(json.dumps(metrics)) < 4600


def test_stage_refuses_missing_runs_and_writes_nothing(tmp_path, config, studies, sens_runs, capsys):
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(small_raw()))
    write_runs(tmp_path, "sensitivity", sens_runs[sens_runs["sample_id"] != 100])
    assert main(stage_args(tmp_path)) == 2
    assert "no runs of study 'ablation'" in capsys.readouterr().err
    write_runs(tmp_path, "ablation", ablation_study_runs(config, studies))
    assert main(stage_args(tmp_path)) == 2
    assert "1 are missing: sample_id 100;" in capsys.readouterr().err
    assert not (tmp_path / "data" / "sensitivity").exists() and not (tmp_path / "metrics").exists()


def test_bootstrap_seeds_are_positive_distinct_and_reproducible():
    a, b = bootstrap_seed(1, "sensitivity_bootstrap"), bootstrap_seed(1, "ablation_bootstrap")
    assert a > 0 and b > 0 and a != b and a == bootstrap_seed(1, "sensitivity_bootstrap")


@pytest.mark.parametrize("study", ["sensitivity", "ablation"])
@pytest.mark.parametrize("place", PLACES)
def test_stage_refuses_a_part_with_one_flipped_bit_naming_it(tmp_path, config, studies, sens_runs, capsys, study,
                                                             place):  # fmt: skip
    # issue 28, item 4: the sensitivity stage verifies what it reads, as the survey does (pipeline.survey.read_runs)
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(small_raw()))
    write_runs(tmp_path, "sensitivity", sens_runs)
    write_runs(tmp_path, "ablation", ablation_study_runs(config, studies))
    damaged = tmp_path / "data" / "runs" / f"study={study}" / "part-000000.parquet"
    flip(damaged, place)
    assert main(stage_args(tmp_path)) == 2
    err = capsys.readouterr().err.strip()
    assert f"{damaged} is damaged: its SHA-256 does not match" in err and "\n" not in err, err
    assert not (tmp_path / "data" / "sensitivity").exists() and not (tmp_path / "metrics").exists()
