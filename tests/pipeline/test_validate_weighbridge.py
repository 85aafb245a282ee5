"""Issue 31, item 8: calibrating to a weighbridge file is one switch, ``observed.kind: weighbridge``.

Before, it took four edits beside the file's path: ``calibrate.protocol: static``, and deleting
``calibrate.fit.site_iri_m_km`` and ``calibrate.fit.sensor_error_pct``, which validate refused for a static
calibration one at a time. Now ``calibrate.protocol: auto`` follows the file's kind, and a static calibration leaves
the WIM quantities out with one line saying so.
"""

import copy
import json
import math
from pathlib import Path

import pytest
import yaml
from test_validate_costs import changed

from bogie.fleet.constants import WIM_QUANTITIES
from pipeline import calibrate, validate
from pipeline.config import ConfigError, load_params, parse_config
from pipeline.config.rules import View, calibration_runs
from pipeline.config.schema import Params

PARAMS = Path(__file__).resolve().parents[2] / "params.yaml"
NOTE = (
    "a static calibration (observed.kind is weighbridge): calibrate.fit's site_iri_m_km, sensor_error_pct, "
    "site_bias_pct left out, a weighbridge has no WIM site or sensor; fitting chassis_tilt_mean_deg, "
    "chassis_tilt_sd_deg, air_share"
)


@pytest.fixture(scope="module")
def raw():
    return load_params(PARAMS)


def without(raw, path):
    """A deep copy of ``raw`` without the dotted key ``path`` (a params.yaml written before the key)."""
    new = copy.deepcopy(raw)
    *parents, last = path.split(".")
    node = new
    for key in parents:
        node = node[key]
    del node[last]
    return new


def fit_of(raw, drop=()):
    return {name: tuple(bounds) for name, bounds in raw["calibrate"]["fit"].items() if name not in drop}


def test_the_default_file_calibrates_a_wim_file_and_follows_the_kind(raw):
    assert raw["observed"]["kind"] == "wim" and raw["calibrate"]["protocol"] == "auto"


def test_one_switch_gives_the_static_calibration_the_stage_builds(raw):
    notes = []
    config = parse_config(changed(raw, observed__path="observed/wb.csv", observed__kind="weighbridge"), notes.append)
    assert config.observed.kind == "weighbridge"
    assert config.calibrate.protocol == "static"
    assert dict(config.calibrate.fit) == fit_of(raw, drop=WIM_QUANTITIES)
    assert notes == [NOTE]
    # what the calibrate stage hands the library: the fit without the WIM quantities, a static table
    assert calibrate.method_settings(config).fit == fit_of(raw, drop=WIM_QUANTITIES)
    table = calibrate.crn_table(config)
    assert table.protocol == "static" and table.settings == config.protocol.static
    assert len(table.iris) == 1 and math.isnan(table.iris[0])  # no site roughness to tabulate
    # and validate's bound on the table's runs counts no roughness levels
    runs, how = calibration_runs(
        View(Params, changed(raw, observed__path="observed/wb.csv", observed__kind="weighbridge"))
    )
    assert how.endswith("x 1 site roughnesses") and runs == 300 * 2 * 17


def test_a_wim_file_still_gets_the_wim_calibration(raw):
    notes = []
    config = parse_config(changed(raw, observed__path="observed/site.mon"), notes.append)
    assert (config.observed.kind, config.calibrate.protocol) == ("wim", "wim")
    assert dict(config.calibrate.fit) == fit_of(raw) and notes == []
    assert calibrate.method_settings(config).fit == fit_of(raw)
    table = calibrate.crn_table(config)
    assert table.protocol == "wim" and table.settings == config.protocol.wim
    assert table.iris.tolist() == raw["calibrate"]["site_iri_levels_m_km"]
    runs, how = calibration_runs(View(Params, changed(raw, observed__path="observed/site.mon")))
    assert how.endswith("x 3 site roughnesses") and runs == 300 * 2 * 17 * 3


def test_a_file_written_before_the_switch_reads_as_before(raw):
    # no observed.kind: a WIM file; calibrate.protocol as written wins, and the old way to a static calibration
    # (calibrate.protocol: static) now needs no edit of calibrate.fit either
    config = parse_config(without(changed(raw, calibrate__protocol="wim"), "observed.kind"))
    assert (config.observed.kind, config.calibrate.protocol) == ("wim", "wim")
    notes = []
    config = parse_config(without(changed(raw, calibrate__protocol="static"), "observed.kind"), notes.append)
    assert config.calibrate.protocol == "static" and dict(config.calibrate.fit) == fit_of(raw, drop=WIM_QUANTITIES)
    assert notes == [NOTE.replace("observed.kind is weighbridge", "calibrate.protocol is static")]


def test_a_protocol_named_overrides_the_kind(raw):
    config = parse_config(changed(raw, observed__kind="weighbridge", calibrate__protocol="wim"))
    assert config.calibrate.protocol == "wim" and dict(config.calibrate.fit) == fit_of(raw)


def test_a_static_calibration_with_only_wim_quantities_is_refused(raw):
    with pytest.raises(ConfigError) as err:
        parse_config(changed(raw, observed__kind="weighbridge", calibrate__fit={"sensor_error_pct": [0.0, 5.0]}))
    assert err.value.key == "calibrate.fit"
    assert str(err.value) == (
        "calibrate.fit = {'sensor_error_pct': [0.0, 5.0]}: names only WIM quantities, which a static calibration "
        "(observed.kind is weighbridge) does not fit: a weighbridge has no WIM site or sensor; name one of "
        "chassis_tilt_mean_deg, chassis_tilt_sd_deg, air_share, contact_roll_radius_mean_mm, bush_stiffness_geomean"
    )


def test_an_unknown_kind_is_named_with_the_kinds_allowed(raw):
    with pytest.raises(ConfigError, match=r"observed.kind = 'static': unknown survey kind: must be one of wim, weigh"):
        parse_config(changed(raw, observed__kind="static"))


def test_the_validate_stage_writes_the_static_calibration_and_says_what_it_left_out(raw, tmp_path, capsys):
    (tmp_path / "observed").mkdir()
    # weighbridge records: a static weighing has no speed (docs/weighings.md, the CSV layout)
    (tmp_path / "observed" / "wb.csv").write_text(
        "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,spacing_1\n2026-01-05T06:00:00,,1,2,8000,9000,1.31\n"
    )
    params = tmp_path / "params.yaml"
    params.write_text(
        yaml.safe_dump(changed(raw, observed__path="observed/wb.csv", observed__kind="weighbridge"), sort_keys=False)
    )
    out = tmp_path / "data" / "config.json"
    assert validate.main(["--params", str(params), "--out", str(out)]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"validate: {params} is valid; wrote {out}",
        f"validate: {NOTE}",
    ]
    written = json.loads(out.read_text())
    assert written["observed"]["kind"] == "weighbridge" and written["calibrate"]["protocol"] == "static"
    assert list(written["calibrate"]["fit"]) == list(fit_of(raw, drop=WIM_QUANTITIES))
