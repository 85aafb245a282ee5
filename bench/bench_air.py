"""Air groups: the compiled RK4 of ``bogie.air._core`` against the LSODA reference, measured in one process.

Two scenarios on the tri-axle (1 degree tilt, wear 0 / 5 / 10 mm): a 3 s WIM pass at 22 m/s over ISO 8608 class B
at 1 ms rows, and the static-weighbridge chain (load ramp 0.2 to 0.8 in 2 s, crawl 1.4 m/s for ~8 m, hold 3 s,
each continued from the previous ``final_state``).
RK4: median of 20 runs after a warm-up (compilation excluded); LSODA: one run.
"""

from __future__ import annotations

import math
import os
import statistics
import time

import numpy as np

from bogie import air
from bogie.air import dynamics as air_dynamics
from bogie.air import static as air_static
from bogie.road import ISO8608Profile
from bogie.steel import nonlinear

DT = 1e-3


def _bogie():
    return air.air_triaxle(chassis_tilt=math.radians(1.0), tyre_wear=(0.0, 0.005, 0.01))


def _wim(b, method):
    prof = ISO8608Profile("B", length=200.0, seed=123)
    inputs = nonlinear.road_inputs(b, prof, 22.0, 3.0, DT, 0.0, load_factor=0.8)
    st = air_static.equilibrium(b, 0.8, float(inputs.kingpin_rise[0]), inputs.road_height[0])
    return air_dynamics.simulate(b, inputs, initial=st, method=method).wheel_loads


def _static_chain(b, method):
    ramp = air_dynamics.simulate(b, nonlinear.load_ramp(b, 0.2, 0.8, 2.0, DT), method=method)
    prof = ISO8608Profile("B", length=50.0, seed=7)
    crawl_in = nonlinear.road_inputs(b, prof, 1.4, 8.0 / 1.4, DT, 0.0, load_factor=0.8)
    crawl = air_dynamics.simulate(b, crawl_in, initial=ramp.final_state, method=method)
    road = crawl_in.road_height[-1]
    hold = air_dynamics.simulate(b, nonlinear.hold(b, 3.0, DT, 0.8, road), initial=crawl.final_state, method=method)
    return np.vstack([ramp.wheel_loads, crawl.wheel_loads, hold.wheel_loads])


def main() -> None:
    b = _bogie()
    ref = b.design_bag_load + b.axle_mass * 9.81
    print(f"load average {os.getloadavg()}")
    print(f"{'scenario':<14}{'rk4 [ms]':>10}{'lsoda [s]':>11}{'ratio':>9}{'max |dW|/W_static':>20}")
    for name, run in (("WIM pass", _wim), ("static chain", _static_chain)):
        run(b, "rk4")
        times = []
        for _ in range(20):
            start = time.perf_counter()
            w_rk4 = run(b, "rk4")
            times.append(time.perf_counter() - start)
        t_rk4 = statistics.median(times)
        start = time.perf_counter()
        w_lsoda = run(b, "lsoda")
        t_lsoda = time.perf_counter() - start
        diff = np.max(np.abs(w_rk4 - w_lsoda)) / ref
        print(f"{name:<14}{t_rk4 * 1e3:>10.2f}{t_lsoda:>11.2f}{t_lsoda / t_rk4:>9.0f}{diff:>20.2e}", flush=True)
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
