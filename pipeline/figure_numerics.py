"""numpy's AVX2 loops at most in the stage processes, for the figures matplotlib draws (imports nothing).

The results do not depend on what numpy dispatches to (``bogie/numerics.py``, ``tests/pipeline/test_portable.py``):
the samples, runs, statistics and metrics are the same bits whether numpy runs its baseline, AVX2 or AVX-512 loops.
matplotlib does use numpy's elementary functions, though, where we cannot reach them: a log axis maps every point
through ``numpy.log10``, and on an AVX-512 machine numpy's AVX-512 loop may put a coordinate of the report's PDF one
digit off in its tenth decimal. So ``pipeline/__init__.py`` calls :func:`limit_numpy_dispatch` before anything
imports numpy, and a stage process (``python -m pipeline.<stage>``) runs numpy's AVX2 loops at most: on an AVX-512
machine they are the same functions as on an AVX2 one (the C library's, for the float64 elementary functions). This is
the one thing that an environment variable still does, and only for figures; a variable the user set is kept.
"""

from __future__ import annotations

import os
import platform

#: numpy's dispatch targets above AVX2, by numpy 2.4's names (``numpy.show_runtime()``); an older numpy warns of
#: names it does not know and goes on
NUMPY_DISABLED = "X86_V4 AVX512_ICL AVX512_SPR"


def limit_numpy_dispatch(environ: dict[str, str] | None = None) -> bool:
    """Set ``NPY_DISABLE_CPU_FEATURES`` to :data:`NUMPY_DISABLED` in ``environ`` (default ``os.environ``) on an x86-64
    machine where it is not set; return whether it set it. Takes effect only if numpy is imported after it."""
    env = os.environ if environ is None else environ
    if platform.machine().lower() not in ("x86_64", "amd64") or "NPY_DISABLE_CPU_FEATURES" in env:
        return False
    env["NPY_DISABLE_CPU_FEATURES"] = NUMPY_DISABLED
    return True
