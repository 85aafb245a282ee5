"""One name and one unit per thing (issue 31 item 7): the stems of params.yaml's keys are the data's column names,
a suffix states a unit other than SI, and axles count from 1 wherever a name or a file numbers them."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bogie.fleet.sampling.sample import TYRE_WEAR_COLUMNS
from bogie.fleet.weighing.runs import RESULT_COLUMNS, UNITS
from bogie.weighings.groups import axle_groups
from bogie.weighings.readers import read_weighings
from bogie.weighings.stats import STATISTICS_COLUMNS, statistics_dict, survey_statistics
from pipeline.config import load_params

ROOT = Path(__file__).resolve().parents[2]
#: a params.yaml suffix -> the SI unit of the same quantity in the data (docs/outputs.md)
SUFFIX_SI = {"_mm": "m", "_kn": "N", "_deg": "rad"}


def _stem(key: str) -> tuple[str, str | None]:
    for suffix in SUFFIX_SI:
        if key.endswith(suffix):
            return key.removesuffix(suffix), suffix
    return key, None


@pytest.mark.parametrize("key", list(load_params(ROOT / "params.yaml")["distributions"]))
def test_every_sampled_quantity_has_one_name_its_unit_in_the_suffix(key):
    stem, suffix = _stem(key)
    columns = TYRE_WEAR_COLUMNS if stem == "tyre_wear" else (stem,)
    for column in columns:
        assert column in UNITS, f"params.yaml's {key} has no column {column} in the runs"
        if suffix is not None:  # the data holds the SI unit the suffix converts from
            assert UNITS[column] == SUFFIX_SI[suffix], (key, column, UNITS[column])


def test_numbered_columns_count_axles_from_one():
    numbered = [c for c in UNITS if re.search(r"_\d+$", c)]
    assert numbered, "the runs have axle-numbered columns"
    families: dict[str, list[int]] = {}
    for c in numbered:
        stem, k = c.rsplit("_", 1)
        families.setdefault(stem, []).append(int(k))
    assert set(families) == {"axle_load", "load_share", "tyre_wear"}
    for stem, ks in families.items():
        assert sorted(ks) == list(range(1, len(ks) + 1)), (stem, ks)
    assert RESULT_COLUMNS[0] == "axle_load_1"


def test_a_record_files_axle_numbers_are_the_tables_and_the_statistics_json(tmp_path):
    # a CSV names its axles axle_load_1..n (docs/weighings.md): the table read from it keeps the same names, and
    # the statistics' quantiles name axle k as "axle_k"
    path = tmp_path / "two.csv"
    path.write_text(
        "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,axle_load_3,axle_load_4,axle_load_5,"
        "spacing_1,spacing_2,spacing_3,spacing_4\n"
        "2026-01-05T06:00:00,80,1,5,6000,9000,8000,8200,7800,3.6,5.2,1.31,1.31\n"
        "2026-01-05T06:00:05,80,1,5,6100,9100,8100,8100,8100,3.6,5.2,1.31,1.31\n"
    )
    result = read_weighings(path, "csv")
    assert [c for c in result.vehicles.columns if c.startswith("axle_load_")] == [f"axle_load_{k}" for k in range(1, 6)]
    assert result.vehicles.loc[0, "axle_load_1"] == 6000.0 and result.vehicles.loc[0, "spacing_3"] == 1.31
    groups = axle_groups(result.vehicles, 2.0)
    tri = groups[groups["n_axles"] == 3].iloc[0]
    # the third group of the vehicle (1 = front), starting at its third axle (1 = front)
    assert (tri["group_index"], tri["first_axle"]) == (3, 3)
    assert (tri["axle_load_1"], tri["axle_load_3"]) == (8000.0, 7800.0)
    stats = survey_statistics(groups[groups["n_axles"] == 3].assign(group="triaxle"), by="group")
    assert "share_over_10pct" in STATISTICS_COLUMNS and "share_over_10pct" in stats.columns
    assert not [c for c in stats.columns if "outside_10pct" in c]  # one name for the 10 % flag
    # the JSON's axle k is the table's load_share_k: the middle axle carries 8200 / 8000 = 1.025 in the first tri-axle
    # and 1.0 in the second (8100 each), median 1.0125
    quantiles = statistics_dict(stats)["triaxle"]["load_share_quantiles"]
    assert set(quantiles) == {"axle_1", "axle_2", "axle_3"}
    assert quantiles["axle_2"]["p50"] == pytest.approx(1.0125, abs=1e-4)
