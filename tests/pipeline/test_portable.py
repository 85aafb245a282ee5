"""The same bits whatever numpy dispatches, whatever BLAS kernel OpenBLAS picks, whatever was imported first
(bogie/numerics.py, pipeline/portable.py; docs/architecture.md, "The same bits on every machine").

Each test runs its computation in fresh processes that differ in what the CPU-dependent libraries do, so it can fail
on any machine: numpy without its AVX2 loops (``NPY_DISABLE_CPU_FEATURES``), OpenBLAS with another kernel
(``OPENBLAS_CORETYPE``), and numpy's elementary functions made to round differently in the last bit, as its AVX-512
(SVML) loops do on an AVX-512 machine.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import yaml
from scipy.stats import truncnorm

from bogie import numerics
from bogie.digest import numerics_digest
from bogie.fleet.sampling.distributions import truncated_standard_normal_ppf
from pipeline import portable
from pipeline.deps import ROOT

X86 = numerics.is_x86_64()
V3_HOST = X86 and numerics.V3_FLAGS <= numerics.cpu_flags()

#: numpy's dispatch targets above its x86-64 baseline, all off: every loop is the baseline's
NO_SIMD = "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"

#: a prelude that makes numpy's float64 elementary functions give other last bits (one ulp up, everywhere), as
#: another SIMD implementation may: code that feeds results through them would change its bits
OTHER_ROUNDING = textwrap.dedent(
    """
    import numpy as np
    import numba.np.npyimpl  # numba's table of numpy's ufuncs, made from the real ones first

    def _other(f):
        def g(*args, **kwargs):
            r = f(*args, **kwargs)
            if isinstance(r, (np.ndarray, np.floating)) and r.dtype == np.float64:
                r = np.where(np.isfinite(r), np.nextafter(r, np.inf), r)[()]
            return r
        return g

    for _name in ("exp", "log", "log1p", "expm1", "log10", "log2", "exp2", "sin", "cos", "tan", "arcsin", "arccos",
                  "arctan", "arctan2", "sinh", "cosh", "tanh", "power", "hypot", "cbrt"):
        setattr(np, _name, _other(getattr(np, _name)))
    """
)

#: a small study end to end in one process: samples, weighings of every kind, the static and finite element models,
#: a linear run; prints a SHA-256 of every bit of it
STUDY = textwrap.dedent(
    """
    import hashlib, math, sys
    import numpy as np
    import pipeline
    from bogie import numerics
    from bogie.steel import cases, fe
    from bogie.steel.static import nondimensional_loads, wheel_loads
    from bogie.params import triaxle_stage1
    from pipeline.config import load_config
    from pipeline.sample import sample_studies
    from pipeline.simulate import chunk_table, study_protocols

    digest = hashlib.sha256()
    config = load_config(sys.argv[1])
    studies = sample_studies(config)
    for study, frame in studies.items():
        digest.update(frame.to_csv().encode())  # repr of every float: all of its bits
        rows = {c: frame[c].iloc[:3].tolist() for c in frame.columns if c != "study"}
        table = chunk_table(rows, study_protocols(config, study))
        digest.update(table.to_pandas().to_csv(float_format=repr).encode())
    digest.update(repr(fe.figure2_points()).encode())
    digest.update(nondimensional_loads(np.linspace(0.0, 20.0, 41)[:, None], np.linspace(-1.0, 1.0, 9)).tobytes())
    digest.update(wheel_loads(triaxle_stage1(), 0.057, math.radians(1.0)).tobytes())
    digest.update(np.ascontiguousarray(cases.run("L01").wheel_loads).tobytes())
    print(digest.hexdigest(), numerics.compile_target())
    """
)


def _small_params(tmp_path) -> str:
    raw = yaml.safe_load((ROOT / "params.yaml").read_text(encoding="utf-8"))
    raw["fleet"]["n_bogies"] = 12
    raw["fleet"]["suspension_mix"] = {"tandem": {"steel": 0.5, "air": 0.5}, "triaxle": {"steel": 0.5, "air": 0.5}}
    raw["ablation"]["n_bogies"] = 2
    raw["sensitivity"]["base_size"] = 4
    path = tmp_path / "params.yaml"
    path.write_text(yaml.safe_dump(raw), encoding="utf-8")
    return str(path)


#: what a fresh process must not inherit from this one (bogie set numba's target variables here on import)
INHERITED = ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES", "NUMBA_CACHE_DIR")


def _fresh_env(**changes: str) -> dict[str, str]:
    return {**{k: v for k, v in os.environ.items() if k not in INHERITED}, **changes}


def _run(code: str, *args: str, env: dict[str, str] | None = None, prelude: str = "") -> str:
    clean = _fresh_env()
    out = subprocess.run(
        [sys.executable, "-c", prelude + code, *args], cwd=ROOT, env={**clean, **(env or {})},
        capture_output=True, text=True, check=False, timeout=900,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout.strip()


@pytest.mark.skipif(not X86, reason="NPY_DISABLE_CPU_FEATURES and OPENBLAS_CORETYPE name x86 targets")
def test_a_study_gives_the_same_bits_whatever_numpy_dispatches_and_openblas_picks(tmp_path):
    params = _small_params(tmp_path)
    usual = _run(STUDY, params)
    # numpy's baseline loops only, OpenBLAS's generic SSE3 kernels
    plain = _run(STUDY, params, env={"NPY_DISABLE_CPU_FEATURES": NO_SIMD, "OPENBLAS_CORETYPE": "Prescott"})
    # AVX kernels without FMA: other sums in dot products, solves and eigensolvers
    sandy = _run(STUDY, params, env={"OPENBLAS_CORETYPE": "Sandybridge"})
    assert plain == usual
    assert sandy == usual


def test_a_study_gives_the_same_bits_when_numpys_elementary_functions_round_otherwise(tmp_path):
    # what an AVX-512 machine's numpy does to exp, log, sin, cos, power, ...: nothing that feeds a result may use them
    params = _small_params(tmp_path)
    assert _run(STUDY, params, prelude=OTHER_ROUNDING) == _run(STUDY, params)


def test_the_prelude_does_change_numpys_bits():
    # the test above would pass for nothing if the prelude changed nothing
    code = "import numpy as np, math; x = np.linspace(0.1, 3, 7); print(np.exp(x).tolist() == [math.exp(v) for v in x])"
    assert _run(code) == "True"
    assert _run(code, prelude=OTHER_ROUNDING) == "False"


def test_numerics_are_the_c_librarys_scalar_functions_bit_for_bit():
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(-50.0, 50.0, 2000), [0.0, 1e-300, 709.0, -745.0, math.pi, 1e6]])
    y = rng.uniform(-3.0, 3.0, x.size)
    assert numerics.exp(x[x < 709.5]).tolist() == [math.exp(v) for v in x[x < 709.5]]
    with np.errstate(over="ignore"):
        assert numerics.exp(1e6) == math.inf  # numpy's overflow, where math raises
    for ours, scalar in ((numerics.sin, math.sin), (numerics.cos, math.cos)):
        assert ours(x).tolist() == [scalar(v) for v in x]
    positive = np.abs(x) + 1e-3
    assert numerics.log(positive).tolist() == [math.log(v) for v in positive]
    assert numerics.power(positive, y).tolist() == [math.pow(a, b) for a, b in zip(positive, y)]
    assert numerics.arctan2(y, x).tolist() == [math.atan2(a, b) for a, b in zip(y, x)]
    # numpy's conventions where the C library's Python wrappers raise
    assert numerics.log(0.0) == -math.inf and math.isnan(numerics.log(-1.0)) and math.isnan(numerics.power(-2.0, 0.5))
    assert numerics.power(-2.0, 3.0) == -8.0
    assert isinstance(numerics.exp(1.0), float) and numerics.exp(np.zeros((2, 3))).shape == (2, 3)


def test_order_fixed_products_and_solves_agree_with_numpy_to_rounding():
    rng = np.random.default_rng(11)
    a, b = rng.normal(size=(6, 6)), rng.normal(size=(6, 4))
    assert np.allclose(numerics.matmul(a, b), a @ b, rtol=0, atol=1e-13)
    assert numerics.matmul(a, b[:, 0]).shape == (6,) and numerics.matmul(b[:, 0], b).shape == (4,)
    assert numerics.matmul(rng.normal(size=(3, 5, 6)), a).shape == (3, 5, 6)
    x = numerics.solve(a, b)
    assert np.allclose(a @ x, b, rtol=0, atol=1e-12)
    with pytest.raises(np.linalg.LinAlgError):
        numerics.solve(np.ones((3, 3)), np.ones(3))
    with pytest.raises(ValueError, match="shapes"):
        numerics.matmul(a, rng.normal(size=(5, 2)))


@pytest.mark.parametrize("a, b", [(-1.6666, 2.9167), (-2.875, 2.125), (0.5, 3.0), (-math.inf, 1.0), (1.0, math.inf),
                                  (-6.0, -1.0), (-30.0, 30.0)])  # fmt: skip
def test_the_truncated_normal_is_scipys_to_rounding_and_inside_its_bounds(a, b):
    u = np.random.default_rng(2).uniform(size=20_000)
    ours = truncated_standard_normal_ppf(u, a, b)
    assert np.max(np.abs(ours - truncnorm.ppf(u, a, b))) < 2e-14
    assert np.all((ours >= a) & (ours <= b))
    if math.isfinite(a):
        assert truncated_standard_normal_ppf(0.0, a, b) == pytest.approx(a)


def test_check_answers_from_what_numpy_dispatches_not_from_the_hardware():
    code = (
        "import io, contextlib, json, numpy as np\n"
        "from pipeline import portable\n"
        "buf = io.StringIO()\n"
        "with contextlib.redirect_stdout(buf): np.show_runtime()\n"
        "found = [s for s in buf.getvalue().split(\"'found': [\")[1].split(']')[0].replace(\"'\", '').split(', ') if s]"
        " if \"'found'\" in buf.getvalue() else []\n"
        "print(json.dumps([portable.numpy_dispatch(), found, portable.check()]))"
    )
    usual = json.loads(_run(code))
    plain = json.loads(_run(code, env={"NPY_DISABLE_CPU_FEATURES": NO_SIMD}))
    assert usual[0] == usual[1] and plain[0] == plain[1]  # what numpy.show_runtime() calls found
    if X86:
        assert plain[0] == []
    # numpy's dispatch makes no difference to the results, so none to the answer either
    assert usual[2] == plain[2]
    if V3_HOST:
        assert usual[2] == [], usual[2]


@pytest.mark.skipif(not V3_HOST, reason="needs an x86-64 host with every instruction of the x86-64-v3 level")
def test_import_bogie_fixes_the_compile_target_whatever_was_imported_before():
    for first in ("", "import numpy, numba; "):
        assert _run(first + "import bogie; from bogie import numerics; print(numerics.compile_target())") == (
            "x86-64-v3 +avx2,+fma"
        )


@pytest.mark.skipif(not V3_HOST, reason="needs an x86-64 host with every instruction of the x86-64-v3 level")
def test_the_compile_target_holds_through_a_first_compilation_with_an_empty_cache(tmp_path):
    # numba rereads its configuration from the environment at a compilation once a NUMBA_ variable changed (bogie
    # sets NUMBA_CACHE_DIR on import): the target must survive that, as it must in a fresh clone's first stage
    code = (
        "import numba, bogie\n"
        "from bogie import numerics\n"
        "numerics.exp(1.0)\n"  # compiled now: the cache is empty
        "from numba.core import config\n"
        "print(numerics.compile_target(), config.CPU_NAME)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=_fresh_env(XDG_CACHE_HOME=str(tmp_path)),
                         capture_output=True, text=True, check=True)  # fmt: skip
    assert out.stdout.split() == ["x86-64-v3", "+avx2,+fma", "x86-64-v3"]
    assert any(tmp_path.rglob("*.nbi")), "nothing was compiled into the empty cache"


@pytest.mark.skipif(not V3_HOST, reason="needs an x86-64 host with every instruction of the x86-64-v3 level")
def test_a_kernel_compiled_before_bogie_is_reported_once_with_what_to_do():
    code = (
        "import numba\n"
        "numba.njit(lambda x: x + 1.0)(1.0)\n"  # numba's code generator made for the host, before bogie
        "from pipeline import portable\n"
        "print(portable.warn_if_unportable('stage'))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=_fresh_env(), capture_output=True, text=True,
                         check=True)  # fmt: skip
    assert "numba compiles for host, not x86-64-v3" in out.stdout
    assert out.stderr.count("stage: note:") == 1 and "constraints.txt" in out.stderr


@pytest.mark.skipif(not V3_HOST, reason="the reference digest is the x86-64-v3 machines'")
def test_the_reference_digest_is_this_machines():
    # a change to the kernels changes the digest: then set portable.REFERENCE_DIGEST to the new one (all x86-64
    # machines with AVX2 and FMA compute the same)
    assert numerics_digest() == portable.REFERENCE_DIGEST
