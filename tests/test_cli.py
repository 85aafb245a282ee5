import re
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


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "bogie.cli", *args], capture_output=True, text=True, timeout=120)


def test_version_is_the_installed_package_version():
    from importlib.metadata import version

    proc = run_cli("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"bogie {version('bogie')}"


def test_case_list_names_every_run_with_its_whole_description_wrapped(capsys):
    from bogie import cases

    assert main(["case", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines if not line.startswith(" ")] == list(cases.CASES)
    assert all(len(line) <= 110 for line in lines)
    # each description whole (issue 31: cut at 110 characters, N07 and N08 read the same)
    entries, name = {}, None
    for line in lines:
        if not line.startswith(" "):
            name, line = line.split(maxsplit=1)[0], line.split(maxsplit=1)[1]
        entries[name] = (entries.get(name, "") + " " + line.strip()).strip()
    for name in cases.CASES:
        assert entries[name] == cases.get(name).description.split(":", 1)[-1].strip()
    assert entries["N07"] != entries["N08"]


def test_a_bad_flag_prints_the_subcommands_usage():
    proc = run_cli("case", "N10", "--bogus")
    assert proc.returncode == 2
    assert "usage: bogie case" in proc.stderr and "unrecognized arguments: --bogus" in proc.stderr


def test_an_unknown_image_suffix_is_refused_before_the_simulation(tmp_path):
    proc = run_cli("case", "N10", "--plot", str(tmp_path / "x.xyz"))  # N10 takes seconds: refused at once
    assert proc.returncode == 2 and "the suffix 'xyz' is not an image format" in proc.stderr
    assert "status" not in proc.stdout  # nothing ran
    assert run_cli("figure2", "--out", str(tmp_path / "f.txt")).returncode == 2


def test_every_printed_figure_has_its_unit(capsys):
    assert main(["case", "L03"]) == 0
    out = capsys.readouterr().out
    ours = next(line for line in out.splitlines() if line.startswith("ours:"))
    assert "peak_p " in ours and all(item.strip().endswith(("[-]", "N")) for item in ours[5:].split(","))


def test_figures_are_byte_reproducible_in_every_vector_format(tmp_path):
    for suffix in ("pdf", "svg", "png"):
        first, second = tmp_path / f"a.{suffix}", tmp_path / f"b.{suffix}"
        assert main(["figure2", "--out", str(first)]) == 0
        assert main(["figure2", "--out", str(second)]) == 0
        assert first.read_bytes() == second.read_bytes(), suffix  # no creation date stamped into the file


def test_result_objects_print_one_line():
    from bogie import cases

    text = repr(cases.run("L03"))
    assert text.startswith("DynamicResult(status='ok', 2 axles, 201 samples, t 0 to 25 s, wheel loads ")
    assert "\n" not in text and len(text) < 300


def test_a_cases_csv_header_gives_every_columns_unit(tmp_path, capsys):
    # issue 31 item 9: the case CSV header had no units
    for name in ("L01", "N10"):  # the linear and the non-linear model's histories
        out = tmp_path / f"{name}.csv"
        assert main(["case", name, "--csv", str(out)]) == 0
        header = out.read_text().splitlines()[0].split(",")
        assert header[:4] == ["t [s]", "wheel_load_0 [N]", "wheel_load_1 [N]", "nondimensional_load_0 [-]"]
        assert all(re.fullmatch(r"\w+ \[(N|-|m|rad|s|N m)\]", column) for column in header), header
    assert "stop_moment_0 [N m]" in header and "spring_hysteresis_1 [N]" in header
