"""Issue 27's bad inputs and size: each found case is a clear message or a counted skip with its line number.

The files are written here from the hand-written ``tests/data/weighings/site.*`` records (whose fields are listed in
``test_weighings_readers.py``): vehicle A of site.mon is 5 axles, 6500 | 9000 | 7400 8000 8600 kg, on 14 March 2026
at 07:05:09.120 (MON offsets: day 9, month 11, year 13 (I4), hour 17, minute 19, millisecond 21 (I5), n_axles 26,
gross 30 (I6), axle 1 at 50, I5 kg, 10 characters per axle).
"""

import gzip
import os
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from bogie.weighings.readers import YEAR_RANGE, read_weighings
from bogie.weighings.stats import at_resolution

DATA = Path(__file__).parent / "data" / "weighings"
ROOT = Path(__file__).resolve().parents[1]
MON_A = (DATA / "site.mon").read_text().splitlines()[0]
CSV_HEADER = "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,spacing_1,vehicle_class\n"
REPEAT = "repeat of an earlier record"


def mon_at(minute: int, hour: int = 7, day: int = 14) -> str:
    """Vehicle A at another day, hour and minute: another vehicle, not a repeat."""
    return MON_A[:9] + f"{day:02d}" + MON_A[11:17] + f"{hour:02d}{minute:02d}" + MON_A[21:]


def csv_row(minute: int, lane: str = "1", stamp: str | None = None, cls: str = "R2") -> str:
    stamp = stamp if stamp is not None else f"2026-03-14T07:{minute:02d}:00"
    return f"{stamp},80,{lane},2,5000,6000,3.2,{cls}\n"


def good_mon(n: int) -> list[str]:
    return [mon_at(k % 60, hour=k // 60 % 24, day=1 + k // 1440) for k in range(n)]


def bad_lines(path: Path, fmt: str) -> dict[str, list[int]]:
    return read_weighings(path, fmt).bad_lines


# ---- size --------------------------------------------------------------------------------------------------------
def test_memory_is_a_few_times_the_file_not_45_times(tmp_path):
    # the line-by-line reader took 9.1 GB for a 200 MB MON file (45 times its size); 1 GiB for 1,000,000 records of
    # about 100 bytes is 10 times. numpy's allocations are traced by tracemalloc
    path = tmp_path / "big.mon"
    path.write_text("\n".join(good_mon(20_000)) + "\n")
    read_weighings(path, "mon")  # imports and caches outside the measurement
    tracemalloc.start()
    try:
        result = read_weighings(path, "mon")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert result.n_read == 20_000 and result.n_skipped == 0
    assert peak < 10 * path.stat().st_size, peak / path.stat().st_size


@pytest.mark.parametrize("fmt", ["mon", "castor", "csv"])
def test_a_gzip_file_is_read_as_the_file_it_holds(tmp_path, fmt):
    plain = read_weighings(DATA / f"site.{fmt}", fmt)
    packed = tmp_path / f"site.{fmt}.gz"
    packed.write_bytes(gzip.compress((DATA / f"site.{fmt}").read_bytes(), mtime=0))
    again = read_weighings(packed)  # auto: gzip is told by its first bytes, the format by its records
    assert again.format == fmt and again.bad_lines == plain.bad_lines
    assert again.vehicles.equals(plain.vehicles)


def test_a_gzip_file_that_does_not_decompress_is_refused_by_name(tmp_path):
    path = tmp_path / "cut.mon.gz"
    path.write_bytes(gzip.compress((DATA / "site.mon").read_bytes())[:40])
    with pytest.raises(ValueError, match=r"cut\.mon\.gz: starts as a gzip file but does not decompress"):
        read_weighings(path, "mon")


# ---- CSV cells -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("lane", ["1e300", "1.7", "-7", "0", "10"])
def test_a_csv_lane_that_is_not_a_whole_number_1_to_9_is_a_bad_record(tmp_path, lane):
    path = tmp_path / "lanes.csv"
    path.write_text(CSV_HEADER + csv_row(1) + csv_row(2, lane=lane) + csv_row(3, lane="2"))
    result = read_weighings(path, "csv")
    assert result.bad_lines == {"implausible lane (allowed a whole number 1-9, or empty)": [3]}
    assert result.vehicles["lane"].tolist() == [1, 2]


@pytest.mark.parametrize("stamp", ["now", "today", "2026-03-14T07:05:09Z", "2026-03-14T07:05:09+01:00", "14/03/2026"])
def test_a_csv_timestamp_that_is_not_iso_8601_local_time_is_a_bad_record_not_the_wall_clock(tmp_path, stamp):
    path = tmp_path / "stamps.csv"
    path.write_text(CSV_HEADER + csv_row(1) + csv_row(2, stamp=stamp) + csv_row(3))
    result = read_weighings(path, "csv")
    ((reason, lines),) = result.bad_lines.items()
    assert lines == [3] and ("invalid date or time" in reason or "time zone" in reason)
    assert result.vehicles["timestamp"].dt.strftime("%H:%M").tolist() == ["07:01", "07:03"]


def test_a_csv_line_over_128_kib_is_a_counted_bad_record_quoted_or_not(tmp_path):
    # Python's csv module refuses a field over 131,072 characters with an exception: it must not reach the user
    huge = "x" * 200_000
    path = tmp_path / "long.csv"
    rows = [csv_row(1), csv_row(2, cls=huge), csv_row(3, cls=f'"{huge}"'), csv_row(4), csv_row(5)]
    path.write_text(CSV_HEADER + "".join(rows))
    result = read_weighings(path, "csv")
    assert result.vehicles["line"].tolist() == [2, 3, 5, 6]  # the unquoted long class is an ignored column
    assert result.bad_lines == {"unreadable CSV row (an unclosed quote or a huge field)": [4]}


def test_a_csv_number_that_overflows_is_non_numeric(tmp_path):
    path = tmp_path / "overflow.csv"
    path.write_text(CSV_HEADER + csv_row(1) + "2026-03-14T07:02:00,80,1,2,1e400,6000,3.2,R2\n" + csv_row(3))
    assert read_weighings(path, "csv").bad_lines == {"non-numeric field": [3]}


# ---- years, repeats ------------------------------------------------------------------------------------------------
def test_year_2999_is_an_implausible_year_in_mon_and_csv(tmp_path):
    low, high = YEAR_RANGE
    reason = f"implausible year (allowed {low}-{high})"
    mon = tmp_path / "y.mon"
    mon.write_text("\n".join([mon_at(1), mon_at(2)[:13] + "2999" + mon_at(2)[17:], mon_at(3)]) + "\n")
    assert bad_lines(mon, "mon") == {reason: [2]}
    csv = tmp_path / "y.csv"
    csv.write_text(CSV_HEADER + csv_row(1) + csv_row(2, stamp="2999-03-14T07:02:00") + csv_row(3))
    assert bad_lines(csv, "csv") == {reason: [3]}


def test_a_two_digit_year_reads_with_the_posix_pivot(tmp_path):
    # CASTOR's year is I2 at offset 8: 95 is 1995, 26 is 2026 (strptime's %y: 69-99 -> 19xx, 00-68 -> 20xx)
    lines = (DATA / "site.castor").read_text().splitlines()
    path = tmp_path / "old.castor"
    path.write_text("\n".join([lines[0][:8] + "95" + lines[0][10:], lines[1]]) + "\n")
    years = read_weighings(path, "castor").vehicles["timestamp"].dt.year.tolist()
    assert years == [1995, 2026]


def test_a_record_repeated_1000_times_is_counted_and_a_file_of_repeats_refused(tmp_path):
    path = tmp_path / "repeats.mon"
    path.write_text("\n".join([mon_at(0)] * 1000) + "\n")
    with pytest.raises(ValueError, match=rf"999 of 1000 records bad \({REPEAT}.*: 999, lines 2, 3, 4, 5, 6, \.\.\."):
        read_weighings(path, "mon")
    # among good records: each repeat counted with its line, the first copy kept
    path.write_text("\n".join([mon_at(1), mon_at(2), mon_at(1), mon_at(3), mon_at(1)]) + "\n")
    result = read_weighings(path, "mon")
    assert result.vehicles["line"].tolist() == [1, 2, 4]
    ((reason, lines),) = result.bad_lines.items()
    assert reason.startswith(REPEAT) and lines == [3, 5]


# ---- bytes that are not records ----------------------------------------------------------------------------------
@pytest.mark.parametrize("char", ["\f", "\v", "\u2028", "\x00", "\t"])
def test_a_form_feed_or_line_separator_inside_a_record_is_a_bad_byte_not_a_line_end(tmp_path, char):
    # splitlines() used to cut the record in two and shift every later line number
    path = tmp_path / "ff.mon"
    middle = mon_at(2)
    path.write_text("\n".join([mon_at(1), middle[:60] + char + middle[61:], mon_at(3), mon_at(4)]) + "\n")
    result = read_weighings(path, "mon")
    assert result.bad_lines == {"non-numeric field": [2]}
    assert result.vehicles["line"].tolist() == [1, 3, 4]
    # in the padding past the last axle too: nothing but digits and spaces is a MON record
    path.write_text("\n".join([mon_at(1), mon_at(2) + "00" + char + "00", mon_at(3)]) + "\n")
    assert read_weighings(path, "mon").bad_lines == {"non-numeric field": [2]}


def test_a_line_separator_in_an_ignored_csv_column_shifts_no_line_number(tmp_path):
    path = tmp_path / "sep.csv"
    path.write_text(CSV_HEADER + csv_row(1, cls="T2\u2028S3") + csv_row(2, cls="a\fb") + "x\n" + csv_row(4))
    result = read_weighings(path, "csv")
    assert result.vehicles["line"].tolist() == [2, 3, 5]
    assert result.bad_lines == {"wrong length": [4]}


def test_binary_data_is_refused_in_one_line_in_every_format(tmp_path):
    path = tmp_path / "noise.bin"
    path.write_bytes(np.random.default_rng(27).integers(0, 256, 300_000, dtype=np.uint8).tobytes())
    with pytest.raises(ValueError, match="format auto: no known format fits"):
        read_weighings(path)
    for fmt in ("mon", "castor", "bedit", "ditis"):
        with pytest.raises(ValueError, match=rf"not read as \w+ records \(format {fmt}\): \d+ of \d+ records bad"):
            read_weighings(path, fmt)
    with pytest.raises(ValueError, match=r"not the CSV layout \(format csv\)"):
        read_weighings(path, "csv")


def test_a_field_that_overflows_into_the_next_is_a_bad_record(tmp_path):
    # a gross weight written with 7 digits pushes every later field one character right: the speed, the lane and
    # direction, the axles no longer line up (here: direction 5 at offset 45)
    a = mon_at(2)
    overflow = a[:30] + "0039500" + a[36:]
    path = tmp_path / "shift.mon"
    path.write_text("\n".join([mon_at(1), overflow, mon_at(3)]) + "\n")
    result = read_weighings(path, "mon")
    assert result.vehicles["line"].tolist() == [1, 3] and list(result.bad_lines.values()) == [[2]]


def test_blank_lines_are_not_records_and_do_not_shift_line_numbers(tmp_path):
    path = tmp_path / "blank.mon"
    path.write_bytes(("\n".join([mon_at(1), "", "   \t", mon_at(2)]) + "\r\n").encode())
    assert read_weighings(path, "mon").vehicles["line"].tolist() == [1, 4]


# ---- the command ---------------------------------------------------------------------------------------------------
def test_the_command_into_a_closed_pipe_is_not_a_traceback(tmp_path):
    # ``bogie weighings site.mon | head -0``: the reader of the output has gone before the command writes
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "bogie.cli", "weighings", str(DATA / "site.mon")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=tmp_path,
    )  # fmt: skip
    proc.stdout.close()
    with proc.stderr:
        stderr = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, stderr
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, stderr


# ---- resolution ----------------------------------------------------------------------------------------------------
def test_the_weight_resolution_is_the_largest_step_the_loads_support(tmp_path):
    castor = read_weighings(DATA / "site.castor", "castor")
    assert castor.resolution.step_kg == 100.0 and castor.resolution.source == "format"
    assert castor.describe_resolution().startswith("weight resolution 100 kg (the format's unit")
    # site.mon's loads are all whole hundreds of kilograms: a 100 kg file, though MON writes kg
    assert read_weighings(DATA / "site.mon", "mon").weight_step_kg == 100.0
    path = tmp_path / "ten.mon"
    a = mon_at(2)
    path.write_text("\n".join([mon_at(1), a[:50] + "06510" + a[55:80] + "07390" + a[85:]]) + "\n")  # +10, -10 kg
    result = read_weighings(path, "mon")
    assert result.n_read == 2 and result.weight_step_kg == 10.0
    assert "detected: 10 of 10 axle loads within 1 kg of a multiple of 10 kg: 100.0 % on one" in (
        result.describe_resolution()
    )
    csv = tmp_path / "decimal.csv"
    csv.write_text(CSV_HEADER + csv_row(1) + "2026-03-14T07:02:00,80,1,2,5000.5,6000,3.2,R2\n")
    assert read_weighings(csv, "csv").weight_step_kg is None


def test_at_resolution_rounds_to_the_nearest_step_and_refuses_a_step_that_is_not_one():
    loads = np.array([[7449.0, 7451.0, np.nan], [149.9, 50.1, 0.0]])
    np.testing.assert_array_equal(at_resolution(loads, 100.0), [[7400.0, 7500.0, np.nan], [100.0, 100.0, 0.0]])
    np.testing.assert_array_equal(at_resolution(loads, None), loads)
    with pytest.raises(ValueError, match="step_kg = 0.0 kg"):
        at_resolution(loads, 0.0)


def test_a_csv_date_that_does_not_exist_is_an_invalid_date_and_the_others_are_read(tmp_path):
    path = tmp_path / "feb30.csv"
    path.write_text(CSV_HEADER + csv_row(1) + csv_row(2, stamp="2026-02-30T07:02:00") + csv_row(3, stamp="2024-02-29"))
    result = read_weighings(path, "csv")
    assert result.bad_lines == {"invalid date or time": [3]}
    stamps = result.vehicles["timestamp"].dt.strftime("%Y-%m-%d %H:%M").tolist()
    assert stamps == ["2026-03-14 07:01", "2024-02-29 00:00"]


@pytest.mark.parametrize("fmt", ["mon", "castor", "bedit", "ditis"])
def test_lane_0_is_a_counted_bad_record_in_every_fixed_width_format(tmp_path, fmt):
    # issue 40 item 9: the formats count lanes from 1 (wim-record-formats.md); lane 0 was read silently
    from bogie.weighings.formats import LAYOUTS
    from bogie.weighings.readers import read_weighings

    lane = next(f for f in LAYOUTS[fmt].header if f.name == "lane")
    source = Path(__file__).resolve().parent / "data" / "weighings" / f"site.{fmt}"
    good = read_weighings(source, fmt)
    lines = source.read_bytes().split(b"\n")
    target = int(good.vehicles["line"].iloc[0]) - 1
    edited = bytearray(lines[target])
    edited[lane.start : lane.start + lane.width] = b"0" * lane.width
    lines[target] = bytes(edited)
    path = tmp_path / f"x.{fmt}"
    path.write_bytes(b"\n".join(lines))
    try:
        result = read_weighings(path, fmt)
    except ValueError as exc:  # too many bad records for the file to be this format: the lane is named among them
        assert "lane 0" in str(exc)
        return
    reason = next(r for r in result.skipped if r.startswith("lane 0"))
    assert result.skipped[reason] == 1 and result.bad_lines[reason] == [target + 1]
    assert len(result.vehicles) == len(good.vehicles) - 1
