"""Peak memory of every stage after simulate, per 10^6 runs of the fleet study (issue 46 Musts 3 and 5).

Each stage of dvc.yaml runs in order (``python -m pipeline.<stage>``, its default paths) in a copy of the project's
tracked files in a temporary directory, with ``fleet.n_bogies`` set to each size asked and everything else as
params.yaml has it (its ablation, sensitivity and design studies keep their own sizes; no observed survey, so the
calibration is skipped). Each stage's peak resident memory is the kernel's ``ru_maxrss`` of that process and the
children it waited for (``os.wait4``; simulate's loky workers are not its waited children, so its figure is the
main process's). Per stage it prints the peak at each size, the slope between the two largest sizes in bytes per
fleet run, and the peak extrapolated to 10^6 fleet runs (5x10^5 bogies weighed static and by WIM) on that line: a
linear model of memory in the runs, which the two sizes measure and a third would check. The load average is
printed at the start and the end. Nothing here passes or fails.

Run alone: ``python -m bench.bench_stage_memory [--bogies 10000 40000]`` (about 5 minutes at the default sizes on 2
cores, most of it simulate).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
#: the fleet sizes measured [bogies]
SIZES = (10_000, 40_000)
#: the stages, in dvc.yaml's order (each after those it depends on)
STAGES = ("figure2", "validate", "sample", "simulate", "survey", "sensitivity", "observed", "calibrate", "design",
          "road", "headline", "report")  # fmt: skip
#: the stages that read data/runs
READERS = ("survey", "sensitivity", "observed", "road", "headline", "report")


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def project(where: Path, bogies: int) -> Path:
    """The project's tracked files in ``where``, its params.yaml's fleet of ``bogies``."""
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout.split(b"\0")
    with tempfile.TemporaryFile() as buf:
        with tarfile.open(fileobj=buf, mode="w") as tar:
            for name in filter(None, files):
                tar.add(ROOT / name.decode(), arcname=name.decode(), recursive=False)
        buf.seek(0)
        with tarfile.open(fileobj=buf) as tar:
            tar.extractall(where, filter="data")
    params = where / "params.yaml"
    raw = yaml.safe_load(params.read_text())
    raw["fleet"]["n_bogies"] = bogies
    params.write_text(yaml.safe_dump(raw, sort_keys=False))
    return where


def run_stage(root: Path, stage: str) -> tuple[float, int]:
    """``python -m pipeline.<stage>`` in ``root``: its wall time [s] and peak resident memory [bytes]."""
    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-m", f"pipeline.{stage}"], cwd=root, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE)  # fmt: skip
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{stage} failed: {child.stderr.read().decode()[-2000:]}")
    return wall, usage.ru_maxrss * 1024


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_stage_memory", description=__doc__.splitlines()[0])
    parser.add_argument("--bogies", type=int, nargs="+", default=list(SIZES), help="fleet sizes (default 10^4 4x10^4)")
    args = parser.parse_args(argv)
    print(f"load average at start {_load()}")
    peaks: dict[int, dict[str, tuple[float, int]]] = {}
    for bogies in args.bogies:
        with tempfile.TemporaryDirectory(prefix="bench-memory-") as tmp:
            root = project(Path(tmp), bogies)
            peaks[bogies] = {stage: run_stage(root, stage) for stage in STAGES}
        print(f"{bogies:,} bogies done")
    sizes = sorted(peaks)
    print("\npeak resident memory [MiB] by fleet size (bogies; fleet runs are twice as many); slope between the two "
          "largest sizes; the line at 10^6 fleet runs:")  # fmt: skip
    print("| stage | " + " | ".join(f"{b:,}" for b in sizes) + " | bytes per fleet run | at 10^6 runs [MiB] |")
    print("|---|" + "---|" * (len(sizes) + 2))
    for stage in STAGES:
        mib = [peaks[b][stage][1] / 2**20 for b in sizes]
        cells = " | ".join(f"{m:,.0f} ({peaks[b][stage][0]:.0f} s)" for m, b in zip(mib, sizes))
        if len(sizes) > 1:
            (b0, b1), (m0, m1) = sizes[-2:], (peaks[sizes[-2]][stage][1], peaks[sizes[-1]][stage][1])
            slope = (m1 - m0) / (2 * (b1 - b0))
            at = (m1 + slope * (1_000_000 - 2 * b1)) / 2**20
            tail = f"{slope:,.0f} | {at:,.0f}"
        else:
            tail = "- | -"
        mark = " (reads data/runs)" if stage in READERS else ""
        print(f"| {stage}{mark} | {cells} | {tail} |")
    print(f"load average at end {_load()}")


if __name__ == "__main__":
    main()
