"""params.yaml is kept in the style DVC writes, so ``dvc exp run -S key=value`` in the workspace changes only the
value set (issue 45 Must 6): DVC rewrites the whole file through ruamel.yaml, wrapping flow collections longer than
its line width and writing ``null`` as an empty value; a file already in that style comes back byte for byte."""

import difflib
import shutil
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def _set(tmp_path, *overrides: str) -> tuple[str, str]:
    """params.yaml before and after ``dvc exp run -S`` sets ``overrides`` (DVC's own code for it)."""
    from dvc.utils.hydra import apply_overrides

    copy = tmp_path / "params.yaml"
    shutil.copyfile(ROOT / "params.yaml", copy)
    apply_overrides(copy, list(overrides))
    return (ROOT / "params.yaml").read_text(encoding="utf-8"), copy.read_text(encoding="utf-8")


def test_dvcs_writer_gives_params_yaml_back_byte_for_byte(tmp_path):
    seed = yaml.safe_load((ROOT / "params.yaml").read_text(encoding="utf-8"))["seed"]
    before, after = _set(tmp_path, f"seed={seed}")
    changed = [line for line in difflib.unified_diff(before.splitlines(), after.splitlines(), lineterm="", n=0)
               if line[:1] in "+-" and not line.startswith(("+++", "---"))]  # fmt: skip
    assert not changed, "params.yaml is not in the style DVC writes; dvc exp run -S would rewrite:\n" + "\n".join(
        changed[:20]
    )


def test_setting_one_value_changes_one_line(tmp_path):
    before, after = _set(tmp_path, "fleet.n_bogies=500")
    changed = [(a, b) for a, b in zip(before.splitlines(), after.splitlines()) if a != b]
    assert len(before.splitlines()) == len(after.splitlines()) and len(changed) == 1, changed
    assert changed[0][1].startswith("  n_bogies: 500 ") and "# bogies in the fleet study" in changed[0][1]
