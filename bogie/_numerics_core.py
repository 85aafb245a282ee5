"""The compiled kernels of :mod:`bogie.numerics` that are not ufuncs: products, solves and a Cholesky factor with every
sum in index order (one multiply and one add at a time), so their bits do not depend on a BLAS kernel.

At module level, not made inside a function: numba's cache finds a function by its module and qualified name, and a
function made afresh in every process (a closure over imported kernels) missed it and compiled again each time
(``tests/test_numba_cache.py``, "a fresh process compiles nothing").
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bogie._lu import lu_factor, lu_solve


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
