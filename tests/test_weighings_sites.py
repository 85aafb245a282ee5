"""Many WIM sites side by side (issue 46 Must 1): bogie.weighings.sites and ``bogie weighings`` on several files."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bogie.cli import main
from bogie.weighings.sites import FAMILY_LEVEL, compare_sites
from bogie.weighings.survey import observed_survey

HEADER = "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,axle_load_3,axle_load_4,axle_load_5,"
HEADER += "spacing_1,spacing_2,spacing_3,spacing_4\n"
#: a tri-axle of each kind behind a steer and a drive axle (docs/weighings.md's rules: outside 5 % when
#: (max - min) / max > 0.05, over 10 % when max / mean > 1.10): within 5 % (400 / 8200 = 0.049), outside 5 % but
#: not over 10 % (1000 / 8500 = 0.118; 8500 / 8000 = 1.0625) and over 10 % (9000 / 8000 = 1.125)
TRIAXLES = {"within": (8000, 8200, 7800), "outside": (7500, 8000, 8500), "over": (7000, 8000, 9000)}


def site_file(path, kinds: dict[str, int]) -> None:
    """A CSV of vehicles, each a steer axle, a drive axle and a tri-axle of the given kinds, counted."""
    lines = [HEADER]
    second = 0
    for kind, count in kinds.items():
        for _ in range(count):
            a, b, c = TRIAXLES[kind]
            lines.append(f"2026-01-05T06:{second // 60:02d}:{second % 60:02d},80,1,5,6000,9000,{a},{b},{c},"
                         "3.6,5.2,1.31,1.31\n")  # fmt: skip
            second += 1
    path.write_text("".join(lines))


def counts(n: int, k5: int, k10: int, spread: float = 500.0) -> dict:
    return {"triaxle": {"n_groups": n, "n_outside_5pct": k5, "n_over_10pct": k10, "mean_spread_kg": spread}}


def test_an_odd_site_is_flagged_and_does_not_make_the_others_look_odd():
    # worked by hand: C (60 of 200) against A and B pooled (42 of 400): pooled share 102 / 600 = 0.17,
    # z = (0.3 - 0.105) / sqrt(0.17 0.83 (1/200 + 1/400)) = 5.99432, p = erfc(z / sqrt 2) = 2.05e-9, under
    # 0.05 / 6; then A against B alone (20 and 22 of 200): z = -0.01 / sqrt(0.105 0.895 0.01) = -0.326208,
    # p = 0.744267. Against the rest of all sites A would have looked odd too (0.1 against 82 / 400: p = 0.00125)
    frame = compare_sites({"A": counts(200, 20, 8), "B": counts(200, 22, 9), "C": counts(200, 60, 30, 900.0)})
    assert list(frame["site"]) == ["C", "B", "A"]  # the most unequal sharing first
    row = frame.set_index("site")
    assert row.loc["C", "p_outside_5pct"] == pytest.approx(math.erfc(5.99432 / math.sqrt(2.0)), rel=1e-4)
    assert row.loc["A", "p_outside_5pct"] == pytest.approx(0.744267, abs=1e-6)
    assert list(row["disagrees"]) == [True, False, False]
    # C's Wilson interval (scipy's binomtest(60, 200).proportion_ci(method="wilson"): 0.2407 to 0.3668)
    assert (row.loc["C", "share_outside_5pct_low"], row.loc["C", "share_outside_5pct_high"]) == pytest.approx(
        (0.240747, 0.366791), abs=1e-6
    )
    assert row.loc["C", "share_outside_5pct"] == 0.3 and row.loc["C", "n_outside_5pct"] == 60


def test_a_size_no_site_saw_has_no_row_and_stops_nothing():
    # a network of tandems alone: the tri-axles of both sites have no group (a state-wide file's stations gave
    # n_groups 0 and None); before, the Bonferroni threshold divided by the zero sites of that size
    none = {"n_groups": 0, "n_outside_5pct": 0, "n_over_10pct": 0, "mean_spread_kg": None}
    tandems = [{"n_groups": 30, "n_outside_5pct": k, "n_over_10pct": k, "mean_spread_kg": 500.0} for k in (6, 24)]
    frame = compare_sites({"A": {"tandem": tandems[0], "triaxle": none}, "B": {"tandem": tandems[1], "triaxle": none}})
    assert list(frame["group"]) == ["tandem", "tandem"] and list(frame["site"]) == ["B", "A"]


def test_two_sites_that_differ_are_both_flagged_and_small_counts_flag_nothing():
    frame = compare_sites({"A": counts(40, 5, 0), "B": counts(40, 30, 5)}).set_index("site")
    assert bool(frame.loc["A", "disagrees"]) and bool(frame.loc["B", "disagrees"])
    # the same shares on 8 groups each: every count but one under 5, nothing tested, nothing flagged
    small = compare_sites({"A": counts(8, 1, 0), "B": counts(8, 6, 1)})
    assert small["few"].all() and not small["disagrees"].any()


def test_a_network_of_sites_with_one_truth_flags_a_site_in_at_most_about_five_percent_of_surveys():
    # Bonferroni over 2 m tests: 300 networks of 10 sites, every count binomial(500, 0.3) and binomial(500, 0.1).
    # Without the correction (each test at 0.05) nearly every network would flag a site; with it, at most 5 % do:
    # at most 25 of 300 (the binomial(300, 0.05) count's 99.9th percentile)
    rng = np.random.default_rng(46)
    flagged = 0
    for _ in range(300):
        sites = {f"s{i}": counts(500, int(rng.binomial(500, 0.3)), int(rng.binomial(500, 0.1))) for i in range(10)}
        flagged += bool(compare_sites(sites)["disagrees"].any())
    assert flagged <= 25, flagged
    # and one site at 0.45 among nine at 0.3 is found nearly always, alone
    found = alone = 0
    for _ in range(50):
        sites = {f"s{i}": counts(500, int(rng.binomial(500, 0.3)), 50) for i in range(9)}
        sites["odd"] = counts(500, int(rng.binomial(500, 0.45)), 50)
        frame = compare_sites(sites).set_index("site")
        found += bool(frame.loc["odd", "disagrees"])
        alone += int(frame["disagrees"].sum()) == 1
    assert found >= 45 and alone >= 45, (found, alone)
    assert FAMILY_LEVEL == 0.05


def test_bad_counts_are_refused_naming_the_site_and_the_range():
    with pytest.raises(ValueError, match=r"sites\['A'\]\['triaxle'\]\['n_outside_5pct'\] = 41: must be a whole"):
        compare_sites({"A": counts(40, 41, 0), "B": counts(40, 3, 0)})
    with pytest.raises(ValueError, match="at least 2"):
        compare_sites({"A": counts(40, 4, 0)})


def test_the_survey_counts_each_file_as_a_site(tmp_path):
    site_file(tmp_path / "a.csv", {"within": 12, "outside": 6, "over": 2})
    survey = observed_survey(tmp_path / "a.csv", "csv", position="trailer")
    # 20 tri-axles: 8 outside 5 % (6 + 2), 2 over 10 %; spreads 400, 1000 and 2000 kg: mean (12 400 + 6 1000 +
    # 2 2000) / 20 = 740 kg
    got = survey.site_counts("a")["a"]["triaxle"]
    assert (got["n_groups"], got["n_outside_5pct"], got["n_over_10pct"]) == (20, 8, 2)
    assert got["mean_spread_kg"] == pytest.approx(740.0, abs=1e-9)


def test_bogie_weighings_compares_several_files(tmp_path, capsys):
    site_file(tmp_path / "north.csv", {"within": 35, "outside": 4, "over": 1})  # 5 of 40 outside 5 %
    site_file(tmp_path / "south.csv", {"within": 10, "outside": 20, "over": 10})  # 30 of 40
    files = [str(tmp_path / "north.csv"), str(tmp_path / "south.csv")]
    assert main(["weighings", *files, "--position", "trailer"]) == 0
    out = capsys.readouterr().out
    table = out[out.index("sites side by side") :].splitlines()
    south = next(line for line in table if line.startswith("triaxle  south.csv"))
    north = next(line for line in table if line.startswith("triaxle  north.csv"))
    assert table.index(south) < table.index(north)  # the most unequal first
    assert " 75.0 (" in south and south.endswith("disagrees") and north.endswith("disagrees")
    assert "all 2 sites" in out and " 43.8 (" in out  # 35 of 80 pooled
    assert main(["weighings", *files, "--position", "trailer", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data["surveys"]) == set(files)
    rows = {r["site"]: r for r in data["sites"] if r["group"] == "triaxle"}
    assert (rows["north.csv"]["n_outside_5pct"], rows["south.csv"]["n_outside_5pct"]) == (5, 30)


def test_two_files_of_one_name_in_two_folders_are_two_sites(tmp_path, capsys):
    for folder, kinds in (("a", {"within": 35, "outside": 5}), ("b", {"within": 10, "outside": 30})):
        (tmp_path / folder).mkdir()
        site_file(tmp_path / folder / "site.csv", kinds)
    files = [str(tmp_path / "a" / "site.csv"), str(tmp_path / "b" / "site.csv")]
    assert main(["weighings", *files, "--position", "trailer", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["sites"]
    assert sorted(r["site"] for r in rows) == sorted(files)


def test_bogie_weighings_by_site_needs_several_sites(tmp_path, capsys):
    site_file(tmp_path / "one.csv", {"within": 5})
    assert main(["weighings", str(tmp_path / "one.csv"), "--by-site"]) == 2
    assert "holds one site" in capsys.readouterr().err
    assert main(["weighings", str(tmp_path / "one.csv"), str(tmp_path / "one.csv")]) == 2
    assert "given twice" in capsys.readouterr().err


def test_the_docs_table_is_what_the_command_prints(tmp_path, capsys):
    # docs/weighings.md, "Many sites": its table is this network's, line for line
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "weighings.md").read_text(encoding="utf-8")
    section = text[text.index("## Many sites") :]
    block = section[section.index("```text\n") + 8 : section.index("```\n", section.index("```text\n") + 8)]
    site_file(tmp_path / "north.csv", {"within": 35, "outside": 4, "over": 1})
    site_file(tmp_path / "south.csv", {"within": 10, "outside": 20, "over": 10})
    site_file(tmp_path / "east.csv", {"within": 30, "outside": 7, "over": 3})
    assert main(["weighings", *(str(tmp_path / f) for f in ("north.csv", "south.csv", "east.csv")), "--position",
                 "trailer"]) == 0  # fmt: skip
    printed = capsys.readouterr().out.splitlines()
    start = printed.index(block.splitlines()[0])
    assert printed[start : start + len(block.splitlines())] == block.splitlines()
