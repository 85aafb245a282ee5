"""AASHTO 1993's flexible-pavement load equivalence factors against the guide's published values (issue 44 Must 2),
and the refusals of bad arguments."""

import math

import numpy as np
import pandas as pd
import pytest

from bogie.weighings.pavement import (
    AUSTROADS_GROUP_LOAD_KN,
    KIPS_PER_KG,
    aashto_flexible_lef,
    aashto_view,
    group_baseline_factor,
    sharing_factors,
    write_sharing_factors,
)  # fmt: skip
from bogie.weighings.wear import DAMAGE_EXPONENTS, wear_statistics


@pytest.mark.parametrize(
    ("kips", "axles", "sn", "published", "places"),
    [
        (40.0, 2, 5.0, 2.08, 2),  # tandem, SN 5, p_t 2.5: the guide's Table D.5 (p. D-7), its worked example
        (30.0, 1, 3.0, 7.9, 1),  # single, SN 3, p_t 2.5: Table D.4 (p. D-6)
        (20.0, 1, 5.0, 1.51, 2),  # single, SN 5: 1.51 and 3.03, as the guide's table is quoted in course solutions
        (24.0, 1, 5.0, 3.03, 2),
        (10.0, 1, 5.0, 0.0877, 4),  # the Asphalt Institute's table of the same equations (SN 5, p_t 2.5): 0.08770
        (10.0, 2, 5.0, 0.00688, 5),  # and 0.00688 for a 10-kip tandem (ours 0.006888: the table cuts, not rounds)
    ],
)
def test_the_guides_published_factors(kips, axles, sn, published, places):
    lef = float(aashto_flexible_lef(kips, axles, sn, 2.5))
    assert abs(lef - published) <= 0.6 * 10.0**-places + 1e-3 * published


def test_the_standard_axle_is_one_on_every_pavement_and_a_group_factor_is_not_its_axles():
    assert np.allclose(aashto_flexible_lef([18.0, 18.0, 18.0], 1, 3.0), 1.0, rtol=0, atol=1e-12)
    assert float(aashto_flexible_lef(18.0, 1, 8.0, 3.0)) == pytest.approx(1.0, abs=1e-12)
    # two 20-kip single axles against one 40-kip tandem (SN 5): 3.03 against 2.08; the group's factor is of its
    # total, so a tandem shared 24 + 16 kips has the same 2.08 while its two axles as singles would be 3.03 + 0.40
    singles = 2 * float(aashto_flexible_lef(20.0, 1))
    assert singles == pytest.approx(3.025, abs=0.001) and float(aashto_flexible_lef(40.0, 2)) < 0.7 * singles
    unequal = float(aashto_flexible_lef(24.0, 1)) + float(aashto_flexible_lef(16.0, 1))
    assert unequal > singles  # per axle, unequal sharing costs more; the tandem's group factor cannot show it


def test_what_aashto_says_about_groups_as_they_share():
    # a 40-kip tandem shared 20 + 20 and 24 + 16 kips: the guide's 2.08 for both (Table D.5); its axles as singles
    # 3.03 equally shared (1.51 twice, Table D.4's row), 3.03 + 0.40 as the second shares it
    view = aashto_view(np.array([[20.0, 20.0], [24.0, 16.0]]) / KIPS_PER_KG)
    assert view["group"] == pytest.approx([2.08, 2.08], abs=0.006)
    assert view["single_axles_equal"] == pytest.approx([3.025, 3.025], abs=0.001)
    assert view["single_axles"][0] == pytest.approx(3.025, abs=0.001)
    second = float(aashto_flexible_lef(24.0, 1)) + float(aashto_flexible_lef(16.0, 1))
    assert view["single_axles"][1] == pytest.approx(second, rel=1e-12) and second > 3.4
    # a tridem: its total's factor, on another pavement too
    tri = aashto_view([[8000.0, 8000.0, 8000.0]], 3.0, 2.0)
    assert tri["group"][0] == pytest.approx(float(aashto_flexible_lef(24_000 * KIPS_PER_KG, 3, 3.0, 2.0)), rel=1e-12)
    with pytest.raises(ValueError, match=r"loads_kg of shape \(1, 4\): must be groups of 2 or 3"):
        aashto_view([[1.0, 2.0, 3.0, 4.0]])
    with pytest.raises(ValueError, match="positive, finite"):
        aashto_view([[1.0, 0.0]])


def test_units_and_the_group_loads():
    # 1 lbf = 4.4482216152605 N: 18,000 kg at g = 9.81 weigh 39.70 kips
    assert 18_000.0 * KIPS_PER_KG == pytest.approx(39.697, abs=1e-3)
    # Austroads' group loads against 80 kN x n^(3/4), the loads at which a group shared equally does the damage of
    # its axles at the fourth power: 134.5 and 182.4 kN against the guide's 135 and 181
    for size, n in (("tandem", 2), ("triaxle", 3)):
        assert AUSTROADS_GROUP_LOAD_KN[size] == pytest.approx(80.0 * n**0.75, rel=0.01)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ((40.0, 4), "axles = 4: must be 1 (single), 2 (tandem) or 3 (tridem)"),
        ((40.0, 2, 0.0), "structural_number"),
        ((40.0, 2, 5.0, 4.2), "terminal_serviceability"),
        ((-1.0, 2), "load_kips = -1.0: must be positive and finite [kip]"),
        ((float("nan"), 1), "load_kips"),
    ],
)
def test_bad_arguments_are_refused_by_name(args, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")):
        aashto_flexible_lef(*args)


def test_the_extra_wear_against_austroads_group_baseline_by_hand():
    # a tandem of 10 t and 8 t: per axle at k = 4 its damage is (98.1 / 80)^4 + (78.48 / 80)^4 = 3.18726 standard axles,
    # shared equally 2 (88.29 / 80)^4 = 2.96700, so 7.42 % more than equal sharing; Austroads counts the group as
    # (176.58 / 135)^4 = 2.92703 standard axle repetitions, so the extra is 0.22026 / 2.92703 = 7.53 % of that
    groups = pd.DataFrame({"group": ["tandem"], "n_axles": [2], "axle_load_1": [10_000.0], "axle_load_2": [8_000.0]})
    row = wear_statistics(groups, {"tandem": 18_000.0}, 10_000.0, resamples=0).iloc[0]
    kn = np.array([10_000.0, 8_000.0]) * 9.81 / 1000.0
    damage, equal = ((kn / 80.0) ** 4).sum(), 2 * (kn.mean() / 80.0) ** 4
    by_hand = (damage - equal) / (kn.sum() / 135.0) ** 4
    assert by_hand == pytest.approx(0.07525, abs=5e-5)
    assert row["extra_wear_group_overall"] == pytest.approx(by_hand, rel=1e-12)
    assert row["extra_wear_overall"] == pytest.approx(damage / equal - 1.0, rel=1e-12)
    # at k = 12 the group's count is far above the per-axle equal-sharing baseline: the share is a quarter of it
    assert group_baseline_factor("tandem", 12) == pytest.approx(2.0**-11 * (135 / 80) ** 12, rel=1e-12)
    assert group_baseline_factor("tandem", 12) == pytest.approx(0.260, abs=1e-3)
    assert group_baseline_factor("triaxle", 12) == pytest.approx(0.102, abs=1e-3)
    assert math.isnan(group_baseline_factor("single", 4))


def test_the_sharing_factors_by_hand_and_their_file(tmp_path):
    # the tandem of 10 t and 8 t: per axle D / D_eq = ((10/9)^4 + (8/9)^4) / 2 = 1.07425; against Austroads' count
    # 1 + 0.07525 (above)
    groups = pd.DataFrame({"group": ["tandem"], "n_axles": [2], "axle_load_1": [10_000.0], "axle_load_2": [8_000.0]})
    wear = wear_statistics(groups, {"tandem": 18_000.0}, 10_000.0, resamples=0)
    factors = sharing_factors(wear, DAMAGE_EXPONENTS, source="observed", position="trailer", suspension="as observed")
    row = factors.iloc[0]
    assert list(factors.columns[:6]) == ["source", "group", "position", "suspension", "n_groups", "factor_k4"]
    assert row["factor_k4"] == pytest.approx(((10 / 9) ** 4 + (8 / 9) ** 4) / 2, rel=1e-12)
    assert row["guide_factor_k4"] == pytest.approx(1.07525, abs=5e-5)
    # at k = 12 the per-axle factor is far above the guide's: the equal-shared baseline is 0.26 of Austroads' count
    per_axle_12 = ((10 / 9) ** 12 + (8 / 9) ** 12) / 2
    assert row["factor_k12"] == pytest.approx(per_axle_12, rel=1e-12)
    assert row["guide_factor_k12"] == pytest.approx(1 + (per_axle_12 - 1) * group_baseline_factor("tandem", 12))
    path = tmp_path / "factors.csv"
    write_sharing_factors(factors, path)
    text = path.read_text()
    assert text.startswith("# Sharing factors of axle groups") and "guide_factor_k<k> [-]" in text
    back = pd.read_csv(path, comment="#")
    assert back.loc[0, "factor_k4"] == pytest.approx(row["factor_k4"], rel=1e-5)  # 6 significant digits
    assert not list(tmp_path.glob("*.partial"))
    # an empty survey: the header and the columns, no rows
    empty = sharing_factors(pd.DataFrame(columns=["group"]), DAMAGE_EXPONENTS, source="observed")
    assert len(empty) == 0 and "factor_k12_high" in empty.columns
