"""A unit the docs give a name is the unit the outputs have (issue 45 Must 1): wherever the README or docs/ write
"`name` [unit]", the unit is the one the name's suffix states (docs/outputs.md's rule) or, for a Parquet column the
stages write, the unit in that column's field metadata; and each params.yaml key whose name states a unit says the same
unit in its comment."""

from __future__ import annotations

import re
from pathlib import Path

from bogie.fleet.weighing.runs import UNITS
from pipeline.observed import GROUPS_SCHEMA, SIMULATED_SCHEMA

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: a name's unit suffix -> the unit written in brackets (docs/outputs.md: "any other unit is in the name's suffix")
SUFFIX_UNIT = {
    "_m_km": "m/km", "_m_s": "m/s", "_kmh": "km/h", "_kg": "kg", "_pct": "%", "_deg": "degree", "_mm": "mm",
    "_kn": "kN", "_t": "t",
}  # fmt: skip
#: suffixes that qualify a column without changing its unit (an interval's ends, a bin, a paired protocol)
QUALIFIERS = ("_low", "_high", "_bin", "_baseline", "_static", "_wim", "_diff")
#: a name followed by its unit, an aside in parentheses allowed between: "`spread_kg` (same spread) [kg]"
NAME_UNIT = re.compile(r"`([A-Za-z][A-Za-z0-9_]*)`(?: \([^()]*\))? \[([^\]\s]{1,12})\]")
#: the Parquet columns whose unit is in their field metadata, each with every unit a schema gives it
SCHEMA_UNITS: dict[str, set[str]] = {}
for _name, _unit in UNITS.items():
    SCHEMA_UNITS.setdefault(_name, set()).add(_unit)
for _field in (*GROUPS_SCHEMA, *SIMULATED_SCHEMA):
    SCHEMA_UNITS.setdefault(_field.name, set()).add(_field.metadata[b"unit"].decode())


def units_of(name: str) -> set[str] | None:
    """The units a name may carry: its columns' metadata, else its suffix's unit; None when neither says."""
    if name in SCHEMA_UNITS:
        return SCHEMA_UNITS[name]
    for qualifier in QUALIFIERS:
        if name.endswith(qualifier):
            return units_of(name.removesuffix(qualifier))
    if re.search(r"(outside_5pct|over_10pct)$", name):  # a tolerance in the name, a fraction of groups
        return {"-"}
    if re.match(r"(share|frac)_", name):
        return {"-"}
    return next(({unit} for suffix, unit in SUFFIX_UNIT.items() if name.endswith(suffix)), None)


def test_the_rule_reads_names_as_the_outputs_do():
    # the rule this file applies, on names whose units the docs' rule states outright
    assert units_of("mean_spread_kg") == {"kg"} and units_of("median_spread_pct") == {"%"}
    assert units_of("share_outside_5pct") == {"-"} and units_of("over_10pct_baseline") == {"-"}
    assert units_of("wear_diff_mm_low") == {"mm"} and units_of("site_iri_m_km") == {"m/km"}
    assert units_of("chassis_tilt") == {"rad"} and units_of("chassis_tilt_deg") == {"degree"}
    # one name, two units: the runs' group_load in N, a survey's groups' (bogie.weighings.groups) in kg, against the
    # rule that a name without a suffix is SI; each file's metadata says which, and the docs must say the same
    assert units_of("group_load") == {"N", "kg"}
    assert units_of("bush_note") is None


def test_every_unit_the_docs_give_a_name_is_the_unit_the_name_has():
    checked, wrong = 0, []
    for doc in DOCS:
        for match in NAME_UNIT.finditer(doc.read_text(encoding="utf-8")):
            name, unit = match.groups()
            allowed = units_of(name)
            if allowed is None:
                continue
            checked += 1
            if unit not in allowed:
                wrong.append(f"{doc.relative_to(ROOT)}: `{name}` [{unit}], its unit is {sorted(allowed)}")
    assert checked >= 25, checked  # docs/outputs.md's and docs/observed.md's tables at least
    assert not wrong, "\n".join(wrong)


def test_a_params_keys_comment_gives_the_unit_its_name_states():
    checked, wrong = 0, []
    for line in (ROOT / "params.yaml").read_text(encoding="utf-8").splitlines():
        found = re.match(r"\s*([a-z0-9_]+):.*#.*\[([^\]]+)\]\s*$", line)
        allowed = next(({u} for s, u in SUFFIX_UNIT.items() if found and found[1].endswith(s)), None)
        if allowed is not None:
            checked += 1
            if found[2] not in allowed:
                wrong.append(f"params.yaml's {found[1]} says [{found[2]}]; its name says {sorted(allowed)}")
    assert checked >= 20, checked
    assert not wrong, "\n".join(wrong)
