"""The ``sample`` stage: fleet, Sobol' sensitivity design and ablation tables (pipeline.sample)."""

import copy
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from SALib.analyze import sobol as sobol_analyze

from bogie.fleet.sampling.sample import COLUMNS, TYRE_WEAR_COLUMNS, VARIANTS, bogie_from_sample, road_seed, sensor_seed
from bogie.fleet.sampling.sensitivity import sensitivity_problem
from bogie.params import GRAVITY, INHIBITORS, design_spring_loads
from pipeline.config import ConfigError, load_params, parse_config
from pipeline.sample import (
    check_memory,
    memory_needed,
    sample_ablation,
    sample_fleet,
    sample_sensitivity,
    sample_studies,
    write_parquet_atomic,
)

ROOT = Path(__file__).resolve().parents[2]
SCALARS = (
    "bush_stiffness",
    "bush_damping",
    "friction_coefficient",
    "contact_roll_radius",
    "chassis_tilt",
    "spring_friction_band",
    "spring_friction_decay",
)


def small_raw(**changes):
    """The default params with a small fleet, design and ablation; ``changes`` maps dotted paths to values."""
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 300
    raw["sensitivity"]["base_size"] = 16
    raw["ablation"]["n_bogies"] = 20
    for path, value in changes.items():
        *parents, last = path.split("__")
        node = raw
        for key in parents:
            node = node[key]
        node[last] = value
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


# ---- schema and support ------------------------------------------------------------------------------------------
def test_every_study_has_the_schema_and_no_missing_values(studies):
    for study, frame in studies.items():
        assert list(frame.columns) == list(COLUMNS)
        assert {c: str(t) for c, t in frame.dtypes.items()} == COLUMNS
        assert not frame.isna().any().any()
        assert (frame["study"] == study).all()
        assert frame["sample_id"].tolist() == list(range(len(frame)))


def test_sampled_columns_are_si_and_inside_their_distributions_support(config, studies):
    for frame in studies.values():
        frame = frame[frame["variant"] == "baseline"]  # the ablation's other variants switch inhibitors to 0
        for name in SCALARS:
            low, high = config.distributions[name].support
            assert frame[name].between(low, high).all(), name
        tilt = frame["chassis_tilt"]
        assert tilt.abs().max() <= math.radians(2.0)  # rad, not degrees
        assert frame["contact_roll_radius"].max() <= 0.120  # m, not mm
        assert 4.0 < frame["spring_friction_band"].max() <= 4000.0  # N, not kN
        assert frame["spring_friction_decay"].between(0.002, 0.008).all()  # m, not mm
        wear = frame[list(TYRE_WEAR_COLUMNS)]
        assert ((wear >= 0.0) & (wear <= 0.012)).all().all()
        assert frame["payload_fraction"].between(0.5, 1.0).all()
        assert set(frame["road_class"]) <= {"A", "B", "C"}


def test_axles_a_group_does_not_have_wear_nothing(studies):
    fleet = studies["fleet"]
    tandem = fleet[fleet["group"] == "tandem"]
    triaxle = fleet[fleet["group"] == "triaxle"]
    assert (tandem["n_axles"] == 2).all() and (triaxle["n_axles"] == 3).all()
    assert (tandem["tyre_wear_3"] == 0.0).all()
    assert (triaxle["tyre_wear_3"] > 0.0).all()


# ---- the fleet design --------------------------------------------------------------------------------------------
def test_latin_hypercube_puts_one_bogie_in_every_stratum_of_every_marginal():
    config = parse_config(small_raw(fleet__n_bogies=500))
    fleet = sample_fleet(config)
    n = len(fleet)
    edges_u = np.arange(n + 1) / n
    for name in (*SCALARS, "payload_fraction", "tyre_wear_1", "tyre_wear_2"):
        dist = config.distributions["tyre_wear" if name.startswith("tyre_wear") else name]
        x = np.sort(fleet[name].to_numpy())
        edges = dist.ppf(np.minimum(edges_u, 1.0))
        assert np.all(x >= edges[:-1] - 1e-12 * abs(edges[:-1])), name
        assert np.all(x <= edges[1:] + 1e-12 * abs(edges[1:])), name
    # discrete dimensions: the stratification gives each value its share to within one bogie
    assert abs((fleet["group"] == "tandem").sum() - 0.3 * n) <= 1
    for road_class, weight in zip("ABC", (0.3, 0.5, 0.2)):
        assert abs((fleet["road_class"] == road_class).sum() - weight * n) <= 1


def test_tyre_wear_is_independent_per_axle(config):
    fleet = sample_fleet(parse_config(small_raw(fleet__n_bogies=1000)))
    tri = fleet[fleet["group"] == "triaxle"]
    corr = np.corrcoef(tri[list(TYRE_WEAR_COLUMNS)].to_numpy().T)
    assert np.abs(corr[np.triu_indices(3, 1)]).max() < 0.1


def test_sobol_fleet_marginals_match_the_distributions():
    config = parse_config(small_raw(fleet__n_bogies=1024, fleet__sampling="sobol"))
    fleet = sample_fleet(config)
    q = np.array([0.1, 0.25, 0.5, 0.75, 0.9])
    for name in (*SCALARS, "payload_fraction"):
        dist = config.distributions[name]
        low, high = dist.support
        empirical = np.quantile(fleet[name].to_numpy(), q)
        assert empirical == pytest.approx(dist.ppf(q), abs=0.01 * (high - low)), name


def test_same_params_give_identical_tables_and_another_seed_different_ones(config, studies):
    again = sample_studies(parse_config(small_raw()))
    for study in studies:
        assert studies[study].equals(again[study])
    other = sample_studies(parse_config(small_raw(seed=config.seed + 1)))
    for study in studies:
        assert not studies[study]["bush_stiffness"].equals(other[study]["bush_stiffness"])
        assert not studies[study]["road_seed"].equals(other[study]["road_seed"])


def test_road_seeds_depend_only_on_seed_study_and_sample_id(config, studies):
    fleet = studies["fleet"]
    bigger = sample_fleet(parse_config(small_raw(fleet__n_bogies=600)))
    assert bigger["road_seed"].iloc[: len(fleet)].tolist() == fleet["road_seed"].tolist()
    assert fleet["road_seed"].iloc[7] == road_seed(config.seed, "fleet", 7)
    assert fleet["road_seed"].is_unique
    assert (fleet["road_seed"] >= 0).all()
    assert road_seed(config.seed, "fleet", 7) != road_seed(config.seed, "ablation", 7)


def test_sensor_seeds_are_per_bogie_apart_from_the_road_and_kept_by_the_ablation_variants(config, studies):
    fleet, ablation = studies["fleet"], studies["ablation"]
    bigger = sample_fleet(parse_config(small_raw(fleet__n_bogies=600)))
    assert bigger["sensor_seed"].iloc[: len(fleet)].tolist() == fleet["sensor_seed"].tolist()
    assert fleet["sensor_seed"].iloc[7] == sensor_seed(config.seed, "fleet", 7)
    assert fleet["sensor_seed"].is_unique and (fleet["sensor_seed"] >= 0).all()
    # a stream of its own: no bogie's sensor seed is any bogie's road seed
    assert not set(fleet["sensor_seed"]) & set(fleet["road_seed"])
    # common random numbers: every variant reads with its fleet bogie's sensor errors
    merged = ablation.merge(fleet[["sample_id", "sensor_seed"]], left_on="base_id", right_on="sample_id")
    assert (merged["sensor_seed_x"] == merged["sensor_seed_y"]).all()
    assert studies["sensitivity"]["sensor_seed"].nunique() == 1


# ---- the ablation ------------------------------------------------------------------------------------------------
def test_ablation_variants_differ_from_their_baseline_only_in_the_switched_off_inhibitors(config, studies):
    fleet, ablation = studies["fleet"], studies["ablation"]
    assert len(ablation) == config.ablation.n_bogies * len(VARIANTS)
    assert ablation["variant"].tolist() == list(VARIANTS) * config.ablation.n_bogies
    physical = [c for c in COLUMNS if c not in ("sample_id", "study", "variant")]
    for base_id, rows in ablation.groupby("base_id"):
        rows = rows.set_index("variant")[physical]
        baseline = rows.loc["baseline"]
        fleet_row = fleet.loc[fleet["sample_id"] == base_id, physical].iloc[0]
        pd.testing.assert_series_equal(baseline, fleet_row, check_names=False)
        for variant in VARIANTS[1:]:
            off = set(INHIBITORS) if variant == "all" else {variant}
            changed = {c for c in physical if rows.loc[variant, c] != baseline[c]}
            assert changed <= off, (variant, changed)
            for name in off:
                assert rows.loc[variant, name] == INHIBITORS[name]


def test_ablation_takes_the_first_fleet_bogies(config, studies):
    assert sorted(set(studies["ablation"]["base_id"])) == list(range(config.ablation.n_bogies))
    assert sample_ablation(config, studies["fleet"]).equals(studies["ablation"])


# ---- the sensitivity design --------------------------------------------------------------------------------------
def test_sensitivity_design_has_n_times_groups_plus_two_rows_with_tyre_wear_as_one_group(config, studies):
    problem = design_problem(config)
    n_groups = len(config.sensitivity.factors)
    # five inhibitors, chassis tilt and tyre wear; three tyre wears, one group
    assert n_groups == 7 and problem["num_vars"] == 9
    assert problem["groups"].count("tyre_wear") == 3
    design = studies["sensitivity"]
    assert len(design) == config.sensitivity.base_size * (n_groups + 2)
    assert (design["group"] == "triaxle").all()


def test_sensitivity_holds_non_factors_at_their_median_and_one_road(config, studies):
    design = studies["sensitivity"]
    assert (design["payload_fraction"] == config.distributions["payload_fraction"].quantile(0.5)).all()
    assert (design["road_class"] == "B").all()
    assert design["road_seed"].nunique() == 1
    without_tilt = small_raw(sensitivity__factors=["bush_stiffness", "tyre_wear_mm"])
    reduced = sample_sensitivity(parse_config(without_tilt))
    assert len(reduced) == 16 * 4
    assert (reduced["chassis_tilt"] == config.distributions["chassis_tilt"].quantile(0.5)).all()


def test_saltelli_blocks_change_one_factor_group_at_a_time(config, studies):
    design = studies["sensitivity"]
    names = design_problem(config)["names"]
    groups = design_problem(config)["groups"]
    block = design[design["base_id"] == 3][names].to_numpy()
    a = block[0]
    for k, factor in enumerate(dict.fromkeys(groups)):
        differs = {names[j] for j in np.flatnonzero(block[1 + k] != a)}
        assert differs == {n for n, g in zip(names, groups) if g == factor}


def test_salib_analysis_of_the_design_finds_the_only_influential_group():
    # at the default base size, not the fixture's 16: with y a function of one group, AB_g = B for that group and
    # AB_k = A for every other, so Jansen's total index of the group is 0.5 mean((y_A - y_B)^2) / var(y), about
    # 1 - r(y_A, y_B); its error is the sample correlation of the independent halves A and B, whose spread over
    # seeds is about 0.15 at N = 16 (this seed gives 1.29) and under 0.01 at N = 512
    config = parse_config(small_raw(sensitivity__base_size=512))
    design = sample_sensitivity(config)
    problem = design_problem(config)
    y = design[list(TYRE_WEAR_COLUMNS)].sum(axis=1).to_numpy()  # depends on tyre wear only
    indices = sobol_analyze.analyze(problem, y, calc_second_order=False, num_resamples=20, seed=1)
    total = dict(zip(dict.fromkeys(problem["groups"]), indices["ST"]))
    assert total["tyre_wear"] == pytest.approx(1.0, abs=0.05)
    for factor, st in total.items():
        if factor != "tyre_wear":
            assert abs(st) < 1e-12


# ---- bogies from rows --------------------------------------------------------------------------------------------
def test_bogies_from_rows_carry_the_legal_group_load_when_fully_laden(config, studies):
    for group in ("tandem", "triaxle"):
        rows = studies["fleet"][studies["fleet"]["group"] == group]
        for _, row in rows.head(5).iterrows():
            bogie = bogie_from_sample(row)
            assert bogie.n_axles == row["n_axles"]
            one_side = sum(design_spring_loads(bogie)) + bogie.n_axles * bogie.axle_mass * GRAVITY
            assert 2.0 * one_side == pytest.approx(config.fleet.legal_group_load[group], rel=1e-9)
            assert 2.0 * one_side == pytest.approx(row["legal_group_load"], rel=1e-9)
            assert bogie.chassis_pitch_inertia == pytest.approx(bogie.payload_mass * (bogie.payload_cg_x**2 + 3.5**2))
            for name in SCALARS:
                assert getattr(bogie, name) == row[name]
            assert bogie.tyre_wear == tuple(row[c] for c in TYRE_WEAR_COLUMNS[: bogie.n_axles])


def test_every_sampled_row_builds_a_valid_bogie(studies):
    for frame in studies.values():
        for row in frame.head(60).to_dict("records"):
            bogie_from_sample(row)


# ---- the stage ---------------------------------------------------------------------------------------------------
def run_stage(cwd, *args):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "pipeline.sample", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=120
    )


def test_stage_with_bad_params_exits_non_zero_and_writes_nothing(tmp_path):
    raw = small_raw()
    raw["sensitivity"]["base_size"] = 500
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw), encoding="utf-8")
    result = run_stage(tmp_path)
    assert result.returncode != 0
    assert "sensitivity.base_size = 500" in result.stderr
    assert "power of 2" in result.stderr
    assert result.stdout == ""
    assert not (tmp_path / "data").exists()


def test_stage_writes_each_study_atomically_and_reproducibly(tmp_path, studies):
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(small_raw()), encoding="utf-8")
    first = run_stage(tmp_path)
    assert first.returncode == 0, first.stderr
    assert first.stdout.count("\n") == 1 and "fleet 300" in first.stdout
    out = tmp_path / "data" / "samples"
    assert sorted(p.name for p in out.iterdir()) == ["ablation.parquet", "fleet.parquet", "sensitivity.parquet"]
    content = {p.name: p.read_bytes() for p in out.iterdir()}
    for study, frame in studies.items():
        assert pd.read_parquet(out / f"{study}.parquet").equals(frame)
    assert run_stage(tmp_path).returncode == 0
    assert {p.name: p.read_bytes() for p in out.iterdir()} == content


def test_a_failed_write_leaves_the_previous_file_and_no_temporary(tmp_path, studies):
    target = tmp_path / "fleet.parquet"
    write_parquet_atomic(studies["fleet"], target)
    before = target.read_bytes()
    unwritable = pd.DataFrame({"x": [object()]})
    with pytest.raises(Exception):  # noqa: B017 - pyarrow's error type is not the point
        write_parquet_atomic(unwritable, target)
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["fleet.parquet"]


def test_default_studies_sample_in_well_under_a_few_seconds():
    config = parse_config(load_params(ROOT / "params.yaml"))
    start = time.perf_counter()
    studies = sample_studies(config)
    elapsed = time.perf_counter() - start
    # fleet; Saltelli N (G + 2) with G = 7 factor groups; the baseline, each of 5 inhibitors off and all off
    assert [len(f) for f in studies.values()] == [2000, 512 * (7 + 2), 500 * (1 + 5 + 1)]
    assert elapsed < 3.0


def test_studies_that_would_not_fit_in_memory_are_refused_before_sampling():
    # 4,000,000 bogies fit validate's fixed budget (pipeline.resources.MEMORY_BUDGET), not 8 GiB of free memory
    config = parse_config(small_raw(fleet__n_bogies=4_000_000))
    need = memory_needed(config)
    assert need > 4_000_000 * 3 * 1024  # the fleet alone at 3 KiB a bogie
    check_memory(config, available=need)  # just fits
    check_memory(config, available=None)  # unknown memory: no check
    with pytest.raises(ConfigError, match=r"fleet.n_bogies = 4000000: .* more than the 8.0 GiB available") as err:
        check_memory(config, available=8 * 2**30)
    assert err.value.key == "fleet.n_bogies"
