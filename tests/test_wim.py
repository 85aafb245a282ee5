"""The WIM site and sensor sub-model (bogie.road.wim): the sensor's error, the weighing length, the site's pavement."""

import math

import numpy as np
import pytest
from scipy import signal

from bogie.road import ISO8608Profile
from bogie.road.wim import (
    COST323_TOLERANCES,
    SENSOR_ERRORS,
    SENSORS,
    SITE_BLEND_LENGTH,
    SiteRoad,
    gd_n0_for_iri,
    iri_of_iso8608,
    sensor_factors,
    sensor_normals,
    sensor_reading,
)


# ---- the sensor's error -------------------------------------------------------------------------------------------
def test_the_tolerances_widen_from_the_gross_weight_to_an_axle_of_a_group_and_from_class_a_to_d():
    classes = list(COST323_TOLERANCES.values())
    for tol in classes:
        assert tol["gross"] < tol["group"] < tol["single_axle"] < tol["axle_of_group"]
    for a, b in zip(classes, classes[1:]):
        assert all(a[k] < b[k] for k in a)


def test_every_sensor_type_has_two_fractions_and_none_has_no_error():
    assert SENSOR_ERRORS["none"] == (0.0, 0.0) and set(SENSORS) == set(SENSOR_ERRORS)
    for s_v, s_a in SENSOR_ERRORS.values():
        assert 0.0 <= s_v < 0.1 and 0.0 <= s_a < 0.1  # a few per cent: a sensor's, not a whole system's error
    assert np.array_equal(sensor_factors(0.0, 0.0, 5, 3), np.ones(3))


def test_over_many_passes_each_part_has_its_sd_and_the_pass_part_is_common_to_the_axles():
    n_seeds, n_axles, s_v, s_a = 6000, 3, 0.015, 0.02
    f = np.array([sensor_factors(s_v, s_a, seed, n_axles) for seed in range(n_seeds)])
    log_f = np.log(f)
    # per pass, the axles share log(1 + s_v z_v): the covariance of two axles' logs is its variance, about s_v^2
    cov = np.cov(log_f.T)
    pair = cov[np.triu_indices(n_axles, 1)].mean()
    assert abs(pair - s_v**2) < 4.0 * s_a**2 * math.sqrt(2.0 / n_seeds) * 2
    # each axle's own part: the variance of an axle's log less the common one is s_a^2 (to first order)
    own = np.mean(np.diag(cov)) - pair
    assert abs(own - s_a**2) < 4.0 * s_a**2 * math.sqrt(2.0 / (n_seeds * n_axles)) * 2
    # the load shares do not see the pass's part: with s_a = 0 every axle reads with the same factor
    common = np.array([sensor_factors(s_v, 0.0, seed, n_axles) for seed in range(50)])
    assert np.allclose(common / common[:, :1], 1.0, rtol=0, atol=1e-15)


def test_the_draws_are_deterministic_per_seed_and_axle_and_the_pass_part_changes_no_axle_draw():
    z_pass, z_axles = sensor_normals(12345, 3)
    assert np.array_equal(z_axles, np.random.default_rng(12345).standard_normal(3))  # the old per-axle draws
    assert sensor_normals(12345, 2)[1].tolist() == z_axles[:2].tolist() and sensor_normals(12345, 3)[0] == z_pass
    assert sensor_normals(12346, 3)[0] != z_pass
    f = sensor_factors(0.01, 0.03, 12345, 3)
    assert f == pytest.approx((1.0 + 0.01 * z_pass) * (1.0 + 0.03 * z_axles), rel=1e-15)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ((0.6, 0.02, 1, 3), ["vehicle_sd = 0.6", "[0, 0.5)"]),
        ((0.01, -0.1, 1, 3), ["axle_sd = -0.1", "[0, 0.5)"]),
        ((0.01, 0.02, -1, 3), ["seed = -1"]),
    ],
)
def test_a_bad_sd_or_seed_is_refused_naming_it_and_the_allowed_range(args, words):
    with pytest.raises(ValueError) as excinfo:
        sensor_factors(*args)
    for word in words:
        assert word in str(excinfo.value)


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
    with pytest.raises(ValueError, match=r"scale = -0.5 is out of range: must be >= 0"):
        SiteRoad(road, 60.0, 50.0, 25.0, -0.5)


@pytest.mark.parametrize("road_class", ["A", "B", "C"])
def test_the_site_has_the_roughness_asked_for_on_every_road_even_a_smoother_one(road_class):
    # issue 43: r was capped at 1, so a site of 3.5 m/km on a class A road (its own 2.17 m/km) was the road itself,
    # 2.17 m/km: the calibration's roughness above it changed nothing when its site lay on class A, and read otherwise
    # when the survey's did not. IRI is proportional to sqrt(G_d(n0)), so r = IRI_site / IRI_road, above 1 on A
    import dataclasses

    from bogie.fleet import WimProtocol
    from bogie.fleet.weighing.protocols import wim_site

    road = ISO8608Profile(road_class, length=200.0, seed=3)
    spec = WimProtocol(speed=22.0, approach_length=60.0, dt=1e-3)
    spec = dataclasses.replace(spec, site_iri=3.5, site_length_before=50.0, site_length_after=25.0)
    site = wim_site(road, road_class, spec)
    own_iri = {"A": 2.172553, "B": 4.345106, "C": 8.690212}[road_class]  # docs/wim-site.md's table, from G_d(n0)
    assert site.scale == pytest.approx(3.5 / own_iri, rel=1e-6)
    on = np.linspace(spec.approach_length - spec.site_length_before + 1.0, spec.approach_length + 1.0, 101)
    assert site(on) == pytest.approx(site.scale * road(on), rel=1e-12, abs=1e-15)
