"""Rewrite each stage's code dependencies in ``dvc.yaml`` to the project files it imports (``pipeline.deps``).

``tests/pipeline/test_dvc_deps.py`` asserts that every stage of ``dvc.yaml`` lists exactly the ``bogie/`` and
``pipeline/`` files its module imports; after a change to the import graph, run ``python tools/dvc_deps.py`` (from
the project root) and commit ``dvc.yaml``. Only the lines of the form ``      - bogie/...`` or ``      - pipeline/...``
inside a stage's ``deps:`` are replaced, so comments, the order of the other dependencies and the rest of the file
stay as written; the report stage's whole-package deps (``bogie``, ``pipeline``) are left alone.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pipeline.deps import project_files  # noqa: E402

CODE_DEP = re.compile(r"^(\s+)- (bogie|pipeline)/\S+\s*$")


def rewrite(text: str) -> str:
    """``text`` (dvc.yaml) with each stage's code dependencies replaced by the files its command's module imports."""
    stages = yaml.safe_load(text)["stages"]
    lines = text.splitlines(keepends=True)
    out: list[str] = []
    stage = None
    k = 0
    while k < len(lines):
        line = lines[k]
        top = re.match(r"^  ([A-Za-z_][\w-]*):\s*$", line)
        if top:
            stage = top.group(1)
        match = CODE_DEP.match(line)
        if match and stage in stages:
            indent = match.group(1)
            while k < len(lines) and CODE_DEP.match(lines[k]):
                k += 1  # the stage's old block of code deps
            module = stages[stage]["cmd"].removeprefix("python -m ").split()[0]
            files = sorted(p.relative_to(ROOT).as_posix() for p in project_files(module))
            out += [f"{indent}- {f}\n" for f in files]
            continue
        out.append(line)
        k += 1
    return "".join(out)


def main() -> int:
    path = ROOT / "dvc.yaml"
    old = path.read_text(encoding="utf-8")
    new = rewrite(old)
    if new != old:
        path.write_text(new, encoding="utf-8")
        print("dvc.yaml: code deps rewritten")
    else:
        print("dvc.yaml: code deps already match the imports")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
