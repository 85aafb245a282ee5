"""Where the ``simulate`` stage's time goes: by study, protocol and group, the compiled kernel against the Python.

``python -m bench.profile_stage [--fraction F]`` weighs the first fraction ``F`` (default 0.1) of each study of this
checkout's ``data/samples`` (run ``make repro`` or ``dvc repro sample`` first) by the study's protocols, serially in
one process, as a chunk of the stage does (:func:`bogie.fleet.weighing.weigher.weigh`, the road tables' cache emptied
first), after an untimed warm-up that loads the kernels. For each (study, protocol, group) it prints the runs, the time
per run, the compiled call's share (``bogie.steel.phases._core.run_phases``, timed around each call), the Python around
it (road tables, phases, packing, result row), ``bogie_from_sample`` per run, the step attempts per run (accepted
and rejected steps, from the kernel's statistics), the kernel's time per attempt and the category's share of the
total; then the totals and the load average. Contiguous slices keep the ablation's variants of a bogie together,
as in the stage (they share a road). Compare shares and ratios, not times: the machine is shared.
"""

from __future__ import annotations

import argparse
import collections
import os
import time
from pathlib import Path

import pipeline  # noqa: F401 - first: pins numpy's and numba's instruction sets as the stage does

ROOT = Path(__file__).resolve().parent.parent
STUDIES = ("fleet", "ablation", "sensitivity")
WARM_SAMPLES = 4


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.profile_stage", description=__doc__.splitlines()[0])
    parser.add_argument("--fraction", type=float, default=0.1, help="share of each study weighed (default 0.1)")
    args = parser.parse_args(argv)
    from bogie.settings import check_value

    check_value(
        "--fraction", args.fraction, low=0.0, low_open=True, high=1.0, note="share of each study", error=SystemExit
    )

    import pandas as pd

    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.fleet.weighing import protocols as protocol
    from bogie.fleet.weighing import weigher
    from bogie.steel.phases import _core as pc
    from pipeline.config import load_config
    from pipeline.simulate import study_protocols

    config = load_config(ROOT / "params.yaml")
    kernel = pc.run_phases
    call = {"time": 0.0, "attempts": 0}

    def timed(*a):
        start = time.perf_counter()
        out = kernel(*a)
        call["time"] += time.perf_counter() - start
        stats = a[23]  # the per-phase statistics the kernel fills (bogie.steel.phases.run's argument order)
        call["attempts"] += int(stats[:, pc.S_STEPS].sum() + stats[:, pc.S_REJECTED].sum())
        return out

    pc.run_phases = timed
    tables = {study: pd.read_parquet(ROOT / "data" / "samples" / f"{study}.parquet") for study in STUDIES}
    for study, table in tables.items():  # untimed: loads (or compiles) the kernels
        for record in table.head(WARM_SAMPLES).to_dict("records"):
            bogie = bogie_from_sample(record)
            for name, spec in study_protocols(config, study):
                weigher.weigh(bogie, record, name, spec)
    protocol._static_table.cache_clear()
    protocol._wim_table.cache_clear()
    load_start = os.getloadavg()
    # per category: runs, weigh time, kernel time, bogie_from_sample time, attempts [s, -]
    found: dict[tuple[str, str, str], list[float]] = collections.defaultdict(lambda: [0, 0.0, 0.0, 0.0, 0])
    for study, table in tables.items():
        protocols = study_protocols(config, study)
        for record in table.iloc[: max(1, int(len(table) * args.fraction))].to_dict("records"):
            start = time.perf_counter()
            bogie = bogie_from_sample(record)
            built = (time.perf_counter() - start) / len(protocols)
            for name, spec in protocols:
                call["time"], call["attempts"] = 0.0, 0
                start = time.perf_counter()
                weigher.weigh(bogie, record, name, spec)
                row = found[(study, name, str(record["group"]))]
                row[0] += 1
                row[1] += time.perf_counter() - start
                row[2] += call["time"]
                row[3] += built
                row[4] += call["attempts"]
    total = sum(r[1] + r[3] for r in found.values())
    print(f"{'study':12s} {'protocol':8s} {'group':8s} {'runs':>5s} {'ms/run':>7s} {'kernel':>7s} {'python':>7s} "
          f"{'b_f_s':>6s} {'attempts':>8s} {'us/att':>6s} {'share':>6s}")  # fmt: skip
    for (study, name, group), (n, weigh, kern, built, attempts) in sorted(found.items()):
        print(f"{study:12s} {name:8s} {group:8s} {n:5d} {1e3 * weigh / n:7.3f} {1e3 * kern / n:7.3f} "
              f"{1e3 * (weigh - kern) / n:7.3f} {1e3 * built / n:6.3f} {attempts / n:8.0f} "
              f"{1e6 * kern / max(attempts, 1):6.2f} {(weigh + built) / total:6.1%}")  # fmt: skip
    kern = sum(r[2] for r in found.values())
    runs = sum(r[0] for r in found.values())
    print(f"total: {runs} runs, {total:.2f} s, kernel {kern:.2f} s ({kern / total:.0%}), Python {total - kern:.2f} s; "
          f"load average {load_start[0]:.2f} -> {os.getloadavg()[0]:.2f} (2 cores)")  # fmt: skip


if __name__ == "__main__":
    main()
