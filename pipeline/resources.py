"""What the stages may use: the fixed memory budget validate checks against, and the workers a stage runs.

The memory budget is a constant, not this machine's free memory: the same params.yaml gets the same verdict from
``validate`` on every machine and at every moment. The worker cap is applied when a stage runs (the cores and free
memory of this machine), to every stage that runs workers (``simulate``, ``calibrate``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

__all__ = ["MAX_JOBS", "MEMORY_BUDGET", "WORKER_MEMORY", "available_memory", "worker_count"]

#: the memory the pipeline's peak may need [bytes]: 16 GiB, what a GitHub-hosted Linux runner and a common
#: workstation have; validate refuses params whose estimate (pipeline.config.rules) exceeds it, on any machine
MEMORY_BUDGET = 16 * 2**30

#: the most workers ``execution.n_jobs`` may ask for [-]: the cores of the largest single machines (two 128-core
#: CPUs); more is a typo. A stage runs at most this machine's cores (:func:`worker_count`)
MAX_JOBS = 256

#: memory one loky worker needs: its interpreter, numpy, numba and the compiled kernels, and one run's histories
WORKER_MEMORY = 300 * 2**20  # [bytes]


def available_memory() -> int | None:
    """The memory available to new processes [bytes] (``MemAvailable`` of /proc/meminfo), or None if unknown."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def cpu_cores() -> int:
    """The cores this process may run on [-]."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def worker_count(
    n_jobs: int, log: Callable[[str], None], stage: str, cores: int | None = None, memory: int | None = None
) -> int:
    """``n_jobs`` capped at the cores and at what the available memory holds (:data:`WORKER_MEMORY` a worker).

    A cap is logged as a warning naming ``stage``; results do not depend on the number of workers, only the time does.
    """
    cores = cpu_cores() if cores is None else cores
    memory = available_memory() if memory is None else memory
    limits = {"the cores": cores}
    if memory is not None:
        limits["the available memory"] = max(1, memory // WORKER_MEMORY)
    limit = min(limits.values())
    if n_jobs <= limit:
        return n_jobs
    reason = min(limits, key=limits.get)
    mib = "" if memory is None else f", {memory / 2**20:,.0f} MiB free, about {WORKER_MEMORY // 2**20} MiB a worker"
    log(
        f"{stage}: warning: execution.n_jobs = {n_jobs} is more than {reason} can hold ({cores} cores{mib}); "
        f"running {limit} workers"
    )
    return limit
