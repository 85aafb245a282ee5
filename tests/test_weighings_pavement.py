"""AASHTO 1993's flexible-pavement load equivalence factors against the guide's published values (issue 44 Must 2),
and the refusals of bad arguments."""

import numpy as np
import pytest

from bogie.weighings.pavement import AUSTROADS_GROUP_LOAD_KN, KIPS_PER_KG, aashto_flexible_lef


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


def test_units_and_the_group_loads():
    # 1 lbf = 4.4482216152605 N: 18,000 kg at g = 9.81 weigh 39.70 kips
    assert 18_000.0 * KIPS_PER_KG == pytest.approx(18_000.0 * 9.81 / 4448.2216152605, rel=1e-15)
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
