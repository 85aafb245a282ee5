"""The surveyed groups spilled to disk give the statistics and road figures of the same groups held in memory (issue
41 Must 4): counts, shares, medians, quantiles and wear to the bit, the mean spread to 1e-12, whatever the blocks
the spill is read in and however many passes the order statistics take."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from bogie.weighings import _spill
from bogie.weighings._spill import GroupSpill, spilled_statistics, spilled_wear
from bogie.weighings.legal import POSITIONS
from bogie.weighings.stats import survey_statistics
from bogie.weighings.wear import wear_statistics


def groups(m: int, seed: int, step: float, stations: int = 1) -> pd.DataFrame:
    """``m`` tandems and tri-axles, loads at ``step`` kg (at 100 kg many ties), ``stations`` station codes, each at a
    position and spacings across 96/53/EC's bands (so that the limits differ from group to group)."""
    rng = np.random.default_rng(seed)
    loads = (rng.normal(8000.0, 900.0, (m, 3)) / step).round() * step
    n = rng.integers(2, 4, m)
    loads[n == 2, 2] = np.nan
    return pd.DataFrame({
        "group": np.where(n == 2, "tandem", "triaxle"), "n_axles": n, "station_code": rng.integers(0, stations, m),
        **{f"axle_load_{i + 1}": loads[:, i] for i in range(3)},
        "position": rng.choice(["steer", "drive", "trailer"], m),
        "spacing_1": rng.choice([0.9, 1.2, 1.3, 1.5, 1.9], m), "spacing_2": rng.choice([1.3, 1.4], m),
    })  # fmt: skip


def spilled(table: pd.DataFrame) -> GroupSpill:
    spill = GroupSpill()
    for part in np.array_split(np.arange(len(table)), 7):  # chunks as a stream gives them
        rows = table.iloc[part]
        spill.append(
            rows["n_axles"].to_numpy(),
            rows["station_code"].to_numpy(),
            rows[["axle_load_1", "axle_load_2", "axle_load_3"]].to_numpy(),
            rows["position"].map(POSITIONS.index).to_numpy(),
            rows[["spacing_1", "spacing_2"]].to_numpy(),
        )
    return spill


def same_statistics(got: pd.DataFrame, want: pd.DataFrame) -> None:
    assert list(got.columns) == list(want.columns)
    for column in want.columns:
        if column == "mean_spread_kg":
            assert got[column].to_numpy() == pytest.approx(want[column].to_numpy(), rel=1e-12)
        else:  # to the bit (NaN where a tandem has no third axle)
            np.testing.assert_array_equal(got[column].to_numpy(), want[column].to_numpy(), err_msg=column)


@pytest.mark.parametrize(("m", "step"), [(1, 1.0), (2, 1.0), (3, 100.0), (5_000, 1.0), (5_000, 100.0)])
def test_the_statistics_of_the_spill_are_the_tables(monkeypatch, m, step):
    table = groups(m, seed=m, step=step)
    monkeypatch.setattr(_spill, "SPILL_BLOCK", 700)  # many blocks
    monkeypatch.setattr(_spill, "_BINS_TOTAL", 64)  # 16 bins a rank: several passes to every order statistic
    spill = spilled(table)
    try:
        got = spilled_statistics(spill)
    finally:
        spill.close()
    same_statistics(got, survey_statistics(table.drop(columns="station_code"), by="group"))
    assert not spill.dir.exists()


def test_the_statistics_of_each_station_from_the_spill_are_its_tables():
    table = groups(3_000, seed=4, step=10.0, stations=4)
    table = table[table["station_code"] != 2]  # a station code with no group
    spill = spilled(table)
    got = spilled_statistics(spill, by_station=True)
    spill.close()
    want = survey_statistics(table, by=["station_code", "group"])
    same_statistics(got, want)


@pytest.mark.parametrize("largest", [20_000, 500])  # every size bootstrapped; both by the delta method
def test_the_road_figures_of_the_spill_are_the_tables(monkeypatch, largest):
    table = groups(4_000, seed=8, step=100.0)
    monkeypatch.setattr(_spill, "SPILL_BLOCK", 900)
    spill = spilled(table)
    got = spilled_wear(spill, spacing_step_m=0.1, resamples=200, bootstrap_max_groups=largest)
    stated = spilled_wear(spill, {"tandem": 17_000.0, "triaxle": 23_000.0}, 9_000.0, resamples=200)
    spill.close()
    kept = table.drop(columns="station_code")
    want = wear_statistics(kept, spacing_step_m=0.1, resamples=200, bootstrap_max_groups=largest)
    same = wear_statistics(kept, {"tandem": 17_000.0, "triaxle": 23_000.0}, 9_000.0, resamples=200)
    for column in same.columns:
        np.testing.assert_array_equal(stated[column].to_numpy(), same[column].to_numpy(), err_msg=column)
    assert 0 < want["n_hidden"].sum() < want["n_groups"].sum()  # the limits by position and spacing judge some
    assert list(got.columns) == list(want.columns)
    for column in want.columns:
        np.testing.assert_array_equal(got[column].to_numpy(), want[column].to_numpy(), err_msg=column)


def test_an_order_statistic_is_found_among_ties_and_extremes():
    # ranks at a bin's first and last value, among ties, and a value far from the rest (one wide bin)
    table = pd.DataFrame({"group": "tandem", "n_axles": 2, "station_code": 0, "axle_load_3": np.nan,
                          "axle_load_1": [5000.0] * 6 + [5001.0, 5002.0, 9000.0, 40000.0],
                          "axle_load_2": 5000.0, "position": "trailer", "spacing_1": 1.3,
                          "spacing_2": np.nan})  # fmt: skip
    spill = spilled(table)
    got = spilled_statistics(spill)
    spill.close()
    same_statistics(got, survey_statistics(table.drop(columns="station_code"), by="group"))


def test_the_interpolation_is_pandas_to_the_bit():
    rng = np.random.default_rng(12)
    for _ in range(2_000):
        x = rng.normal(1.0, 0.1, rng.integers(1, 50))
        p = float(rng.choice([rng.random(), 0.05, 0.25, 0.5, 0.75, 0.95, 0.0, 1.0]))
        ordered = np.sort(x)
        assert _spill._quantile(len(x), p, lambda r, o=ordered: float(o[r])) == pd.Series(x).quantile(p)


def test_values_outside_the_quantities_bounds_are_still_found(monkeypatch):
    # a negative load (no reader passes one) puts a share above 3 and a spread above 300 %: outside the first
    # histograms' bounds, so those ranks start from the values' range
    table = groups(400, seed=5, step=1.0)
    table.loc[table.index[:150], "axle_load_1"] = -4000.0
    monkeypatch.setattr(_spill, "_BINS_TOTAL", 64)
    spill = spilled(table)
    got = spilled_statistics(spill)
    spill.close()
    same_statistics(got, survey_statistics(table.drop(columns="station_code"), by="group"))
