"""Issue 28, items 2, 5 and 7: validate bounds every cost a setting implies and refuses what would fail later,
reports the rules between keys with the other errors, caps the workers, and refuses hostile YAML quickly."""

import copy
import dataclasses
import time
from concurrent.futures import Future
from pathlib import Path

import pytest

from bogie.fleet.calibration import table as calibration_table
from pipeline import calibrate, workers
from pipeline.config import ConfigError, load_config, load_params, parse_config
from pipeline.config.schema import Params
from pipeline.resources import MAX_JOBS, MEMORY_BUDGET, worker_count

PARAMS = Path(__file__).resolve().parents[2] / "params.yaml"


@pytest.fixture(scope="module")
def raw():
    return load_params(PARAMS)


#: a survey named, so that the calibration would run and its rules apply (with observed.path null it is skipped)
SURVEY = {"observed__path": "observed/site.csv"}


def changed(raw, **values):
    """A deep copy of ``raw`` with each dotted key (``__`` for ``.``) set."""
    new = copy.deepcopy(raw)
    for path, value in values.items():
        *parents, last = path.split("__")
        node = new
        for key in parents:
            node = node[key]
        node[last] = value
    return new


def refused(raw, **values):
    start = time.perf_counter()
    with pytest.raises(ConfigError) as err:
        parse_config(changed(raw, **values))
    assert time.perf_counter() - start < 1.0  # bounded before anything is built
    return err.value


# ---- item 2: every cost bounded, every late refusal made early ----------------------------------------------------
@pytest.mark.parametrize(
    ("values", "key", "words"),
    [
        ({"design__tilt_step_deg": 1e-6}, "design.tilt_step_deg", ["runs, more than 10,000,000"]),
        (
            {"design__grid": {"bush_stiffness": [1.0 + i for i in range(1000)],
                              "contact_roll_radius_mm": [0.1 * i for i in range(1000)],
                              "equaliser_arm_mm": [100.0 + 0.1 * i for i in range(1000)]}},
            "design.tilt_step_deg",
            ["1,000,000,000 grid combinations"],
        ),
        ({"calibrate__tilt_step_deg": 1e-9, **SURVEY}, "calibrate.tilt_step_deg", ["tilts", "more than 10,000,000"]),
        ({"sensitivity__factors": ["bush_stiffness", "road_class"]}, "sensitivity.factors[1]", ["categorical"]),
        ({"execution__dask_scheduler": "file:///tmp/scheduler.json"}, "execution.dask_scheduler", ["tcp://"]),
        ({"calibrate__site_iri_levels_m_km": [1.0, 2.0, 1000.0]}, "calibrate.site_iri_levels_m_km[2]", ["[0.3, 10]"]),
        ({"fleet__n_bogies": 8_000_000}, "fleet.n_bogies", ["memory budget of 16 GiB", "MEMORY_BUDGET"]),
    ],
)  # fmt: skip
def test_a_setting_that_would_fail_after_sample_and_simulate_is_refused_by_validate(raw, values, key, words):
    err = refused(raw, **values)
    assert err.key == key
    for word in words:
        assert word in str(err)


def test_a_design_tilt_range_without_level_is_refused_by_the_schema(raw):
    tilt = {"kind": "truncnormal", "mean": 1.0, "sd": 0.5, "low": 0.5, "high": 2.0}
    err = refused(raw, distributions__chassis_tilt_deg=tilt, calibrate__fit={"air_share": [0.0, 1.0]})
    assert err.key == "distributions.chassis_tilt_deg" and "must include level" in str(err)


def test_the_memory_verdict_is_the_same_on_any_machine(raw, monkeypatch):
    import pipeline.resources as resources

    monkeypatch.setattr(resources, "available_memory", lambda: 1)  # a machine with no memory free: same verdict
    parse_config(changed(raw, fleet__n_bogies=4_000_000))
    assert MEMORY_BUDGET == 16 * 2**30


# ---- item 5: resources ------------------------------------------------------------------------------------------
def test_an_absurd_worker_count_is_refused(raw):
    err = refused(raw, execution__n_jobs=4096)
    assert err.key == "execution.n_jobs" and f"[1, {MAX_JOBS}]" in str(err)


def test_calibrate_runs_its_workers_through_the_shared_cap(monkeypatch):
    seen = []

    class FakePool:  # simulate's pool of loky workers, as pipeline.workers.local_executor gives it
        def submit(self, f, *args):
            done = Future()
            done.set_result(f(*args))
            return done

    def fake_executor(max_workers):
        seen.append(max_workers)
        return FakePool()

    monkeypatch.setattr(workers, "local_executor", fake_executor)
    monkeypatch.setattr(calibration_table, "_weigh_kg", lambda *task: [1.0, 2.0, 3.0])
    monkeypatch.setattr(calibrate, "worker_count", lambda n, log, stage: worker_count(n, log, stage, cores=2))
    execution = load_config(PARAMS).execution
    mapper = calibrate.workers_map(dataclasses.replace(execution, n_jobs=16))
    loads = calibration_table.weigh_readings([({}, "static", None)] * 40, mapper)
    assert loads.shape == (40, 3)
    assert seen == [1]  # 16 asked, 2 cores: 2 processes (a worker and this one), not 16


def test_worker_cap_is_the_cores_and_the_free_memory():
    logged = []
    assert worker_count(16, logged.append, "calibrate", cores=2, memory=64 * 2**30) == 2
    assert "calibrate: warning: execution.n_jobs = 16" in logged[0]
    assert worker_count(8, logged.append, "simulate", cores=64, memory=3 * 300 * 2**20) == 3


@pytest.mark.parametrize("which", ["bomb", "deep"])
def test_an_alias_bomb_or_deep_nesting_is_refused_quickly_with_a_message(tmp_path, which):
    text = PARAMS.read_text()
    if which == "bomb":
        bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n"
        bomb += "".join(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]\n" for i in range(1, 10))
        text = text.replace("seed: 20261122", "seed: *a9").replace("figure2:", bomb + "figure2:")
    else:
        text = text.replace("seed: 20261122", "seed: " + "[" * 5000 + "]" * 5000)
    path = tmp_path / "params.yaml"
    path.write_text(text)
    start = time.perf_counter()
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert time.perf_counter() - start < 1.0
    assert ("aliases are expanded" if which == "bomb" else "nested more than 32 levels") in str(err.value)
    assert len(str(err.value)) < 300


def test_a_huge_value_is_shown_cut_short(raw):
    err = refused(raw, seed=[list(range(1000))] * 1000)
    line = str(err).splitlines()[0]
    assert line.startswith("seed = [[0, 1, 2") and "..." in line and len(line) < 200


# ---- item 7: messages -------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("values", "key", "words"),
    [
        ({"calibrate__fit": {}}, "calibrate.fit", ["at least one quantity to fit", "chassis_tilt_mean_deg"]),
        ({"calibrate__fit": {"air_share": 1.0}}, "calibrate.fit.air_share", ["[low, high]"]),
        ({"design__grid": {}}, "design.grid", ["at least one design factor", "bush_stiffness"]),
        ({"design__grid": {"bush_stiffness": 3.0}}, "design.grid.bush_stiffness", ["list of one or more levels"]),
    ],
)
def test_every_refusal_says_what_is_expected(raw, values, key, words):
    err = refused(raw, **values)
    assert err.key == key and "another form" not in str(err)
    for word in words:
        assert word in str(err)


def test_the_hint_for_a_nan_parameter_names_the_quantitys_range(raw):
    tilt = {"kind": "uniform", "low": float("nan"), "high": 2.0}
    err = refused(raw, distributions__chassis_tilt_deg=tilt)
    assert err.key == "distributions.chassis_tilt_deg.low"
    assert "not a finite number" in str(err) and "[-10, 10] degree" in str(err)


def test_a_calibration_that_will_not_run_is_not_checked_against_the_fleet(raw):
    # no survey: the calibrate stage skips, so a fleet smaller than calibrate.n_bogies (300) is not refused
    assert parse_config(changed(raw, fleet__n_bogies=250, ablation__n_bogies=100)).calibrate.n_bogies == 300


def test_a_rule_between_keys_is_reported_with_the_other_errors(raw):
    no_site = {"protocol__wim__site_length_before_m": 0.0, "protocol__wim__site_length_after_m": 0.0}
    err = refused(raw, sensitivity__base_size=500, protocol__run=["wim"], **no_site, **SURVEY)
    keys = [key for key, _ in err.errors]
    assert keys == ["sensitivity.base_size", "sensitivity.protocol", "calibrate.fit.site_iri_m_km"]


def test_the_schema_alone_enforces_the_rules(raw):
    with pytest.raises(ValueError, match="is not run: protocol.run lists only wim"):
        Params.model_validate(changed(raw, protocol__run=["wim"]))


def test_one_switch_makes_a_small_study_the_sizes_that_reuse_fleet_bogies_follow_it(raw):
    # issue 31: the README's `dvc exp run --temp -S fleet.n_bogies=100` stopped at "ablation.n_bogies = 500: must
    # not exceed fleet.n_bogies = 100"; the ablation and the calibration fleet now take at most the fleet's bogies
    config = parse_config(changed(raw, fleet__n_bogies=100, **SURVEY))
    assert config.ablation.n_bogies == 500 and config.calibrate.n_bogies == 300  # as written; used at most 100
    from pipeline.sample import VARIANTS, sample_ablation, sample_fleet

    fleet = sample_fleet(config)
    ablation = sample_ablation(config, fleet)
    assert len(fleet) == 100 and len(ablation) == 100 * len(VARIANTS)  # the default fleet is all steel
    assert len(calibrate.calibration_samples(config)) == 100


def test_config_json_gives_each_distribution_its_kind_and_no_section_or_protocol_one():
    """data/config.json's shape: a distribution is tagged by its kind; the sections and the protocols' settings (now
    bogie.fleet classes, not pipeline.config.settings ones) are plain objects, as before they moved."""
    from pipeline.validate import as_json

    config = as_json(load_config(Path(__file__).resolve().parents[2] / "params.yaml"))
    assert config["distributions"]["chassis_tilt"]["kind"] == "truncnormal"
    assert config["distributions"]["road_class"]["kind"] == "choice"
    assert "kind" not in config["protocol"]["static"] and "kind" not in config["protocol"]["wim"]
    assert "kind" not in config["fleet"] and config["protocol"]["wim"]["sensor"] == "quartz"
