"""The compiled kernels of :mod:`bogie.numerics`: the elementary functions as loops that call the C library's scalar
function once per element (``math.exp`` compiled by numba is a call to libm's ``exp``), and products, solves and a
Cholesky factor with every sum in index order (one multiply and one add at a time), so their bits depend neither on
numpy's SIMD dispatch nor on a BLAS kernel.

Plain compiled loops rather than numba ufuncs: a ufunc rebuilds its loop wrapper in every process (about 45 ms each,
0.6 s for the eight), where a compiled function loads whole from numba's cache.

At module level, not made inside a function: numba's cache finds a function by its module and qualified name, and a
function made afresh in every process (a closure over imported kernels) missed it and compiled again each time
(``tests/test_numba_cache.py``, "a fresh process compiles nothing").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bogie.lu import lu_factor, lu_solve


@njit(cache=True)
def exp_loop(x, out):
    for i in range(x.size):
        out[i] = math.exp(x[i])


@njit(cache=True)
def log_loop(x, out):
    for i in range(x.size):
        v = x[i]
        out[i] = math.log(v) if v > 0.0 else (-math.inf if v == 0.0 else math.nan)


@njit(cache=True)
def log1p_loop(x, out):
    for i in range(x.size):
        v = x[i]
        out[i] = math.log1p(v) if v > -1.0 else (-math.inf if v == -1.0 else math.nan)


@njit(cache=True)
def expm1_loop(x, out):
    for i in range(x.size):
        out[i] = math.expm1(x[i])


@njit(cache=True)
def sin_loop(x, out):
    for i in range(x.size):
        out[i] = math.sin(x[i])


@njit(cache=True)
def cos_loop(x, out):
    for i in range(x.size):
        out[i] = math.cos(x[i])


@njit(cache=True)
def power_loop(x, y, out):
    for i in range(x.size):
        a, b = x[i], y[i]
        out[i] = math.pow(a, b) if not (a < 0.0 and b != math.floor(b)) else math.nan


@njit(cache=True)
def arctan2_loop(y, x, out):
    for i in range(x.size):
        out[i] = math.atan2(y[i], x[i])


@njit(cache=True)
def matmul(a, b):
    n, m, p = a.shape[0], a.shape[1], b.shape[1]
    c = np.zeros((n, p))
    for i in range(n):
        for j in range(p):
            s = 0.0
            for k in range(m):
                s += a[i, k] * b[k, j]
            c[i, j] = s
    return c


@njit(cache=True)
def solve(a, b):
    lu = a.copy()
    piv = np.zeros(a.shape[0], dtype=np.int64)
    x = b.copy()
    if not lu_factor(lu, piv):
        return x, False
    for j in range(x.shape[1]):
        col = x[:, j].copy()
        lu_solve(lu, piv, col)
        x[:, j] = col
    return x, True


@njit(cache=True)
def cholesky(a):
    """The lower factor L of a = L L' (Cholesky-Banachiewicz, sums in index order); ok False if a is not positive
    definite."""
    n = a.shape[0]
    low = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = a[i, j]
            for k in range(j):
                s -= low[i, k] * low[j, k]
            if i == j:
                if not s > 0.0:
                    return low, False
                low[i, i] = math.sqrt(s)
            else:
                low[i, j] = s / low[j, j]
    return low, True
