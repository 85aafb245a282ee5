"""What `dvc metrics show` and `dvc exp show` compare (issue 31 item 4): one screen, the headline, nothing dropped.

`dvc exp show` had 597 columns and `dvc metrics show` printed 122 KB: every stage's JSON was declared as DVC metrics.
Only metrics/headline.json is now; the stages' full JSONs are plain outputs (cache: false, committed). With one
metrics file DVC names its columns by key alone, so the README's filter keeps `failed` instead of dropping a column
it would have named `metrics/headline.json:failed`.
"""

import json
import re
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_only_the_headline_is_declared_as_dvc_metrics_and_every_stage_json_is_still_an_output():
    stages = yaml.safe_load((ROOT / "dvc.yaml").read_text())["stages"]
    declared = [next(iter(m)) if isinstance(m, dict) else m for s in stages.values() for m in s.get("metrics", [])]
    assert declared == ["metrics/headline.json"]
    outs = {next(iter(o)) if isinstance(o, dict) else o: o for s in stages.values() for o in s.get("outs", [])}
    for name in ("survey", "sensitivity", "observed", "calibration", "design"):
        entry = outs[f"metrics/{name}.json"]
        assert entry == {f"metrics/{name}.json": {"cache": False}}  # in git, as before, not in DVC's cache


def test_the_readmes_experiment_filter_keeps_every_headline_figure_it_names_and_failed():
    readme = (ROOT / "README.md").read_text()
    keep = re.search(r"dvc exp show --drop '\.\*' --keep '([^']+)'", readme).group(1)
    headline = json.loads((ROOT / "metrics" / "headline.json").read_text())
    kept = [k for k in headline if re.search(keep, k)]
    named = [k for k in keep.strip("^$()").split("|") if k not in ("Experiment", "fleet.n_bogies")]
    assert set(named) <= set(headline), set(named) - set(headline)  # every figure it names is in the headline
    assert "failed" in kept and "runs" not in kept
    assert any(k.startswith("outside_5pct_") for k in kept) and any(k.startswith("spread_kg_") for k in kept)
    # one screen: 120 characters, checked on the command's own output by tests/pipeline/test_readme_commands.py
    assert len(kept) + 2 <= 8
