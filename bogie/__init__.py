"""bogie: why mechanically equalised multi-axle trailer bogies do not share load equally.

Modules: :mod:`bogie.params` (the bogie and its presets), :mod:`bogie.static` (Stage 2, Equation 1),
:mod:`bogie.metrics` (p, P1, RMS, LSC, DLC, road-wear factor), :mod:`bogie.plotting` (figures).
"""

import hashlib
import os
import sys
from pathlib import Path


def _set_numba_cache_dir() -> None:
    """Key numba's on-disk cache by a hash of the compiled sources.

    numba invalidates a cached function only when its own file changes, not when a compiled function it calls
    (in another module) does; a cache directory per source hash rules out running stale machine code. numba reads
    ``NUMBA_CACHE_DIR`` when it is imported, so if a program imported numba before bogie, its configuration is set
    too (otherwise the kernels would load from beside the sources, where an older build's machine code may lie).
    """
    if "NUMBA_CACHE_DIR" in os.environ:
        return
    here = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    os.environ["NUMBA_CACHE_DIR"] = str(base / "bogie-numba" / digest.hexdigest()[:16])
    if "numba" in sys.modules:
        sys.modules["numba"].core.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]


_set_numba_cache_dir()

# before any kernel is compiled or loaded: the same compiled arithmetic on every x86-64-v3 machine (bogie/numerics.py)
from bogie.numerics import fix_compile_target as _fix_compile_target  # noqa: E402

_fix_compile_target()

from bogie.params import INHIBITORS, Bogie, preset, tandem_trrl, triaxle_stage1  # noqa: E402

__all__ = ["INHIBITORS", "Bogie", "preset", "tandem_trrl", "triaxle_stage1"]
__version__ = "0.1.0"
