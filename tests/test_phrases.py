"""One phrase per statistic (issue 45 Must 5): a group is "outside 5 %" (``outside_5pct``, its complement "within
5 %") or "over 10 %" (``over_10pct``, its complement "within 10 %"); the crossed phrases named the wrong statistic
beside its column and are refused in the README, docs/, the report's templates and the code's words."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CROSSED = re.compile(r"\b(outside 10 ?%|over 5 ?%)")


def test_no_page_or_module_uses_the_crossed_phrase_of_a_statistic():
    templates = (ROOT / "pipeline" / "report" / "templates").glob("*.j2")
    files = [ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *templates, *(ROOT / "bogie").rglob("*.py"),
             *(ROOT / "pipeline").rglob("*.py")]  # fmt: skip
    found = [f"{p.relative_to(ROOT)}:{i}: {line.strip()}" for p in files
             for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if CROSSED.search(line)]  # fmt: skip
    assert not found, "\n".join(found)
    assert CROSSED.search("no group outside 10 % in any variant") and not CROSSED.search("groups over 10 %")
