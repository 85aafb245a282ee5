"""fleet.suspension_mix: air-sprung groups in the fleet, through the same protocols, the survey split by kind."""

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from bogie.air import AirBogie
from bogie.fleet.sampling.sample import bogie_from_sample
from pipeline.config import ConfigError, parse_config
from pipeline.sample import VARIANTS, sample_ablation, sample_fleet
from pipeline.simulate import run_chunk, study_protocols

ROOT = Path(__file__).resolve().parents[2]


def raw(air=0.0, n_bogies=200):
    params = yaml.safe_load((ROOT / "params.yaml").read_text())
    params["fleet"]["n_bogies"] = n_bogies
    params["ablation"]["n_bogies"] = 20
    params["fleet"]["suspension_mix"] = {g: {"steel": 1.0 - air, "air": air} for g in ("tandem", "triaxle")}
    return params


def test_the_air_share_changes_only_the_suspension_column_and_only_steel_to_air():
    steel = sample_fleet(parse_config(raw(0.0)))
    half = sample_fleet(parse_config(raw(0.5)))
    more = sample_fleet(parse_config(raw(0.8)))
    assert (steel["suspension"] == "steel").all()
    others = [c for c in steel.columns if c != "suspension"]
    assert steel[others].equals(half[others]) and steel[others].equals(more[others])
    share = (half["suspension"] == "air").mean()
    assert abs(share - 0.5) < 3 * math.sqrt(0.25 / len(half))
    # a higher share turns steel groups into air ones, never back (common random numbers for calibrate)
    assert ((half["suspension"] == "air") <= (more["suspension"] == "air")).all()


def test_the_mix_must_sum_to_one_per_group():
    params = raw()
    params["fleet"]["suspension_mix"]["triaxle"] = {"steel": 0.6, "air": 0.6}
    with pytest.raises(ConfigError, match="suspension_mix.triaxle"):
        parse_config(params)


def test_an_air_row_is_the_air_group_on_the_steel_groups_trailer():
    fleet = sample_fleet(parse_config(raw(1.0)))
    row = fleet.iloc[0].to_dict()
    air = bogie_from_sample(row)
    steel = bogie_from_sample({**row, "suspension": "steel"})
    assert isinstance(air, AirBogie)
    assert air.axle_x == steel.axle_x and air.payload_mass == steel.payload_mass
    assert air.chassis_tilt == row["chassis_tilt"] and air.tyre_wear == steel.tyre_wear


def test_the_ablation_takes_steel_groups_only_and_says_when_too_few():
    config = parse_config(raw(0.5))
    fleet = sample_fleet(config)
    ablation = sample_ablation(config, fleet)
    assert (ablation["suspension"] == "steel").all()
    assert set(ablation["base_id"]) <= set(fleet.loc[fleet["suspension"] == "steel", "sample_id"])
    # fewer steel bogies than ablation.n_bogies: all of them (the size follows the fleet, issue 31)
    params = raw(0.5, n_bogies=30)
    params["ablation"]["n_bogies"] = 25
    config = parse_config(params)
    fleet = sample_fleet(config)
    steel = int((fleet["suspension"] == "steel").sum())
    assert 0 < steel < 25 and len(sample_ablation(config, fleet)) == steel * len(VARIANTS)
    # no steel bogie at all: nothing to ablate, said naming the mix
    config = parse_config(raw(1.0, n_bogies=30))
    with pytest.raises(ConfigError, match="fleet.suspension_mix = .* no steel-equalised bogie"):
        sample_ablation(config, sample_fleet(config))


def test_air_groups_go_through_both_protocols_and_share_better_when_tilted():
    config = parse_config(raw(0.5, n_bogies=40))
    fleet = sample_fleet(config)
    # tri-axles tilted 1.5 degree nose up: the steel ones part their loads, the air ones hardly
    rows = fleet[fleet["group"] == "triaxle"].copy()
    rows["chassis_tilt"] = math.radians(1.5)
    rows = rows.groupby("suspension").head(3).sort_values("sample_id")
    runs = run_chunk(rows, study_protocols(config, "fleet"))
    assert (runs["status"] == "ok").all(), runs.loc[runs["status"] != "ok", "message"].tolist()
    static = runs[runs["protocol"] == "static"]
    by_kind = static.groupby(static["suspension"].astype(str))["max_deviation"].max()
    assert by_kind["air"] < 0.02 < by_kind["steel"]
    air_rows = runs[runs["suspension"].astype(str) == "air"]
    assert not air_rows["equaliser_on_stop"].astype(bool).any()
    assert np.isfinite(air_rows["axle_load_2"]).all()
