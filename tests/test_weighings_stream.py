"""A file read in chunks gives what a whole-file read gives (issue 41 Must 4): the records, the skipped ones with
their line numbers, the repeats across chunks, the resolution, and the survey statistics."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bogie.weighings._stream import SeenStore, blocks, key_hashes
from bogie.weighings.readers import read_weighings, stream_weighings
from bogie.weighings.survey import observed_survey
from bogie.weighings.writers import write_weighings

DATA = Path(__file__).parent / "data" / "weighings"
WHOLE = 1 << 30  # one chunk for any test file


def fleet(n: int, seed: int = 3) -> pd.DataFrame:
    """``n`` five-axle vehicles a second apart, loads in whole 100 kg."""
    rng = np.random.default_rng(seed)
    loads = 100.0 * rng.integers(50, 95, (n, 5))
    return pd.DataFrame({
        "timestamp": pd.Timestamp("2026-03-14") + pd.to_timedelta(np.arange(n), "s"), "speed": 22.0, "lane": 1,
        "direction": 1, "n_axles": 5, "gross_weight": loads.sum(axis=1), "length": 16.5,
        **{f"axle_load_{i + 1}": loads[:, i] for i in range(5)},
        "spacing_1": 3.6, "spacing_2": 1.31, "spacing_3": 8.0, "spacing_4": 1.31,
    })  # fmt: skip


def same(a, b) -> None:
    assert a.vehicles.equals(b.vehicles)
    assert (a.format, dict(a.skipped), a.bad_lines, a.counted) == (b.format, dict(b.skipped), b.bad_lines, b.counted)
    assert a.resolution == b.resolution


@pytest.mark.parametrize("fmt", ["mon", "castor", "bedit", "ditis", "csv", "tmg2001", "tmg2013"])
def test_a_file_read_in_small_chunks_is_the_file_read_whole(tmp_path, fmt):
    vehicles = fleet(300)
    if fmt.startswith("tmg"):
        vehicles = vehicles.assign(station="06-000101", vehicle_class=9)
    path = tmp_path / f"site.{fmt}"
    write_weighings(vehicles, path, fmt)
    lines = path.read_text().splitlines()
    # bad records in the middle, and repeats of records of earlier chunks (a record copied 200 lines on)
    body = 1 if fmt == "csv" else 0
    lines[body + 50] = lines[body + 50][:20]
    lines += [lines[body + 10], lines[body + 120]]
    path.write_text("\n".join(lines) + "\n")
    whole = read_weighings(path, fmt, chunk_bytes=WHOLE)
    for chunk in (500, 4_096):
        same(read_weighings(path, fmt, chunk_bytes=chunk), whole)
    if fmt.startswith("tmg"):  # hourly stamps: the copies are alike trucks, kept and counted
        assert whole.n_read == 301 and sum(whole.counted.values()) == 2
    else:
        assert whole.n_read == 299 and whole.skipped["repeat of an earlier record (same time, lane, direction, "
                                                    "speed, axle loads and spacings)"] == 2  # fmt: skip
        assert any(body + 51 in lines for lines in whole.bad_lines.values())


def test_the_whole_files_resolution_is_applied_when_the_first_chunk_shows_another(tmp_path):
    # the first 200 vehicles at 100 kg, the rest at 10 kg: the first chunk says 100 kg, the file 10 kg; a record
    # whose gross weight is off by 60 kg on 5 axles passes at 100 kg (slack 2 % + 50 + 5 x 50 kg) and at 10 kg
    # (2 % + 5 + 5 x 5 kg = 2 % of the sum + 30 kg) only within 2 %: the answer must be the whole file's either way
    vehicles = fleet(400)
    later = vehicles.index >= 200
    vehicles.loc[later, "axle_load_1"] += 10.0
    vehicles.loc[later, "gross_weight"] += 10.0
    path = tmp_path / "site.mon"
    write_weighings(vehicles, path, "mon")
    whole = read_weighings(path, "mon", chunk_bytes=WHOLE)
    assert whole.weight_step_kg == 10.0
    chunked = read_weighings(path, "mon", chunk_bytes=4_096)
    same(chunked, whole)


def test_a_multi_member_gzip_file_streams_as_its_members_together(tmp_path):
    text = (DATA / "site.mon").read_bytes()
    half = text.index(b"\n", len(text) // 2) + 1
    path = tmp_path / "site.mon.gz"
    path.write_bytes(gzip.compress(text[:half], mtime=0) + gzip.compress(text[half:], mtime=0))
    assert b"".join(b for b, _ in blocks(path, WHOLE, 64)) == text
    same(read_weighings(path, "mon", chunk_bytes=64), read_weighings(DATA / "site.mon", "mon", chunk_bytes=WHOLE))


def test_blocks_end_at_line_ends_and_count_the_lines_before_them(tmp_path):
    path = tmp_path / "x.txt"
    path.write_bytes(b"a\n\nbb\nccc\nd")
    got = list(blocks(path, WHOLE, 3))
    assert b"".join(b for b, _ in got) == b"a\n\nbb\nccc\nd"
    assert all(b.endswith(b"\n") for b, _ in got[:-1])
    assert [n for _, n in got] == [sum(b.count(b"\n") for b, _ in got[:k]) for k in range(len(got))]


def test_the_hashes_do_not_depend_on_the_chunks_widest_vehicle():
    loads = np.array([[5000.0, 6000.0, np.nan], [5000.0, 6000.0, 7000.0]])
    spacings = np.array([[3.0, np.nan], [3.0, 1.3]])
    wide = key_hashes([np.array([1, 1])], loads, spacings, np.array([2, 3]))
    narrow = key_hashes([np.array([1])], loads[:1, :2], spacings[:1, :1], np.array([2]))
    assert wide[0] == narrow[0] and wide[0] != wide[1]


DAY = np.timedelta64(1, "D")


def test_the_seen_store_finds_what_was_added_on_disk_or_in_memory():
    values = np.arange(1, 20_001, dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15)
    stamps = np.repeat(np.datetime64("2026-03-14T01:00") + np.arange(10) * DAY, 2_000)  # ten days of 2,000
    seen = SeenStore(in_memory=3_000)
    first = np.arange(20_000) % 2 == 0  # every other record of every day
    seen.add(stamps[first], values[first])
    # the ten days hold 10,000 hashes: at most 3,000 in memory (and the day in hand), the rest on disk
    assert seen.count == 10_000 and seen.held <= 3_000 + 1_000 and len(seen.on_disk) >= 6
    on_disk = sorted(seen._dir.iterdir())
    assert len(on_disk) == len(seen.on_disk)
    found = seen.contains(stamps, values)
    np.testing.assert_array_equal(found, first)
    # a hash known on another day is not a repeat: a repeat has its record's time
    assert not seen.contains(stamps[:1] + DAY * 20, values[:1]).any()
    seen.add(stamps, values)  # those already in stay once
    assert seen.count == 20_000 and seen.contains(stamps, values).all()
    where = seen._dir
    seen.close()
    assert not where.exists()


def test_a_repeat_far_back_in_the_file_is_found_when_its_day_is_on_disk(tmp_path, monkeypatch):
    from bogie.weighings import _stream

    vehicles = fleet(3_000)
    vehicles["timestamp"] = pd.Timestamp("2026-03-14") + pd.to_timedelta(np.arange(3_000) * 600, "s")  # 21 days
    path = tmp_path / "site.mon"
    write_weighings(vehicles, path, "mon")
    lines = path.read_bytes().splitlines(keepends=True)
    path.write_bytes(b"".join(lines) + lines[5] + lines[1_500])  # two repeats at the end, of days 0 and 10
    whole = read_weighings(path, "mon", chunk_bytes=WHOLE)
    monkeypatch.setattr(_stream, "SEEN_IN_MEMORY", 300)  # a day or two in memory
    monkeypatch.setattr(SeenStore.__init__, "__defaults__", (300,))
    streamed = read_weighings(path, "mon", chunk_bytes=8_192)
    assert sum(n for reason, n in whole.skipped.items() if reason.startswith("repeat")) == 2
    same(whole, streamed)


def test_the_survey_of_a_streamed_file_is_the_survey_of_the_whole(tmp_path):
    path = tmp_path / "site.mon"
    write_weighings(fleet(600), path, "mon")
    whole = observed_survey(path, "mon", chunk_bytes=WHOLE)
    streamed = observed_survey(path, "mon", chunk_bytes=4_096, keep_groups=False)
    a, b = whole.to_dict(), streamed.to_dict()
    assert a == b
    assert len(streamed.groups) < len(whole.groups) and streamed.n_kept == len(whole.groups)


def test_the_statistics_of_a_large_table_block_by_block_are_the_tables(monkeypatch):
    from bogie.weighings import stats

    rng = np.random.default_rng(9)
    m = 5_000
    loads = rng.normal(8000.0, 700.0, (m, 3)).round(-1)
    n = rng.integers(2, 4, m)
    loads[n == 2, 2] = np.nan
    groups = pd.DataFrame({"group": np.where(n == 2, "tandem", "triaxle"), "n_axles": n,
                           **{f"axle_load_{i + 1}": loads[:, i] for i in range(3)}})  # fmt: skip
    table = stats.survey_statistics(groups)
    monkeypatch.setattr(stats, "STATISTICS_BLOCK", 700)
    blocked = stats.survey_statistics(groups)
    assert list(blocked.columns) == list(table.columns)
    for column in table.columns:
        if column == "mean_spread_kg":
            assert blocked[column].to_numpy() == pytest.approx(table[column].to_numpy(), rel=1e-12)
        else:  # counts, shares, median and quantiles to the bit (NaN where a size has no third axle)
            np.testing.assert_array_equal(blocked[column].to_numpy(), table[column].to_numpy(), err_msg=column)


def test_a_sink_gets_every_kept_group_once_and_afresh_on_a_second_pass(tmp_path):
    class Sink:
        def __init__(self):
            self.starts, self.parts = 0, []

        def start(self):
            self.starts += 1
            self.parts = []

        def write(self, groups):
            self.parts.append(groups)

    vehicles = fleet(400)
    later = vehicles.index >= 200  # the second half at 10 kg: the first chunk's resolution is not the file's
    vehicles.loc[later, "axle_load_1"] += 10.0
    vehicles.loc[later, "gross_weight"] += 10.0
    path = tmp_path / "site.mon"
    write_weighings(vehicles, path, "mon")
    whole = observed_survey(path, "mon", min_group_load_kg=10_000, chunk_bytes=WHOLE)
    sink = Sink()
    streamed = observed_survey(path, "mon", min_group_load_kg=10_000, chunk_bytes=4_096, keep_groups=False, sink=sink)
    assert sink.starts == 2 and len(sink.parts) > 1  # read again with the file's resolution
    assert pd.concat(sink.parts, ignore_index=True).equals(whole.groups)
    assert streamed.to_dict() == whole.to_dict()


def test_a_consumers_error_stops_the_read_and_reaches_the_caller(tmp_path):
    """The chunks are consumed on a second thread while the next is parsed: an error of the consumer is the
    caller's, raised as it was, and no chunk after the failing one is consumed; the chunks come in file order."""
    path = tmp_path / "site.mon"
    write_weighings(fleet(400), path, "mon")
    firsts: list[int] = []

    def consume(vehicles: pd.DataFrame) -> None:
        firsts.append(int(vehicles["line"].iloc[0]))
        if len(firsts) == 3:
            raise RuntimeError("the consumer's own failure")

    with pytest.raises(RuntimeError, match="the consumer's own failure"):
        stream_weighings(path, "mon", None, lambda: None, consume, chunk_bytes=4_096)
    assert len(firsts) == 3 and firsts == sorted(firsts) and firsts[0] == 1
