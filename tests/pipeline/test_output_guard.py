"""No output option can delete what a stage did not write (issue 40 Must 1 and 4).

Every stage that replaces a folder, and every one of its output options, is tried with the places that lost a project
before: ``.``, ``..``, ``/``, the home folder, the project root and a parent of it, a folder of other files, another
stage's output, an existing file. Each must be refused with exit 2 and one line naming the option's value, before
anything is touched: a sentinel file in each place is still there, and nothing new appears beside it.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path

import pytest

from pipeline import atomic
from pipeline.deps import ROOT

#: stage -> (module, its folder options, its file options)
STAGES = {
    "road": ("pipeline.road", ["--out"], ["--metrics"]),
    "observed": ("pipeline.observed", ["--out"], ["--metrics"]),
    "survey": ("pipeline.survey", ["--out"], ["--metrics"]),
    "sensitivity": ("pipeline.sensitivity", ["--out"], ["--metrics"]),
    "calibrate": ("pipeline.calibrate", ["--out"], ["--metrics"]),
    "design": ("pipeline.design", ["--out"], ["--metrics"]),
    "report": ("pipeline.report.build", ["--png", "--plots"], ["--pdf"]),
}
# imported here, before a test moves HOME: importing bogie makes its numba cache folder under the home's .cache
MODULES = {stage: importlib.import_module(module) for stage, (module, _, _) in STAGES.items()}
FOLDER_OPTIONS = [(stage, option) for stage, (_, dirs, _) in STAGES.items() for option in dirs]
FILE_OPTIONS = [(stage, option) for stage, (_, _, files) in STAGES.items() for option in files]


def snapshot(*folders: Path) -> dict[str, float]:
    return {str(p): p.stat().st_mtime_ns for folder in folders for p in [folder, *folder.iterdir()]}


@pytest.fixture
def place(tmp_path, monkeypatch):
    """A scratch home and a scratch project (the working directory) with a sentinel file in each."""
    home, project = tmp_path / "home", tmp_path / "home" / "work" / "project"
    project.mkdir(parents=True)
    (home / "keep.txt").write_text("mine")
    (project / "keep.txt").write_text("mine")
    (project / "data").mkdir()
    (project / "data" / "other.csv").write_text("another stage's\n")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(project)
    return home, project


def run(stage: str, *args: str) -> int:
    return MODULES[stage].main(list(args))


def _cases(home: Path, project: Path) -> dict[str, str]:
    foreign = project / "notes"
    foreign.mkdir(exist_ok=True)
    (foreign / "todo.txt").write_text("mine")
    other = project / "data" / "survey"
    other.mkdir(exist_ok=True)
    (other / "groups.csv").write_text("x\n")
    (other / atomic.OUTPUT_MARKER).write_text("survey\n")
    return {
        ".": ".", "..": "..", "/": "/", "home": str(home), "~ expanded": os.path.expanduser("~"),
        "project root": str(project), "a parent of the project": str(project.parent), "data": "data",
        "a folder of other files": "notes", "another stage's output": "data/survey",
        "an existing file": "keep.txt", "the code's project root": str(ROOT),
    }  # fmt: skip


@pytest.mark.parametrize("stage, option", FOLDER_OPTIONS)
def test_a_folder_option_that_would_delete_what_the_stage_did_not_write_is_refused(stage, option, place, capsys):
    home, project = place
    for name, value in _cases(home, project).items():
        if stage == "survey" and name == "another stage's output":
            continue  # its own: allowed (below)
        before = snapshot(home, project, project / "data", project / "notes")
        assert run(stage, option, value) == 2, name
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"{stage}: the output folder {value}" in err, (name, err)
        assert snapshot(home, project, project / "data", project / "notes") == before, name
        assert (home / "keep.txt").read_text() == "mine" and (project / "notes" / "todo.txt").read_text() == "mine"


@pytest.mark.parametrize("stage, option", FILE_OPTIONS)
def test_a_file_option_naming_a_folder_is_refused(stage, option, place, capsys):
    home, project = place
    for value in (".", "..", "/", str(home), "data"):
        assert run(stage, option, value) == 2, value
        err = capsys.readouterr().err
        assert f"{stage}: the output file {value}" in err, err
    assert (home / "keep.txt").read_text() == "mine" and (project / "data" / "other.csv").is_file()


def test_a_folder_that_is_the_stages_own_empty_or_new_passes_the_guard(place):
    _, project = place
    own = project / "mine"
    own.mkdir()
    (own / "groups.csv").write_text("x\n")
    (own / atomic.OUTPUT_MARKER).write_text("survey\n")
    (project / "empty").mkdir()
    atomic.guard_outputs("survey", files=["metrics/s.json"], dirs=["mine", "empty", "new/deeper"])
    with pytest.raises(atomic.OutputError, match="holds the survey stage's output"):
        atomic.guard_outputs("road", dirs=["mine"])
    # the stage's default folder, written before the marker existed, is its own
    (project / "data" / "road").mkdir()
    (project / "data" / "road" / "wear.csv").write_text("x\n")
    atomic.guard_outputs("road", dirs=["data/road"], own=[Path("data/road")])
    with pytest.raises(atomic.OutputError, match="did not write"):
        atomic.guard_outputs("road", dirs=["data/road"])


def test_a_symlink_to_the_project_is_refused(place, capsys):
    home, project = place
    (project / "link").symlink_to(project)
    (home / "to_home").symlink_to(home)
    assert run("road", "--out", "link") == 2 and "is the working directory" in capsys.readouterr().err
    assert run("road", "--out", str(home / "to_home")) == 2 and "home folder" in capsys.readouterr().err


def test_atomic_outputs_marks_each_folder_with_its_stage_and_a_second_write_replaces_it(tmp_path):
    out = tmp_path / "out"
    for content in ("first", "second"):
        with atomic.atomic_outputs(files=[tmp_path / "m.json"], dirs=[out], stage="road") as ((f,), (d,)):
            (d / "wear.csv").write_text(content)
            f.write_text("{}")
        assert (out / "wear.csv").read_text() == content
        assert (out / atomic.OUTPUT_MARKER).read_text() == "road\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json", "out"]


def test_a_replaced_folder_is_never_missing_and_the_old_content_is_cleaned_by_the_next_run(tmp_path, monkeypatch):
    # a kill right after the swap (here: the removal of the old content fails) leaves the new output in place and the
    # old one under the temporary's name, which the next run removes
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.csv").write_text("old")
    (out / atomic.OUTPUT_MARKER).write_text("road\n")
    if atomic._EXCHANGE is None:
        pytest.skip("this system has no renameat2 exchange: the .old rename is used (tested in test_atomic.py)")
    monkeypatch.setattr(atomic.shutil, "rmtree", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt))
    with pytest.raises(KeyboardInterrupt):
        with atomic.atomic_outputs(dirs=[out], stage="road") as (_, (d,)):
            (d / "new.csv").write_text("new")
    monkeypatch.undo()
    assert (out / "new.csv").read_text() == "new"
    left = [p for p in tmp_path.iterdir() if p.name != "out"]
    assert left and all(atomic.temporary_name(out).fullmatch(p.name) for p in left)
    assert atomic.remove_leftovers(out) == left and [p.name for p in tmp_path.iterdir()] == ["out"]


def test_road_refuses_a_named_survey_whose_observed_stage_has_not_run(tmp_path, capsys):
    import yaml

    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["observed"]["path"] = "observed/site.csv"
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    args = ["--params", str(tmp_path / "params.yaml"), "--observed", str(tmp_path / "missing"),
            "--out", str(tmp_path / "road"), "--metrics", str(tmp_path / "road.json"),
            "--runs", str(tmp_path / "no-runs")]  # fmt: skip
    assert run("road", *args) == 2
    err = capsys.readouterr().err
    assert "observed.path names a survey" in err and "run the observed stage first" in err, err
    assert not (tmp_path / "road").exists() and not (tmp_path / "road.json").exists()


@pytest.mark.parametrize("stage", ["road", "observed", "survey", "sensitivity", "report"])
def test_what_a_killed_run_left_beside_the_outputs_is_removed_by_the_next_run(stage, place, capsys):
    # issue 40 item 6: a kill -9 while road, observed or report wrote left temporaries no rerun removed (git status
    # showed them); every stage now owns its outputs as calibrate does, and cleans them first
    _, project = place
    module, dirs, files = STAGES[stage]
    parser_defaults = {opt: None for opt in (*dirs, *files)}
    args: list[str] = ["--params", "missing.yaml"]
    for option in parser_defaults:
        target = project / "out" / f"{stage}{option.replace('--', '_')}"
        args += [option, str(target)]
        target.parent.mkdir(parents=True, exist_ok=True)
        leftover = target.parent / f".{target.name}.k2x9a_7q.tmp"
        leftover.mkdir() if option in dirs else leftover.write_text("half")
    assert run(stage, *args) == 2  # the params file is missing: the stage fails after cleaning
    err = capsys.readouterr().err
    assert not [p for p in (project / "out").iterdir() if p.name.endswith(".tmp")], list((project / "out").iterdir())
    assert err.count("left by an interrupted run") == len(parser_defaults), err
