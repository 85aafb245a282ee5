"""The same bits on every x86-64 machine: numpy's and numba's instruction sets pinned before either is imported.

The same code, parameters and seed gave different last bits on two of this project's machines, both AMD EPYC:
one with AVX-512 (numpy dispatching its ``X86_V4`` loops, numba compiling for ``znver4``) and one without
(``X86_V3``, ``znver3``). numpy's AVX-512 loops of the float64 exp, log, power, sin and cos (Intel's SVML) round
differently in the last bit from its AVX2 and baseline loops, which agree with each other: the sampled bush
stiffnesses, the ISO 8608 roads and so every run moved by an ulp, and the committed ``dvc.lock`` did not reproduce
on the other machine (``docs/architecture.md``, "Reproducible on any machine").

:func:`pin` sets, for this process and the processes it starts (the loky workers inherit its environment):

* ``NPY_DISABLE_CPU_FEATURES`` = :data:`NUMPY_DISABLED`: numpy dispatches at most its AVX2 (``X86_V3``) loops;
* ``NUMBA_CPU_NAME`` = :data:`NUMBA_CPU` and ``NUMBA_CPU_FEATURES`` = :data:`NUMBA_FEATURES`: numba compiles for
  the x86-64-v3 level (AVX2 and FMA, which the kernels' ``fastmath`` contraction uses) whatever the host, only on a
  host that has every instruction of that level (:data:`V3_FLAGS`; elsewhere numba compiles for the host and the
  last bits may differ from an x86-64-v3 machine's).

A variable already set is left as it is (a deliberate choice of the user's). It works only if numpy and numba are
not yet imported: ``pipeline/__init__.py`` calls it first thing, so every ``python -m pipeline.<stage>`` and every
loky worker gets it. A dask.distributed worker imports numpy before it runs a task: start the workers with these
variables set (``docs/architecture.md``). :func:`check` tells whether the pin took effect in this process.

Measured on the second machine: the x86-64-v3 kernels give the same rows as the host's ``znver3`` ones, bit for
bit, and no slower (``bench/README.md``); numpy's baseline and AVX2 loops give the same samples, bit for bit.
"""

from __future__ import annotations

import os
import platform
import sys
from collections.abc import MutableMapping

#: the environment variables :func:`pin` sets
PINNED = ("NPY_DISABLE_CPU_FEATURES", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")
#: numpy's dispatch targets above AVX2, by numpy 2.4's names (``numpy.show_runtime()``)
NUMPY_DISABLED = "X86_V4 AVX512_ICL AVX512_SPR"
#: the CPU numba compiles for on an x86-64 host that has all of :data:`V3_FLAGS`
NUMBA_CPU = "x86-64-v3"
#: the features numba compiles with there (implied by the level; given so that none of the host's is added)
NUMBA_FEATURES = "+avx2,+fma"
#: the /proc/cpuinfo flags of the x86-64-v3 level (``abm`` is LZCNT)
V3_FLAGS = frozenset({"avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave"})


def _cpu_flags() -> frozenset[str]:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("flags"):
                    return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


def _numpy_version() -> tuple[int, ...]:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return tuple(int(part) for part in version("numpy").split(".")[:2])
    except (PackageNotFoundError, ValueError):
        return (0, 0)


def pin(environ: MutableMapping[str, str] | None = None, flags: frozenset[str] | None = None) -> dict[str, str]:
    """Set the variables of the module text in ``environ`` (default ``os.environ``) where they are not set; return
    those it set. ``flags``: the CPU's flags (default: this machine's)."""
    env = os.environ if environ is None else environ
    wanted: dict[str, str] = {}
    # numpy 2.4 named its x86 targets by level; an older numpy does not know these names (and warns)
    if platform.machine().lower() in ("x86_64", "amd64") and _numpy_version() >= (2, 4):
        wanted["NPY_DISABLE_CPU_FEATURES"] = NUMPY_DISABLED
    if V3_FLAGS <= (_cpu_flags() if flags is None else flags):
        wanted["NUMBA_CPU_NAME"] = NUMBA_CPU
        wanted["NUMBA_CPU_FEATURES"] = NUMBA_FEATURES
    if "NUMBA_CPU_NAME" in env:  # a user's own CPU name comes with the user's own features, or the host's
        wanted.pop("NUMBA_CPU_FEATURES", None)
    done = {k: v for k, v in wanted.items() if k not in env}
    env.update(done)
    return done


def check() -> list[str]:
    """What keeps this process from the pinned numerics: empty if numpy dispatches no AVX-512 loop and numba
    compiles for :data:`NUMBA_CPU` (or, on a host without the x86-64-v3 level, for the host); else one line each."""
    problems = []
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_features__ as features
    on = sorted(name for name, enabled in features.items() if enabled and name.startswith(("AVX512", "X86_V4")))
    if on:
        problems.append(f"numpy dispatches AVX-512 loops ({' '.join(on)}): NPY_DISABLE_CPU_FEATURES was not "
                        f"{NUMPY_DISABLED!r} when numpy was imported")  # fmt: skip
    config = sys.modules.get("numba.core.config")  # numba not imported: nothing compiled here, nothing to check
    if config is not None and V3_FLAGS <= _cpu_flags() and config.CPU_NAME != NUMBA_CPU:
        problems.append(f"numba compiles for {config.CPU_NAME or 'the host CPU'}, not {NUMBA_CPU}: NUMBA_CPU_NAME "
                        "was not set when numba was imported")  # fmt: skip
    return problems


def warn_unpinned(stage: str) -> None:
    """Print a warning line on stderr for each of :func:`check`'s problems, for the stage ``stage``."""
    for problem in check():
        print(f"{stage}: warning: {problem}; the outputs may differ in the last bits from another machine's "
              "(pipeline/portable.py)", file=sys.stderr)  # fmt: skip
