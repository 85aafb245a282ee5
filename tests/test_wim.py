"""The WIM site and sensor sub-model (bogie.road.wim): accuracy classes, the weighing length, the site's pavement."""

import math

import numpy as np
import pytest
from scipy import signal

from bogie.road import ISO8608Profile
from bogie.road.wim import (
    ACCURACY_CLASSES,
    COST323_TOLERANCES,
    SITE_BLEND_LENGTH,
    SiteRoad,
    axle_error_sd,
    axle_errors,
    gd_n0_for_iri,
    iri_of_iso8608,
    sensor_reading,
)

Z95 = 1.959963984540054  # Phi^-1(0.975)


# ---- accuracy ------------------------------------------------------------------------------------------------------
def test_the_error_sd_is_the_single_axle_tolerance_over_the_normal_quantile():
    assert axle_error_sd("B(10)", 0.95) == pytest.approx(0.15 / Z95, rel=1e-12)
    assert axle_error_sd("A(5)", 0.95) == pytest.approx(0.08 / Z95, rel=1e-12)
    assert axle_error_sd("D(25)", 0.90) == pytest.approx(0.30 / 1.6448536269514722, rel=1e-12)
    assert axle_error_sd("none", 0.95) == 0.0
    # classes in order of accuracy: each tolerance grows from A(5) to D(25), the axle of a group widest
    sds = [axle_error_sd(c, 0.95) for c in ACCURACY_CLASSES]
    assert sds == sorted(sds)
    for tol in COST323_TOLERANCES.values():
        assert tol["gross"] < tol["group"] < tol["single_axle"] < tol["axle_of_group"]


@pytest.mark.parametrize("accuracy_class", ACCURACY_CLASSES[1:])
def test_over_many_draws_the_errors_spread_is_what_the_class_says(accuracy_class):
    n_seeds, n_axles = 4000, 3
    e = np.concatenate([axle_errors(accuracy_class, 0.95, seed, n_axles) for seed in range(n_seeds)])
    n = e.size
    sd = axle_error_sd(accuracy_class, 0.95)
    # 4 standard errors: the sample sd of n normals has SE sd / sqrt(2 (n - 1)); a share has SE sqrt(p (1 - p) / n)
    assert abs(e.std(ddof=1) - sd) < 4.0 * sd / math.sqrt(2.0 * (n - 1))
    assert abs(e.mean()) < 4.0 * sd / math.sqrt(n)
    delta = COST323_TOLERANCES[accuracy_class]["single_axle"] / 100.0
    inside = np.mean(np.abs(e) <= delta)
    assert abs(inside - 0.95) < 4.0 * math.sqrt(0.95 * 0.05 / n)
    # the axles of one reading are independent: their correlation is zero within 4 / sqrt(n_seeds)
    r = np.corrcoef(e.reshape(n_seeds, n_axles).T)
    assert np.all(np.abs(r[np.triu_indices(n_axles, 1)]) < 4.0 / math.sqrt(n_seeds))


def test_errors_are_deterministic_per_seed_and_per_axle():
    a = axle_errors("C(15)", 0.95, 12345, 3)
    assert np.array_equal(a, axle_errors("C(15)", 0.95, 12345, 3))
    assert np.array_equal(a[:2], axle_errors("C(15)", 0.95, 12345, 2))  # axle i's draw whatever the group size
    assert not np.array_equal(a, axle_errors("C(15)", 0.95, 12346, 3))
    # another class scales the same draws (common random numbers across classes too)
    ratio = axle_error_sd("D(25)", 0.95) / axle_error_sd("C(15)", 0.95)
    assert axle_errors("D(25)", 0.95, 12345, 3) == pytest.approx(ratio * a, rel=1e-12)
    assert np.array_equal(axle_errors("none", 0.95, 12345, 3), np.zeros(3))


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (("B10", 0.95), ["'B10'", "B(10)", "none"]),
        (("B(10)", 1.0), ["confidence_level = 1.0", "(0, 1)"]),
        (("B(10)", 0.0), ["confidence_level = 0.0", "(0, 1)"]),
    ],
)
def test_a_bad_class_or_level_is_refused_naming_it_and_the_allowed_values(args, words):
    with pytest.raises(ValueError) as excinfo:
        axle_error_sd(*args)
    for word in words:
        assert word in str(excinfo.value)
    with pytest.raises(ValueError, match="seed = -1"):
        axle_errors("B(10)", 0.95, -1, 3)


# ---- weighing length -----------------------------------------------------------------------------------------------
T = np.arange(0.0, 1.0 + 1e-12, 1e-4)


def test_a_point_sensor_reads_the_instantaneous_force_and_a_constant_force_reads_itself():
    force = 30e3 + 2e3 * np.sin(2 * np.pi * 7.0 * T)
    assert sensor_reading(T, force, 0.4123, 22.0, 0.0, 0.0) == pytest.approx(np.interp(0.4123, T, force), rel=1e-15)
    for sensor_length, contact_length in ((0.05, 0.2), (0.5, 0.2), (3.0, 0.25), (0.2, 0.2), (0.0, 0.2)):
        assert sensor_reading(T, np.full_like(T, 31e3), 0.5, 22.0, sensor_length, contact_length) == pytest.approx(
            31e3, rel=1e-13
        )
    # a linear force reads its value at the centre: the weighting is symmetric about it
    assert sensor_reading(T, 1e3 + 5e4 * T, 0.5, 22.0, 0.5, 0.2) == pytest.approx(1e3 + 5e4 * 0.5, rel=1e-13)


@pytest.mark.parametrize(("sensor_length", "contact_length"), [(0.05, 0.2), (0.5, 0.2), (3.0, 0.2), (0.2, 0.2)])
@pytest.mark.parametrize("frequency", [2.5, 12.0])
def test_a_sinusoidal_force_is_attenuated_by_the_trapezoids_transform(sensor_length, contact_length, frequency):
    # the weighting is the overlap of patch and strip, a trapezoid: the convolution of two rectangles of S / v and
    # L / v, so a cosine about the centre reads sinc(f S / v) sinc(f L / v) of its amplitude (numpy's sinc has the pi)
    speed, centre = 22.0, 0.5
    force = np.cos(2 * np.pi * frequency * (T - centre))
    expected = np.sinc(frequency * sensor_length / speed) * np.sinc(frequency * contact_length / speed)
    # the force is linear between samples 0.1 ms apart: within (2 pi f dt)^2 / 12 of the cosine's integral
    tolerance = (2 * np.pi * frequency * 1e-4) ** 2 / 12 + 1e-12
    assert sensor_reading(T, force, centre, speed, sensor_length, contact_length) == pytest.approx(
        expected, abs=tolerance
    )


def test_the_integration_is_exact_for_a_force_linear_between_coarse_samples():
    # samples 10 ms apart, coarser than the 32 ms passage's breakpoints: a dense resampling of the same piecewise
    # linear force gives the same reading
    coarse = np.arange(0.0, 1.0 + 1e-12, 0.01)
    force = 3e4 + np.random.default_rng(1).normal(0.0, 3e3, coarse.size)
    dense = np.linspace(0.0, 1.0, 200_001)
    a = sensor_reading(coarse, force, 0.503, 22.0, 0.5, 0.2)
    b = sensor_reading(dense, np.interp(dense, coarse, force), 0.503, 22.0, 0.5, 0.2)
    assert a == pytest.approx(b, rel=1e-9)


def test_a_passage_outside_the_record_reads_nan():
    assert math.isnan(sensor_reading(T, np.ones_like(T), 0.999, 22.0, 0.5, 0.2))


# ---- site pavement ------------------------------------------------------------------------------------------------
def golden_car_iri(profile, length, dx=0.05):
    """IRI [m/km] of ``profile`` from a time simulation of the golden car at 80 km/h (Sayers et al. 1986)."""
    speed, k1, k2, c, mu = 80.0 / 3.6, 653.0, 63.3, 6.0, 0.15
    x = np.arange(0.0, length, dx)
    base = round(0.25 / dx)
    h = np.convolve(profile(x), np.ones(base) / base, mode="valid")  # the 250 mm moving average
    a = [[0, 1, 0, 0], [-k2, -c, k2, c], [0, 0, 0, 1], [k2 / mu, c / mu, -(k1 + k2) / mu, -c / mu]]
    system = (np.array(a), np.array([[0], [0], [0], [k1 / mu]]), np.array([[0, 1, 0, -1]]), np.array([[0]]))
    _, y, _ = signal.lsim(system, h, np.arange(h.size) * dx / speed)
    return float(np.mean(np.abs(y[round(20.0 / dx) :])) / speed * 1000.0)  # after 20 m of start transient


def test_the_iri_of_an_iso8608_psd_matches_the_golden_car_on_generated_roads():
    # four 1 km class A roads: the mean rectified velocity of each is within about 2 % of the Gaussian closed form
    simulated = np.mean([golden_car_iri(ISO8608Profile("A", length=1000.0, seed=s), 1000.0) for s in range(4)])
    assert simulated == pytest.approx(iri_of_iso8608(16e-6), rel=0.03)


def test_iri_scales_with_the_root_of_the_psd_and_inverts():
    assert iri_of_iso8608(64e-6) == pytest.approx(2.0 * iri_of_iso8608(16e-6), rel=1e-12)
    assert iri_of_iso8608(gd_n0_for_iri(1.3)) == pytest.approx(1.3, rel=1e-12)
    # COST 323 class I (IRI 1.3 m/km) is smoother than ISO 8608 class A's geometric mean and in class A
    assert 0.0 < gd_n0_for_iri(1.3) < 16e-6
    with pytest.raises(ValueError, match="iri = 0.0"):
        gd_n0_for_iri(0.0)


def test_the_site_scales_the_road_over_its_length_and_leaves_it_elsewhere():
    road = ISO8608Profile("C", length=200.0, seed=3)
    site = SiteRoad(road, sensor=60.0, before=50.0, after=25.0, scale=0.2)
    on = np.linspace(10.0, 85.0, 301)
    assert site(on) == pytest.approx(0.2 * road(on), rel=1e-12, abs=1e-15)
    off = np.concatenate([np.linspace(0.0, 10.0 - SITE_BLEND_LENGTH, 50), np.linspace(90.0, 150.0, 50)])
    assert site(off) == pytest.approx(road(off), rel=1e-12, abs=1e-15)
    x = np.linspace(0.0, 150.0, 150_001)
    w = site.site_weight(x)
    assert np.all((w >= 0.0) & (w <= 1.0)) and np.max(np.abs(np.diff(w))) < 1e-3  # continuous taper
    assert np.array_equal(SiteRoad(road, 60.0, 0.0, 0.0, 0.2)(x), road(x))  # no site


def test_a_bad_site_is_refused_naming_the_value_and_range():
    road = ISO8608Profile("A", length=100.0, seed=0)
    with pytest.raises(ValueError, match=r"before = -1.0 is out of range: must be >= 0 m"):
        SiteRoad(road, 60.0, -1.0, 25.0, 0.5)
    with pytest.raises(ValueError, match=r"scale = 1.5 is out of range: must be in \[0, 1\]"):
        SiteRoad(road, 60.0, 50.0, 25.0, 1.5)
