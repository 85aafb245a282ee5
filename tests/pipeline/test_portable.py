"""The pinned instruction sets of numpy and numba (pipeline/portable.py)."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

from pipeline import portable
from pipeline.deps import ROOT

X86 = platform.machine().lower() in ("x86_64", "amd64")
V3_HOST = X86 and portable.V3_FLAGS <= portable._cpu_flags()


@pytest.mark.skipif(not X86, reason="numpy's x86 target names apply on x86-64 only")
def test_pin_sets_numpy_and_numba_on_an_x86_64_v3_host_and_only_numpy_on_an_older_one():
    env: dict[str, str] = {"PATH": "/bin"}
    done = portable.pin(env, flags=portable.V3_FLAGS | {"sse4_2"})
    assert done == {
        "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
        "NUMBA_CPU_NAME": "x86-64-v3",
        "NUMBA_CPU_FEATURES": "+avx2,+fma",
    }
    assert env["PATH"] == "/bin" and set(env) == {"PATH", *done}
    older: dict[str, str] = {}
    assert portable.pin(older, flags=portable.V3_FLAGS - {"avx2"}) == {
        "NPY_DISABLE_CPU_FEATURES": portable.NUMPY_DISABLED
    }
    assert "NUMBA_CPU_NAME" not in older  # compiling for x86-64-v3 there would crash on an illegal instruction


def test_pin_leaves_what_the_user_set():
    env = {"NPY_DISABLE_CPU_FEATURES": "", "NUMBA_CPU_NAME": "generic"}
    done = portable.pin(env, flags=portable.V3_FLAGS)
    assert done == {}
    assert env == {"NPY_DISABLE_CPU_FEATURES": "", "NUMBA_CPU_NAME": "generic"}  # no features added to generic


def _fresh(code: str) -> str:
    env = {k: v for k, v in os.environ.items() if k not in portable.PINNED}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


@pytest.mark.skipif(not V3_HOST, reason="needs an x86-64 host with every instruction of the x86-64-v3 level")
def test_a_stage_process_gets_the_pin_and_a_late_import_is_reported():
    # as `python -m pipeline.<stage>`: the package first, then numpy and numba
    first = "import pipeline, numpy, numba; from pipeline import portable; print(portable.check())"
    assert _fresh(first) == "[]"
    late = "import numpy, numba; from pipeline import portable; print(portable.check())"
    # numba was imported for the host before the pin (and numpy, on a host with AVX-512, with its AVX-512 loops)
    assert "numba compiles for the host CPU, not x86-64-v3" in _fresh(late)
