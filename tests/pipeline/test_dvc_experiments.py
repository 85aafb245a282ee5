"""DVC experiments as a new user runs them: every parameter change reaches the results, a bad value loses nothing.

DVC leaves every parameter named ``size`` or ``nfiles``, at any depth, out of its run-cache key (DVC issue #10296):
with ``fleet.size`` a ``dvc exp run -S fleet.size=500`` restored the cached 2000-bogie sample and skipped the
simulation. These tests run the README's experiment commands in a temporary git repository holding a copy of the
project with a tiny study. As in ``test_end_to_end``, the stages run this checkout's code (``PYTHONPATH``), whose
compiled kernels are cached, while DVC hashes the copy's identical files.
"""

import copy
import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml

from pipeline.config import load_params

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
FORBIDDEN = {"size", "nfiles"}


def keys(tree, path=""):
    """Every key path of a nested mapping (lists of mappings included)."""
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield f"{path}.{key}" if path else str(key)
            yield from keys(value, f"{path}.{key}" if path else str(key))
    elif isinstance(tree, list):
        for i, value in enumerate(tree):
            yield from keys(value, f"{path}[{i}]")


def test_no_params_key_is_one_that_dvcs_run_cache_ignores():
    bad = [k for k in keys(load_params(ROOT / "params.yaml")) if k.rsplit(".", 1)[-1] in FORBIDDEN]
    assert bad == [], f"DVC leaves these keys out of its run-cache key (issue #10296): {bad}"
    # the check itself sees nested keys
    assert list(keys({"a": {"size": 1}})) == ["a", "a.size"]


def run(project, *args, check=True):
    env = {
        **os.environ,
        "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
        "PYTHONSAFEPATH": "1",
        "PYTHONPATH": str(ROOT),
        "DVC_NO_ANALYTICS": "1",
        "MPLBACKEND": "Agg",
        "GIT_AUTHOR_NAME": "test", "GIT_AUTHOR_EMAIL": "test@example.invalid",
        "GIT_COMMITTER_NAME": "test", "GIT_COMMITTER_EMAIL": "test@example.invalid",
    }  # fmt: skip
    result = subprocess.run(args, cwd=project, env=env, capture_output=True, text=True, timeout=600)
    if check:
        assert result.returncode == 0, f"{' '.join(args)}:\n{result.stdout}\n{result.stderr}"
    return result


def tiny_params(n_bogies):
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = n_bogies
    raw["sensitivity"]["base_size"] = 2
    raw["ablation"]["n_bogies"] = 1
    raw["protocol"]["static"]["dt_s"] = 0.002
    raw["protocol"]["wim"]["dt_s"] = 0.002
    raw["execution"].update({"backend": "loky", "n_jobs": 1, "chunk_size": 4})
    raw["calibrate"] = None  # a calibration of a few bogies is not one (calibrate.n_bogies >= 20), and not tested here
    return raw


@pytest.fixture()
def project(tmp_path):
    """A git repository with DVC holding a copy of the project and a tiny params.yaml, one commit."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for name in ("bogie", "pipeline", "observed", "bogies"):  # bogies/: a dependency of the stages (base bogie files)
        shutil.copytree(ROOT / name, tmp_path / name, ignore=ignore)
    for name in ("dvc.yaml", ".dvcignore", ".gitignore"):
        shutil.copy2(ROOT / name, tmp_path / name)
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(tiny_params(3), sort_keys=False))
    run(tmp_path, "git", "init", "--quiet")
    run(tmp_path, str(BIN / "dvc"), "init", "--quiet")
    run(tmp_path, "git", "add", "-A")
    run(tmp_path, "git", "commit", "--quiet", "-m", "tiny study")
    return tmp_path


def sizes(project):
    """Fleet bogies in the samples, and fleet runs per protocol."""
    samples = pd.read_parquet(project / "data" / "samples" / "fleet.parquet")
    runs = pd.read_parquet(project / "data" / "runs", filters=[("study", "==", "fleet")])
    return len(samples), runs.groupby("protocol", observed=True).size().to_dict()


@pytest.mark.slow
def test_dvc_exp_run_gives_the_requested_fleet_each_time_and_back(project):
    dvc = str(BIN / "dvc")
    for n in (3, 5, 3):  # back to the first value: a run-cache hit must be the right one, not a stale one
        run(project, dvc, "exp", "run", "simulate", "-S", f"fleet.n_bogies={n}")
        assert sizes(project) == (n, {"static": n, "wim": n})


@pytest.mark.slow
def test_an_edited_params_yaml_and_dvc_repro_give_the_new_fleet(project):
    dvc = str(BIN / "dvc")
    run(project, dvc, "repro", "simulate")
    assert sizes(project) == (3, {"static": 3, "wim": 3})
    (project / "params.yaml").write_text(yaml.safe_dump(tiny_params(4), sort_keys=False))
    out = run(project, dvc, "repro", "simulate").stdout
    assert "Running stage 'sample'" in out and "Running stage 'simulate'" in out
    assert sizes(project) == (4, {"static": 4, "wim": 4})


@pytest.mark.slow
def test_a_failed_experiment_stops_at_validate_and_loses_no_result(project):
    dvc = str(BIN / "dvc")
    run(project, dvc, "repro", "simulate")
    results = sorted(p for d in ("data/samples", "data/runs") for p in (project / d).rglob("*") if p.is_file())
    before = {p: p.read_bytes() for p in results}
    failed = run(project, dvc, "exp", "run", "simulate", "-S", "fleet.n_bogies=-5", check=False)
    assert failed.returncode != 0
    assert "fleet.n_bogies = -5: must be an integer in [1, 10000000]" in failed.stdout + failed.stderr
    assert "Running stage 'sample'" not in failed.stdout  # stopped before any stage that writes results
    assert {p: p.read_bytes() for p in results} == before  # samples and runs untouched
    # DVC itself leaves the bad value in params.yaml; the README's recovery: restore it, then `dvc checkout`
    assert "n_bogies: -5" in (project / "params.yaml").read_text()
    run(project, "git", "checkout", "params.yaml")
    run(project, dvc, "checkout", "validate")  # what the failed run deleted: its own data/config.json
    status = run(project, dvc, "status", "simulate").stdout
    assert "up to date" in status, status


@pytest.mark.slow
def test_an_experiment_in_a_temporary_copy_reads_a_dvc_tracked_survey_file(project):
    """docs/observed.md: `dvc add` the survey's file, and `dvc exp run --temp` finds it in its copy."""
    dvc = str(BIN / "dvc")
    shutil.copy(ROOT / "tests" / "data" / "weighings" / "site.csv", project / "observed" / "site.csv")
    run(project, dvc, "add", "--quiet", "observed/site.csv")
    # the records stay out of git (observed/.gitignore), their .dvc pointer goes in
    assert run(project, "git", "status", "--porcelain", "--ignored", "observed/site.csv").stdout.startswith("!!")
    run(project, "git", "add", "-A")
    run(project, "git", "commit", "--quiet", "-m", "a survey")
    args = ["-S", "observed.path=observed/site.csv", "-S", "observed.format=csv"]
    out = run(project, dvc, "exp", "run", "--temp", "observed", *args).stdout
    assert "Running stage 'observed'" in out, out
    # the experiment's metrics/observed.json: the survey's path, format read and asked, sha256, records read and
    # skipped, weight resolution. A plain output committed in the experiment, not DVC metrics (only the headline is,
    # issue 31): read from the experiment's commit
    sha = hashlib.sha256((project / "observed" / "site.csv").read_bytes()).hexdigest()
    refs = run(project, "git", "for-each-ref", "--format=%(refname)", "refs/exps").stdout.split()
    found = [json.loads(run(project, "git", "show", f"{ref}:metrics/observed.json").stdout)["observed"] for ref in refs]
    [observed] = [o for o in found if o is not None]  # the one experiment with a survey
    assert (observed["path"], observed["format"], observed["format_asked"], observed["sha256"]) == (
        "observed/site.csv", "csv", "csv", sha
    )  # fmt: skip
    assert (observed["records"]["read"], observed["records"]["skipped"]) == (5, 4)
    assert observed["records"]["weight_step_kg"] == 100.0
