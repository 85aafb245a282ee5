"""Why a 300 N m/rad bush tolerates more tilt than a free bearing in the design study (``docs/design.md``).

``python tools/design_bush_friction.py [--conditions 8] [--tilt 0.75]`` weighs the tri-axle of the design study
(fixed contact points, 250 mm arms, the other factors at the fleet's medians) statically over the first
``--conditions`` operating conditions of the design stage (the same tyre wear, payload and road), all at the same
nose-up ``--tilt``, for bush stiffnesses 1 to 3000 N m/rad, with and without spring-end friction and the springs'
band, and prints the mean and largest max_deviation [%] of each. The reference's first inhibitor, rotational
stiffness, shows in the frictionless rows (deviation rising with the bush); the rows with friction show how a
moderate bush interacts with the moments friction locks in.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from bogie.fleet.design.experiment import FLEET_SLOT, conditions, design_points, design_samples, typical_design
from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.weigher import weigh
from pipeline.config import load_config

BUSHES = (1.0, 30.0, 100.0, 300.0, 1000.0, 3000.0)  # [N m/rad]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml")
    parser.add_argument("--conditions", type=int, default=8, help="operating conditions (default 8)")
    parser.add_argument("--tilt", type=float, default=0.75, help="nose-up chassis tilt [degree] (default 0.75)")
    args = parser.parse_args(argv)
    config = load_config(args.params)
    fleet, spec = config.fleet_study, config.design
    if spec is None:
        raise SystemExit(f"{args.params}: design is null: there is no design study to look into")
    designs = design_points(fleet, spec, config.seed)
    conds = conditions(fleet, spec.n_conditions, config.seed)
    samples = design_samples(fleet, designs, conds.iloc[: args.conditions], np.zeros(1))
    rows = samples[(samples["group"] == "triaxle") & (samples["slot"] == FLEET_SLOT)]
    rows = rows[rows["design"] == rows["design"].iloc[0]].to_dict("records")
    print(f"tri-axle, fixed contact points, 250 mm arms, {args.tilt:g} degree nose up, {len(rows)} conditions")
    print("friction  band [kN]  bush [N m/rad]  mean max_deviation [%]  largest [%]")
    typical = typical_design(fleet)
    for mu, band in ((typical["friction_coefficient"], typical["spring_friction_band"]), (0.0, 0.0)):
        for bush in BUSHES:
            dev = []
            for row in rows:
                sample = {**row, "bush_stiffness": bush, "contact_roll_radius": 0.0, "equaliser_arm": 0.25,
                          "friction_coefficient": mu, "spring_friction_band": band,
                          "chassis_tilt": math.radians(args.tilt)}  # fmt: skip
                result = weigh(bogie_from_sample(sample), sample, "static", config.protocol.static)
                dev.append(result["max_deviation"] if result["status"] == "ok" else math.nan)
            d = 100.0 * np.array(dev)
            print(f"{mu:8.2f}  {band / 1e3:9.1f}  {bush:14.0f}  {np.nanmean(d):22.2f}  {np.nanmax(d):11.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
