"""Small dense LU factorisation with partial pivoting, compiled (numba), for the Newton iterations.

The iteration matrices of the time-stepping kernel (:mod:`bogie.steel.newmark`) and of the static equilibrium
(:func:`bogie.steel.nonlinear.equilibrium`) have 4 to 10 rows; factoring them in place in compiled code, without the
allocation and dispatch of ``numpy.linalg``, keeps a step's cost at a few microseconds. :func:`invert` is for a
matrix that is solved with many more times than it is formed (:mod:`bogie.steel.phases._core` keeps its iteration
matrices over many steps): a solve with the inverse is a matrix-vector product, with no pivoting or division.
All are compiled without numba's reference counting (``_nrt=False``): they make no array, and their callers hold
the arguments.

References
----------
.. [1] G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins University Press, 2013,
   Section 3.4 (Gaussian elimination with partial pivoting); W. H. Press et al., *Numerical Recipes*, 3rd ed.,
   Cambridge University Press, 2007, Section 2.1 (Gauss-Jordan elimination in place).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline="always")
def _pivot(a, piv, k):
    """Partial pivoting at column k: the row of the largest |a[i, k]|, i >= k, swapped into row k and recorded in
    ``piv[k]``. False if that pivot is zero or not finite."""
    n = a.shape[0]
    p = k
    big = abs(a[k, k])
    for i in range(k + 1, n):
        if abs(a[i, k]) > big:
            big = abs(a[i, k])
            p = i
    piv[k] = p
    if big == 0.0 or not math.isfinite(big):
        return False
    if p != k:
        for j in range(n):
            tmp = a[k, j]
            a[k, j] = a[p, j]
            a[p, j] = tmp
    return True


@njit(cache=True, _nrt=False)
def lu_factor(a, piv):
    """LU factorisation with partial pivoting, in place. Returns False if a pivot is zero.

    Parameters
    ----------
    a
        Square matrix, overwritten by its factors: L (unit diagonal, below) and U (on and above the diagonal).
    piv
        Integer array of ``a``'s order, overwritten by the row interchanges: row k was swapped with ``piv[k]``.
    """
    n = a.shape[0]
    for k in range(n):
        if not _pivot(a, piv, k):
            return False
        inv = 1.0 / a[k, k]
        for i in range(k + 1, n):
            a[i, k] *= inv
            lik = a[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= lik * a[k, j]
    return True


@njit(cache=True, _nrt=False)
def lu_solve(lu, piv, b):
    """Solve with the factors of :func:`lu_factor`; ``b`` is overwritten with the solution."""
    n = lu.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= lu[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= lu[i, j] * b[j]
        b[i] = s / lu[i, i]


@njit(cache=True, _nrt=False)
def invert(a, piv):
    """Inverse by Gauss-Jordan elimination with partial pivoting, in place. Returns False if a pivot is zero.

    Parameters
    ----------
    a
        Square matrix, overwritten by its inverse (left partly eliminated if a pivot is zero).
    piv
        Integer array of ``a``'s order, overwritten by the row interchanges of the elimination.

    Notes
    -----
    Each column of the identity the elimination acts on is stored in the column of ``a`` it has just cleared;
    the row interchanges are undone at the end as column interchanges in the reverse order. About n^3
    multiply-adds, three times a factorisation's, for a solve of n^2 multiply-adds.
    """
    n = a.shape[0]
    for k in range(n):
        if not _pivot(a, piv, k):
            return False
        inv = 1.0 / a[k, k]
        a[k, k] = 1.0
        for j in range(n):
            a[k, j] *= inv
        for i in range(n):
            lik = a[i, k]
            if i != k and lik != 0.0:
                a[i, k] = 0.0
                for j in range(n):
                    a[i, j] -= lik * a[k, j]
    for k in range(n - 1, -1, -1):
        p = piv[k]
        if p != k:
            for i in range(n):
                tmp = a[i, k]
                a[i, k] = a[i, p]
                a[i, p] = tmp
    return True
