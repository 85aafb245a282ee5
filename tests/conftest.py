"""Test session set-up shared by all tests."""

from _fingerprint import fingerprint


def pytest_report_header(config):
    """The machine and library facts that stored bit-for-bit runs depend on (tests/test_kernel_identity.py)."""
    return "bogie machine: " + ", ".join(f"{k}={v}" for k, v in fingerprint().items())


def pytest_configure(config):
    """The tests give every dask scheduler they use: an address in the environment (dask's DASK_SCHEDULER_ADDRESS,
    which the pipeline reads when execution.dask_scheduler is null) must not change what they check."""
    import os

    os.environ.pop("DASK_SCHEDULER_ADDRESS", None)
