"""A survey of several files, each a site (issue 46 Must 1): pooled, it is the survey of the files as one; per site,
each file's own; a file read again (its resolution not its first chunk's) leaves the files before it as they were."""

from __future__ import annotations

import pandas as pd
import pytest
from test_weighings_stream import WHOLE, fleet

from bogie.weighings.survey import observed_survey
from bogie.weighings.writers import write_weighings

LADEN = 10_000.0  # [kg] the groups kept: laden ones, so that the filters matter


def split(vehicles: pd.DataFrame, at: list[int]) -> list[pd.DataFrame]:
    edges = [0, *at, len(vehicles)]
    return [vehicles.iloc[a:b].reset_index(drop=True) for a, b in zip(edges, edges[1:])]


def written(tmp_path, parts: list[pd.DataFrame], fmt: str = "mon") -> list:
    folder = tmp_path / "network"
    folder.mkdir()
    paths = []
    for k, part in enumerate(parts):
        paths.append(folder / f"site{k}.{fmt}")
        write_weighings(part, paths[-1], fmt)
    return paths


def statistics(survey) -> dict:
    d = survey.to_dict()
    return {key: d[key] for key in ("records", "positions", "groups", "road")}


def steps_change(vehicles: pd.DataFrame, first: int) -> pd.DataFrame:
    """The vehicles from row ``first`` on at 10 kg: a file's first chunk says 100 kg, the whole file 10 kg."""
    vehicles = vehicles.copy()
    later = vehicles.index >= first
    vehicles.loc[later, "axle_load_1"] += 10.0
    vehicles.loc[later, "gross_weight"] += 10.0
    return vehicles


@pytest.mark.parametrize("keep_groups", [True, False])
def test_a_folder_of_files_pooled_is_the_survey_of_the_files_as_one(tmp_path, keep_groups):
    vehicles = fleet(600)
    write_weighings(vehicles, tmp_path / "whole.mon", "mon")
    written(tmp_path, split(vehicles, [250, 420]))
    whole = observed_survey(tmp_path / "whole.mon", "mon", min_group_load_kg=LADEN, chunk_bytes=WHOLE)
    pooled = observed_survey(tmp_path / "network", "mon", min_group_load_kg=LADEN, chunk_bytes=4_096,
                             keep_groups=keep_groups)  # fmt: skip
    assert statistics(pooled) == statistics(whole)
    assert pooled.n_kept == whole.n_kept
    assert [f["site"] for f in pooled.files] == ["site0.mon", "site1.mon", "site2.mon"]
    assert [f["records"]["read"] for f in pooled.files] == [250, 170, 180]


def test_each_site_of_a_survey_of_several_files_is_that_file_alone(tmp_path):
    paths = written(tmp_path, split(fleet(600, seed=5), [200, 400]))
    pooled = observed_survey(paths, "mon", min_group_load_kg=LADEN, keep_groups=False)
    assert sorted(pooled.stations) == ["site0.mon", "site1.mon", "site2.mon"]
    for path in paths:
        alone = observed_survey(path, "mon", min_group_load_kg=LADEN)
        entry = pooled.stations[path.name]
        assert entry["vehicles"] == alone.read.n_read == 200
        for size, figures in alone.to_dict()["groups"].items():
            mine = entry["groups"][size]
            if figures["n_groups"]:
                assert {key: mine[key] for key in figures} == figures
            else:  # no tri-axle in these five-axle vehicles
                assert mine == {"n_groups": 0}
    sites = pooled.site_counts("ignored")  # named by their files, as compare_sites takes them
    assert sorted(sites) == ["site0.mon", "site1.mon", "site2.mon"]


@pytest.mark.parametrize("keep_groups", [True, False])
def test_a_file_read_again_leaves_the_files_before_it_as_they_were(tmp_path, keep_groups):
    # the second file's first chunk says 100 kg, the file 10 kg: it is read twice; the first file (10 kg as a whole)
    # must be counted once, and the second once, as the concatenated file gives
    vehicles = steps_change(fleet(600, seed=7), 450)  # rows 450 on at 10 kg: the second file's tail
    first = vehicles.iloc[:300].copy()
    first.loc[:, "axle_load_1"] += 10.0  # the whole first file at 10 kg too
    first.loc[:, "gross_weight"] += 10.0
    vehicles = pd.concat([first, vehicles.iloc[300:]], ignore_index=True)
    write_weighings(vehicles, tmp_path / "whole.mon", "mon")
    paths = written(tmp_path, split(vehicles, [300]))

    class Sink:
        def __init__(self):
            self.files, self.starts = {}, 0

        def next_file(self, site):
            self.site = site
            self.files[site] = []

        def start(self):
            self.starts += 1
            self.files[self.site] = []

        def write(self, groups):
            self.files[self.site].append(groups)

    whole = observed_survey(tmp_path / "whole.mon", "mon", min_group_load_kg=LADEN, chunk_bytes=WHOLE)
    sink = Sink()
    pooled = observed_survey(paths, "mon", min_group_load_kg=LADEN, chunk_bytes=4_096, keep_groups=keep_groups,
                             sink=sink)  # fmt: skip
    assert sink.starts == 3  # the second file twice
    assert [f["records"]["weight_step_kg"] for f in pooled.files] == [10.0, 10.0]
    assert statistics(pooled) == statistics(whole)
    got = pd.concat([part for parts in sink.files.values() for part in parts], ignore_index=True)
    lines = got["line"].to_numpy()
    assert len(got) == len(whole.groups)
    # the same groups, the second file's lines counted from its own first line
    assert got[["axle_load_1", "axle_load_2", "axle_load_3"]].equals(whole.groups[["axle_load_1", "axle_load_2",
                                                                                     "axle_load_3"]])  # fmt: skip
    assert lines.max() <= 300


def test_files_of_another_format_or_resolution_are_refused_naming_them(tmp_path):
    a, b = split(fleet(400), [200])
    folder = tmp_path / "network"
    folder.mkdir()
    write_weighings(a, folder / "a.mon", "mon")
    write_weighings(b, folder / "b.csv", "csv")
    with pytest.raises(ValueError, match=r"one format: a\.mon is mon, b\.csv is csv"):
        observed_survey(folder, "auto")
    (folder / "b.csv").unlink()
    write_weighings(steps_change(b, 0), folder / "b.mon", "mon")
    refused = r"one weight resolution: a\.mon at 100 kg, b\.mon at 10 kg; set resolution_kg"
    with pytest.raises(ValueError, match=refused):
        observed_survey(folder, "mon")
    both = observed_survey(folder, "mon", resolution_kg=100.0)  # one resolution for both: read
    assert both.read.weight_step_kg == 100.0 and both.read.n_read == 400


def test_a_sink_without_next_file_an_empty_folder_and_a_file_given_twice_are_refused(tmp_path):
    paths = written(tmp_path, split(fleet(200), [100]))

    class OneFileSink:
        def start(self):
            pass

        def write(self, groups):
            pass

    with pytest.raises(ValueError, match=r"sink: a survey of several files needs a sink with next_file"):
        observed_survey(paths, "mon", sink=OneFileSink())
    with pytest.raises(ValueError, match=r"a file given twice"):
        observed_survey([paths[0], paths[0]], "mon")
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / ".hidden").write_text("x")
    with pytest.raises(ValueError, match=r"holds no file of records"):
        observed_survey(tmp_path / "empty", "mon")


def test_the_bad_lines_of_a_survey_of_several_files_are_named_by_their_file(tmp_path):
    paths = written(tmp_path, split(fleet(300), [150]))
    lines = paths[1].read_text().splitlines()
    lines[9] = lines[9][:20]  # line 10 of the second file cut short
    paths[1].write_text("\n".join(lines) + "\n")
    pooled = observed_survey(paths, "mon")
    assert pooled.read.n_read == 299 and pooled.read.n_skipped == 1
    assert "site1.mon:10" in pooled.read.summary()
    assert pooled.files[1]["records"]["skipped"] == 1 and pooled.files[0]["records"]["skipped"] == 0


def test_bogie_weighings_reads_a_folder_pooled_and_sets_its_files_side_by_side(tmp_path, capsys):
    import json

    from bogie.cli import main

    written(tmp_path, split(fleet(600, seed=5), [200, 400]))
    assert main(["weighings", str(tmp_path / "network"), "--by-site", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["records"]["read"] == 600 and [f["site"] for f in out["files"]] == [
        "site0.mon",
        "site1.mon",
        "site2.mon",
    ]
    assert {row["site"] for row in out["sites"]} == {"site0.mon", "site1.mon", "site2.mon"}
