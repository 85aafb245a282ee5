"""How much one WIM site's road moves a survey's group statistics (issue 43 Must 2; ``docs/calibration.md``, "The
site").

``python tools/site_study.py [--n-bogies 120] [--sites 12] [--workers 2]`` takes the first N bogies of params.yaml's
fleet (its design, distributions and seed), keeps them steel at their own sampled tilts, and weighs every one by the
WIM protocol (params.yaml's site roughness and sensor length, no sensor error) on each of the calibration's sites
0..S (:func:`bogie.fleet.calibration.site.site_of`: one road for every bogie, each bogie at its own speed,
:func:`bogie.fleet.calibration.site.bogie_speeds`), then once more with each bogie on a road of its own at the
protocol's speed (the model before issue 43). It prints, per site, the road's class and the mean spread
(heaviest - lightest axle) of the laden tandems and tri-axles [kg], then their mean, sd and range over the sites.
The same bogies, tilts, payloads and speeds on every site: the rows differ by the site's road alone.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from bogie.fleet import sample_fleet
from bogie.fleet.calibration.site import bogie_speeds, site_of
from bogie.fleet.calibration.table import weigh_readings, wim_task
from pipeline.config import load_config  # params.yaml's one reader; the study is bogie.fleet's

ROOT = Path(__file__).resolve().parents[1]


def spreads(loads: np.ndarray, groups: np.ndarray) -> dict[str, float]:
    """The mean spread [kg] of each size's groups with every axle read (rows of ``loads``, NaN past a group)."""
    out = {}
    for size, n in (("tandem", 2), ("triaxle", 3)):
        rows = loads[groups == size, :n]
        rows = rows[np.all(np.isfinite(rows), axis=1)]
        out[size] = float(np.mean(rows.max(axis=1) - rows.min(axis=1))) if len(rows) else math.nan
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python tools/site_study.py", description=__doc__.splitlines()[0])
    parser.add_argument("--n-bogies", type=int, default=120, help="fleet bogies weighed on every site (default 120)")
    parser.add_argument("--sites", type=int, default=12, help="sites besides the table's own (default 12)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    args = parser.parse_args(argv)
    config = load_config(ROOT / "params.yaml")
    samples = sample_fleet(config.fleet_study, args.n_bogies, config.seed, config.fleet.sampling)
    spec = dataclasses.replace(config.protocol.wim, sensor="none", sensor_vehicle_error=None, sensor_axle_error=None)
    rows = [{**row, "suspension": "steel"} for row in samples.to_dict("records")]
    classes = [str(c) for c in samples["road_class"]]
    speeds = bogie_speeds(config.seed, "fleet", samples["sample_id"].to_numpy(), spec.speed)
    sites = [site_of(config.seed, "fleet", classes, k) for k in range(args.sites + 1)]
    tasks = [wim_task(row, spec, site, speeds[i]) for site in sites for i, row in enumerate(rows)]
    tasks += [wim_task(row, spec, None, None) for row in rows]  # each on its own road: the model of before
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        loads = weigh_readings(tasks, pool if args.workers > 1 else None)
    seconds = time.perf_counter() - start
    groups = samples["group"].astype(str).to_numpy()
    per_site = [spreads(loads[k * len(rows) : (k + 1) * len(rows)], groups) for k in range(len(sites))]
    print(f"{len(rows)} steel bogies of params.yaml's fleet (seed {config.seed}), {len(tasks)} WIM weighings in "
          f"{seconds:.0f} s on {args.workers} workers; mean spread of the laden groups [kg]")  # fmt: skip
    print("site                       road class   tandem   tri-axle")
    for k, (site, s) in enumerate(zip(sites, per_site, strict=True)):
        name = "0 (the table's)" if k == 0 else str(k)
        print(f"  {name:24s} {site.road_class:>10s} {s['tandem']:8.0f} {s['triaxle']:10.0f}")
    own = spreads(loads[len(sites) * len(rows) :], groups)
    print(f"  {'each on its own road':24s} {'-':>10s} {own['tandem']:8.0f} {own['triaxle']:10.0f}")
    for size in ("tandem", "triaxle"):
        x = np.array([s[size] for s in per_site])
        print(f"{size} over the {len(x)} sites: mean {x.mean():.0f} kg, sd {x.std(ddof=1):.0f} kg "
              f"({100 * x.std(ddof=1) / x.mean():.0f} %), {x.min():.0f}-{x.max():.0f} kg")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
