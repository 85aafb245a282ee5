"""Does the calibration's table read the site roughness as a direct simulation does? (issue 43)

The table's bogies weighed directly (no table: :func:`bogie.fleet.calibration.checks.simulate_fleet`) at a site
roughness, against the table's readings of the same bogies interpolated at that roughness
(:func:`bogie.fleet.calibration.table.fleet_readings`): their mean spread [kg] and mean relative difference per axle;
then the direct weighings taken as the observed survey and the distance (:class:`~bogie.fleet.calibration.problem.
Problem`'s objective) profiled over the roughness, everything else at its params.yaml value: a faithful table has the
profile's least at the roughness the survey was made at. A roughness between the table's levels tests its
interpolation; one above the table site's own road class (class A: 2.17 m/km) tested the cap the WIM site had until
issue 43 (docs/wim-site.md).

Run: ``python -m bench.bench_table_roughness [--levels 1,2,4] [--at 2.5,3.0,3.5]`` (a table, about 2.5 minutes on 2
cores, then about 20 s a roughness).
"""

from __future__ import annotations

import argparse
import copy
import os
import time
from pathlib import Path

import numpy as np
import yaml

from bench.bench_calibrate import FIT

ROOT = Path(__file__).resolve().parent.parent


def mean_spread(loads: np.ndarray, present: np.ndarray, ok: np.ndarray) -> float:
    """The mean over the rows ``ok`` of heaviest minus lightest of the ``present`` axles [kg]."""
    y = np.where(present, loads, np.nan)[ok]
    return float(np.mean(np.nanmax(y, axis=1) - np.nanmin(y, axis=1)))


#: the roughness profile's step [m/km]
STEP = 0.125


def main(argv: list[str] | None = None) -> None:
    from bogie.fleet.calibration import checks as K
    from bogie.fleet.calibration.problem import Observed, make_problem
    from bogie.fleet.calibration.table import fleet_readings
    from pipeline import calibrate as C
    from pipeline.config import parse_config

    parser = argparse.ArgumentParser(prog="python -m bench.bench_table_roughness", description=__doc__.splitlines()[0])
    parser.add_argument("--levels", default="1,2,4", help="the table's roughness levels [m/km] (default 1,2,4)")
    parser.add_argument("--at", default="2.5,3.0,3.5", help="the roughnesses tried [m/km] (default 2.5,3.0,3.5)")
    args = parser.parse_args(argv)
    levels = [float(x) for x in args.levels.split(",")]
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["calibrate"]["fit"] = copy.deepcopy(FIT)
    raw["calibrate"]["site_iri_levels_m_km"] = levels
    config = parse_config(raw)
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs", flush=True)
    start = time.perf_counter()
    table = C.build_table(config, lambda text: None)
    print(f"table at {levels} m/km built in {time.perf_counter() - start:.0f} s; its site on a class "
          f"{table.site.road_class} road", flush=True)  # fmt: skip
    base, mapper, low = C.defaults(config), C.workers_map(config.execution), config.observed.min_group_load
    for iri in (float(x) for x in args.at.split(",")):
        values = {**base, "site_iri_m_km": iri}
        direct = K.simulate_fleet(table, values, executor=mapper)
        loads = direct[[f"axle_load_{i + 1}" for i in range(3)]].to_numpy()
        tab = fleet_readings(table, values)[np.where(direct["suspension"] == "air", 1, 0), direct["slot"].to_numpy()]
        present = np.arange(3)[None, :] < direct["n_axles"].to_numpy()[:, None]
        ok = np.all(np.where(present, np.isfinite(loads) & np.isfinite(tab), True), axis=1)

        rel = np.abs(tab / loads - 1.0)[ok][present[ok]]
        frame = K.filtered(direct, low)
        groups = {s: frame.loc[frame["group"] == s, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy(dtype=float)
                  for s, n in (("tandem", 2), ("triaxle", 3))}  # fmt: skip
        observed = Observed(groups, {s: np.arange(len(v)) for s, v in groups.items()})
        problem = make_problem(table, observed, {"site_iri_m_km": (levels[0], levels[-1])}, values, low)
        f = problem.objective(problem.unit_weights(), None)
        grid = np.arange(levels[0], levels[-1] + 1e-9, STEP)
        d = np.array([f(np.array([g])) for g in grid])
        print(f"at {iri:g} m/km: mean spread direct {mean_spread(loads, present, ok):.1f} kg, table "
              f"{mean_spread(tab, present, ok):.1f} kg, mean "
              f"|table / direct - 1| {rel.mean():.4f}; distance least at {grid[d.argmin()]:.3f} m/km "
              f"({d.min():.3f}; {d[np.argmin(np.abs(grid - iri))]:.3f} at {iri:g})", flush=True)  # fmt: skip
    print(f"total {time.perf_counter() - start:.0f} s; load average {os.getloadavg()[0]:.2f} after")


if __name__ == "__main__":
    main()
