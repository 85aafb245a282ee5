"""docs/validation.md's tables are what tools/validation_tables.py computes from bogie.steel.cases now (issue 12).

Running every named case takes about a second once numba has compiled the kernels (which the other tests compile
anyway), so the check runs with the rest of the suite instead of being marked slow.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

from bogie.steel import cases

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("validation_tables", ROOT / "tools" / "validation_tables.py")
vt = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = vt  # its dataclass looks its module up there
_spec.loader.exec_module(vt)


@pytest.fixture(scope="module")
def tables():
    figures = vt.compute()
    return {name: make(figures) for name, make in vt.TABLES.items()}


def test_the_committed_tables_are_what_the_cases_give(tables):
    diff = vt.differences(vt.DOC.read_text(encoding="utf-8"), tables)
    assert not diff, "\n".join([*diff, "docs/validation.md is stale: run `make validation-tables`"])


def test_every_run_has_one_row_with_the_references_figures_from_its_record(tables):
    rows = {line.split("|")[1].strip(): line for line in tables["table1"].splitlines()[2:]}
    assert list(rows) == [row.name for row in cases.TABLE1]
    for row in cases.TABLE1:
        assert f"| {row.peak_p:g} | {row.peak_p1:g} |" in rows[row.name]
    rows = {line.split("|")[1].strip(): line for line in tables["table2"].splitlines()[2:]}
    assert list(rows) == [row.name for row in cases.TABLE2]
    assert "| 6000/7400 |" in rows["N14"] and "| (not printed) |" in rows["N23"]
    assert "| High (0.6) |" in rows["N29"]  # the friction the case's bogie has, not the table's "High"


def test_rewriting_touches_only_the_tables_and_is_reproducible(tables):
    text = vt.DOC.read_text(encoding="utf-8")
    blanked = vt.render(text, {name: "| stale |" for name in vt.TABLES})
    assert vt.differences(blanked, tables)[0].startswith("table table1: rows that differ: (header), L01, L02")
    assert vt.render(blanked, tables) == text
    outside = text.split("<!-- table:table2 end -->")[1]
    assert blanked.endswith(outside)


def test_a_missing_or_doubled_marker_is_refused():
    text = vt.DOC.read_text(encoding="utf-8")
    with pytest.raises(ValueError, match="table 'table2' needs exactly one '<!-- table:table2 begin -->'"):
        vt.committed(text.replace("<!-- table:table2 begin -->", ""))
    with pytest.raises(ValueError, match="found 1 and 2"):
        vt.committed(text + "\n<!-- table:table1 end -->\n")


@pytest.mark.parametrize(
    "x, n, text",
    [(0.0059, 3, "0.00590"), (332.05, 3, "332"), (16827.3, 4, "16830"), (9.996, 3, "10.0"), (0.3, 3, "0.300")],
)
def test_significant_figures_keep_trailing_zeros_and_never_an_exponent(x, n, text):
    assert vt.sig(x, n) == text
