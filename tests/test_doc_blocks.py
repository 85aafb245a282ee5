"""Every Python block of the README and docs/ runs as written (issue 45 Must 1): a renamed function, a changed
argument or a missing name in a page fails here, not in a reader's first hour.

Each block runs in a fresh namespace, in the folder :data:`WHERE` names: the repository (paths such as
``tests/data/weighings/site30.csv`` are the repository's), a folder holding the test files of
``tests/data/weighings`` (a block that reads ``site.mon`` or ``site.castor``), or a folder with a small
``data/runs`` made by the simulate stage's own code (the README's pandas examples). A block whose first line is
``# continues docs/tutorial.md`` runs after the tutorial's code, in its namespace, as the page says. Every block must
be in :data:`WHERE`, so a new one is classified when it is written. The tutorial's own block is run and checked by
``tests/test_tutorial.py``.
"""

import contextlib
import copy
import io
import os
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = ["README.md", *sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "docs").glob("*.md"))]
CONTINUES = "# continues docs/tutorial.md"
#: (page, index of the block on the page) -> where it runs: "repo", "weighings" or "runs"; "tutorial": tested by
#: tests/test_tutorial.py
WHERE = {
    ("README.md", 0): "repo", ("README.md", 1): "repo", ("README.md", 2): "repo", ("README.md", 3): "runs",
    ("docs/calibration.md", 0): "repo", ("docs/design.md", 0): "repo", ("docs/tutorial.md", 0): "tutorial",
    ("docs/weighings.md", 0): "weighings", ("docs/weighings.md", 1): "weighings",
}  # fmt: skip


def blocks() -> dict[tuple[str, int], str]:
    found = {}
    for page in PAGES:
        for i, code in enumerate(re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(encoding="utf-8"), re.S)):
            found[(page, i)] = code
    return found


def test_every_python_block_of_the_docs_is_classified():
    assert set(blocks()) == set(WHERE), (
        f"blocks not in WHERE: {set(blocks()) - set(WHERE)}; gone: {set(WHERE) - set(blocks())}"
    )


@pytest.fixture(scope="module")
def tutorial() -> dict:
    """docs/tutorial.md's namespace after its code (run from the repository, as its page says)."""
    namespace: dict = {}
    _run(blocks()[("docs/tutorial.md", 0)], namespace, ROOT, "docs/tutorial.md")
    return namespace


@pytest.fixture(scope="module")
def runs_folder(tmp_path_factory) -> Path:
    """A folder with a small data/runs of the fleet study, written by the simulate stage's own code."""
    import dataclasses

    from pipeline.config import load_params, parse_config
    from pipeline.sample import sample_studies
    from pipeline.simulate import simulate_samples, study_protocols

    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 12
    raw["protocol"]["static"]["dt_s"] = raw["protocol"]["wim"]["dt_s"] = 0.002
    config = parse_config(raw)
    folder = tmp_path_factory.mktemp("runs_folder")
    samples = {"fleet": sample_studies(config)["fleet"]}
    execution = dataclasses.replace(config.execution, backend="loky", n_jobs=1, chunk_size=6)
    simulate_samples(samples, {"fleet": study_protocols(config, "fleet")}, execution, folder / "data" / "runs",
                     lambda line: None)  # fmt: skip
    return folder


def _run(code: str, namespace: dict, where: Path, name: str) -> str:
    out, cwd = io.StringIO(), os.getcwd()
    os.chdir(where)
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(code, name, "exec"), namespace)
    finally:
        os.chdir(cwd)
    return out.getvalue()


@pytest.mark.parametrize("key", [k for k, v in WHERE.items() if v != "tutorial"], ids=lambda k: f"{k[0]}:{k[1]}")
def test_the_block_runs_as_written(key, request, tmp_path):
    code = blocks()[key]
    kind = WHERE[key]
    where = ROOT
    if kind == "weighings":
        where = tmp_path
        for path in (ROOT / "tests" / "data" / "weighings").iterdir():
            shutil.copy(path, tmp_path / path.name)
    elif kind == "runs":
        where = request.getfixturevalue("runs_folder")
    namespace = dict(request.getfixturevalue("tutorial")) if code.startswith(CONTINUES) else {}
    _run(code, namespace, where, f"{key[0]} block {key[1]}")
