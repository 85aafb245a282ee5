"""Issue 31, item 8: validate names every wrong key of params.yaml at once, and no check repeats a reported one.

Before, a rule within a section (a group's payload, a protocol phase's steps, the calibration's bounds, the design
grid's levels) was a pydantic model validator: it stopped at its first broken case, and pydantic ran it only once
every other key of its section was valid; and validate looked for the observed survey's file only once the whole
file was valid. A user fixing params.yaml got the errors a few at a time.
"""

from pathlib import Path

import pytest
import yaml
from test_validate_costs import changed

from pipeline import validate
from pipeline.config import ConfigError, check_params, load_params, parse_config

PARAMS = Path(__file__).resolve().parents[2] / "params.yaml"


@pytest.fixture(scope="module")
def raw():
    return load_params(PARAMS)


def refused(raw, **values) -> ConfigError:
    with pytest.raises(ConfigError) as err:
        parse_config(changed(raw, **values))
    return err.value


#: independent mistakes all over the file: an unknown key, values out of range, a bad distribution, rules within
#: sections (one next to a bad key of its own section) and a rule between sections
MISTAKES = {
    "observed__postion": "trailer",
    "protocol__wim__speed_m_s": 80.0,
    "distributions__bush_stiffness": {"kind": "uniform", "low": 10.0, "high": 1.0},
    "fleet__n_bogies": -5,
    "fleet__legal_group_load_t": {"tandem": 0.5, "triaxle": 1.0},
    "protocol__wim__site_length_before_m": 100.0,
    "protocol__run": ["static"],
    "calibrate__maxiter": 0,
    "calibrate__fit": {"air_share": [1.0, 0.0], "sensor_error_pct": [0.0, 99.0], "payload": [0.0, 1.0]},
    "design__grid": {"bush_stiffness": [1.0, 1.0], "equaliser_arm_mm": [1.0, 250.0]},
    "execution__backend": "dask",
    "execution__n_jobs": 0,
}

#: the line of each mistake: its key, its value, and what is allowed with its unit
LINES = {
    "observed.postion": "unknown key observed.postion (did you mean position?): observed takes path, kind, format",
    "fleet.n_bogies": "fleet.n_bogies = -5: must be an integer in [1, 10000000]",
    "distributions.bush_stiffness.high": "distributions.bush_stiffness.high = 1.0: must be greater than low = 10.0, "
    "in N m/rad",
    "protocol.wim.speed_m_s": "protocol.wim.speed_m_s = 80.0: must be a number in [1, 50] m/s",
    "execution.n_jobs": "execution.n_jobs = 0: must be an integer in [1, 256]",
    "calibrate.maxiter": "calibrate.maxiter = 0: must be an integer in [1, 10000]",
    "fleet.legal_group_load_t.tandem": "fleet.legal_group_load_t.tandem = 0.5: must exceed the unsprung mass of the "
    "tandem_trrl axles, 1.2 t",
    "fleet.legal_group_load_t.triaxle": "fleet.legal_group_load_t.triaxle = 1.0: must exceed the unsprung mass of the "
    "triaxle_stage1 axles, 1.8 t",
    "protocol.wim.site_length_before_m": "protocol.wim.site_length_before_m = 100.0: must not exceed "
    "approach_length_m = 60 m",
    "execution.dask_scheduler": "execution.dask_scheduler = None: backend dask needs the scheduler: an address",
    "calibrate.fit.air_share": "calibrate.fit.air_share = [1.0, 0.0]: bounds inverted or equal: low must be below "
    "high [-]",
    "calibrate.fit.sensor_error_pct": "calibrate.fit.sensor_error_pct = [0.0, 99.0]: must lie within [0, 30] %",
    "calibrate.fit.payload": "calibrate.fit.payload = [0.0, 1.0]: is not a fleet quantity calibrate can fit",
    "design.grid.bush_stiffness": "design.grid.bush_stiffness = [1.0, 1.0]: lists a level twice",
    "design.grid.equaliser_arm_mm[0]": "design.grid.equaliser_arm_mm[0] = 1.0: is outside the allowed range "
    "[50, 500] mm of equaliser_arm",
    "sensitivity.protocol": "sensitivity.protocol = 'wim': is not run: protocol.run lists only static",
}


def test_independent_mistakes_are_all_named_in_one_error_one_line_each(raw):
    err = refused(raw, **MISTAKES, sensitivity__protocol="wim")
    keys = [key for key, _ in err.errors]
    # the unknown key first; the field errors, then the rules within sections, then those between sections, each in
    # the order of the file's sections
    assert keys == list(LINES)
    lines = str(err).splitlines()
    assert len(lines) == len(LINES)
    for line, start in zip(lines, LINES.values()):
        assert line.startswith(start), (line, start)


def test_a_rule_within_a_section_is_checked_next_to_a_bad_key_of_its_section(raw):
    # pydantic runs a section's model validator only once all its fields are valid: the payload, the WIM site, the
    # dask scheduler and the calibration bounds were hidden by the bad key beside them
    err = refused(
        raw,
        fleet__n_bogies=0,
        fleet__legal_group_load_t={"tandem": 0.5, "triaxle": 24.0},
        protocol__wim__sensor="laser",
        protocol__wim__site_length_before_m=100.0,
        execution__backend="dask",
        execution__chunk_size=0,
        calibrate__popsize=1,
        calibrate__fit={"air_share": [0.8, 0.2]},
    )
    assert [key for key, _ in err.errors] == [
        "fleet.n_bogies",
        "protocol.wim.sensor",
        "execution.chunk_size",
        "calibrate.popsize",
        "fleet.legal_group_load_t.tandem",
        "protocol.wim.site_length_before_m",
        "execution.dask_scheduler",
        "calibrate.fit.air_share",
    ]


def test_every_broken_entry_of_a_mapping_is_named_not_the_first(raw):
    grid = {"bush_stiffness": [1.0, 9e9], "contact_roll_radius_mm": [0.0, 0.0], "arm": [150.0]}
    fit = {"chassis_tilt_mean_deg": [2.0, -2.0], "air_share": [0.0, 2.0], "chassis_tilt_sd_deg": [0.1, 1.5]}
    err = refused(raw, design__grid=grid, calibrate__fit=fit)
    assert [key for key, _ in err.errors] == [
        "calibrate.fit.chassis_tilt_mean_deg",
        "calibrate.fit.air_share",
        "design.grid.bush_stiffness[1]",
        "design.grid.contact_roll_radius_mm",
        "design.grid.arm",
    ]


def test_a_bad_entry_of_a_mapping_leaves_the_others_to_check(raw):
    # the type error of one fit quantity's bounds; the other's rule is still checked
    err = refused(raw, calibrate__fit={"air_share": [0.0, "one"], "chassis_tilt_sd_deg": [1.5, 0.1]})
    assert [key for key, _ in err.errors] == ["calibrate.fit.air_share[1]", "calibrate.fit.chassis_tilt_sd_deg"]


# ---- one mistake, one line: a check that reads a value already reported bad does not run ---------------------------
def test_a_check_that_reads_a_reported_value_is_skipped(raw):
    # the site's roughness is held against the levels only if the levels themselves are good
    err = refused(raw, calibrate__site_iri_levels_m_km=[1.0, 4.0, 2.0], calibrate__fit={"site_iri_m_km": [0.5, 5.0]})
    assert [key for key, _ in err.errors] == ["calibrate.site_iri_levels_m_km"]
    # a tilt quantity's bounds found inverted are not held against the tilt distribution's bounds too
    err = refused(raw, calibrate__fit={"chassis_tilt_mean_deg": [3.0, -3.0]}, observed__path="observed/site.csv")
    assert [key for key, _ in err.errors] == ["calibrate.fit.chassis_tilt_mean_deg"]
    # a preset that is not one: that group's payload is not checked, the other group's is
    err = refused(raw, fleet__presets={"tandem": "tandem_x", "triaxle": "triaxle_stage1"},
                  fleet__legal_group_load_t={"tandem": 0.5, "triaxle": 1.0})  # fmt: skip
    assert [key for key, _ in err.errors] == ["fleet.presets.tandem", "fleet.legal_group_load_t.triaxle"]


def test_a_time_step_too_small_for_every_phase_is_one_line(raw):
    # the static phases share dt_s: one line says to raise it, not one per phase
    err = refused(raw, protocol__static__dt_s=1e-7)
    assert [key for key, _ in err.errors] == ["protocol.static.load_time_s"]
    assert "20,000,000 steps of 1e-07 s" in str(err) and "raise dt_s" in str(err)
    # a phase too long on its own, with the step fine for the others
    err = refused(raw, protocol__static__dt_s=1e-4, protocol__static__settle_time_s=500.0)
    assert [key for key, _ in err.errors] == ["protocol.static.settle_time_s"]


# ---- the validate stage ------------------------------------------------------------------------------------------
def test_validate_names_a_missing_survey_file_with_the_bad_keys_and_writes_nothing(raw, tmp_path, capsys):
    params = tmp_path / "params.yaml"
    bad = changed(raw, **MISTAKES, sensitivity__protocol="wim", observed__path="observed/none.csv")
    params.write_text(yaml.safe_dump(bad, sort_keys=False))
    out = tmp_path / "data" / "config.json"
    assert validate.main(["--params", str(params), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert lines[0].startswith(f"validate: {params}: unknown key observed.postion")
    assert lines[-1].startswith("observed.path = 'observed/none.csv': no such file")
    assert len(lines) == len(LINES) + 1
    assert not out.exists() and not out.parent.exists()


def test_a_survey_path_the_schema_refuses_is_named_once_and_no_file_is_looked_for(raw, tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump(changed(raw, observed__path="/etc/passwd", fleet__n_bogies=0)))
    with pytest.raises(ConfigError) as err:
        check_params(params)
    assert [key for key, _ in err.value.errors] == ["fleet.n_bogies", "observed.path"]
    assert "a file or folder in observed/" in str(err.value) and "no such file" not in str(err.value)
