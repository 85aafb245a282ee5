"""A task for tests/pipeline/test_lost_worker.py that kills the loky worker running it, once: importable by the
workers (this folder is on their path, as on the main process's)."""

from __future__ import annotations

import multiprocessing
import os
import time
from pathlib import Path


def square_or_die(marker: str, value: int) -> int:
    """``value ** 2``, after 20 ms of work; but the first task a worker (not the main process) runs ends that worker
    at once (``os._exit``: as the kernel's out-of-memory killer or a lost machine would), leaving ``marker``."""
    time.sleep(0.02)
    if multiprocessing.parent_process() is not None and not Path(marker).exists():
        Path(marker).touch()
        os._exit(1)
    return value**2


def always_die(value: int) -> int:
    """A task whose worker is always lost: the retries run out."""
    if multiprocessing.parent_process() is not None:
        os._exit(1)
    time.sleep(1.0)  # the main process's share: slow, so that the workers take tasks too
    return value
