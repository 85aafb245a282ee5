"""Test session set-up shared by all tests."""

from _fingerprint import fingerprint


def pytest_report_header(config):
    """The machine and library facts that stored bit-for-bit runs depend on (tests/test_kernel_identity.py)."""
    return "bogie machine: " + ", ".join(f"{k}={v}" for k, v in fingerprint().items())
