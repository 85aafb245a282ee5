"""Pavement wear and hidden overloads of axle groups (bogie.weighings.wear), against groups worked by hand."""

import math

import numpy as np
import pandas as pd
import pytest

from bogie.params import GRAVITY
from bogie.weighings.wear import (
    DAMAGE_EXPONENTS,
    STANDARD_AXLE_KG,
    group_wear,
    hidden_overloads,
    wear_dict,
    wear_statistics,
)

LEGAL_GROUP = {"tandem": 18_000.0, "triaxle": 24_000.0}  # Directive 96/53/EC Annex I 3.4 and 3.5 [kg]
LEGAL_AXLE = 10_000.0  # 96/53/EC Annex I 3.1, a single non-driving axle [kg]


def test_equal_loads_do_no_extra_wear_at_any_exponent():
    loads = np.array([[8000.0, 8000.0, 8000.0], [9000.0, 9000.0, np.nan]])
    for k in (1, 4, 5, 7, 12):
        w = group_wear(loads, [3, 2], k, STANDARD_AXLE_KG)
        np.testing.assert_allclose(w["relative"], 0.0, atol=1e-14)  # zero but for rounding
        np.testing.assert_allclose(w["extra"], 0.0, atol=1e-12)


def test_a_triaxle_at_110_100_90_percent_does_four_percent_extra_at_the_fourth_power():
    # (1.1^4 + 1 + 0.9^4) / 3 - 1 = (1.4641 + 1 + 0.6561) / 3 - 1 = 0.040067 (the hand-worked group)
    w = group_wear([[8800.0, 8000.0, 7200.0]], [3], 4)
    assert w["relative"][0] == pytest.approx(3.1202 / 3 - 1, rel=1e-12)
    assert round(100 * w["relative"][0], 1) == 4.0
    # in standard axles of 8000 kg: D = 3.1202, D_eq = 3, extra 0.1202
    w = group_wear([[8800.0, 8000.0, 7200.0]], [3], 4, standard_axle=8000.0)
    assert (w["damage"][0], w["damage_equal"][0], w["extra"][0]) == pytest.approx((3.1202, 3.0, 0.1202), rel=1e-12)
    # at k = 12 the same group: (1.1^12 + 1 + 0.9^12) / 3 - 1 = (3.138428 + 1 + 0.282430) / 3 - 1 = 0.473619
    assert group_wear([[8800.0, 8000.0, 7200.0]], [3], 12)["relative"][0] == pytest.approx(0.4736193, rel=1e-6)


def test_extra_wear_does_not_depend_on_the_standard_axle_or_the_unit_and_grows_with_the_exponent():
    loads = np.array([[9500.0, 8500.0], [7000.0, 9000.0]])
    kg = group_wear(loads, [2, 2], 4, STANDARD_AXLE_KG)["relative"]
    newton = group_wear(loads * GRAVITY, [2, 2], 4, 80_000.0)["relative"]
    np.testing.assert_allclose(kg, newton, rtol=1e-13)
    by_k = [group_wear(loads, [2, 2], k)["relative"] for k in sorted(DAMAGE_EXPONENTS.values())]
    assert all((a < b).all() for a, b in zip(by_k, by_k[1:]))


def test_bad_exponent_or_axle_count_is_refused():
    with pytest.raises(ValueError, match=r"k = 0.5: a damage exponent is a number of 1 or more"):
        group_wear([[1.0, 2.0]], [2], 0.5)
    with pytest.raises(ValueError, match="n_axles must give each of the 1 groups 2 to 2 axles"):
        group_wear([[1.0, 2.0]], [3], 4)


def test_hidden_overloads_are_axles_over_in_groups_within():
    loads = np.array([
        [9000.0, 9000.0, np.nan],    # tandem 18 t, axles 9 t: legal
        [10_100.0, 7900.0, np.nan],  # tandem 18 t, one axle 10.1 t: hidden
        [10_500.0, 8000.0, np.nan],  # tandem 18.5 t over, axle over: not hidden (the group weighing sees it)
        [10_001.0, 7000.0, 6999.0],  # tri-axle 24 t exactly (within), an axle over: hidden
        [8000.0, 8000.0, 8000.1],    # tri-axle 24.0001 t over, axles within
    ])  # fmt: skip
    got = hidden_overloads(loads, [2, 2, 2, 3, 3], [18e3, 18e3, 18e3, 24e3, 24e3], LEGAL_AXLE)
    assert got["hidden"].tolist() == [False, True, False, True, False]
    assert got["group_over"].tolist() == [False, False, True, False, True]
    assert got["axle_over"].tolist() == [False, True, True, True, False]


def _groups():
    # four tri-axles and two tandems worked by hand; loads in kg
    return pd.DataFrame({
        "group": ["triaxle"] * 4 + ["tandem"] * 2, "n_axles": [3, 3, 3, 3, 2, 2],
        "axle_load_1": [8800.0, 8000.0, 10_200.0, 8000.0, 9000.0, 10_500.0],
        "axle_load_2": [8000.0, 8000.0, 7000.0, 8000.0, 9000.0, 7000.0],
        "axle_load_3": [7200.0, 8000.0, 6800.0, 8000.0, np.nan, np.nan],
        "status": ["ok", "ok", "ok", "failed", "ok", "ok"],
    })  # fmt: skip


def test_wear_statistics_leaves_out_and_counts_a_failed_run_and_sums_the_fleet():
    table = wear_statistics(_groups(), LEGAL_GROUP, LEGAL_AXLE, resamples=200, seed=3).set_index("group")
    tri, tan = table.loc["triaxle"], table.loc["tandem"]
    assert (tri["n_groups"], tri["n_failed"], tan["n_groups"], tan["n_failed"]) == (3, 1, 2, 0)
    # the tri-axles: D / W_s^4 per group is 3.1202 x 8000^4, 3 x 8000^4 and (1.275^4 + 0.875^4 + 0.85^4) x 8000^4;
    # equal shares 3 x 8000^4 each (every group 24 t): the fleet's share is sum D / sum D_eq - 1
    d = np.array([3.1202, 3.0, 1.275**4 + 0.875**4 + 0.85**4])
    assert tri["extra_wear_overall"] == pytest.approx(d.sum() / 9.0 - 1.0, rel=1e-12)
    # per 1,000 groups, in standard axles of 80 kN: 1000 x mean(D - D_eq) with W = 8000 kg / W_s
    scale = (8000.0 / STANDARD_AXLE_KG) ** 4
    assert tri["extra_sa_per_1000_overall"] == pytest.approx(1000.0 * np.mean(d - 3.0) * scale, rel=1e-12)
    assert tri["extra_wear_overall_low"] <= tri["extra_wear_overall"] <= tri["extra_wear_overall_high"]
    # hidden overloads: the third tri-axle (24 t, a 10.2 t axle); the second tandem is 17.5 t with a 10.5 t axle
    assert (tri["n_hidden"], tan["n_hidden"]) == (1, 1)
    assert tri["share_hidden_overload"] == pytest.approx(1 / 3) and tan["share_hidden_overload"] == 0.5
    assert 0.0 < tri["share_hidden_overload_low"] < 1 / 3 < tri["share_hidden_overload_high"] < 1.0


def test_wear_statistics_in_newtons_equal_those_in_kg_and_are_reproducible():
    kg = wear_statistics(_groups(), LEGAL_GROUP, LEGAL_AXLE, resamples=100, seed=9)
    frame = _groups()
    for c in ("axle_load_1", "axle_load_2", "axle_load_3"):
        frame[c] = frame[c] * GRAVITY
    newton = wear_statistics(frame, LEGAL_GROUP, LEGAL_AXLE, unit_per_kg=GRAVITY, resamples=100, seed=9)
    pd.testing.assert_frame_equal(kg, newton, rtol=1e-12)
    pd.testing.assert_frame_equal(kg, wear_statistics(_groups(), LEGAL_GROUP, LEGAL_AXLE, resamples=100, seed=9))


def test_wear_dict_nests_the_by_values_and_writes_nan_as_none():
    table = wear_statistics(_groups().assign(position="trailer"), LEGAL_GROUP, LEGAL_AXLE, by=["group", "position"],
                            resamples=0)  # fmt: skip
    out = wear_dict(table, ["group", "position"])
    assert set(out) == {"tandem", "triaxle"} and set(out["triaxle"]) == {"trailer"}
    entry = out["triaxle"]["trailer"]
    assert entry["n_groups"] == 3 and entry["extra_wear_overall_low"] is None
    assert math.isclose(entry["extra_wear_overall"], round(entry["extra_wear_overall"], 4))


def test_above_the_bootstrap_limit_the_normal_intervals_agree_with_the_bootstrap(monkeypatch):
    """The delta method's intervals (cells above BOOTSTRAP_MAX_GROUPS) against the bootstrap's on the same 25,000
    tri-axles: each end within 10 % of the interval's half-width (measured: within 5 %, the bootstrap's own Monte
    Carlo error at 1,000 resamples being about 8 % of a standard error at the 2.5 % point)."""
    from bogie.weighings.wear import BOOTSTRAP_MAX_GROUPS

    rng = np.random.default_rng(5)
    m = 25_000
    assert m > BOOTSTRAP_MAX_GROUPS
    w = rng.normal(8000.0, 600.0, (m, 3))
    groups = pd.DataFrame({"group": "triaxle", "n_axles": 3, **{f"axle_load_{i + 1}": w[:, i] for i in range(3)}})
    normal = wear_statistics(groups, {"triaxle": 24_000.0}, 10_000.0).iloc[0]
    boot = wear_statistics(groups, {"triaxle": 24_000.0}, 10_000.0, bootstrap_max_groups=10**9).iloc[0]
    for name in ("overall", "cemented"):
        for figure in (f"extra_wear_{name}", f"extra_sa_per_1000_{name}"):
            half = (boot[f"{figure}_high"] - boot[f"{figure}_low"]) / 2
            # the large cell's estimate is merged block by block: the single sum's to 1e-12 relative
            assert normal[figure] == pytest.approx(boot[figure], rel=1e-12)
            for end in ("low", "high"):
                assert abs(normal[f"{figure}_{end}"] - boot[f"{figure}_{end}"]) < 0.1 * half, (figure, end)
    # block by block (25 blocks of 1,000 groups) as in one block: the merged moments agree to 1e-12 relative
    from bogie.weighings import wear

    monkeypatch.setattr(wear, "WEAR_BLOCK", 1000)
    blocked = wear_statistics(groups, {"triaxle": 24_000.0}, 10_000.0).iloc[0]
    for column, value in normal.items():
        if isinstance(value, float):
            assert blocked[column] == pytest.approx(value, rel=1e-12), column
        else:
            assert blocked[column] == value, column
