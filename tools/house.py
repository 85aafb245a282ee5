"""The shape of the house, measured (issue 42's before and after): lines per package, modules over 500 lines,
functions over 60, private names imported across files and across packages, and circles of imports.

Run: ``python tools/house.py [--json]``. Reads the source only (``ast``); imports nothing of the project.

- *Lines*: every line of the ``.py`` files of a package (its own folder, not its sub-packages).
- *Function length*: from its ``def`` (decorators excluded) to its last line, docstring included, as the issue
  counts them (``_phases_step._solve_step`` 109). A numba-compiled kernel (``@njit``, ``@jit``) is listed apart: the
  issue allows it to be longer, with its reason stated once (``docs/architecture.md``, "Compiled kernels").
- *Private import*: ``from M import _name`` of a project module ``M`` other than the importing one (a module's own
  underscore kernel counts: the issue's 144 are "across files"); *across packages* when ``M``'s package is not the
  importer's, and then any name of a private module (``from bogie.steel.phases._core import run_phases`` in bogie.fleet)
  counts too.
- *Circle*: a strongly connected component of more than one module in the graph of imports between project modules
  (importing ``a.b.c`` from outside ``a.b`` is an edge to ``a.b`` too: its ``__init__.py`` runs first)
  (every import, lazy ones inside functions included, but for a module ``__getattr__``'s: a deprecation shim).
"""

from __future__ import annotations

import argparse
import ast
import json
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("bogie", "pipeline")
MODULE_LINES = 500
FUNCTION_LINES = 60


def modules(root: Path = ROOT) -> dict[str, Path]:
    """Dotted name -> file of every project module."""
    out = {}
    for top in PACKAGES:
        for path in sorted((root / top).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def _package(name: str, path: Path) -> str:
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


def _resolve(node: ast.ImportFrom, name: str, path: Path) -> str:
    if not node.level:
        return node.module or ""
    base = _package(name, path).split(".")
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _compiled(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Whether a function is a numba-compiled kernel: decorated with ``njit`` or ``jit`` (``@njit(...)``,
    ``@numba.njit``)."""
    for decorator in node.decorator_list:
        target = decorator.func if isinstance(decorator, ast.Call) else decorator
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in ("njit", "jit"):
            return True
    return False


def _packages_run(dest: str, importer: str, mods: dict[str, Path]) -> set[str]:
    """The packages whose ``__init__.py`` importing ``dest`` runs first, but for those enclosing the importer (its
    own package ran before it did): importing ``a.b.c`` from outside ``a.b`` runs ``a/b/__init__.py``, so a heavy
    package ``__init__`` that imports back makes a circle the plain edges do not show."""
    parts = dest.split(".")
    outer = {".".join(parts[:k]) for k in range(1, len(parts))}
    return {p for p in outer if p in mods and not (importer == p or importer.startswith(p + "."))}


def measure(root: Path = ROOT) -> dict:
    mods = modules(root)
    lines: dict[str, int] = defaultdict(int)
    long_modules, long_functions, long_kernels, private, graph = [], [], [], [], defaultdict(set)
    for name, path in mods.items():
        text = path.read_text(encoding="utf-8")
        n = text.count("\n")
        lines[_package(name, path)] += n
        if n > MODULE_LINES:
            long_modules.append((n, str(path.relative_to(root))))
        tree = ast.parse(text)
        # a module's __getattr__ that finds moved names with a DeprecationWarning imports only when one is asked for:
        # its lazy import is not an edge of the graph (issue 42 allows such a shim for one release)
        shims = {id(n) for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "__getattr__"
                 for n in ast.walk(f)}  # fmt: skip
        for node in ast.walk(tree):
            if id(node) in shims:
                continue
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > FUNCTION_LINES:
                    (long_kernels if _compiled(node) else long_functions).append((length, f"{name}.{node.name}"))
            elif isinstance(node, ast.ImportFrom):
                target = _resolve(node, name, path)
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    dest = sub if sub in mods else target
                    if dest in mods and dest != name:
                        graph[name].add(dest)
                        graph[name] |= _packages_run(dest, name, mods)
                    if dest not in mods or dest == name:
                        continue
                    private_name = alias.name.startswith("_")
                    private_module = any(part.startswith("_") for part in dest.split("."))
                    across = _package(dest, mods[dest]) != _package(name, path)
                    if private_name or (private_module and across):
                        private.append((name, sub, private_name, across))
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in mods and alias.name != name:
                        graph[name].add(alias.name)
                        graph[name] |= _packages_run(alias.name, name, mods)
    return {
        "lines_per_package": dict(sorted(lines.items())),
        "modules_over_500": sorted(long_modules, reverse=True),
        "functions_over_60": sorted(long_functions, reverse=True),
        "kernels_over_60": sorted(long_kernels, reverse=True),
        "private_imports": sum(1 for _a, _b, private_name, _across in private if private_name),
        "private_imports_across_packages": sorted({(a, b) for a, b, _private_name, across in private if across}),
        "circles": _circles(graph),
    }


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    out.append(sorted(component))
    return sorted(out)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the whole measurement as JSON")
    args = parser.parse_args(argv)
    m = measure()
    if args.json:
        print(json.dumps(m, indent=1))
        return
    print("lines per package:")
    for package, n in m["lines_per_package"].items():
        print(f"  {package:<28} {n:>6}")
    print(f"modules over {MODULE_LINES} lines: {len(m['modules_over_500'])}")
    for n, path in m["modules_over_500"]:
        print(f"  {n:>5} {path}")
    kernels = m["kernels_over_60"]
    print(f"compiled kernels over {FUNCTION_LINES} lines (allowed; docs/architecture.md says why): {len(kernels)}")
    for n, function in kernels:
        print(f"  {n:5d} {function}")
    print(f"functions over {FUNCTION_LINES} lines: {len(m['functions_over_60'])}")
    for n, function in m["functions_over_60"]:
        print(f"  {n:>5} {function}")
    across = m["private_imports_across_packages"]
    print(f"private names imported across files: {m['private_imports']}; across packages: {len(across)}")
    for importer, name in across:
        print(f"  {importer} <- {name}")
    print(f"circles of imports: {len(m['circles'])}")
    for circle in m["circles"]:
        print("  " + " <-> ".join(circle))


if __name__ == "__main__":
    main()
