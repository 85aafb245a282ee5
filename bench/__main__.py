"""Run every benchmark in :data:`BENCHMARKS` and print each one's table: ``python -m bench`` from the project root."""

from __future__ import annotations

import importlib
import time

#: benchmark modules, each with a ``main()`` that prints its table
BENCHMARKS = (
    "bench.bench_linear",
    "bench.bench_nonlinear",
    "bench.bench_single_run",
    "bench.bench_newton",
    "bench.bench_pipeline",
    "bench.bench_protocol",
    "bench.bench_stage",
    "bench.bench_air",
    "bench.bench_calibrate",
    "bench.bench_distance",
    "bench.bench_readers",
    "bench.bench_weighings",
    "bench.profile_protocol",
    "bench.profile_stage",
)


def main() -> None:
    for name in BENCHMARKS:
        print(f"== {name} ==", flush=True)
        start = time.perf_counter()
        importlib.import_module(name).main()
        print(f"({name} took {time.perf_counter() - start:.0f} s)\n", flush=True)


if __name__ == "__main__":
    main()
