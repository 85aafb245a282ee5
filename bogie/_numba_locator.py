"""Where numba caches bogie's kernels: keyed by the code, not by the clone's path (issue 45 Must 6).

numba's own locator for ``NUMBA_CACHE_DIR`` files each module's kernels under ``<parent>_<sha1 of the parent's
absolute path>``, so another clone of the same code, or the copy ``dvc exp run --temp`` makes in ``.dvc/tmp/exps``,
finds nothing and compiles every kernel again (51-69 s). :class:`PackageLocator` files a module of the ``bogie``
package under its place in the package instead (``bogie.steel.phases`` for ``bogie/steel/phases/_core.py``,
:func:`bogie.numba_cache.subpath`), and stamps it with a hash of the file's bytes (numba >= 0.68 does too; older
numba stamped the modification time, which a fresh clone changes). It answers only inside the directory ``import
bogie`` keyed by the hash of every module of the package (:func:`bogie.numba_cache.source_digest`): there a cached
kernel cannot be stale, because any edit of any module is another directory; in a cache directory the user chose,
or for a file outside the package, numba's own locators answer as before. :func:`install` puts it first among
numba's locators, in every process that imports bogie (the workers too).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from numba.core import caching, config

from bogie.numba_cache import keyed_by_code, subpath


class PackageLocator(caching.UserProvidedCacheLocator):
    """numba's user-provided locator with a cache path by place in the package and a stamp by content."""

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        self._cache_path = str(Path(config.CACHE_DIR) / subpath(py_file))

    def get_source_stamp(self):
        return hashlib.sha256(Path(self._py_file).read_bytes()).hexdigest()

    @classmethod
    def from_function(cls, py_func, py_file):
        if not keyed_by_code(config.CACHE_DIR) or subpath(py_file) is None:
            return None  # the next locator: numba's own
        return super().from_function(py_func, py_file)


def install() -> None:
    """Put :class:`PackageLocator` first among the locators numba's caches ask (once)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    if PackageLocator not in impl._locator_classes:
        impl._locator_classes = [PackageLocator, *impl._locator_classes]
