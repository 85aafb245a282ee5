"""No file the project tracks holds a merge conflict's markers (tools/conflict_markers.py; issue 39 Must 5)."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import conflict_markers  # noqa: E402


def test_no_tracked_file_holds_a_conflict_marker():
    found = conflict_markers.markers(conflict_markers.tracked())
    assert not found, "\n".join(found)


def test_a_conflict_is_found_with_its_line_and_a_heading_underline_is_not(tmp_path):
    (tmp_path / "a.md").write_text("Title\n=======\n\ntext\n<<<<<<< HEAD\nours\n=======\ntheirs\n>>>>>>> item3\n")
    (tmp_path / "b.py").write_text("x = '<<<<<<< not at the start'\n")
    found = conflict_markers.markers(sorted(tmp_path.iterdir()), root=tmp_path)
    assert found == ["a.md:5: <<<<<<<", "a.md:9: >>>>>>>"]
