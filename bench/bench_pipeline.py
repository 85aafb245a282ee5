"""The ``simulate`` stage: runs per second with 1 and 2 workers, growth with fleet size, default-run estimate.

Fleets sampled from the default params.yaml (default protocols and time steps), only ``fleet.n_bogies`` changed, run by
:func:`pipeline.simulate.simulate_samples` into a temporary directory (planning, hashing and writing included, as in
the stage) with the static and WIM protocols. Chunks of :data:`CHUNK_SIZE` bogies give each worker several chunks,
as the default studies do (143 chunks of 64). The loky workers are started and the numba kernels loaded before any
timing; that start-up is reported on its own. ``n_jobs = 1`` runs in the main process (joblib's sequential backend),
the true one-worker baseline. See ``bench/README.md``.
"""

from __future__ import annotations

import dataclasses
import os
import platform
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
import pandas as pd

from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.weigher import weigh
from pipeline.config import Config, load_config
from pipeline.sample import sample_fleet, sample_studies
from pipeline.simulate import simulate_samples, study_protocols

ROOT = Path(__file__).resolve().parent.parent
#: bogies per chunk in every timed run [-]: the default execution.chunk_size
CHUNK_SIZE = 64
#: fleet size of the 1- against 2-worker comparison [-]: since a run costs about 1.5 ms (8 December 2026), 256 bogies
#: took under a second and measured the start and the last chunk more than the runs
SPEEDUP_FLEET = 4096
#: fleet sizes of the growth series, 2 workers [-]
GROWTH_FLEETS = (1024, 2048, 4096)
#: the study of issue 46 Must 5's worked estimate: bogies (each weighed static and by WIM) and cluster cores [-]
NETWORK_BOGIES = 1_000_000
CLUSTER_CORES = (32, 128)
#: timed repeats of each setting; the best is kept (the machine is shared)
REPEATS = 2


def _config(size: int, n_jobs: int) -> Config:
    config = load_config(ROOT / "params.yaml")
    fleet = dataclasses.replace(config.fleet, n_bogies=size)
    execution = dataclasses.replace(config.execution, backend="loky", n_jobs=n_jobs, chunk_size=CHUNK_SIZE)
    return dataclasses.replace(config, fleet=fleet, execution=execution)


def run_fleet(size: int, n_jobs: int) -> tuple[float, pd.DataFrame]:
    """Simulate a fleet of ``size`` bogies (static and WIM); returns the wall time [s] and the runs."""
    config = _config(size, n_jobs)
    samples = {"fleet": sample_fleet(config)}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "runs"
        summary = simulate_samples(
            samples, {"fleet": study_protocols(config, "fleet")}, config.execution, out, log=lambda line: None
        )
        return summary.wall_time, pd.read_parquet(out)


def best_of(size: int, n_jobs: int) -> tuple[float, pd.DataFrame]:
    results = [run_fleet(size, n_jobs) for _ in range(REPEATS)]
    return min(results, key=lambda r: r[0])


def run_costs(n_per_cell: int = 8) -> pd.Series:
    """Mean time of one weighing [s] per (group, protocol), timed in this process on the first fleet samples.

    The runs dataset holds no timing (it would make every rebuild's data differ), so the cost is measured here.
    """
    config = _config(4 * n_per_cell, 1)
    fleet = sample_fleet(config)
    times: dict[tuple[str, str], list[float]] = {}
    warm = fleet.iloc[0].to_dict()
    for protocol, spec in study_protocols(config, "fleet"):  # loads the compiled kernels before any timing
        weigh(bogie_from_sample(warm), warm, protocol, spec)
    for sample in fleet.to_dict("records"):
        bogie = bogie_from_sample(sample)
        for protocol, spec in study_protocols(config, "fleet"):
            cell = times.setdefault((sample["group"], protocol), [])
            if len(cell) < n_per_cell:
                start = time.perf_counter()
                weigh(bogie, sample, protocol, spec)
                cell.append(time.perf_counter() - start)
    return pd.Series({key: float(np.mean(v)) for key, v in sorted(times.items())})


def default_estimate(cost: pd.Series, parallelism: float) -> tuple[int, float]:
    """Runs and estimated wall time [s] of the default simulate stage (every study, 2 workers).

    Every default run is costed at the mean time of its (group, protocol) in ``cost``, and the total divided by the
    parallelism measured with 2 workers (the speed-up over one worker).
    """
    config = load_config(ROOT / "params.yaml")
    total, n_runs = 0.0, 0
    for study, table in sample_studies(config).items():
        counts = table["group"].value_counts()
        for protocol, _ in study_protocols(config, study):
            total += sum(n * cost[(group, protocol)] for group, n in counts.items())
            n_runs += int(counts.sum())
    return n_runs, total / parallelism


def machine() -> str:
    model = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{os.cpu_count()} cores ({model}), Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__}"
    )


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    print(machine())
    print(f"load average at start {_load()}")
    start = time.perf_counter()
    run_fleet(4, 2)  # starts the loky workers and loads the compiled kernels in them
    startup = time.perf_counter() - start
    run_fleet(4, 1)  # loads the kernels in this process

    serial, serial_runs = best_of(SPEEDUP_FLEET, 1)
    parallel, runs = best_of(SPEEDUP_FLEET, 2)
    n = 2 * SPEEDUP_FLEET
    print(f"\nfleet of {SPEEDUP_FLEET} bogies, static + wim ({n} runs), chunks of {CHUNK_SIZE}, best of {REPEATS}:")
    print("| n_jobs | wall time [s] | runs/s |")
    print("|---|---|---|")
    print(f"| 1 | {serial:.2f} | {n / serial:.1f} |")
    print(f"| 2 | {parallel:.2f} | {n / parallel:.1f} |")
    print(f"speed-up 1 -> 2 workers: {serial / parallel:.2f} x (target >= 1.8 x); runs per second per core: "
          f"{n / serial:.0f} on 1 worker, {n / parallel / 2:.0f} on 2")  # fmt: skip
    assert serial_runs.equals(runs), "the runs differ between 1 and 2 workers"
    print(f"worker start-up (2 loky workers: imports and compiled-kernel load), paid once per stage: {startup:.1f} s")
    cost = run_costs()
    shown = ", ".join(f"{g} {p} {1000 * t:.1f}" for (g, p), t in cost.items())
    print(f"mean time of one run [ms], in-process: {shown}")

    print(f"\ngrowth with fleet size, 2 workers, best of {REPEATS}:")
    print("| bogies | runs | wall time [s] | ms per run | time / time of the smallest | size / smallest |")
    print("|---|---|---|---|---|---|")
    first = None
    for size in GROWTH_FLEETS:
        elapsed = parallel if size == SPEEDUP_FLEET else best_of(size, 2)[0]
        first = first or elapsed
        print(
            f"| {size} | {2 * size} | {elapsed:.2f} | {1000 * elapsed / (2 * size):.1f} | {elapsed / first:.2f} | "
            f"{size / GROWTH_FLEETS[0]:.0f} |"
        )

    parallelism = serial / parallel
    n_default, estimate = default_estimate(cost, parallelism)
    print(
        f"\ndefault `make repro` simulate stage: {n_default} runs, estimated {estimate / 60:.1f} min on 2 workers "
        f"(+ {startup:.0f} s start-up; mean run times above, parallelism {parallelism:.2f})"
    )
    per_core = n / parallel / 2  # runs per second per core, two workers sharing a machine
    for cores in CLUSTER_CORES:
        hours = 2 * NETWORK_BOGIES / (per_core * cores) / 3600
        print(f"{NETWORK_BOGIES:,} bogies x 2 protocols on {cores} cores at {per_core:.0f} runs/s a core: "
              f"{60 * hours:.1f} min of simulate ({2 * NETWORK_BOGIES / per_core / 3600:.2f} core-hours)")  # fmt: skip
    print(f"load average at end {_load()}")


if __name__ == "__main__":
    main()
