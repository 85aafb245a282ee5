"""bogie: why mechanically equalised multi-axle trailer bogies do not share load equally.

Modules: :mod:`bogie.params` (the bogie), :mod:`bogie.presets` (its presets), :mod:`bogie.steel` (the steel model: the
reference's four stages, the integrator and the weighing's phases),
:mod:`bogie.metrics` (p, P1, RMS, LSC, DLC, road-wear factor), :mod:`bogie.plotting` (figures).
"""

import os
import sys
from pathlib import Path

from bogie import numba_cache as _numba_cache

#: this process's claim on its cache directory (:func:`bogie.numba_cache.claim`): the lock lasts as long as the process
_CACHE_CLAIM: int | None = None


def _set_numba_cache_dir() -> None:
    """Key numba's on-disk cache by a hash of the compiled sources, and keep the cache bounded.

    numba invalidates a cached function only when its own file changes, not when a compiled function it calls
    (in another module) does; a cache directory per source hash rules out running stale machine code. numba reads
    ``NUMBA_CACHE_DIR`` when it is imported, so if a program imported numba before bogie, its configuration is set
    too (otherwise the kernels would load from beside the sources, where an older build's machine code may lie).
    The directory is claimed for this process and the others beyond the few most recently used are removed
    (:mod:`bogie.numba_cache`): one per version of the sources would otherwise pile up without end.
    """
    global _CACHE_CLAIM
    if "NUMBA_CACHE_DIR" in os.environ:
        return  # set by the user, or inherited from the bogie process that started this one (and holds the claim)
    root = _numba_cache.cache_root()
    directory = root / _numba_cache.source_digest(Path(__file__).parent)
    os.environ["NUMBA_CACHE_DIR"] = str(directory)
    if "numba" in sys.modules:
        sys.modules["numba"].core.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
    _CACHE_CLAIM = _numba_cache.claim(directory)
    _numba_cache.prune(root)


_set_numba_cache_dir()

# before any kernel is compiled or loaded: the same compiled arithmetic on every x86-64-v3 machine (bogie/numerics.py)
from bogie.numerics import fix_compile_target as _fix_compile_target  # noqa: E402

_fix_compile_target()

# numba files the kernels by their place in the package, not by the clone's path (bogie/_numba_locator.py)
from bogie._numba_locator import install as _install_locator  # noqa: E402

_install_locator()

from bogie import _moved  # noqa: E402

_moved.install()  # the steel model's old module paths, for one release (bogie/_moved.py)

from bogie.params import INHIBITORS, Bogie  # noqa: E402
from bogie.presets import preset, tandem_trrl, triaxle_stage1  # noqa: E402

__all__ = ["INHIBITORS", "Bogie", "preset", "tandem_trrl", "triaxle_stage1"]
__version__ = "0.1.0"
