"""Imported by every Python process whose path starts with this folder (``tests/pipeline/test_same_bits.py``): in
such a process numpy's functions that hand work to BLAS or LAPACK give other last bits, as another CPU's kernels may.

With ``BOGIE_OTHER_BLAS=1`` in the environment, ``numpy.dot``, ``matmul``, ``einsum``, ``cov``, the functions of
``numpy.linalg`` and ``Generator.multivariate_normal`` (SVD) return their results moved one ulp up. The ``@``
operator cannot be reached from Python (the static rule of ``tools/numerics_rule.py`` refuses it on result paths),
but ``OPENBLAS_CORETYPE``, set beside this, makes OpenBLAS run another CPU's kernels for it. numpy's elementary
functions are moved by the preloaded ``other_libm.c``. Without the variable this module does nothing.
"""

import os

if os.environ.get("BOGIE_OTHER_BLAS") == "1":
    import functools

    import numpy as np

    def _up(value):
        if isinstance(value, tuple):
            return type(value)(*(_up(v) for v in value)) if hasattr(value, "_fields") else tuple(map(_up, value))
        if isinstance(value, np.ndarray | np.floating) and value.dtype.kind == "f":
            return np.where(np.isfinite(value), np.nextafter(value, np.inf), value)[()]
        return value

    def _other(function):
        @functools.wraps(function)
        def moved(*args, **kwargs):
            return _up(function(*args, **kwargs))

        return moved

    for _name in ("dot", "vdot", "inner", "matmul", "tensordot", "einsum", "cov", "corrcoef", "polyfit"):
        setattr(np, _name, _other(getattr(np, _name)))
    for _name in ("inv", "solve", "eig", "eigh", "eigvals", "eigvalsh", "svd", "cholesky", "lstsq", "det", "pinv",
                  "norm", "qr", "multi_dot", "matrix_power"):  # fmt: skip
        setattr(np.linalg, _name, _other(getattr(np.linalg, _name)))

    class _Generator(np.random.Generator):
        def multivariate_normal(self, *args, **kwargs):
            return _up(super().multivariate_normal(*args, **kwargs))

    _default_rng = np.random.default_rng

    def _default(seed=None):
        rng = _default_rng(seed)
        return _Generator(rng.bit_generator)

    np.random.Generator = _Generator
    np.random.default_rng = _default
