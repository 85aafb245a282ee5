"""What a floating-point result depends on besides the code: the architecture, the compile target and the libraries.

Since issue 26 the results do not depend on the CPU model nor on what numpy dispatches to nor on OpenBLAS's kernel
(``bogie/numerics.py``, ``docs/architecture.md`` "The same bits on every machine"): on every x86-64 machine with AVX2
and FMA, with the library versions of constraints.txt, they are the same bits. So the facts are the architecture, the
CPU numba compiles for (x86-64-v3 wherever the host has it), the C library (its elementary functions) and the
versions of numpy, scipy, numba and llvmlite. Tests that compare stored runs bit for bit store this fingerprint
beside them and compare bits wherever it matches (``tests/test_kernel_identity.py``,
``tests/pipeline/test_protocol_identity.py``), so an AVX-512 machine compares the bits an AVX2 machine wrote. Test
code, not the library's.
"""

from __future__ import annotations

import platform


def fingerprint() -> dict[str, str]:
    """The machine and library facts that a result's last bits depend on, as strings (JSON-ready)."""
    import llvmlite
    import numba
    import numpy as np
    import scipy

    from bogie.numerics import compile_target

    libc, libc_version = platform.libc_ver()
    return {
        "machine": platform.machine(),
        "compile_target": compile_target(),
        "libc": f"{libc} {libc_version}".strip(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "llvmlite": llvmlite.__version__,
    }


def describe(stored: dict[str, str], here: dict[str, str]) -> str:
    """What differs between two fingerprints, for a test's message."""
    keys = sorted(set(stored) | set(here))
    differ = [k for k in keys if stored.get(k) != here.get(k)]
    return "; ".join(f"{k}: {stored.get(k)!r} there, {here.get(k)!r} here" for k in differ)
