"""Refuse a file with a merge conflict's markers (``<<<<<<< ``, ``||||||| ``, ``>>>>>>> `` at a line's start).

A merge left README.md with both sides of a conflict once (issue 39), and nothing failed. ``make lint`` runs this
over every file git tracks, and ``tests/test_conflict_markers.py`` does too; ``python tools/conflict_markers.py``
prints each marker with its file and line and exits 1 if there is one. ``=======`` alone is not looked for: it is a
heading's underline in Markdown and reStructuredText, and a conflict always has the other two.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MARKER = re.compile(rb"^(<{7}|\|{7}|>{7})(?: |$)", re.MULTILINE)
#: folders never read when git cannot list the tracked files
SKIPPED = {".git", ".venv", ".dvc", "data", "dvc_plots", "__pycache__", ".pytest_cache", ".ruff_cache"}


def tracked(root: Path = ROOT) -> list[Path]:
    """The files git tracks under ``root`` (every file but the generated folders, where git is not there)."""
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True, check=True).stdout
        return [root / name for name in out.decode("utf-8").split("\0") if name]
    except (OSError, subprocess.CalledProcessError):
        return [p for p in root.rglob("*") if p.is_file() and not SKIPPED & set(p.relative_to(root).parts)]


def markers(paths: list[Path], root: Path = ROOT) -> list[str]:
    """``path:line: marker`` for each conflict marker in ``paths``."""
    found = []
    for path in paths:
        try:
            data = path.read_bytes()
        except OSError:
            continue
        if b"\0" in data[:8192]:  # a binary file
            continue
        for match in MARKER.finditer(data):
            line = data.count(b"\n", 0, match.start()) + 1
            found.append(f"{path.relative_to(root).as_posix()}:{line}: {match.group(1).decode()}")
    return found


def main() -> int:
    found = markers(tracked())
    for item in found:
        print(item)
    if found:
        print(f"{len(found)} merge conflict marker(s): resolve the conflict before committing", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
