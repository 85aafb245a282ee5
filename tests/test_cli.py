import subprocess
import sys

from bogie.cli import main


def test_figure2_writes_png(tmp_path):
    out = tmp_path / "fig.png"
    assert main(["figure2", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_console_script_reports_bad_value(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "bogie.cli", "figure2", "--out", str(tmp_path / "f.png"), "--q-max", "-3"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "q_max" in proc.stderr
