"""The same bits on every x86-64 machine: what a process computes with, and what could make its last bits differ.

The outputs are the same bits on every x86-64 machine with AVX2 and FMA by construction, not by the environment a
process was started with (``docs/architecture.md``, "The same bits on every machine"):

* the elementary functions that feed results (samples, roads, tapers) are :mod:`bogie.numerics`'s, which call the C
  library's scalar functions whatever SIMD loops numpy dispatches to on the CPU (AVX-512 or AVX2);
* the small matrix products and solves are :mod:`bogie.numerics`'s and :mod:`bogie.lu`'s, with their sums in index
  order, not BLAS's, whose kernel OpenBLAS picks by the CPU;
* ``import bogie`` fixes the CPU numba compiles the kernels for (x86-64-v3) before anything is compiled
  (:func:`bogie.numerics.fix_compile_target`).

So it does not matter whether pytest, a notebook or a dask worker imported numpy first, nor what numpy dispatches
(:func:`numpy_dispatch` says what it does, for the record). What can still make the bits differ is a property of the
machine or of the process, and :func:`check` reports it: another architecture (aarch64: another C library's
functions, no x86-64-v3 target), an x86-64 machine without the x86-64-v3 level, numba compiling for another target
in this process (a kernel compiled before bogie was imported, or ``NUMBA_CPU_NAME`` set), numba using Intel's SVML.
Its last word is :func:`bogie.digest.numerics_digest` against :data:`REFERENCE_DIGEST`, the digest of the machines
that made the committed results: whatever the cause, a process whose digest differs computes other last bits.
"""

from __future__ import annotations

import sys

from bogie import numerics
from bogie.digest import numerics_digest

#: :func:`bogie.digest.numerics_digest` on the x86-64 machines (AVX2 and FMA, with or without AVX-512) that made the
#: committed dvc.lock, with the library versions of constraints.txt
REFERENCE_DIGEST = "7792a8af7c1ce335"


def numpy_dispatch() -> list[str]:
    """The SIMD targets numpy dispatches its loops to in this process (what ``numpy.show_runtime()`` calls found):
    the targets numpy was built for that this CPU has and the environment did not disable when numpy was imported.
    """
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy < 2
        from numpy.core import _multiarray_umath as umath
    features = umath.__cpu_features__
    return [name for name in umath.__cpu_dispatch__ if features.get(name)]


def check() -> list[str]:
    """What may make this process's last bits differ from the committed results': empty if nothing; else one line
    each. Independent of what numpy dispatches to (see the module text)."""
    from numba.core import config

    problems = []
    if not numerics.is_x86_64():
        import platform

        problems.append(f"this is a {platform.machine()} machine, not x86-64: its C library's functions and its "
                        "compiled kernels round differently in the last bit")  # fmt: skip
    elif not numerics.V3_FLAGS <= numerics.cpu_flags():
        missing = " ".join(sorted(numerics.V3_FLAGS - numerics.cpu_flags()))
        problems.append(f"this CPU lacks the x86-64-v3 level ({missing}): numba compiles for it, without the fused "
                        "multiply-adds the kernels use elsewhere")  # fmt: skip
    elif numerics.compile_target() != " ".join(numerics.COMPILE_TARGET):
        problems.append(f"numba compiles for {numerics.compile_target()}, not {numerics.COMPILE_TARGET[0]}: a kernel "
                        "was compiled before bogie was imported, or NUMBA_CPU_NAME is set")  # fmt: skip
    if getattr(config, "USING_SVML", False):
        problems.append("numba uses Intel's SVML (icc_rt is installed), whose vector functions round differently")
    if problems:  # the digest would differ too: spare compiling the kernels for another target to say so
        return problems
    digest = numerics_digest()
    if digest != REFERENCE_DIGEST:
        problems.append(f"its numerics digest is {digest}, not the reference machines' {REFERENCE_DIGEST}")
    return problems


def warn_if_unportable(stage: str) -> list[str]:
    """Print, once, on stderr, what may make this process's results differ in the last bits from the committed ones
    (:func:`check`) and what to do; return the problems (empty: nothing printed)."""
    problems = check()
    if problems:
        print(f"{stage}: note: the results computed here may differ in the last bits from those of the x86-64 "
              f"machines that made dvc.lock ({'; '.join(problems)}). They are still deterministic on this machine; "
              "to reproduce dvc.lock byte for byte, run on an x86-64 machine with AVX2 and FMA with the versions of "
              "constraints.txt (docs/architecture.md, 'The same bits on every machine')", file=sys.stderr)  # fmt: skip
    return problems
