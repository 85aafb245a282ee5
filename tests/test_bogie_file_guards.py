"""Bogie files through the guarded loader params.yaml uses, and only from the project's bogies/ (issue 40 Must 3).

Before: an alias bomb ran ``bogie design show`` and validate on and on (3.8 GB after 6 minutes), 5,000 nested brackets
gave a RecursionError traceback, a 401-digit integer an OverflowError traceback, a FIFO hung and /dev/zero ended in a
MemoryError; ``fleet.presets`` read files outside the project and validate printed a line of one.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from bogie.bogie_file import BogieFileError, load_bogie
from bogie.guarded_yaml import MAX_INT_DIGITS, DocumentTooLargeError, read_yaml

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "bogies" / "example_triaxle.yaml"
BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n" for p, c in zip("abcdefgh", "bcdefghi")
)


@pytest.mark.parametrize(
    "text, words",
    [
        (BOMB + "base: triaxle_stage1\n", "aliases are expanded"),
        ("base: triaxle_stage1\nx: " + "[" * 5000 + "]" * 5000 + "\n", "nested more than"),
        ("base: triaxle_stage1\nbush_stiffness_nm_per_rad: " + "9" * 401 + "\n", "an integer of 401 digits"),
        ("base: triaxle_stage1\nbase: tandem_stage1\n", "duplicated key base"),
    ],
)
def test_a_hostile_bogie_file_is_refused_quickly_with_a_line(tmp_path, text, words):
    path = tmp_path / "b.yaml"
    path.write_text(text)
    start = time.perf_counter()
    with pytest.raises(BogieFileError, match=words):
        load_bogie(path)
    assert time.perf_counter() - start < 5.0


def test_a_fifo_or_a_device_as_a_bogie_file_is_refused_before_it_is_opened(tmp_path):
    fifo = tmp_path / "f.yaml"
    os.mkfifo(fifo)
    with pytest.raises(BogieFileError, match="FIFO"):
        load_bogie(fifo)
    zero = tmp_path / "z.yaml"
    zero.symlink_to("/dev/zero")
    with pytest.raises(BogieFileError, match="a device"):
        load_bogie(zero)
    big = tmp_path / "big.yaml"
    big.write_text("# " + "x" * (2**20 + 10))
    with pytest.raises(BogieFileError, match="more than"):
        load_bogie(big)


def test_bogie_design_show_on_a_bomb_exits_2_in_seconds(tmp_path):
    path = tmp_path / "b.yaml"
    path.write_text(BOMB)
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "bogie.cli", "design", "show", str(path)], capture_output=True,
                         text=True, timeout=120, cwd=ROOT)  # fmt: skip
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert time.perf_counter() - start < 60


def test_the_loader_refuses_an_integer_of_too_many_digits_and_keeps_a_long_one():
    assert read_yaml("seed: " + "9" * MAX_INT_DIGITS) == {"seed": int("9" * MAX_INT_DIGITS)}
    with pytest.raises(DocumentTooLargeError, match="21 digits"):
        read_yaml("seed: " + "1" * 21)


def _project(tmp_path: Path, preset: str) -> list[str]:
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["fleet"]["presets"] = {**raw["fleet"].get("presets", {}), "triaxle": preset}
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    (tmp_path / "bogies").mkdir(exist_ok=True)
    return ["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "config.json")]


@pytest.mark.parametrize("how", ["absolute", "dotdot", "symlink", "outside bogies/"])
def test_a_preset_file_outside_bogies_is_refused_and_its_content_never_shown(tmp_path, monkeypatch, capsys, how):
    from pipeline import validate

    outside = tmp_path / "elsewhere"
    outside.mkdir()
    secret = outside / "secret.yaml"
    secret.write_text("token: SECRET-0123 [\n")  # bad YAML: a message that quoted it would show the token
    project = tmp_path / "project"
    project.mkdir()
    monkeypatch.chdir(project)
    args = _project(project, "")
    name = {
        "absolute": str(secret),
        "dotdot": "bogies/../../elsewhere/secret.yaml",
        "symlink": "bogies/link.yaml",
        "outside bogies/": "other.yaml",
    }[how]
    if how == "symlink":
        (project / "bogies" / "link.yaml").symlink_to(secret)
    if how == "outside bogies/":
        shutil.copy(EXAMPLE, project / "other.yaml")
    _project(project, name)
    assert validate.main(args) == 2
    err = capsys.readouterr().err
    assert "fleet.presets.triaxle" in err and "bogies/" in err, err
    assert "SECRET-0123" not in err


def test_a_preset_file_in_bogies_is_read(tmp_path, monkeypatch, capsys):
    from pipeline import validate

    monkeypatch.chdir(tmp_path)
    args = _project(tmp_path, "bogies/mine.yaml")
    shutil.copy(EXAMPLE, tmp_path / "bogies" / "mine.yaml")
    assert validate.main(args) == 0, capsys.readouterr().err


def test_a_huge_integer_in_params_is_one_line_not_a_traceback(tmp_path, capsys):
    from pipeline import validate

    text = (ROOT / "params.yaml").read_text().replace("seed: ", "seed: " + "7" * 401 + " #", 1)
    (tmp_path / "params.yaml").write_text(text)
    assert validate.main(["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "c.json")]) == 2
    err = capsys.readouterr().err
    assert "an integer of 401 digits" in err and "Traceback" not in err, err
