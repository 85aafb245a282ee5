"""The same bits whatever the CPU: a guard that fails on the machine it runs on (issue 39).

Two halves that work together (``docs/architecture.md``, "The same bits on every machine"):

* the static rule (``tools/numerics_rule.py``): no numpy elementary function, ``**`` on an array, ``@``, BLAS or
  LAPACK call, ``multivariate_normal`` or scipy.stats distribution on a result path in ``bogie/`` or ``pipeline/``,
  each exception named with its reason. It reads tokens, so it catches code written after it;
* every stage of a tiny study, calibrate with a small survey included, run twice: once as usual and once in
  processes where numpy's elementary functions and its BLAS/LAPACK functions give other last bits on purpose
  (``tests/perturb/``: a preloaded C library whose ``exp``, ``log``, ``pow``, ... move one ulp up when numpy's ufunc
  loops call them, numpy's SIMD dispatch off so that every loop calls them, OpenBLAS on another CPU's kernels, and
  numpy's products, solves, covariances and ``multivariate_normal`` one ulp up). Every file of ``data/`` and
  ``metrics/`` must be the same bytes. That is what an AVX-512 machine's numpy or another machine's OpenBLAS would
  do to code that used them, so on an AVX2 machine (where numpy's loops are the C library's) the test fails as it
  would on an AVX-512 one.
"""

from __future__ import annotations

import copy
import hashlib
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml

from pipeline.config import load_params

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
PERTURB = ROOT / "tests" / "perturb"
sys.path.insert(0, str(ROOT / "tools"))

import numerics_rule  # noqa: E402

#: a process's environment without what this one set for itself (bogie sets numba's target on import)
INHERITED = ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES", "LD_PRELOAD")


def _numpy_targets() -> str:
    """Every SIMD target numpy can dispatch to, by its own names: all of them off leaves its baseline loops, which call
    the C library's elementary functions."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy < 2
        from numpy.core import _multiarray_umath as umath
    return " ".join(umath.__cpu_dispatch__)


@pytest.fixture(scope="session")
def other_libm(tmp_path_factory) -> Path:
    """tests/perturb/other_libm.c built as a shared library."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("needs a C compiler (cc, gcc or clang) to build tests/perturb/other_libm.c; the static rule "
                    "(test_no_result_path_uses_cpu_dispatched_numerics) still runs")  # fmt: skip
    out = tmp_path_factory.mktemp("perturb") / "other_libm.so"
    subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(out), str(PERTURB / "other_libm.c"), "-ldl", "-lm"],
                   check=True, capture_output=True)  # fmt: skip
    return out


def perturbed_env(other_libm: Path, base: dict[str, str] | None = None) -> dict[str, str]:
    """The environment of a process whose numpy gives other last bits (the module text)."""
    env = {k: v for k, v in (os.environ if base is None else base).items() if k not in INHERITED}
    path = [str(PERTURB), *([env["PYTHONPATH"]] if env.get("PYTHONPATH") else [])]
    return {
        **env,
        "LD_PRELOAD": str(other_libm),
        "NPY_DISABLE_CPU_FEATURES": _numpy_targets(),
        "OPENBLAS_CORETYPE": "Prescott",
        "BOGIE_OTHER_BLAS": "1",
        "PYTHONPATH": os.pathsep.join(path),
    }


def _python(code: str, env: dict[str, str]) -> str:
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout.strip()


# ---- the static rule ---------------------------------------------------------------------------------------------
def test_no_result_path_uses_cpu_dispatched_numerics():
    findings = numerics_rule.check()
    assert not findings, "\n".join(map(str, findings))


@pytest.mark.parametrize(
    "code, what",
    [
        ("import numpy as np\ny = np.exp(x)", "np.exp"),
        ("import numpy\ny = numpy.log1p(x)", "numpy.log1p"),
        ("from numpy import power\ny = 1", "from numpy import power"),
        ("y = x**4", "**"),
        ("y = x ** k", "**"),
        ("x **= 1.5", "**="),
        ("y = a @ b", "@"),
        ("import numpy as np\ny = np.linalg.inv(a)", "np.linalg.inv"),
        ("import numpy as np\ny = np.cov(a, rowvar=False)", "np.cov"),
        ("import numpy as np\ny = np.geomspace(1.0, 2.0, 5)", "np.geomspace"),
        ("y = rng.multivariate_normal(m, c)", ".multivariate_normal"),
        ("y = a.dot(b)", ".dot"),
        ("from numpy.linalg import solve\ny = solve(a, b)", "solve"),
        ("from scipy.stats import norm\ny = norm.pdf(x)", "norm"),
        ("from scipy import linalg\ny = linalg.expm(a)", "linalg"),
        ("from numba import njit\n@njit\ndef f(a, b):\n    return a @ b", "@"),  # numba's @ is BLAS's too
    ],
)
def test_the_rule_catches_each_kind_of_cpu_dispatched_numerics(code, what):
    findings = numerics_rule.check_source(code, "m.py")
    assert findings and findings[0].what.startswith(what), findings


@pytest.mark.parametrize(
    "code",
    [
        "y = x**2 + x**0.5 + x**-1",  # numpy's exact fast paths: square, sqrt, reciprocal
        "y = 2.0**10",  # constants
        "import numpy as np\ny = np.sqrt(x) + np.abs(x) + np.floor(x)",  # exactly rounded everywhere
        "from numba import njit\nimport numpy as np\n@njit\ndef f(x):\n    return np.exp(x) + x**1.5",  # libm
        "y = x**k  # numerics-ok: x and k are Python floats (libm's pow)",
        "# numerics-ok: a figure's curve, no number out\ny = np.polyfit(\n    a, b, 2)",
        "from bogie import numerics\ny = numerics.multivariate_normal(rng, m, c)",
        "from scipy.stats import qmc\ns = qmc.Sobol(3)",
    ],
)
def test_the_rule_passes_what_is_the_same_everywhere_or_named(code):
    assert numerics_rule.check_source(code, "m.py") == []


def test_an_exception_without_a_reason_is_refused(tmp_path):
    (tmp_path / "bogie").mkdir()
    (tmp_path / "pipeline").mkdir()
    (tmp_path / "bogie" / "m.py").write_text("y = x**k  # numerics-ok:\n", encoding="utf-8")
    # a bare marker excuses nothing, and is itself a finding
    assert [f.what.split(":")[0] for f in numerics_rule.check(tmp_path)] == ["**", "numerics-ok without a reason"]


# ---- the perturbation does what it says ----------------------------------------------------------------------------
PROBE = textwrap.dedent(
    """
    import json, math
    import numpy as np
    from bogie import numerics
    x = np.linspace(0.1, 3.0, 101)
    a = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    out = {
        "exp": np.exp(x).tolist(), "log": np.log(x).tolist(), "log1p": np.log1p(x).tolist(),
        "sin": np.sin(x).tolist(), "pow": (x**4).tolist(), "pow_frac": (x**2.7).tolist(),
        "inv": np.linalg.inv(a).tolist(), "cov": np.cov(np.outer(x, [1.0, 2.0, 3.0]) ** 0.5, rowvar=False).tolist(),
        "mvn": np.random.default_rng(1).multivariate_normal([0.0, 1.0, 2.0], a).tolist(),
        "ours": [numerics.exp(x).tolist(), numerics.power(x, 4.0).tolist(), numerics.inv(a).tolist(),
                 numerics.cov(np.outer(x, [1.0, 2.0, 3.0]) ** 0.5).tolist(),
                 numerics.multivariate_normal(np.random.default_rng(1), [0.0, 1.0, 2.0], a).tolist(),
                 math.exp(0.3), math.pow(1.7, 2.2)],
    }
    print(json.dumps(out))
    """
)


def test_the_perturbed_process_changes_numpys_bits_and_not_bogies(other_libm):
    # the stage test below would pass for nothing if the perturbation changed nothing, on this machine
    import json

    usual = json.loads(_python(PROBE, {k: v for k, v in os.environ.items() if k not in INHERITED}))
    other = json.loads(_python(PROBE, perturbed_env(other_libm)))
    for name in ("exp", "log", "log1p", "sin", "pow", "pow_frac", "inv", "cov", "mvn"):
        assert other[name] != usual[name], f"the perturbation leaves numpy's {name} as it was"
    assert other["ours"] == usual["ours"]


# ---- every stage, a survey given ---------------------------------------------------------------------------------
def tiny_params() -> dict:
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 12
    raw["fleet"]["suspension_mix"] = {"tandem": {"steel": 0.5, "air": 0.5}, "triaxle": {"steel": 0.5, "air": 0.5}}
    raw["sensitivity"].update(base_size=4, bootstrap_resamples=20)
    raw["ablation"]["n_bogies"] = 2
    raw["protocol"]["static"]["dt_s"] = 0.002
    raw["protocol"]["wim"]["dt_s"] = 0.002
    raw["execution"].update({"backend": "loky", "n_jobs": 2, "chunk_size": 4})
    raw["design"].update(groups=["triaxle"], n_conditions=2, tilt_step_deg=2.0, n_space_filling=0,
                         grid={"bush_stiffness": [1.0, 3000.0]})  # fmt: skip
    raw["observed"].update(path="observed/survey.csv", format="csv")
    raw["calibrate"].update(n_bogies=20, tilt_step_deg=1.0, bootstrap_resamples=3, maxiter=3, popsize=3,
                            posterior_draws=120)  # fmt: skip
    return raw


def _survey(path: Path) -> None:
    """A small synthetic survey (200 vehicles of another fleet, written as the csv weighings format)."""
    from bogie.fleet.calibration import checks as K
    from pipeline import calibrate as C
    from pipeline.config import parse_config

    raw = tiny_params()
    raw["seed"] = 777
    raw["calibrate"]["n_bogies"] = raw["fleet"]["n_bogies"] = 200
    config = parse_config(raw)
    truth = {"chassis_tilt_mean_deg": 0.8, "chassis_tilt_sd_deg": 0.5, "air_share": 0.4, "site_iri_m_km": 1.3,
             "sensor_error_pct": 3.0}  # fmt: skip
    frame = K.filtered(K.simulate_fleet(C.crn_table(config), truth, executor=None), 0.0)
    path.parent.mkdir(parents=True, exist_ok=True)
    K.write_csv_survey(frame, path)


def _project(path: Path, survey: Path) -> Path:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for name in ("bogie", "pipeline", "bogies"):
        shutil.copytree(ROOT / name, path / name, ignore=ignore)
    for name in ("dvc.yaml", ".dvcignore"):
        shutil.copy2(ROOT / name, path / name)
    (path / "observed").mkdir()
    shutil.copy2(survey, path / "observed" / "survey.csv")
    (path / "params.yaml").write_text(yaml.safe_dump(tiny_params(), sort_keys=False), encoding="utf-8")
    return path


def _repro(project: Path, env: dict[str, str]) -> str:
    env = {
        **env,
        "PATH": f"{BIN}{os.pathsep}{env.get('PATH', '')}",
        # the stages run this checkout's code (numba's cache is keyed by the source's path), as test_end_to_end's
        "PYTHONSAFEPATH": "1",
        "PYTHONPATH": os.pathsep.join([*filter(None, [env.get("PYTHONPATH")]), str(ROOT)]),
        "DVC_NO_ANALYTICS": "1",
        "MPLBACKEND": "Agg",
    }
    for args in (["init", "--no-scm", "--quiet"], ["repro"]):
        out = subprocess.run([str(BIN / "dvc"), *args], cwd=project, env=env, capture_output=True, text=True,
                             timeout=1800)  # fmt: skip
        assert out.returncode == 0, f"dvc {' '.join(args)}:\n{out.stdout[-4000:]}\n{out.stderr[-4000:]}"
    return out.stdout


def digests(project: Path) -> dict[str, str]:
    """SHA-256 of every file of data/ and metrics/ (the results; the report's figures are drawings)."""
    return {
        p.relative_to(project).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
        for folder in ("data", "metrics")
        for p in sorted((project / folder).rglob("*"))
        if p.is_file()
    }


@pytest.mark.slow
def test_every_stage_gives_the_same_bits_when_numpy_and_blas_round_otherwise(tmp_path, other_libm):
    survey = tmp_path / "survey.csv"
    _survey(survey)
    clean = {k: v for k, v in os.environ.items() if k not in INHERITED}
    usual = _project(tmp_path / "usual", survey)
    log = _repro(usual, clean)
    assert "Running stage 'calibrate'" in log and "calibrate: skipped" not in log
    other = _project(tmp_path / "other", survey)
    _repro(other, perturbed_env(other_libm, clean))
    a, b = digests(usual), digests(other)
    assert any(k.startswith("data/calibration/") for k in a) and "metrics/calibration.json" in a
    assert "metrics/road.json" in a and any(k.startswith("data/runs/") for k in a)
    assert sorted(a) == sorted(b)
    differ = [k for k in a if a[k] != b[k]]
    assert not differ, f"these outputs depend on numpy's SIMD loops or the BLAS kernel: {differ}"
