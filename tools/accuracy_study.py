"""The protocols' accuracy at params.yaml's settings on many bogies: each against the same weighing in fixed steps of
a quarter of the time step.

``tests/pipeline/test_accuracy_tolerance.py`` checks six bogies against the stated tolerance; this study looks at
many: the first ``--fleet`` bogies of the default fleet (both protocols) and the first ``--sensitivity`` samples of the
Sobol' design (the static protocol; its factors reach the ends of their ranges together). It prints, per protocol and
study, the largest and the 90th-percentile difference in an axle load [N], the group load [N] and max_deviation
[points], how many outside_5pct flags differ, and the work of the protocol and of the reference (force evaluations
per weighing). ``--static-tolerance`` overrides ``protocol.static.step_tolerance_m`` [m] (a convergence study).

Run: ``python tools/accuracy_study.py [--fleet 200] [--sensitivity 100] [--static-tolerance 2e-7]``
(about 1 minute per 100 bogies and protocol on one core).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bogie.fleet import sample_fleet, sensitivity_design  # noqa: E402
from bogie.fleet.sampling.sample import bogie_from_sample  # noqa: E402
from bogie.fleet.weighing.weigher import protocols as protocol  # noqa: E402
from pipeline.config import load_config  # noqa: E402

#: the reference's time step is the protocol's divided by this, in fixed steps
DT_DIVISOR = 4


def weighing(name: str, bogie, record: dict, spec):
    """The error-free axle loads [N] and the force evaluations of one weighing (0 if the code does not count them:
    ``--tree`` of a commit before issue 15)."""
    args = (bogie, float(record["payload_fraction"]), str(record["road_class"]), int(record["road_seed"]), spec)
    run = protocol.static_weighbridge(*args) if name == "static" else protocol.wim_pass(*args)
    if not run.success:
        return None, 0
    if hasattr(run, "reading_error_free"):
        return 2.0 * run.reading_error_free, sum(p.force_evaluations for p in run.run.phases)
    return 2.0 * np.asarray(run.extras["reading_error_free" if name == "wim" else "reading"]), 0


def study(protocol: str, records: list[dict], spec) -> dict:
    fine = dataclasses.replace(spec, dt=spec.dt / DT_DIVISOR)
    if hasattr(fine, "step_tolerance"):
        fine = dataclasses.replace(fine, step_tolerance=None)
    if hasattr(spec, "sensor"):
        spec = dataclasses.replace(spec, sensor="none", sensor_vehicle_error=None, sensor_axle_error=None)
        fine = dataclasses.replace(fine, sensor="none", sensor_vehicle_error=None, sensor_axle_error=None)
    rows, work, failed = [], [], 0
    for record in records:
        bogie = bogie_from_sample(record)
        loads, evals = weighing(protocol, bogie, record, spec)
        ref, ref_evals = weighing(protocol, bogie, record, fine)
        if loads is None or ref is None:
            failed += int((loads is None) != (ref is None))
            continue
        axle = np.max(np.abs(loads - ref))
        group = abs(loads.sum() - ref.sum())
        dev = 100.0 * abs(np.max(np.abs(loads / loads.mean() - 1.0)) - np.max(np.abs(ref / ref.mean() - 1.0)))
        flag = ((loads.max() - loads.min()) / loads.max() > 0.05) != ((ref.max() - ref.min()) / ref.max() > 0.05)
        rows.append((axle, group, dev, flag, int(record["sample_id"])))
        work.append((evals, ref_evals))
    a = np.array([r[:4] for r in rows], dtype=float)
    worst = rows[int(np.argmax(a[:, 0]))][4]
    return {
        "n": len(rows), "failed_differently": failed, "axle_max": a[:, 0].max(), "axle_p90": np.quantile(a[:, 0], 0.9),
        "group_max": a[:, 1].max(), "dev_max": a[:, 2].max(), "flags": int(a[:, 3].sum()), "worst_id": worst,
        "evals": float(np.mean([w[0] for w in work])), "ref_evals": float(np.mean([w[1] for w in work])),
    }  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fleet", type=int, default=200)
    parser.add_argument("--sensitivity", type=int, default=100)
    parser.add_argument("--static-tolerance", type=float, default=None)
    args = parser.parse_args()
    config = load_config(ROOT / "params.yaml")
    static = config.protocol.static
    if args.static_tolerance is not None:
        static = dataclasses.replace(static, step_tolerance=args.static_tolerance)
    fleet = sample_fleet(config.fleet_study, config.fleet.n_bogies, config.seed, config.fleet.sampling)
    fleet = fleet.head(args.fleet).to_dict("records")
    sens = config.sensitivity
    design = sensitivity_design(config.fleet_study, sens.factors, sens.group, sens.base_size, config.seed)
    design = design.head(args.sensitivity).to_dict("records")
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"static step_tolerance {getattr(static, 'step_tolerance', None)} m, dt {static.dt} s; reference: fixed "
          f"steps of dt / {DT_DIVISOR}; load average {load}")  # fmt: skip
    print(
        "| protocol | study | bogies | axle load max [N] | p90 [N] | group load max [N] | max_deviation max "
        "[points] | outside_5pct flags differing | worst sample | force evaluations / weighing (reference) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for which, name, records, spec in (("static", "fleet", fleet, static), ("wim", "fleet", fleet,
                                          config.protocol.wim), ("static", "sensitivity", design, static)):  # fmt: skip
        if not records:
            continue
        start = time.perf_counter()
        r = study(which, records, spec)
        print(f"| {which} | {name} | {r['n']} | {r['axle_max']:.2f} | {r['axle_p90']:.2f} | {r['group_max']:.2f} "
              f"| {r['dev_max']:.4f} | {r['flags']} | {r['worst_id']} | {r['evals']:.0f} ({r['ref_evals']:.0f}) |",
              flush=True)  # fmt: skip
        if r["failed_differently"]:
            print(f"  {r['failed_differently']} weighings failed in one run and not the other")
        print(f"  ({time.perf_counter() - start:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
