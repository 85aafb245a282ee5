"""bogie.road.cost323: the COST 323 class of readings against static loads, on hand-worked groups."""

import math

import numpy as np
import pytest

from bogie.road.cost323 import CRITERIA, class_test, relative_errors

NAN = math.nan
#: a tri-axle read -5 %, 0, +5 % (its group exact) and a tandem read +12 % on both axles
STATIC = [[1000.0, 1000.0, 1000.0], [1000.0, 1000.0, NAN]]
WIM = [[1050.0, 1000.0, 950.0], [1120.0, 1120.0, NAN]]


def test_relative_errors_per_group_and_per_axle_present():
    e = relative_errors(STATIC, WIM)
    assert e["group"] == pytest.approx([0.0, 0.12], abs=1e-15)
    assert e["axle_of_group"] == pytest.approx([0.05, 0.0, -0.05, 0.12, 0.12], abs=1e-15)


def test_the_class_is_the_narrowest_whose_every_criterion_holds_the_required_share():
    t = class_test(STATIC, WIM)
    # A(5): group +-7 % holds 1 of 2, axle of a group +-10 % 3 of 5; B+(7): +-10 % 1 of 2, +-14 % 5 of 5;
    # B(10): +-13 % and +-20 %, all
    assert t.shares.loc["A(5)"].tolist() == [0.5, 0.6]
    assert t.shares.loc["B+(7)"].tolist() == [0.5, 1.0]
    assert t.shares.loc["B(10)"].tolist() == [1.0, 1.0]
    assert t.reached == "B(10)" and t.required_share == 0.95
    assert class_test(STATIC, WIM, required_share=0.5).reached == "A(5)"
    assert class_test(STATIC, WIM, required_share=0.6, criteria=("axle_of_group",)).reached == "A(5)"
    assert t.errors.loc["group", "mean"] == pytest.approx(0.06) and t.errors.loc["group", "n"] == 2
    assert t.errors.loc["group", "sd"] == pytest.approx(0.12 / math.sqrt(2.0))
    assert list(t.errors.index) == list(CRITERIA)


def test_no_class_when_even_the_widest_tolerance_is_missed():
    assert class_test([[1000.0, 1000.0]], [[1500.0, 1500.0]]).reached is None


def test_normal_errors_fill_each_tolerance_as_the_normal_law_says():
    rng = np.random.default_rng(7)
    n, sd = 20000, 0.05
    static = np.full((n, 2), 8000.0)
    wim = static * (1.0 + sd * rng.standard_normal((n, 2)))
    t = class_test(static, wim)
    for cls, delta in (("A(5)", 0.10), ("B+(7)", 0.14)):
        expected = math.erf(delta / sd / math.sqrt(2.0))  # 2 Phi(delta / sd) - 1
        assert abs(t.shares.loc[cls, "axle_of_group"] - expected) < 4.0 * math.sqrt(expected * (1 - expected) / (2 * n))
    # the group's error is the mean of two independent ones: sd / sqrt(2)
    assert t.errors.loc["group", "sd"] == pytest.approx(sd / math.sqrt(2.0), rel=0.03)


@pytest.mark.parametrize(
    ("args", "kwargs", "words"),
    [
        (([[1.0, 1.0]], [[1.0, 1.0, 1.0]]), {}, "same (groups, axles) shape"),
        (([[1.0, NAN]], [[1.0, 1.0]]), {}, "present (finite) in one and not in the other"),
        (([[0.0, 1.0]], [[1.0, 1.0]]), {}, "every load present must be > 0"),
        ((STATIC, WIM), {"required_share": 0.0}, "required_share = 0.0 is out of range: must be in (0, 1] -"),
        ((STATIC, WIM), {"criteria": ("gross",)}, "criteria = ['gross']: must be one or more of group"),
        ((np.zeros((0, 2)), np.zeros((0, 2))), {}, "no group to test"),
    ],
)
def test_bad_input_is_refused_naming_what_is_wrong(args, kwargs, words):
    with pytest.raises(ValueError) as excinfo:
        class_test(*args, **kwargs)
    assert words in str(excinfo.value)
