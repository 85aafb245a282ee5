"""Write the figures the README and ``docs/`` quote from the pipeline's outputs, from the outputs (issue 45 Must 1).

A figure that comes from an output is written between two HTML comments, invisible where the Markdown is rendered::

    total Sobol' index <!-- fig metrics/sensitivity.json sobol.indices.contact_roll_radius.ST g2 -->0.26<!-- /fig -->

The opening comment names the output file (a JSON file relative to the project root), the path of keys into it
(dots; a list's item by its index) and how to write it: ``g<n>`` (n significant figures), ``f<n>`` (n decimals),
``pct<n>`` (times 100, n decimals, then " %"), ``pts<n>`` (times 100, n decimals: percentage points, the unit
written beside it), ``int``, ``text`` (a string as it is: a sentence the stage wrote); a ``neg`` before it writes
the value's negative (a reduction named as a rise). ``python tools/doc_figures.py`` rewrites every such figure of
the tracked Markdown files from the outputs (``make repro`` runs it after ``dvc repro``, so the words move with the
results they quote); ``--check`` lists the stale ones and exits 1, which ``tests/test_doc_figures.py`` asserts never
happens. A figure whose file or key is missing is an error naming the file, the key and the line, never a silent
blank.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: one figure: the file, the key path, the optional ``neg``, the format; then the value as written
FIGURE = re.compile(
    r"<!-- fig (?P<file>\S+) (?P<path>\S+) (?:(?P<neg>neg) )?(?P<fmt>g\d+|f\d+|pct\d+|pts\d+|int|text) -->"
    r"(?P<value>.*?)<!-- /fig -->",
    re.S,
)


def _value(root: Path, file: str, path: str, cache: dict, text: bool = False) -> float | str:
    if file not in cache:
        with open(root / file, encoding="utf-8") as fh:
            cache[file] = json.load(fh)
    node = cache[file]
    for key in path.split("."):
        node = node[int(key)] if isinstance(node, list) else node[key]
    if text:
        if not isinstance(node, str):
            raise TypeError(f"{file}: {path} is {node!r}, not a string")
        return node
    if not isinstance(node, (int, float)) or isinstance(node, bool):
        raise TypeError(f"{file}: {path} is {node!r}, not a number")
    return float(node)


def written(value: float, fmt: str) -> str:
    """``value`` as format ``fmt`` writes it (the module docstring)."""
    if fmt == "int":
        return f"{round(value):,}"
    digits = int(re.sub(r"\D", "", fmt))
    if fmt.startswith("pct"):
        return f"{100.0 * value:.{digits}f} %"
    if fmt.startswith("pts"):
        return f"{100.0 * value:.{digits}f}"
    if fmt.startswith("f"):
        return f"{value:.{digits}f}"
    return f"{value:.{digits}g}"


def rewrite(text: str, root: Path = ROOT, where: str = "") -> tuple[str, list[tuple[int, str, str, str]]]:
    """``text`` with every figure written from the outputs under ``root``, and the stale ones: (line, spec, as
    written, from the outputs). A missing file or key is a ValueError naming ``where``, the line, file and key."""
    cache: dict = {}
    stale = []

    def one(match: re.Match) -> str:
        line = text.count("\n", 0, match.start()) + 1
        try:
            value = _value(root, match["file"], match["path"], cache, match["fmt"] == "text")
        except (OSError, KeyError, IndexError, ValueError, TypeError) as exc:
            raise ValueError(f"{where}:{line}: figure {match['file']} {match['path']}: {exc!r}") from exc
        new = value if match["fmt"] == "text" else written(-value if match["neg"] else value, match["fmt"])
        if new != match["value"]:
            stale.append((line, f"{match['file']} {match['path']}", match["value"], new))
        return match[0][: match.start("value") - match.start()] + new + "<!-- /fig -->"

    return FIGURE.sub(one, text), stale


def markdown_files(root: Path = ROOT) -> list[Path]:
    """The tracked Markdown files of the project."""
    out = subprocess.run(["git", "ls-files", "*.md"], cwd=root, capture_output=True, text=True, check=True).stdout
    return [root / name for name in out.split()]


def main(argv: list[str]) -> int:
    check = "--check" in argv
    found = 0
    for path in markdown_files():
        text = path.read_text(encoding="utf-8")
        new, stale = rewrite(text, ROOT, str(path.relative_to(ROOT)))
        for line, spec, old, value in stale:
            found += 1
            print(f"{path.relative_to(ROOT)}:{line}: {spec}: written {old!r}, the outputs say {value!r}")
        if stale and not check:
            path.write_text(new, encoding="utf-8")
    if check and found:
        print(f"{found} figures stale: run python tools/doc_figures.py (make repro does)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
