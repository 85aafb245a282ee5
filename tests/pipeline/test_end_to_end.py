"""The whole pipeline: ``dvc repro`` in a temporary copy of the project on a tiny fleet.

The copy holds the code, dvc.yaml and a params.yaml with tiny studies. The stages run the code of this checkout
(``PYTHONSAFEPATH=1`` and ``PYTHONPATH`` = the project root) rather than the copy of it: numba keys its on-disk
cache by the source file's path, so running the copy would recompile the kernels (about 20 s per worker); the
copy's files are identical and are what DVC hashes as the stages' dependencies.
"""

import copy
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from bogie.params import GRAVITY, INHIBITORS
from bogie.presets import preset
from pipeline.config import load_params
from pipeline.schema import RUN_COLUMNS

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
FLEET = 16
BASE_SIZE = 4
ABLATION = 2


def tiny_params():
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = FLEET
    raw["sensitivity"]["base_size"] = BASE_SIZE
    raw["sensitivity"]["bootstrap_resamples"] = 20
    raw["ablation"]["n_bogies"] = ABLATION
    raw["protocol"]["static"]["dt_s"] = 0.002
    raw["protocol"]["wim"]["dt_s"] = 0.002
    raw["execution"].update({"backend": "loky", "n_jobs": 2, "chunk_size": 4})
    raw["design"].update(groups=["triaxle"], n_conditions=2, tilt_step_deg=2.0, n_space_filling=0,
                         grid={"bush_stiffness": [1.0, 3000.0]})  # fmt: skip
    return raw


def dvc(project, *args):
    env = {
        **os.environ,
        "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",  # the stages' `python` is this environment's
        "PYTHONSAFEPATH": "1",
        "PYTHONPATH": str(ROOT),
        "DVC_NO_ANALYTICS": "1",
        "MPLBACKEND": "Agg",
    }
    result = subprocess.run(
        [str(BIN / "dvc"), *args], cwd=project, env=env, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, f"dvc {' '.join(args)}:\n{result.stdout}\n{result.stderr}"
    return result.stdout


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    """A copy of the project with tiny params.yaml after one `dvc repro`; returns (path, repro output)."""
    path = tmp_path_factory.mktemp("project")
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    # observed/: the observed stage's input directory; bogies/: the base bogie files, a dependency of the stages
    for name in ("bogie", "pipeline", "observed", "bogies"):
        shutil.copytree(ROOT / name, path / name, ignore=ignore)
    for name in ("dvc.yaml", ".dvcignore"):
        shutil.copy2(ROOT / name, path / name)
    (path / "params.yaml").write_text(yaml.safe_dump(tiny_params(), sort_keys=False))
    dvc(path, "init", "--no-scm", "--quiet")
    return path, dvc(path, "repro")


@pytest.fixture(scope="module")
def runs(project):
    frame = pd.read_parquet(project[0] / "data" / "runs")
    frame["study"] = frame["study"].astype(str)
    return frame


@pytest.mark.slow
def test_repro_writes_every_stage_output(project):
    path, _ = project
    for study in ("fleet", "sensitivity", "ablation"):
        assert (path / "data" / "samples" / f"{study}.parquet").is_file()
        assert list((path / "data" / "runs" / f"study={study}").glob("part-*.parquet"))
    for stage in ("survey", "sensitivity", "observed", "design"):
        assert any((path / "data" / stage).iterdir())
        assert isinstance(json.loads((path / "metrics" / f"{stage}.json").read_text()), dict)
    assert (path / "dvc.lock").is_file()


@pytest.mark.slow
def test_runs_have_the_schema_and_one_row_per_sample_and_protocol(project, runs):
    assert list(runs.columns) == [*RUN_COLUMNS, "study"]
    assert {c: str(runs[c].dtype) for c in RUN_COLUMNS} == RUN_COLUMNS
    ok = runs["status"] == "ok"
    assert not runs[ok].isna().any().any()  # a failed row's results are null, a successful row has no null
    counts = runs.groupby(["study", "protocol"], observed=True).size().to_dict()
    n_sensitivity = BASE_SIZE * (len(tiny_params()["sensitivity"]["factors"]) + 2)
    n_variants = 1 + len(INHIBITORS) + 1  # the baseline, each inhibitor off alone, all off
    assert counts == {
        ("ablation", "static"): n_variants * ABLATION,
        ("ablation", "wim"): n_variants * ABLATION,
        ("fleet", "static"): FLEET,
        ("fleet", "wim"): FLEET,
        ("sensitivity", "static"): n_sensitivity,
    }
    assert set(runs["status"]) <= {"ok", "failed"}
    assert (runs.loc[runs["status"] == "ok", "message"] == "ok").all()


@pytest.mark.slow
def test_static_readings_balance_the_load_on_the_bogie(runs):
    ok = runs[(runs["status"] == "ok") & (runs["protocol"] == "static")]
    assert len(ok) > 0.8 * (runs["protocol"] == "static").sum()
    loads = ok[[f"axle_load_{i + 1}" for i in range(3)]].to_numpy()
    np.testing.assert_allclose(loads.sum(axis=1), ok["group_load"], rtol=1e-12)
    np.testing.assert_allclose(ok[[f"load_share_{i + 1}" for i in range(3)]].sum(axis=1), ok["n_axles"], rtol=1e-12)
    # moments about the king pin, both sides: sum_i A_i x_i = 2 (f m g x_cg + m_axle g sum_i x_i), with f the
    # payload fraction; tilt and pad contact move the forces' lines of action slightly off the axle positions
    for row in ok.itertuples():
        bogie = preset(row.preset)
        x = np.asarray(bogie.axle_x)
        moment = float(np.dot(loads[ok.index.get_loc(row.Index), : row.n_axles], x))
        expected = (
            2.0 * GRAVITY * (row.payload_fraction * row.payload_mass * bogie.payload_cg_x + bogie.axle_mass * x.sum())
        )
        assert moment == pytest.approx(expected, rel=0.02), row.sample_id


@pytest.mark.slow
def test_nose_up_tilt_overloads_the_rear_axle(runs):
    fleet = runs[(runs["study"] == "fleet") & (runs["protocol"] == "static") & (runs["status"] == "ok")]
    n = fleet["n_axles"].to_numpy()
    shares = fleet[[f"load_share_{i + 1}" for i in range(3)]].to_numpy()
    rear = shares[np.arange(len(fleet)), n - 1]
    assert np.corrcoef(fleet["chassis_tilt"], rear)[0, 1] > 0.3
    nose_up = fleet["chassis_tilt"].to_numpy() > 0.0
    assert rear[nose_up].mean() > shares[nose_up, 0].mean()


@pytest.mark.slow
def test_a_second_repro_changes_nothing(project):
    path, _ = project
    parts = sorted((path / "data" / "runs").glob("study=*/part-*.parquet"))
    before = {p: p.stat().st_mtime_ns for p in parts}
    lock = (path / "dvc.lock").read_text()
    out = dvc(path, "repro")
    assert "Data and pipelines are up to date" in out, out
    assert "Running stage" not in out
    assert {p: p.stat().st_mtime_ns for p in sorted((path / "data" / "runs").glob("study=*/part-*.parquet"))} == before
    assert (path / "dvc.lock").read_text() == lock


#: a name that reads as a column (a statistic's prefix, or a unit suffix): checked against the outputs
COLUMNISH = re.compile(
    r"^(n|share|mean|median|sd|frac|min|max|p\d\d)_[a-z0-9_]+$|^[a-z0-9_]+_(kg|pct|deg|mm|m|t|s|kn|n)$"
)


@pytest.mark.slow
def test_every_column_the_docs_tables_name_is_in_the_output_they_name(project):
    # issue 45 Must 1: a renamed column left its old name in docs/outputs.md. Each row "| `file` | ... | columns |" of
    # a table in docs/ whose file the stages wrote: every column-like name in it is the file's column, a value of one
    # of its text columns (a quantity, a statistic) or a column of the runs
    path, _ = project
    folders = [d for d in (path / "data").iterdir() if d.is_dir()]
    checked, wrong = 0, []
    for doc in sorted((ROOT / "docs").glob("*.md")):
        for line in doc.read_text(encoding="utf-8").splitlines():
            row = re.match(r"\| `([^`/]+\.(?:csv|parquet))` \|([^|]*)\|(.*)\|\s*$", line)
            found = [d / row.group(1) for d in folders if (d / row.group(1)).is_file()] if row else []
            if not found:
                continue
            frame = pd.read_csv(found[0]) if found[0].suffix == ".csv" else pd.read_parquet(found[0])
            names = {*frame.columns, *RUN_COLUMNS}
            names |= {str(v) for c in frame.columns if not pd.api.types.is_numeric_dtype(frame[c])
                      for v in frame[c].dropna().unique()}  # fmt: skip
            named = set(re.findall(r"`([a-z][a-z0-9_]*)`", row.group(2) + row.group(3)))
            wrong += [(doc.name, row.group(1), n) for n in sorted(named) if COLUMNISH.match(n) and n not in names]
            checked += 1
    assert checked >= 12, checked  # the survey's and the sensitivity stage's tables at least
    assert not wrong, wrong


@pytest.mark.slow
def test_dvc_checkout_restores_the_report_of_the_workspaces_results(project):
    # issue 45 Must 3: back from an experiment, the PDF and the figures were those of the last one built (outputs
    # outside DVC's cache); they are cached now, so `dvc checkout` puts back the ones dvc.lock records
    path, _ = project
    pdf = path / "reports" / "sensitivity_report.pdf"
    figure = sorted((path / "reports" / "figures" / "report").glob("*.png"))[0]
    before = pdf.read_bytes(), figure.read_bytes()
    pdf.write_bytes(b"%PDF-1.4 another experiment's report\n")  # what building another experiment leaves
    figure.write_bytes(b"another figure")
    dvc(path, "checkout", "--force")
    assert (pdf.read_bytes(), figure.read_bytes()) == before
    assert "Data and pipelines are up to date" in dvc(path, "status")


@pytest.mark.slow
def test_an_observed_survey_given_then_changed_reruns_the_observed_stage_only(project):
    path, _ = project
    shutil.copy(ROOT / "tests" / "data" / "weighings" / "site.csv", path / "observed" / "site.csv")
    raw = yaml.safe_load((path / "params.yaml").read_text())
    raw["observed"].update(path="observed/site.csv", format="csv")
    # a survey of 5 records is too small to calibrate to (10 laden groups at least): calibrate: null opts out
    raw["calibrate"] = None
    (path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    out = dvc(path, "repro")
    assert "Running stage 'observed'" in out and "Running stage 'report'" in out
    assert "calibrate: skipped, no calibrate section" in out
    assert "Running stage 'simulate'" not in out
    observed = json.loads((path / "metrics" / "observed.json").read_text())["observed"]
    # observed.position trailer (the default): the laden tri-axles of A and C (24 t each); B's and C's tandems are
    # drive tandems
    assert (observed["records"]["read"], observed["groups"]["triaxle"]["n_groups"]) == (5, 2)
    assert observed["groups"]["tandem"]["n_groups"] == 0
    # the same path, another content: DVC hashes the whole observed/ directory, so it sees the change
    text = (path / "observed" / "site.csv").read_text()
    extra = "2026-03-14T07:13:00.000,80,1,5,6000,9000,8000,8000,8000,,3.6,5.2,1.31,1.31,,T2S3\n"
    (path / "observed" / "site.csv").write_text(text + ("" if text.endswith("\n") else "\n") + extra)
    out = dvc(path, "repro")
    assert "Running stage 'observed'" in out and "Running stage 'validate'" not in out
    observed = json.loads((path / "metrics" / "observed.json").read_text())["observed"]
    assert (observed["records"]["read"], observed["groups"]["triaxle"]["n_groups"]) == (6, 3)
    assert "Data and pipelines are up to date" in dvc(path, "repro")
