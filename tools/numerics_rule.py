"""The static half of the same-bits guard: no CPU-dispatched numerics on a result path in ``bogie/`` or ``pipeline/``.

Why (``docs/architecture.md``, "The same bits on every machine"): numpy hands its float64 elementary functions
(``exp``, ``log``, ``power``, ``sin``, ...) to SIMD loops it picks by the CPU when it is imported (AVX-512 loops,
partly Intel's SVML, on an AVX-512 machine; the C library's scalar functions on an AVX2 one), and its products,
solves, covariances and ``multivariate_normal`` to BLAS/LAPACK kernels OpenBLAS picks by the CPU. Both round
differently in the last bit from one machine to another, so a value computed with them is not the same bits on every
machine. ``bogie.numerics`` has the functions to use instead (the C library's scalar functions; sums in index order).

What the rule refuses, in every module of ``bogie/`` and ``pipeline/`` (tokens, so that code written after the rule is
caught too, not a list of functions known today):

* ``np.<f>`` / ``numpy.<f>`` for a float transcendental ufunc ``<f>`` (:data:`TRANSCENDENTAL`), also imported by name;
* ``**`` whose exponent is not a literal that numpy computes exactly (0, 1, -1, 0.5, 2: ``ones``, a copy, a
  reciprocal, ``sqrt``, ``square``; :data:`EXACT_EXPONENTS`) and whose operands are not both literals: on an array it
  is numpy's ``power``;
* ``@``, ``.dot(``, ``np.dot`` / ``matmul`` / ``inner`` / ``vdot`` / ``tensordot`` / ``einsum`` / ``cov`` /
  ``corrcoef`` / ``polyfit``, anything of ``numpy.linalg`` or ``scipy.linalg``, ``multivariate_normal``
  (:data:`BLAS`): BLAS and LAPACK;
* a ``scipy.stats`` distribution or test other than ``qmc`` (their densities and tails are numpy's ufuncs).

Inside a numba-compiled function (``@njit``, ``@jit``, ``@vectorize``, ...) the elementary functions and ``**`` are
the C library's (numba compiles them to calls of libm), so only the BLAS rule applies there (numba's ``@`` and
``np.linalg`` call scipy's BLAS and LAPACK).

An exception is a comment on the flagged line, the first line of its statement or a comment line right above the
statement, ``# numerics-ok: <reason>``, the
reason in words (a scalar, a figure, a diagnostic that feeds no result...); a module that only draws figures is
exempt by :data:`EXEMPT_MODULES`, with its reason. ``make lint`` and ``tests/test_numerics_rule.py`` run it;
``python tools/numerics_rule.py`` lists every finding, with the line, and exits 1 if there is one.
"""

from __future__ import annotations

import ast
import re
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: numpy's float ufuncs whose float64 loops numpy dispatches by the CPU (or may, in a later numpy): every
#: transcendental one. sqrt, the arithmetic, floor, abs and the comparisons are exactly rounded everywhere.
TRANSCENDENTAL = frozenset(
    """geomspace logspace exp exp2 expm1 log log2 log10 log1p logaddexp logaddexp2 power float_power pow
    sin cos tan arcsin arccos arctan arctan2 sinh cosh tanh arcsinh arccosh arctanh asin acos atan atan2 asinh acosh
    atanh hypot cbrt sinc i0
    """.split()
)
#: numpy's functions that hand float work to BLAS or LAPACK (the kernel OpenBLAS picks by the CPU)
BLAS = frozenset("dot vdot inner matmul tensordot einsum cov corrcoef polyfit multivariate_normal".split())
#: numpy's submodules of which every function is LAPACK or BLAS (or one of the functions above)
BLAS_MODULES = frozenset({"linalg", "emath"})
#: exponents for which numpy's power on an array is exact (numpy's fast scalar power: ones, copy, reciprocal,
#: sqrt, square), and Python's too
EXACT_EXPONENTS = frozenset({0, 1, -1, 0.5, 2})
#: decorators that compile a function with numba (its elementary functions are then libm's)
NUMBA_DECORATORS = frozenset({"njit", "jit", "vectorize", "guvectorize", "cfunc", "generated_jit", "stencil"})
#: modules the rule does not read, with the reason
EXEMPT_MODULES = {
    "bogie/numerics.py": "the numerics module itself: the C library's functions and the order-fixed product and solve",
}
#: the marker of a named exception, with its reason after the colon
MARKER = re.compile(r"#\s*numerics-ok:\s*(\S.*)$")


@dataclass(frozen=True)
class Finding:
    path: str
    line: int
    what: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.what}"


def _dotted(node: ast.AST) -> str | None:
    """``a.b.c`` of an attribute chain of names, or None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return ".".join(reversed(parts))
    return None


def _is_number(node: ast.AST) -> bool:
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        node = node.operand
    return isinstance(node, ast.Constant) and type(node.value) in (int, float)


def _number(node: ast.AST) -> float | None:
    if not _is_number(node):
        return None
    if isinstance(node, ast.UnaryOp):
        value = node.operand.value  # type: ignore[attr-defined]
        return -value if isinstance(node.op, ast.USub) else value
    return node.value  # type: ignore[attr-defined]


def _decorator_name(node: ast.expr) -> str:
    if isinstance(node, ast.Call):
        node = node.func
    name = _dotted(node) or ""
    return name.rsplit(".", 1)[-1]


class _Visitor(ast.NodeVisitor):
    def __init__(self, path: str, numpy_names: set[str], scipy_stats: set[str], blas_names: set[str]):
        self.path = path
        self.numpy_names = numpy_names  # what numpy is called here (np, numpy)
        self.scipy_stats = scipy_stats  # names bound to scipy.stats or one of its objects
        self.blas_names = blas_names  # names imported from numpy.linalg / scipy.linalg / numpy's BLAS functions
        self.findings: list[tuple[int, str]] = []
        self.compiled = 0  # depth of numba-compiled functions

    def flag(self, node: ast.AST, what: str) -> None:
        self.findings.append((node.lineno, what))

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        compiled = any(_decorator_name(d) in NUMBA_DECORATORS for d in node.decorator_list)
        self.compiled += compiled
        self.generic_visit(node)
        self.compiled -= compiled

    visit_AsyncFunctionDef = visit_FunctionDef  # type: ignore[assignment]

    def visit_Attribute(self, node: ast.Attribute) -> None:
        name = _dotted(node)
        if name is not None:
            parts = name.split(".")
            if parts[0] in self.numpy_names and len(parts) >= 2:
                if parts[1] in BLAS_MODULES:
                    self.flag(node, f"{name}: numpy.{parts[1]} runs LAPACK/BLAS kernels chosen by the CPU")
                    return
                if parts[-1] in BLAS and len(parts) == 2:
                    self.flag(node, f"{name}: BLAS/LAPACK kernels chosen by the CPU")
                    return
                if parts[-1] in TRANSCENDENTAL and len(parts) == 2 and not self.compiled:
                    self.flag(node, f"{name}: numpy's SIMD loop chosen by the CPU; use bogie.numerics.{parts[1]}")
                    return
            if parts[0] == "scipy" and len(parts) >= 2 and parts[1] == "linalg":
                self.flag(node, f"{name}: scipy.linalg runs LAPACK/BLAS kernels chosen by the CPU")
                return
            if parts[0] in self.scipy_stats and not (len(parts) >= 2 and parts[1] == "qmc"):
                self.flag(node, f"{name}: scipy.stats computes with numpy's SIMD loops")
                return
        if node.attr in ("dot", "multivariate_normal") and _dotted(node.value) != "numerics":
            self.flag(node, f".{node.attr}: BLAS/LAPACK kernels chosen by the CPU")
        self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> None:
        if node.id in self.blas_names:
            self.flag(node, f"{node.id}: imported from numpy/scipy's BLAS or LAPACK functions")
        elif node.id in self.scipy_stats:
            self.flag(node, f"{node.id}: scipy.stats computes with numpy's SIMD loops")

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        module = node.module or ""
        for alias in node.names:
            bound = alias.asname or alias.name
            if module in ("numpy", "numpy.linalg", "scipy.linalg", "scipy") or module.startswith("numpy.linalg"):
                if module == "numpy" and alias.name in TRANSCENDENTAL and not self.compiled:
                    self.flag(node, f"from numpy import {alias.name}: numpy's SIMD loop chosen by the CPU")
                elif module == "numpy" and (alias.name in BLAS or alias.name in BLAS_MODULES):
                    self.blas_names.add(bound)
                elif module in ("numpy.linalg", "scipy.linalg") or module.startswith("numpy.linalg"):
                    self.blas_names.add(bound)
                elif module == "scipy" and alias.name == "linalg":
                    self.blas_names.add(bound)
                elif module == "scipy" and alias.name == "stats":
                    self.scipy_stats.add(bound)
            elif module == "scipy.stats" and alias.name != "qmc":
                self.scipy_stats.add(bound)

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            if alias.name == "numpy":
                self.numpy_names.add(alias.asname or "numpy")
            elif alias.name in ("numpy.linalg", "scipy.linalg") and alias.asname:
                self.blas_names.add(alias.asname)
            elif alias.name == "scipy.stats" and alias.asname:
                self.scipy_stats.add(alias.asname)

    def visit_BinOp(self, node: ast.BinOp) -> None:
        if isinstance(node.op, ast.MatMult):
            self.flag(node, "@: BLAS kernels chosen by the CPU; use bogie.numerics.matmul")
        elif isinstance(node.op, ast.Pow) and not self.compiled:
            exponent = _number(node.right)
            if not (_is_number(node.left) and exponent is not None) and exponent not in EXACT_EXPONENTS:
                self.flag(node, "**: on an array, numpy's power (a SIMD loop chosen by the CPU); use "
                                "bogie.numerics.power, or name the exception (a scalar)")  # fmt: skip
        self.generic_visit(node)

    def visit_AugAssign(self, node: ast.AugAssign) -> None:
        if isinstance(node.op, ast.MatMult):
            self.flag(node, "@=: BLAS kernels chosen by the CPU")
        elif isinstance(node.op, ast.Pow) and not self.compiled and _number(node.value) not in EXACT_EXPONENTS:
            self.flag(node, "**=: on an array, numpy's power (a SIMD loop chosen by the CPU)")
        self.generic_visit(node)


def _statement_starts(tree: ast.AST) -> dict[int, int]:
    """Each line of a statement -> the statement's first line (for a marker on the first line of a long call)."""
    starts: dict[int, int] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.stmt) and not isinstance(node, ast.FunctionDef | ast.ClassDef | ast.AsyncFunctionDef):
            end = getattr(node, "end_lineno", node.lineno) or node.lineno
            body_start = min((c.lineno for c in ast.iter_child_nodes(node) if isinstance(c, ast.stmt)), default=None)
            last = end if body_start is None else body_start - 1
            for line in range(node.lineno, last + 1):
                starts.setdefault(line, node.lineno)
    return starts


def check_source(source: str, path: str = "<string>") -> list[Finding]:
    """The findings of the rule in one module's source, less the lines whose exception is named."""
    tree = ast.parse(source, filename=path)
    visitor = _Visitor(path, {"np", "numpy"}, set(), set())
    # imports first (a module may import a name below its first use in a function)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            visitor.visit(node)
    visitor.findings.clear()
    visitor.visit(tree)
    lines = source.splitlines()
    starts = _statement_starts(tree)

    def excused(line: int) -> bool:
        first = starts.get(line, line)
        for candidate in {line, first}:
            if 0 < candidate <= len(lines) and MARKER.search(lines[candidate - 1]):
                return True
        above = first - 1  # a comment line of its own right above the statement
        return (
            0 < above <= len(lines)
            and lines[above - 1].lstrip().startswith("#")
            and bool(MARKER.search(lines[above - 1]))
        )

    seen: set[tuple[int, str]] = set()
    out = []
    for line, what in visitor.findings:
        if (line, what) in seen or excused(line):
            continue
        seen.add((line, what))
        out.append(Finding(path, line, what))
    return out


def bare_markers(source: str, path: str) -> list[Finding]:
    """Markers with no reason (``# numerics-ok:`` and nothing after it)."""
    return [
        Finding(path, k, "numerics-ok without a reason")
        for k, text in enumerate(source.splitlines(), start=1)
        if re.search(r"#\s*numerics-ok\s*:?\s*$", text)
    ]


def modules(root: Path = ROOT) -> list[Path]:
    """The modules the rule reads: every .py file of bogie/ and pipeline/ but the exempt ones."""
    found = sorted(p for package in ("bogie", "pipeline") for p in (root / package).rglob("*.py"))
    return [p for p in found if p.relative_to(root).as_posix() not in EXEMPT_MODULES]


def check(root: Path = ROOT) -> list[Finding]:
    """Every finding in bogie/ and pipeline/."""
    out: list[Finding] = []
    for path in modules(root):
        rel = path.relative_to(root).as_posix()
        source = path.read_text(encoding="utf-8")
        out.extend(check_source(source, rel))
        out.extend(bare_markers(source, rel))
    return out


def main() -> int:
    findings = check()
    for finding in findings:
        print(finding)
    if findings:
        print(f"{len(findings)} place(s) where a result may depend on numpy's SIMD dispatch or the BLAS kernel: use "
              "bogie.numerics, or name the exception with '# numerics-ok: <reason>' (tools/numerics_rule.py)",
              file=sys.stderr)  # fmt: skip
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
