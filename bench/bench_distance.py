"""The calibration's objective, one evaluation, against its peer measured in the same run (issue 30 Must 7).

The fit evaluates the distance thousands of times per refit (``docs/calibration.md``), so its cost sets the
calibration's. The objective presorts the observed side once per fit
(:class:`bogie.fleet.calibration.problem._SortedSample`) and computes each group's shares and spread without the survey
statistics' other quantities. The peer is the same distance by the previous code's path:
:func:`bogie.fleet.calibration.problem.simulated`, then the distance with :func:`scipy.stats.energy_distance` sorting
both sides at every evaluation (:func:`scipy_distance`, here). Both are checked equal (to 1e-12 relative) before they
are timed.

The table is an analytic one (no simulation; its readings linear in tilt and in the contact-roll radius, as in
``tests/test_fleet_tilted.py``) of :data:`N_BOGIES` calibration bogies, tri-axles and tandems, against
:data:`N_OBSERVED` observed groups: the sizes of the 5,000-vehicle benchmark (``bench_calibrate``), fitting the
tilt, the air share and the mean radius. Run alone: ``python -m bench.bench_distance``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time

import numpy as np
import pandas as pd

#: calibration bogies [-] and observed groups [-]
N_BOGIES, N_OBSERVED = 300, 2500
#: evaluations timed per side [-]
REPEATS = 400


def _problem():
    from bogie.fleet.calibration import problem as L
    from bogie.fleet.calibration import table as T
    from bogie.fleet.sampling.distributions import LogUniform, TruncNormal, Uniform
    from bogie.fleet.weighing.settings import StaticProtocol

    tilt, radius, bush = TruncNormal(0.005, 0.014, -0.035, 0.035), Uniform(0.0, 0.12), LogUniform(1.0, 3000.0)
    rng = np.random.default_rng(5)
    size = np.where(rng.random(N_BOGIES) < 0.3, "tandem", "triaxle")
    samples = pd.DataFrame({
        "sample_id": np.arange(N_BOGIES), "group": size, "chassis_tilt": tilt.ppf(rng.random(N_BOGIES)),
        "sensor_seed": np.arange(N_BOGIES), "contact_roll_radius": radius.ppf(rng.random(N_BOGIES)),
        "bush_stiffness": bush.ppf(rng.random(N_BOGIES)),
    })  # fmt: skip
    static = StaticProtocol(load_time=2.0, approach_length=5.0, crawl_speed=1.4, settle_time=3.0, dt=1e-3)
    grid = np.linspace(-2.0, 2.0, 17)
    table = T.crn_table(samples, tilt, 1, "static", static, grid,
                        inhibitor_distributions={"contact_roll_radius": radius, "bush_stiffness": bush})  # fmt: skip
    slope = 0.02 * (1.0 + 10.0 * samples["contact_roll_radius"].to_numpy())  # share per degree, radius-dependent
    loads = np.full(table.loads.shape, np.nan)
    for n, sign in ((2, [-1.0, 1.0, 0.0]), (3, [-1.0, 0.0, 1.0])):
        sel = size == ("tandem" if n == 2 else "triaxle")
        shape = 8000.0 * (1.0 + np.multiply.outer(slope[sel, None] * grid[None, :], sign))  # (k, tilts, 3)
        loads[0, sel, :, 0, :n] = shape[..., :n]
        loads[1, sel, :, 0, :n] = 8000.0
    table = dataclasses.replace(table, loads=loads)
    obs_rng = np.random.default_rng(6)
    observed = {}
    for name, n in (("tandem", 2), ("triaxle", 3)):
        k = int(N_OBSERVED * (0.3 if n == 2 else 0.7))
        observed[name] = 8000.0 * (1.0 + 0.03 * obs_rng.standard_normal((k, n)))
    obs = L.Observed(observed, {k: np.arange(len(v)) for k, v in observed.items()})
    base = L.base_values(tilt, 0.0, None, {"contact_roll_radius": radius, "bush_stiffness": bush})
    fit = {"chassis_tilt_mean_deg": (-1.0, 1.5), "air_share": (0.0, 1.0), "contact_roll_radius_mean_mm": (5.0, 115.0)}
    return L.make_problem(table, obs, fit, base)


def scipy_distance(obs, obs_weights, sim, scales) -> float:
    """The distance by :func:`scipy.stats.energy_distance` on each side as it is: the previous code, the peer."""
    from scipy.stats import energy_distance

    total = 0.0
    for size, q in obs.items():
        s = sim.quantities[size]
        if len(s) == 0 or sim.weights[size].sum() <= 0.0:
            return math.inf
        for c in range(q.shape[1]):
            total += energy_distance(q[:, c], s[:, c], obs_weights[size], sim.weights[size]) / scales[size][c]
    return float(total)


def _time(f, thetas) -> float:
    start = time.perf_counter()
    for theta in thetas:
        f(theta)
    return (time.perf_counter() - start) / len(thetas)


def main() -> None:
    from bogie.fleet.calibration import problem as L

    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} on {os.cpu_count()} CPUs", flush=True)
    problem = _problem()
    objective = problem.objective(problem.unit_weights(), None)

    def peer(theta):
        values = L._values(theta, problem.fitted, problem.base)
        sim = L.simulated(problem.table, values, problem.min_group_load_kg, None, problem.weight_step_kg)
        return scipy_distance(problem.obs, problem.unit_weights(), sim, problem.scales)

    rng = np.random.default_rng(7)
    lows, highs = (np.array(b) for b in zip(*problem.bounds))
    thetas = [lows + (highs - lows) * rng.random(len(lows)) for _ in range(REPEATS)]
    for theta in thetas[:20]:
        a, b = objective(theta), peer(theta)
        assert math.isclose(a, b, rel_tol=1e-12), (a, b)
    objective(thetas[0]), peer(thetas[0])  # warm
    ours, theirs = [], []
    for _ in range(3):  # interleaved, the median of three
        ours.append(_time(objective, thetas))
        theirs.append(_time(peer, thetas))
    ours_s, theirs_s = float(np.median(ours)), float(np.median(theirs))
    print(f"one evaluation, {N_BOGIES} calibration bogies against {N_OBSERVED} observed groups, 3 fitted quantities:")
    print(f"  the fit's objective      {ours_s * 1e3:7.3f} ms")
    print(f"  peer (scipy both sides)  {theirs_s * 1e3:7.3f} ms   ratio peer / ours {theirs_s / ours_s:.2f}")
    print(f"load average {os.getloadavg()[0]:.2f} after")


if __name__ == "__main__":
    main()
