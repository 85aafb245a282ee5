"""The physics library installs and runs without the pipeline: `pip install .` gives bogie, `.[pipeline]` the rest."""

import ast
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: import name of each distribution the library may use
IMPORT_NAMES = {
    "numpy": "numpy",
    "scipy": "scipy",
    "pandas": "pandas",
    "matplotlib": "matplotlib",
    "numba": "numba",
    "pyyaml": "yaml",
}
#: what only the pipeline needs: the library must not import any of it
PIPELINE_ONLY = ("pyarrow", "joblib", "dvc", "pydantic", "tqdm", "SALib", "dask", "distributed", "jinja2", "vl_convert")


def third_party_imports(package: Path) -> set[str]:
    stdlib = set(sys.stdlib_module_names)
    found = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            found |= {n.split(".")[0] for n in names}
    return {n for n in found if n not in stdlib and n not in ("bogie", "__future__")}


def test_the_library_imports_only_its_declared_core_dependencies():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = {d.split(">")[0].split("=")[0].split("[")[0].strip().lower() for d in meta["dependencies"]}
    assert core == set(IMPORT_NAMES)
    # and its optional extras': SALib for bogie.fleet.sensitivity_design only, imported inside that function
    optional = {d.split(">")[0].strip() for d in meta["optional-dependencies"]["sensitivity"]}
    assert optional == {"SALib"}
    assert third_party_imports(ROOT / "bogie") <= set(IMPORT_NAMES.values()) | optional
    pipeline = {d.split(">")[0].split("[")[0].strip().lower() for d in meta["optional-dependencies"]["pipeline"]}
    assert {"pyarrow", "dvc", "salib", "dask"} <= pipeline and not pipeline & core
    assert meta["license"] == "MIT" and (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert (ROOT / "bogie" / "py.typed").exists()


def test_every_bogie_module_imports_and_runs_with_the_pipeline_packages_missing():
    script = textwrap.dedent(f"""
        import importlib, pkgutil, sys
        blocked = {PIPELINE_ONLY!r}
        class Block:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in blocked:
                    raise ImportError(f"{{name}} is not installed (blocked by the test)")
        sys.meta_path.insert(0, Block())
        import bogie
        for info in pkgutil.walk_packages(bogie.__path__, "bogie."):  # subpackages too (air, fleet, weighings)
            importlib.import_module(info.name)
        from bogie import triaxle_stage1
        from bogie.steel.static import wheel_loads
        loads = wheel_loads(triaxle_stage1(), 0.057, 0.0174533)
        assert loads[-1] > loads[0], loads  # nose up: the rear axle heaviest
        print("ok")
    """)
    result = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr


def test_the_compiled_kernels_cache_by_source_hash_even_when_numba_was_imported_first(tmp_path):
    # numba reads NUMBA_CACHE_DIR when it is imported: a program that imports numba before bogie must still get the
    # per-source-hash cache, not the machine code an older build left beside the sources
    script = textwrap.dedent("""
        import os, numba
        assert numba.core.config.CACHE_DIR == ""
        import bogie
        print(numba.core.config.CACHE_DIR)
        print(os.environ["NUMBA_CACHE_DIR"])
    """)
    env = {k: v for k, v in __import__("os").environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    result = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, env=env,
                            timeout=300)  # fmt: skip
    assert result.returncode == 0, result.stderr
    config_dir, env_dir = result.stdout.split()
    assert config_dir == env_dir and config_dir.startswith(str(tmp_path / "bogie-numba"))
