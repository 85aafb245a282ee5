"""What design and calibrate own while they run (pipeline.atomic.stage_outputs): a second process of the stage is
refused in one line, and the temporaries a killed run's all-or-nothing write left are removed by the next run, and
nothing else. Each stage runs its skip path (design: null; calibrate: no survey): a second of work."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from pipeline import calibrate as C
from pipeline import design as D
from pipeline.atomic import stage_outputs
from pipeline.chunks import runs_lock

ROOT = Path(__file__).resolve().parents[2]
STAGES = {"design": D, "calibrate": C}


def project(tmp_path, stage):
    """params.yaml asking the stage for nothing, and its command-line arguments into tmp_path/{data,metrics}."""
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["design"] = None  # calibrate skips too: observed.path is null in params.yaml
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    out, metrics = tmp_path / "data" / stage.replace("calibrate", "calibration"), tmp_path / "metrics" / "m.json"
    args = ["--params", str(tmp_path / "params.yaml"), "--out", str(out), "--metrics", str(metrics)]
    if stage == "design":
        args += ["--runs", str(tmp_path / "data" / "design_runs")]
    return args, out, metrics


def kill_while_writing(stage, out, metrics):
    """Run the stage's own write_outputs in a process killed (SIGKILL) half-way: its temporaries stay behind."""
    code = (
        "import json, os, signal, sys, types\n"
        f"from pipeline import {stage} as stage\n"
        "stage.json = types.SimpleNamespace(dump=lambda *a, **k: os.kill(os.getpid(), signal.SIGKILL))\n"
        "outputs = ({}, {'skipped': 'x', 'reason': 'x'})\n"
        f"stage.write_outputs(*(outputs if {stage == 'design'} else outputs[::-1]), sys.argv[1], sys.argv[2])\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", code, str(out), str(metrics)], env=env, capture_output=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr


@pytest.mark.parametrize("stage", STAGES)
def test_what_a_killed_run_left_is_removed_by_the_next_and_nothing_else(tmp_path, capsys, stage):
    args, out, metrics = project(tmp_path, stage)
    kill_while_writing(stage, out, metrics)
    left = sorted(p for p in (*out.parent.iterdir(), *metrics.parent.iterdir()) if p.name.endswith(".tmp"))
    assert len(left) == 2 and left[0].is_dir()  # data/.<out>.XXXXXXXX.tmp/ and metrics/.m.json.XXXXXXXX.tmp
    theirs = [
        out.parent / f".{out.name}.notes.tmp",
        out.parent / f"{out.name}-notes.txt",
        metrics.parent / ".m.json.bak",
    ]
    for path in theirs:
        path.write_text("mine")

    assert STAGES[stage].main(args) == 0
    err = capsys.readouterr().err
    for path in left:
        assert not path.exists()
        assert f"{stage}: removed {path}, left by an interrupted run of the stage" in err
    assert all(path.read_text() == "mine" for path in theirs)
    assert out.is_dir() and metrics.is_file()
    # nothing else beside the outputs: no temporary, no lock file (git status shows nothing new)
    dots = sorted(p.name for p in (*out.parent.iterdir(), *metrics.parent.iterdir()) if p.name.startswith("."))
    assert dots == sorted(p.name for p in theirs if p.name.startswith("."))


@pytest.mark.parametrize("stage", STAGES)
def test_a_second_run_of_the_stage_is_refused_in_one_line_and_touches_nothing(tmp_path, capsys, stage):
    args, out, metrics = project(tmp_path, stage)
    with stage_outputs(stage, files=[metrics], dirs=[out]):  # what the first run holds while it works
        writing = out.parent / f".{out.name}.k2x9a_7q.tmp"  # the first run's temporary, being written
        writing.mkdir()
        assert STAGES[stage].main(args) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and "Traceback" not in err
        assert err.startswith(f"{stage}: {metrics} is being written by another {stage} process (pid {os.getpid()}")
        assert writing.is_dir() and not out.exists() and not metrics.exists()
    assert STAGES[stage].main(args) == 0  # released: the next run goes ahead


def test_a_design_whose_runs_another_process_writes_stops_in_one_line(tmp_path, capsys):
    # today's design died with a RunsLockedError traceback from the simulation of its runs
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["execution"].update(n_jobs=1, chunk_size=16)
    raw["design"].update(groups=["tandem"], n_conditions=2, tilt_step_deg=1.0, n_space_filling=0,
                         grid={"bush_stiffness": [1.0, 3000.0]})  # fmt: skip
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw, sort_keys=False))
    runs = tmp_path / "data" / "design_runs"
    args = ["--params", str(tmp_path / "params.yaml"), "--runs", str(runs), "--out", str(tmp_path / "data" / "design"),
            "--metrics", str(tmp_path / "metrics" / "design.json")]  # fmt: skip
    with runs_lock(runs):
        assert D.main(args) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert (
        err.strip()
        .splitlines()[-1]
        .startswith(f"design: {runs} is being written by another simulate process (pid {os.getpid()}")
    )
    assert not (tmp_path / "metrics").exists() and not (tmp_path / "data" / "design").exists()
