import numpy as np
import pytest

from bogie import metrics


def test_p_matches_equation_2_for_three_axles():
    w = np.array([1.2, 1.0, 0.7])
    assert metrics.p(w) == pytest.approx(np.hypot(0.2, -0.3))


def test_p_two_axles_is_difference_and_p1_is_half_of_it():
    rng = np.random.default_rng(1)
    w = rng.uniform(0.5, 1.5, size=(100, 2))
    assert np.allclose(metrics.p(w), np.abs(w[:, 0] - w[:, 1]))
    assert np.allclose(metrics.p1(w), metrics.p(w) / 2.0)


def test_p1_hand_worked():
    # mean 1, deviations 0.3, 0, -0.3 -> sqrt(0.18 / 3)
    assert metrics.p1([1.3, 1.0, 0.7]) == pytest.approx(np.sqrt(0.06))


def test_rms_is_equation_5_for_two_wheels():
    w = np.array([[10.0, 10.0], [12.0, 8.0], [9.0, 11.0]])
    expected = np.sqrt(np.mean(((w[:, 0] - w[:, 1]) / (w[:, 0] + w[:, 1])) ** 2))
    assert metrics.rms(w) == pytest.approx(expected)
    with pytest.raises(ValueError, match="time history"):
        metrics.rms([1.0, 2.0])


def test_lsc_max_deviation_spread_road_wear():
    w = np.array([110.0, 100.0, 90.0])
    assert metrics.lsc(w) == pytest.approx([1.1, 1.0, 0.9])
    assert metrics.max_deviation(w) == pytest.approx(0.1)
    assert metrics.spread(w) == pytest.approx(20.0)
    assert metrics.road_wear_factor(w) == pytest.approx((1.1**4 + 1.0 + 0.9**4) / 3.0)
    assert metrics.road_wear_factor([5.0, 5.0, 5.0]) == pytest.approx(1.0)


def test_road_wear_factor_exceeds_one_for_any_inequality():
    rng = np.random.default_rng(2)
    w = rng.uniform(1.0, 2.0, size=(500, 3))
    assert np.all(metrics.road_wear_factor(w) >= 1.0)


def test_dlc_hand_worked():
    h = np.array([[9.0, 20.0], [11.0, 20.0]])
    assert metrics.dlc(h) == pytest.approx([0.1, 0.0])


def test_metrics_broadcast_over_leading_axes():
    w = np.ones((4, 5, 3))
    assert metrics.p(w).shape == (4, 5)
    assert metrics.lsc(w).shape == (4, 5, 3)


def test_bad_shape_is_refused():
    with pytest.raises(ValueError, match=">= 2 axles"):
        metrics.p([1.0])
