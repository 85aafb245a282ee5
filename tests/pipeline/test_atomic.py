"""The all-or-nothing writer every stage uses: old outputs survive a failure, no temporaries are left behind."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from pipeline.atomic import atomic_file, atomic_outputs


def _listing(path):
    return sorted(p.name for p in path.iterdir())


def test_files_and_directories_replace_their_targets(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "old.csv").write_text("old")
    (tmp_path / "m.json").write_text("{}")
    with atomic_outputs(files=[tmp_path / "m.json"], dirs=[tmp_path / "out"]) as ((json_tmp,), (dir_tmp,)):
        json_tmp.write_text('{"a": 1}')
        (dir_tmp / "new.csv").write_text("new")
        # nothing is visible before the block ends
        assert (tmp_path / "m.json").read_text() == "{}"
        assert _listing(tmp_path / "out") == ["old.csv"]
    assert (tmp_path / "m.json").read_text() == '{"a": 1}'
    assert _listing(tmp_path / "out") == ["new.csv"]  # the old directory is replaced, not merged
    assert _listing(tmp_path) == ["m.json", "out"]  # no temporaries or .old directory left


def test_an_error_leaves_the_old_outputs_and_no_temporaries(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "old.csv").write_text("old")
    (tmp_path / "m.json").write_text("{}")
    with pytest.raises(RuntimeError, match="half-way"):
        with atomic_outputs(files=[tmp_path / "m.json"], dirs=[tmp_path / "out"]) as ((json_tmp,), (dir_tmp,)):
            json_tmp.write_text("partial")
            (dir_tmp / "new.csv").write_text("partial")
            raise RuntimeError("half-way")
    assert (tmp_path / "m.json").read_text() == "{}"
    assert _listing(tmp_path / "out") == ["old.csv"]
    assert _listing(tmp_path) == ["m.json", "out"]


def test_new_outputs_get_the_users_umask_not_private_modes(tmp_path):
    old = os.umask(0o022)
    try:
        with atomic_outputs(files=[tmp_path / "sub" / "a.txt"], dirs=[tmp_path / "d"]) as ((f,), (d,)):
            f.write_text("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "sub" / "a.txt").stat().st_mode) == 0o644  # mkstemp alone gives 0600
    assert stat.S_IMODE((tmp_path / "d").stat().st_mode) == 0o755  # mkdtemp alone gives 0700


def test_atomic_file_creates_parents_and_writes_once(tmp_path):
    target = tmp_path / "a" / "b" / "c.bin"
    with atomic_file(target) as tmp:
        assert tmp.parent == target.parent and tmp.name.startswith(".c.bin.")
        tmp.write_bytes(b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"
    assert _listing(target.parent) == ["c.bin"]


def test_a_stage_that_cannot_write_says_so_in_one_line_and_writes_nothing(tmp_path, capsys):
    from pipeline.validate import main

    blocker = tmp_path / "data"
    blocker.write_text("a file where the output directory should be")  # fails for root too, unlike a chmod
    assert main(["--out", str(blocker / "config.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"validate: cannot write {blocker}") and "[Errno" in err
    assert "\n" not in err and "Traceback" not in err
    assert blocker.read_text() == "a file where the output directory should be"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data"]


def test_io_error_names_the_path_and_the_cause():
    from pipeline.atomic import io_error

    full = OSError(28, "No space left on device", "data/survey")
    assert io_error("survey", full) == "survey: cannot write data/survey: [Errno 28] No space left on device"


def test_the_pipeline_imports_where_there_is_no_fcntl():
    # Windows has no fcntl (issue 40 item 9): the locks take a byte with msvcrt there. The lock module imports without
    # it, and no other module of ours imports fcntl but inside a try (third-party packages are theirs to port)
    import ast
    import subprocess
    import sys

    code = (
        "import sys, types\n"
        "sys.modules['fcntl'] = None\n"
        "fake = types.ModuleType('msvcrt'); fake.LK_NBLCK, fake.LK_UNLCK = 2, 0; fake.locking = lambda *a: None\n"
        "sys.modules['msvcrt'] = fake\n"
        "import pipeline.atomic as a\n"
        "assert a.fcntl is None and a._try_lock(open(sys.argv[1], 'a+'))\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code, __file__], capture_output=True, text=True, timeout=300)
    assert out.stdout.strip() == "ok", out.stderr[-2000:]
    root = Path(__file__).resolve().parents[2]
    for path in [*root.glob("bogie/**/*.py"), *root.glob("pipeline/**/*.py")]:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        guarded = {id(n) for t in ast.walk(tree) if isinstance(t, ast.Try) for b in t.body for n in ast.walk(b)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) and any(a.name == "fcntl" for a in node.names):
                assert id(node) in guarded, f"{path}:{node.lineno} imports fcntl outside a try"


# ---- the one stage runner (issue 42 Must 3) ----------------------------------------------------------------------
def _runner(work, tmp_path):
    import argparse

    from pipeline.atomic import run_stage

    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default=str(tmp_path / "out"))
    args = parser.parse_args([])
    return run_stage("demo", parser, args, lambda own: work(), dirs=["out"])


@pytest.mark.parametrize(
    ("error", "more", "line"),
    [
        (ValueError("x = 3: must be below 2"), (), "demo: x = 3: must be below 2"),
        (FileNotFoundError(2, "No such file or directory", "params.yaml"), (),
         "demo: [Errno 2] No such file or directory: 'params.yaml'"),
        (__import__("yaml").YAMLError("mapping values are not allowed here"), (),
         "demo: mapping values are not allowed here"),
        (KeyError("axle_load_3"), (KeyError,), "demo: 'axle_load_3'"),  # a stage reading another's files adds it
    ],
)  # fmt: skip
def test_an_input_error_is_one_line_naming_the_stage_and_exit_2(tmp_path, capsys, error, more, line):
    from pipeline.atomic import stage_inputs

    def work():
        with stage_inputs("demo", *more):
            raise error

    assert _runner(work, tmp_path) == 2
    assert capsys.readouterr().err.splitlines() == [line]


def test_a_write_error_is_the_file_systems_line_and_a_bug_is_not_swallowed(tmp_path, capsys):
    def full():
        raise OSError(28, "No space left on device", str(tmp_path / "out" / "a.csv"))

    assert _runner(full, tmp_path) == 2
    assert (
        capsys.readouterr().err.strip()
        == f"demo: cannot write {tmp_path / 'out' / 'a.csv'}: [Errno 28] No space left on device"
    )

    def bug():
        from pipeline.atomic import stage_inputs

        with stage_inputs("demo"):
            raise RuntimeError("a bug, not an input")  # not an input error: a traceback, never exit 2

    with pytest.raises(RuntimeError, match="a bug"):
        _runner(bug, tmp_path)

    def missing_key():
        from pipeline.atomic import stage_inputs

        with stage_inputs("demo"):
            return {}["fitted"]  # a bug in a stage's own code, not a damaged input: a traceback

    with pytest.raises(KeyError, match="fitted"):
        _runner(missing_key, tmp_path)
