"""The calibrate stage's cost on a 5,000-vehicle survey with four fitted quantities (issue 14: under 20 minutes).

A synthetic survey of :data:`N_VEHICLES` groups is simulated from known fleet values on an independent fleet
(master seed 777) and written in the csv weighings format; then the stage's whole calibration
(:func:`pipeline.calibrate.run`: the table of readings, the fit, the bootstrap, the held-out fit, the direct
simulation of the calibrated fleet and its ablation) runs on it with params.yaml's settings, fitting the four
quantities of :data:`FIT`; the sensor's error is not fitted, so the synthetic survey has the protocol's own (its
class's sd, which the fit keeps), and the fitted model is the one that made the survey. It prints the time of each
part, the number of evaluations of the distance and the time per evaluation, and, against a peer measured in the
same run, the time one evaluation would take by simulating the calibration fleet directly instead of interpolating
the table (the ratio is what the table buys). Absolute times depend on the machine and its load (printed).

Run alone: ``python -m bench.bench_calibrate [--vehicles N]``.
"""

from __future__ import annotations

import argparse
import copy
import os
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
#: vehicles in the synthetic survey [-]
N_VEHICLES = 5000
#: the known fleet of the synthetic survey
TRUTH = {
    "chassis_tilt_mean_deg": 0.8, "chassis_tilt_sd_deg": 0.5, "air_share": 0.4, "site_iri_m_km": 2.0,
}  # fmt: skip
#: the four quantities fitted
FIT = {
    "chassis_tilt_mean_deg": [-1.0, 1.5], "chassis_tilt_sd_deg": [0.1, 1.5], "air_share": [0.0, 1.0],
    "site_iri_m_km": [1.0, 4.0],
}  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    from bogie.fleet import calibration_checks as K
    from pipeline import calibrate as C
    from pipeline.config import parse_config

    parser = argparse.ArgumentParser(prog="python -m bench.bench_calibrate", description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=N_VEHICLES, help=f"survey size (default {N_VEHICLES})")
    args = parser.parse_args(argv)
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["calibrate"]["fit"] = copy.deepcopy(FIT)
    truth_raw = copy.deepcopy(raw)
    truth_raw["seed"] = 777
    truth_raw["fleet"]["n_bogies"] = args.vehicles
    truth_raw["ablation"]["n_bogies"] = min(raw["ablation"]["n_bogies"], args.vehicles // 4)
    truth_raw["calibrate"]["n_bogies"] = args.vehicles
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} on {os.cpu_count()} CPUs", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        survey = Path(tmp) / "observed" / "synthetic.csv"
        start = time.perf_counter()
        truth = parse_config(truth_raw)
        known = {**C.defaults(truth), **TRUTH}  # the sensor's error: the protocol's class, as the fit keeps it
        mapper = C.workers_map(truth.execution)
        frame = K.filtered(K.simulate_fleet(C.crn_table(truth), known, executor=mapper), 0.0)
        K.write_csv_survey(frame, survey)
        print(f"synthetic survey: {len(frame)} groups in {time.perf_counter() - start:.0f} s (not part of the cost)")
        raw["observed"].update(path="observed/synthetic.csv", format="csv")
        config = parse_config(raw)
        marks: list[tuple[str, float]] = []
        start = time.perf_counter()

        def progress(text: str) -> None:
            if "generation" not in text:
                marks.append((text, time.perf_counter() - start))

        metrics, _ = C.run(config, survey, progress)
        total = time.perf_counter() - start
        for text, at in marks:
            print(f"  {at:7.1f} s  {text}")
        # the peer: one evaluation by direct simulation of the calibration fleet at the fitted values
        table = C.crn_table(config)
        values = {**C.defaults(config), **{q: e["value"] for q, e in metrics["fitted"].items()}}
        t0 = time.perf_counter()
        K.simulate_fleet(table, values, executor=C.workers_map(config.execution))
        direct = time.perf_counter() - t0
    per_eval = next(float(t.split(" of ")[1].split()[0]) for t, _ in marks if "evaluations of" in t) / 1000.0
    print(f"calibration of a {len(frame)}-group survey, {len(FIT)} quantities, {config.calibrate.n_bogies} "
          f"calibration bogies: {total:.0f} s ({total / 60:.1f} min; the issue's limit is 20 min)")  # fmt: skip
    print(f"evaluations of the distance in the full-data fit: {metrics['evaluations']}, {per_eval * 1e3:.2f} ms each")
    print(f"one evaluation by direct simulation instead: {direct:.1f} s, {direct / per_eval:,.0f} x the table's")
    for q, e in metrics["fitted"].items():
        print(f"  {q:24s} truth {TRUTH[q]:6.3f}  fitted {e['value']:6.3f}  interval [{e['low']:.3f}, {e['high']:.3f}]")
    print(f"load average {os.getloadavg()[0]:.2f} after")


if __name__ == "__main__":
    main()
