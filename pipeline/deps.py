"""Which source files of the project a module depends on: the static import graph over ``bogie`` and ``pipeline``.

The simulate stage hashes these files into every part file's content hash (:func:`pipeline.chunks.code_version`),
and ``dvc.yaml`` lists them as each stage's code dependencies (``tests/pipeline/test_dvc_deps.py`` checks the two
agree), so an edit to a module a stage does not import (the CLI, the report) neither reruns nor recomputes it.
Every ``import`` statement counts, including those inside functions: the graph is a safe over-approximation.
"""

from __future__ import annotations

import ast
from pathlib import Path

__all__ = ["ROOT", "module_file", "project_files"]

#: the project root: the directory holding the ``bogie`` and ``pipeline`` packages
ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("bogie", "pipeline")


def module_file(name: str, root: Path = ROOT) -> Path | None:
    """The source file of project module ``name`` (a package's ``__init__.py``), or None if it is not one."""
    if name.split(".")[0] not in PACKAGES:
        return None
    base = root.joinpath(*name.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _imports(path: Path, name: str) -> set[str]:
    """Project modules named by the import statements of ``path`` (module ``name``), ``from x import y`` as x.y too."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, base] if base else parts)
            found.add(base)
            found |= {f"{base}.{a.name}" for a in node.names}
    return {m for m in found if m.split(".")[0] in PACKAGES}


def project_files(*modules: str, root: Path = ROOT) -> list[Path]:
    """Every project source file the given modules import, directly or through others, and their packages'
    ``__init__.py`` files, sorted; the modules' own files included."""
    seen: set[Path] = set()
    todo = list(modules)
    while todo:
        name = todo.pop()
        parts = name.split(".")
        for k in range(1, len(parts) + 1):  # importing a.b.c runs a/__init__.py and a/b/__init__.py first
            path = module_file(".".join(parts[:k]), root)
            if path is None or path in seen:
                continue
            seen.add(path)
            module = ".".join(parts[:k])
            todo.extend(_imports(path, module))
    return sorted(seen)
