"""What a floating-point result depends on besides the code: the CPU the kernels were compiled for and the libraries.

The kernels are compiled by numba for the host CPU (its instruction set decides, with ``fastmath``'s contraction,
where fused multiply-adds replace a multiply and an add), numpy dispatches its own loops by the CPU's features, and
BLAS/LAPACK pick kernels per CPU. So the same code, parameters and seed give the same bits on one machine and may
differ in the last bits on another (measured: 1e-12 of a group load on a different CPU, amplified by a run that
fails). Tests that compare stored runs bit for bit store this fingerprint beside them and compare bits only where it
matches (``tests/test_kernel_identity.py``, ``tests/pipeline/test_protocol_identity.py``). Test code, not the
library's: it imports llvmlite, which the library does not declare.
"""

from __future__ import annotations

import platform


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def fingerprint() -> dict[str, str]:
    """The machine and library facts that a result's last bits depend on, as strings (JSON-ready).

    ``numba_cpu`` is the CPU name numba compiles for (``NUMBA_CPU_NAME`` overrides the host's), ``numpy_simd`` the
    SIMD extensions numpy dispatches to on this CPU (``NPY_DISABLE_CPU_FEATURES`` removes some).
    """
    import llvmlite
    import numba
    import numpy as np
    from numba.core import config

    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_features__ as features
    import llvmlite.binding as llvm

    return {
        "machine": platform.machine(),
        "cpu_model": _cpu_model(),
        "numba_cpu": config.CPU_NAME or llvm.get_host_cpu_name(),
        "numpy_simd": " ".join(sorted(name for name, on in features.items() if on)),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "llvmlite": llvmlite.__version__,
    }


def describe(stored: dict[str, str], here: dict[str, str]) -> str:
    """What differs between two fingerprints, for a test's message."""
    keys = sorted(set(stored) | set(here))
    differ = [k for k in keys if stored.get(k) != here.get(k)]
    return "; ".join(f"{k}: {stored.get(k)!r} there, {here.get(k)!r} here" for k in differ)
