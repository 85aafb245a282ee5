"""Duplicated keys in params.yaml are refused (pipeline.config.yaml_loader), at any depth, with both line numbers."""

from pathlib import Path

import pytest
import yaml

from bogie.guarded_yaml import DuplicateKeyError, read_yaml
from pipeline.config import ConfigError, load_config, load_params

PARAMS = Path(__file__).resolve().parents[2] / "params.yaml"


def test_the_default_file_reads_as_safe_load_reads_it():
    text = PARAMS.read_text(encoding="utf-8")
    assert read_yaml(text) == yaml.safe_load(text)


def test_empty_and_aliased_documents_read_as_safe_load_reads_them():
    assert read_yaml("") is None
    text = "base: &b {p: 1, q: [1, 2]}\nother: *b\nmerged:\n  <<: *b\n  p: 3\n"
    assert read_yaml(text) == yaml.safe_load(text)


def test_a_top_level_key_given_twice_is_refused_with_both_lines():
    with pytest.raises(DuplicateKeyError) as excinfo:
        read_yaml("seed: 1\nfleet: {}\nseed: 2\n", "p.yaml")
    assert excinfo.value.duplicates == [("seed", 1, 3)]
    assert str(excinfo.value) == (
        "p.yaml: duplicated key seed at line 3 (first at line 1): YAML keeps only the last, remove one"
    )


def test_nested_duplicates_are_all_reported_with_their_key_paths():
    text = "a:\n  b:\n    c: 1\n    c: 2\n  l:\n    - {x: 1, x: 2}\nd: 0\na2: {k: 1}\n"
    with pytest.raises(DuplicateKeyError) as excinfo:
        read_yaml(text)
    assert excinfo.value.duplicates == [("a.b.c", 3, 4), ("a.l[0].x", 6, 6)]


def test_load_params_and_load_config_refuse_a_duplicated_key(tmp_path):
    text = PARAMS.read_text(encoding="utf-8")
    # a second fleet.n_bogies, below the first: YAML alone would silently keep the second value
    bad = tmp_path / "params.yaml"
    bad.write_text(text.replace("  n_bogies: 2000 ", "  n_bogies: 2000\n  n_bogies: 5 ", 1), encoding="utf-8")
    line = text.splitlines().index(next(s for s in text.splitlines() if s.startswith("  n_bogies: 2000"))) + 1
    for load in (load_params, load_config):
        with pytest.raises(ConfigError) as excinfo:
            load(bad)
        assert excinfo.value.key == "fleet.n_bogies"
        assert f"duplicated key fleet.n_bogies at line {line + 1} (first at line {line})" in str(excinfo.value)


def test_a_duplicated_top_level_section_is_refused(tmp_path):
    bad = tmp_path / "params.yaml"
    bad.write_text(PARAMS.read_text(encoding="utf-8") + "\nablation:\n  n_bogies: 10\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="duplicated key ablation at line"):
        load_config(bad)
