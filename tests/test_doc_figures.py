"""The figures the README and docs/ quote from the outputs are the outputs' (tools/doc_figures.py; issue 45 Must 1):
every marked figure is what the committed outputs give, and the tool's own parts work as its docstring says."""

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import doc_figures  # noqa: E402


def test_every_figure_in_the_docs_is_the_outputs():
    stale, marked = [], 0
    for path in doc_figures.markdown_files():
        text = path.read_text(encoding="utf-8")
        marked += len(doc_figures.FIGURE.findall(text))
        stale += [(path.name, *s) for s in doc_figures.rewrite(text, ROOT, path.name)[1]]
    assert not stale, f"stale figures (python tools/doc_figures.py rewrites them): {stale}"
    assert marked >= 20  # the README's ranking and the WIM ablation at least


def test_a_figure_is_rewritten_from_its_output_and_a_missing_key_is_named(tmp_path):
    (tmp_path / "m.json").write_text(json.dumps({"a": {"b": [0.123456, -0.155]}}))
    text = (
        "x <!-- fig m.json a.b.0 g2 -->9<!-- /fig --> y <!-- fig m.json a.b.1 neg pct1 -->16 %<!-- /fig -->"
        " z <!-- fig m.json a.b.0 pts2 -->12.35<!-- /fig --> <!-- fig m.json a.b.0 f3 -->0.123<!-- /fig -->"
    )
    new, stale = doc_figures.rewrite(text, tmp_path, "t.md")
    assert "-->0.12<!--" in new and "-->15.5 %<!--" in new and "-->12.35<!--" in new
    assert [(line, old, value) for line, _, old, value in stale] == [(1, "9", "0.12"), (1, "16 %", "15.5 %")]
    with pytest.raises(ValueError, match=r"t.md:2: figure m.json a.c"):
        doc_figures.rewrite("\n<!-- fig m.json a.c g2 -->1<!-- /fig -->", tmp_path, "t.md")
    assert doc_figures.written(1234.4, "int") == "1,234"
    # a sentence the stage wrote, as it is; a number where a sentence is asked for is an error
    (tmp_path / "s.json").write_text(json.dumps({"guidance": ["Keep the tilt within 0.7 degree.", 3]}))
    new, stale = doc_figures.rewrite("<!-- fig s.json guidance.0 text -->old<!-- /fig -->", tmp_path, "t.md")
    assert new == "<!-- fig s.json guidance.0 text -->Keep the tilt within 0.7 degree.<!-- /fig -->" and len(stale) == 1
    with pytest.raises(ValueError, match="not a string"):
        doc_figures.rewrite("<!-- fig s.json guidance.1 text -->3<!-- /fig -->", tmp_path, "t.md")
