"""The smaller refusals of issue 40 item 9: each used to end in a traceback or a wrong hint."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import yaml

from pipeline import validate

ROOT = Path(__file__).resolve().parents[2]


def _validate(tmp_path: Path, text: str, capsys) -> str:
    (tmp_path / "params.yaml").write_text(text)
    assert validate.main(["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "c.json")]) == 2
    assert not (tmp_path / "c.json").exists()
    return capsys.readouterr().err


def test_a_nul_byte_in_the_observed_path_is_one_line(tmp_path, capsys):
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["observed"]["path"] = "observed/a\0b.csv"
    err = _validate(tmp_path, yaml.safe_dump(raw), capsys)
    assert "observed.path" in err and "NUL byte" in err and "Traceback" not in err, err


def test_an_unquoted_nan_is_not_told_to_lose_its_quotes(tmp_path, capsys):
    text = (ROOT / "params.yaml").read_text()
    old = "bush_stiffness: {kind: loguniform, low: 1.0"
    assert old in text
    err = _validate(tmp_path, text.replace(old, "bush_stiffness: {kind: loguniform, low: NaN"), capsys)
    assert "distributions.bush_stiffness.low = 'NaN'" in err and "without quotes" not in err, err
    assert "must be a number > 0 N m/rad" in err


def test_an_image_that_cannot_be_written_is_one_line_and_leaves_nothing(tmp_path):
    out = subprocess.run([sys.executable, "-m", "bogie.cli", "figure2", "--out", "/proc/x.png"], capture_output=True,
                         text=True, timeout=300, cwd=ROOT)  # fmt: skip
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert out.stderr.startswith("bogie: error: cannot write")
