"""docs/tutorial.md runs as written, within its 20 lines, and gives what its prose says (issue 29 Must 5)."""

import contextlib
import io
import os
import re
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial.md"


def tutorial_code() -> str:
    blocks = re.findall(r"```python\n(.*?)```", TUTORIAL.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) == 1, "the tutorial is one block of code"
    return blocks[0]


def test_the_tutorial_is_at_most_twenty_lines_of_code():
    lines = [line for line in tutorial_code().splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert len(lines) <= 20, len(lines)
    assert all(len(line) <= 120 for line in lines)


def test_the_tutorial_runs_and_gives_what_it_says():
    namespace: dict = {}
    out = io.StringIO()
    cwd = os.getcwd()
    os.chdir(ROOT)  # the observed file's path is relative to the repository's root, as the page says
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(tutorial_code(), str(TUTORIAL), "exec"), namespace)
    finally:
        os.chdir(cwd)
    samples, runs, tables = namespace["samples"], namespace["runs"], namespace["tables"]
    assert len(samples) == 50 and samples["sample_id"].tolist() == list(range(50))
    # one row per bogie and protocol, sample by sample, none dropped
    assert len(runs) == 100 and runs["protocol"].astype(str).tolist() == ["static", "wim"] * 50
    assert (runs["sample_id"].to_numpy() == samples["sample_id"].repeat(2).to_numpy()).all()
    summary = tables["summary"]
    assert int(summary["n_runs"].sum()) == 100
    assert set(map(tuple, summary[["protocol", "group"]].astype(str).to_numpy())) == {
        ("static", "tandem"), ("static", "triaxle"), ("wim", "tandem"), ("wim", "triaxle"),
    }  # fmt: skip
    printed = out.getvalue()
    for source in ("observed", "static", "wim"):
        assert source in printed
    # the headline columns are printed, none hidden behind "..." (issue 45: the first print hid them)
    assert "..." not in printed and all(c in printed for c in ("share_outside_5pct", "mean_spread_kg", "n_groups"))
    # the comparison's observed rows are the observed survey's own statistics
    table = namespace["bf"].compare(runs, namespace["observed"], position="trailer")
    observed = table[table["source"] == "observed"].drop(columns="source").reset_index(drop=True)
    pd.testing.assert_frame_equal(observed, namespace["observed"].statistics.reset_index(drop=True))
