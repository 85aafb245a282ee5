"""The fitted inhibitor distributions (issue 30 Must 3): the exponential tilt of a fleet distribution, its weights and
its quantile map against closed forms, and a fleet's mean contact-roll radius recovered from the load shares.

The recovery needs no simulation: a steel tri-axle's outer axles share its load ``1 -+ C r`` for its contact-roll
radius ``r`` (a stand-in for what the radius does to a tilted bogie), an air group equally; the survey comes from an
independent fleet whose radius distribution is the tilt of U(0, 120) mm with mean 35 mm, and its air share 0.3.
"""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from bogie.fleet.calibration import fitting as F
from bogie.fleet.calibration import problem as L
from bogie.fleet.calibration import table as T
from bogie.fleet.sampling.distributions import LogUniform, TruncNormal, Uniform
from bogie.fleet.sampling.tilted import Tilted, effective_fraction

RADIUS = Uniform(0.0, 0.12)  # [m]
BUSH = LogUniform(1.0, 3000.0)  # [N m/rad]


def test_the_tilt_has_the_mean_asked_for_and_the_density_of_its_closed_form():
    family = Tilted.of(RADIUS, 1000.0)  # fitted in mm
    assert family.fleet_mean == 60.0 and family.tilt(60.0) == 0.0
    # by hand: t = -3 on [0, 120] mm has the mean 120 (1 / (1 - e^3) + 1 / 3) = 33.75 mm
    assert family.tilt(120.0 * (1.0 / (1.0 - math.exp(3.0)) + 1.0 / 3.0)) == pytest.approx(-3.0, abs=1e-9)
    x = (np.arange(200_000) + 0.5) / 200_000 * 0.12  # a fine midpoint grid over the support [m]
    for mean in (8.0, 35.0, 90.0, 117.0):
        t = family.tilt(mean)
        w = family.weights(x, t)
        assert np.sum(1000.0 * x * w) / np.sum(w) == pytest.approx(mean, rel=1e-6)
        # the weights are the density t e^(t u) / (e^t - 1) up to a constant
        u = x / 0.12
        density = t * np.exp(t * u) / math.expm1(t)
        np.testing.assert_allclose(w / w.mean(), density / density.mean(), rtol=1e-9)
    # symmetric: the tilt of 120 - m is minus that of m
    assert family.tilt(90.0) == pytest.approx(-family.tilt(30.0), rel=1e-12)
    with pytest.raises(ValueError, match=r"strictly within .* \(0, 120\)"):
        family.tilt(120.0)


def test_the_quantile_map_gives_the_tilted_distribution_and_keeps_each_rank():
    family = Tilted.of(RADIUS, 1000.0)
    u = (np.arange(100_000) + 0.5) / 100_000
    x = RADIUS.ppf(u)  # the fleet's own sample, evenly over its ranks
    for mean in (20.0, 35.0, 100.0):
        t = family.tilt(mean)
        moved = family.moved(x, t)
        assert 1000.0 * moved.mean() == pytest.approx(mean, rel=1e-4)
        assert np.all(np.diff(moved) > 0.0) and moved.min() >= 0.0 and moved.max() <= 0.12  # ranks kept, support
        # its CDF at 60 mm is the closed form expm1(t u) / expm1(t) at u = 1/2
        assert np.mean(moved <= 0.06) == pytest.approx(math.expm1(t / 2) / math.expm1(t), abs=1e-4)
    np.testing.assert_array_equal(family.moved(x, 0.0), x)


def test_a_log_uniform_is_moved_to_a_geometric_mean_and_other_kinds_are_refused():
    family = Tilted.of(BUSH)
    assert family.fleet_mean == pytest.approx(math.sqrt(3000.0), rel=1e-12)
    x = np.exp((np.arange(100_000) + 0.5) / 100_000 * math.log(3000.0))
    t = family.tilt(300.0)
    w = family.weights(x, t)
    assert math.exp(np.sum(np.log(x) * w) / np.sum(w)) == pytest.approx(300.0, rel=1e-6)
    assert math.exp(np.log(family.moved(x, t)).mean()) == pytest.approx(300.0, rel=1e-4)
    # the further the mean from the fleet's, the fewer bogies count: Kish's fraction falls from 1
    fractions = [effective_fraction(family.weights(x, family.tilt(g))) for g in (54.77, 300.0, 1000.0)]
    assert fractions[0] == pytest.approx(1.0, abs=1e-6) and fractions[0] > fractions[1] > fractions[2] > 0.2
    with pytest.raises(ValueError, match="uniform or a log-uniform"):
        Tilted.of(TruncNormal(0.25, 0.12, 0.05, 0.6))


#: the survey's fleet: what the fit must find
TRUTH = {"contact_roll_radius_mean_mm": 35.0, "air_share": 0.3}
FIT = {"contact_roll_radius_mean_mm": (5.0, 115.0), "air_share": (0.0, 1.0)}
#: the outer axles' load share per mm of contact-roll radius of a steel tri-axle [1/mm]
SLOPE = 0.001
TILT = TruncNormal(0.0, 0.01, -0.03, 0.03)  # [rad]; not fitted here


def steel_loads(radius_m):
    """A steel tri-axle's axle loads [kg] for its radius [m]: 8 t an axle, the front and rear -+ SLOPE a mm."""
    return 8000.0 * (1.0 + SLOPE * np.multiply.outer(1000.0 * np.asarray(radius_m), [-1.0, 0.0, 1.0]))


def radius_table(n=600, seed=21):
    """A static table of ``n`` tri-axles of the fleet's radius distribution, readings :func:`steel_loads`."""
    rng = np.random.default_rng(seed)
    radius = RADIUS.ppf(rng.random(n))
    samples = pd.DataFrame({
        "sample_id": np.arange(n), "group": "triaxle", "chassis_tilt": 0.0, "sensor_seed": np.arange(n),
        "contact_roll_radius": radius, "bush_stiffness": BUSH.ppf(rng.random(n)),
    })  # fmt: skip
    static = T.StaticProtocol(load_time=2.0, approach_length=5.0, crawl_speed=1.4, settle_time=3.0, dt=1e-3)
    table = T.crn_table(samples, TILT, 1, "static", static, [-2.0, 2.0],
                        inhibitor_distributions={"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})  # fmt: skip
    loads = np.full(table.loads.shape, np.nan)
    loads[0, :, :, 0, :] = steel_loads(radius)[:, None, :]
    loads[1, :, :, 0, :] = 8000.0
    return dataclasses.replace(table, loads=loads)


def radius_survey(n=2000, seed=22):
    """``n`` tri-axles of an independent fleet with the values of TRUTH: radii by the tilted quantile function."""
    rng = np.random.default_rng(seed)
    family = Tilted.of(RADIUS, 1000.0)
    radius = family.moved(RADIUS.ppf(rng.random(n)), family.tilt(TRUTH["contact_roll_radius_mean_mm"]))
    air = rng.random(n) < TRUTH["air_share"]
    loads = np.where(air[:, None], 8000.0, steel_loads(radius))
    return L.Observed({"tandem": np.zeros((0, 2)), "triaxle": loads}, {"tandem": np.zeros(0), "triaxle": np.arange(n)})


def test_a_fleets_mean_contact_roll_radius_is_recovered_by_reweighting_the_calibration_bogies():
    table, observed = radius_table(), radius_survey()
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    assert base["contact_roll_radius_mean_mm"] == 60.0 and base["bush_stiffness_geomean"] == pytest.approx(54.772, 1e-4)
    settings = L.CalibrationSettings(FIT, seed=4, maxiter=30, popsize=8, bootstrap_resamples=8)
    problem = L.make_problem(table, observed, FIT, base)
    result = F.calibrate(problem, settings)
    # Monte Carlo error: the radius's sd 28 mm x sqrt(1/400 + 1/1400) / (its effect's share) ~ 2 mm; 5 of those
    for name, tolerance in (("contact_roll_radius_mean_mm", 8.0), ("air_share", 0.06)):
        entry = result.fitted[name]
        assert abs(entry["value"] - TRUTH[name]) < tolerance, (name, entry)
        assert entry["low"] <= TRUTH[name] + tolerance and entry["high"] >= TRUTH[name] - tolerance
        assert entry["at_bound"] is None
    # the direct simulation's radii: every bogie moved to its rank under the fitted distribution
    moved = T.moved_samples(table, result.values)["contact_roll_radius"]
    assert 1000.0 * moved.mean() == pytest.approx(result.values["contact_roll_radius_mean_mm"], abs=4.0)
    assert (np.argsort(moved.to_numpy()) == np.argsort(table.samples["contact_roll_radius"].to_numpy())).all()


def test_fitting_an_inhibitor_the_table_cannot_move_is_refused_with_its_reason():
    table, observed = radius_table(40), radius_survey(40)
    base = L.base_values(TILT, 0.0, None, {"contact_roll_radius": RADIUS, "bush_stiffness": BUSH})
    with pytest.raises(L.CalibrationError, match=r"strictly within .* \(0, 120\) mm"):
        L.make_problem(table, observed, {"contact_roll_radius_mean_mm": (0.0, 100.0)}, base)
    bare = dataclasses.replace(table, tilted={})
    with pytest.raises(L.CalibrationError, match="bush_stiffness_geomean moves the fleet's distribution of bush_"):
        L.make_problem(bare, observed, {"bush_stiffness_geomean": (10.0, 100.0)}, base)
