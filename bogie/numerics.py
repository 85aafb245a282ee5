"""Elementary functions and a compile target whose last bits do not depend on the CPU a process runs on.

Why (``docs/architecture.md``, "The same bits on every machine"): numpy dispatches its float64 ``exp``, ``log``,
``sin``, ``cos``, ``power``, ``arctan2``, ``tanh`` and others to SIMD loops chosen by the CPU when numpy is imported
(AVX-512 loops, partly Intel's SVML, on an AVX-512 machine; the C library's scalar functions on an AVX2 one), and
those loops round differently in the last bit. A sampled bush stiffness, an ISO 8608 road and so every run moved by
an ulp from one machine to the other. Which loops a process gets depends on the CPU and on what the environment said
when numpy was imported (``NPY_DISABLE_CPU_FEATURES``), so the bits depended on the import order of pytest, a
notebook or a dask worker.

This module's functions take that choice away by construction: each is a compiled loop (``bogie/_numerics_core.py``)
that calls the C library's scalar function once per element (``math.exp`` compiled by numba is a call to libm's
``exp``), so their bits are the C library's, whatever numpy dispatches and whatever the environment said. glibc
picks its own variant of ``exp``, ``log``, ``pow``, ``sin``, ``cos`` and ``atan2`` by the CPU's features too, but on
every x86-64 machine with AVX2 and FMA (the x86-64-v3 level, which every AVX-512 machine has) it picks the same FMA
variant, so these are the same bits on all of them; on aarch64 they are that machine's libm's.

:func:`fix_compile_target` fixes the CPU numba compiles bogie's kernels for (x86-64-v3 on a host with that level),
from Python, before the first kernel is compiled: the kernels' ``fastmath`` contraction fuses multiplies and adds
where the target has FMA, so a machine without FMA would give other bits; one target also gives one numba cache.
:func:`bogie.digest.numerics_digest` is a digest of results that would differ if any of this did not hold in a
process (the C library's functions, the compiled kernels' arithmetic), which the simulate stage records in every part
file and compares between its workers.

These functions are for values that end up in results (samples, roads, tapers, packs). Comparisons and plotting may
use numpy's.
"""

from __future__ import annotations

import math
import os
import platform
import sys

import numpy as np

__all__ = [
    "COMPILE_TARGET",
    "arctan2",
    "compile_target",
    "matmul",
    "cholesky",
    "cos",
    "cov",
    "exp",
    "expm1",
    "fix_compile_target",
    "geomspace",
    "inv",
    "log",
    "log1p",
    "multivariate_normal",
    "power",
    "sin",
    "sinc",
    "solve",
]

#: the CPU numba compiles for on an x86-64 host that has every instruction of :data:`V3_FLAGS` (name, features)
COMPILE_TARGET = ("x86-64-v3", "+avx2,+fma")
#: the /proc/cpuinfo flags of the x86-64-v3 level (``abm`` is LZCNT)
V3_FLAGS = frozenset({"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave"})


def cpu_flags() -> frozenset[str]:
    """The CPU's flags as /proc/cpuinfo lists them (empty where there is no /proc/cpuinfo)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("flags"):
                    return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


def is_x86_64() -> bool:
    """Whether this is an x86-64 machine."""
    return platform.machine().lower() in ("x86_64", "amd64")


def _codegen_started() -> bool:
    """Whether numba has made its CPU code generator (it reads the target CPU then, once per process)."""
    registry = sys.modules.get("numba.core.registry")
    if registry is None:
        return False
    # CPUTarget makes its target context, and with it the code generator, on first use (a cached property)
    return "_toplevel_target_context" in vars(registry.cpu_target)


def fix_compile_target(flags: frozenset[str] | None = None) -> tuple[str, str] | None:
    """Make numba compile for :data:`COMPILE_TARGET` in this process, if this host can run it; return the target
    numba compiles for, or None for the host CPU.

    numba reads the target CPU when it makes its code generator, on the first compilation or cache load, so this
    works whether or not numba was imported before, as long as nothing was compiled yet. It sets numba's
    configuration and the environment variables numba reads it from (``NUMBA_CPU_NAME``, ``NUMBA_CPU_FEATURES``):
    numba rereads its whole configuration from the environment at a compilation whenever a ``NUMBA_`` variable
    changed (bogie's own ``NUMBA_CACHE_DIR`` does, on import), which would otherwise put the host's name back in the
    configuration and in the cache's keys while the code generator keeps compiling for x86-64-v3. Child processes
    inherit the variables. A target the user chose (``NUMBA_CPU_NAME``) is kept. On a host without the x86-64-v3
    level (or not x86-64) numba compiles for the host, and the last bits may differ from an x86-64-v3 machine's.
    """
    if "NUMBA_CPU_NAME" in os.environ:
        return (os.environ["NUMBA_CPU_NAME"], os.environ.get("NUMBA_CPU_FEATURES", ""))
    if not is_x86_64() or not V3_FLAGS <= (cpu_flags() if flags is None else flags):
        return None
    if _codegen_started():
        return None
    os.environ["NUMBA_CPU_NAME"], os.environ["NUMBA_CPU_FEATURES"] = COMPILE_TARGET
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.CPU_NAME, config.CPU_FEATURES = COMPILE_TARGET
    return COMPILE_TARGET


def compile_target() -> str:
    """The CPU numba compiles for in this process, as ``name features`` (``host`` for the host CPU)."""
    from numba.core import config

    if config.CPU_NAME is None:
        return "host"
    return f"{config.CPU_NAME} {config.CPU_FEATURES or ''}".strip()


def _apply(name: str, *args):
    """The compiled loop of ``name`` (:mod:`bogie._numerics_core`) over ``args`` broadcast: a float for scalars, else an
    array of the broadcast shape."""
    from bogie import _numerics_core

    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in args])
    flat = [np.ascontiguousarray(a).ravel() for a in arrays]
    out = np.empty(flat[0].size)
    getattr(_numerics_core, f"{name}_loop")(*flat, out)
    if all(np.ndim(a) == 0 for a in args):
        return float(out[0])
    return out.reshape(arrays[0].shape)


def exp(x):
    """e^x, element by element, with the C library's bits [-]. A float for a scalar, else an array."""
    return _apply("exp", x)


def log(x):
    """Natural logarithm, element by element, with the C library's bits (-inf at 0, nan below) [-]."""
    return _apply("log", x)


def log1p(x):
    """ln(1 + x), element by element, with the C library's bits (-inf at -1, nan below) [-]."""
    return _apply("log1p", x)


def expm1(x):
    """e^x - 1, element by element, with the C library's bits [-]."""
    return _apply("expm1", x)


def sin(x):
    """sin x (x in rad), element by element, with the C library's bits [-]."""
    return _apply("sin", x)


def cos(x):
    """cos x (x in rad), element by element, with the C library's bits [-]."""
    return _apply("cos", x)


def power(x, y):
    """x^y, element by element and broadcast, with the C library's bits (nan for a negative base and a fractional
    exponent) [-]."""
    return _apply("power", x, y)


def arctan2(y, x):
    """The angle of (x, y) in (-pi, pi], element by element and broadcast, with the C library's bits [rad]."""
    return _apply("arctan2", y, x)


def matmul(a, b) -> np.ndarray:
    """The matrix product a b with every sum taken in index order, one multiply and one add at a time [-].

    ``numpy.matmul`` hands float64 products to BLAS, whose kernel (and so the order of the sums and where fused
    multiply-adds are used) OpenBLAS chooses by the CPU: the last bits differ between an AVX2 and an AVX-512 machine.
    Here they do not. For the small matrices of the static, linear and finite element models. 1-D operands are taken
    as a row (``a``) or a column (``b``) and the result has numpy's shape.
    """
    a_arr = np.asarray(a, dtype=np.float64)
    b_arr = np.asarray(b, dtype=np.float64)
    if a_arr.ndim == 0 or b_arr.ndim == 0:
        raise ValueError("matmul: scalar operands are not matrices; use *")
    a2 = a_arr.reshape(1, -1) if a_arr.ndim == 1 else a_arr.reshape(-1, a_arr.shape[-1])
    b2 = b_arr.reshape(-1, 1) if b_arr.ndim == 1 else b_arr
    if b2.ndim != 2 or a2.shape[1] != b2.shape[0]:
        raise ValueError(f"matmul: shapes {a_arr.shape} and {b_arr.shape} do not match")
    from bogie import _numerics_core

    c = _numerics_core.matmul(np.ascontiguousarray(a2), np.ascontiguousarray(b2))
    lead = a_arr.shape[:-1]
    tail = () if b_arr.ndim == 1 else (b2.shape[1],)
    return c.reshape(lead + tail)


def solve(a, b) -> np.ndarray:
    """x with a x = b, by LU with partial pivoting (:mod:`bogie.lu`), every sum in index order [-].

    ``numpy.linalg.solve`` calls LAPACK, whose BLAS kernels OpenBLAS chooses by the CPU; this gives the same bits on
    every x86-64 machine. ``b`` is a vector or a matrix of columns. Raises ``numpy.linalg.LinAlgError`` for a singular
    ``a``, as numpy does.
    """
    a_arr = np.ascontiguousarray(a, dtype=np.float64)
    b_arr = np.asarray(b, dtype=np.float64)
    if a_arr.ndim != 2 or a_arr.shape[0] != a_arr.shape[1] or b_arr.shape[:1] != a_arr.shape[:1]:
        raise ValueError(f"solve: a must be square and b have as many rows, got {a_arr.shape} and {b_arr.shape}")
    from bogie import _numerics_core

    x, ok = _numerics_core.solve(a_arr, np.ascontiguousarray(b_arr.reshape(b_arr.shape[0], -1)))
    if not ok:
        raise np.linalg.LinAlgError("Singular matrix")
    return x.reshape(b_arr.shape)


def geomspace(start: float, stop: float, num: int) -> np.ndarray:
    """``num`` points from ``start`` to ``stop`` (both > 0) evenly spaced on a log scale, the ends exact [-]:
    ``numpy.geomspace``'s formula (10 to the power of an even spacing of the ends' logarithms) with the C library's
    ``pow`` and ``log10``."""
    if not (start > 0.0 and stop > 0.0 and math.isfinite(start) and math.isfinite(stop)):
        raise ValueError(f"geomspace: start = {start!r} and stop = {stop!r} must be finite and > 0")
    out = power(10.0, np.linspace(math.log10(start), math.log10(stop), num))
    out = np.atleast_1d(out)
    if num > 0:
        out[0] = start
    if num > 1:
        out[-1] = stop
    return out


def sinc(x):
    """sin(pi x) / (pi x), 1 at 0, element by element [-]: numpy's ``sinc`` (its formula) with the C library's sine."""
    y = np.pi * np.where(np.asarray(x, dtype=np.float64) == 0.0, 1.0e-20, x)
    out = sin(y) / y
    return float(out) if np.ndim(out) == 0 else out


def inv(a) -> np.ndarray:
    """The inverse of a square matrix by :func:`solve` against the identity, every sum in index order [-]."""
    a_arr = np.asarray(a, dtype=np.float64)
    if a_arr.ndim != 2 or a_arr.shape[0] != a_arr.shape[1]:
        raise ValueError(f"inv: a must be a square matrix, got shape {a_arr.shape}")
    return solve(a_arr, np.eye(a_arr.shape[0]))


def cov(x) -> np.ndarray:
    """The sample covariance of the columns of ``x`` (rows: observations), divided by n - 1, as
    ``numpy.cov(x, rowvar=False)`` computes it but with the product's sums in index order [-]. A (d, d) matrix, also
    for one column."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[0] < 2:
        raise ValueError(f"cov: x must be a 2-D array of at least 2 rows (observations), got shape {arr.shape}")
    centred = arr - arr.mean(axis=0)
    return matmul(centred.T, centred) / (arr.shape[0] - 1)


def cholesky(a) -> np.ndarray:
    """The lower triangular L with a = L L' of a symmetric positive definite matrix, sums in index order [-]. Raises
    ``numpy.linalg.LinAlgError`` if ``a`` is not positive definite, as numpy does."""
    from bogie import _numerics_core

    a_arr = np.ascontiguousarray(a, dtype=np.float64)
    if a_arr.ndim != 2 or a_arr.shape[0] != a_arr.shape[1]:
        raise ValueError(f"cholesky: a must be a square matrix, got shape {a_arr.shape}")
    low, ok = _numerics_core.cholesky(a_arr)
    if not ok:
        raise np.linalg.LinAlgError("Matrix is not positive definite")
    return low


def multivariate_normal(rng: np.random.Generator, mean, covariance) -> np.ndarray:
    """One draw of N(mean, covariance) from ``rng``: mean + L z, L the :func:`cholesky` factor and z ``rng``'s d
    standard normals [-].

    ``Generator.multivariate_normal`` factors the covariance by LAPACK's SVD, whose kernels OpenBLAS picks by the CPU,
    so its draws differ in the last bits between machines (and, through an accept/reject step, in more than that).
    Needs a positive definite covariance (a semi-definite one raises ``numpy.linalg.LinAlgError``)."""
    m = np.asarray(mean, dtype=np.float64)
    low = cholesky(covariance)
    if low.shape[0] != m.shape[0]:
        raise ValueError(f"multivariate_normal: mean has {m.shape[0]} entries, covariance is {low.shape}")
    return m + matmul(low, rng.standard_normal(m.shape[0]))
