"""bogie.weighings.readers: every format read from small hand-written files, bad records skipped and counted.

Every site.<format> file in tests/data/weighings/ holds the same five vehicles (layouts: docs/weighings.md) and
four bad records, interleaved (lines 3, 5, 7, 9; in site.csv lines 4, 6, 8, 10, under the header):

    A  5 axles  6500 | 9000 | 7400 8000 8600 kg, spacings 3.6 5.2 1.31 1.31 m, 82 km/h, gross 39 500 kg, 16.5 m
    B  3 axles  6000 | 9500 8500 kg, spacings 4.2 1.35 m, 75 km/h, gross 24 000 kg, 9.0 m
    C  6 axles  7000 | 9000 9000 | 9000 7000 8000 kg, spacings 3.8 1.35 6.0 1.31 1.31 m, 88 km/h, 49 000 kg
    D  5 axles  5000 | 6000 | 2000 2100 1900 kg (unladen), as A's spacings, 90 km/h, 17 000 kg
    E  2 axles  1200 | 1100 kg, spacing 2.6 m, 100 km/h, 2 300 kg, 4.5 m

Formats with spacings in dm read 1.31 m as 13 dm (1.3 m) and 1.35 m as 14 dm (1.4 m); with speeds in dm/s read
82 km/h as 228 dm/s (82.08 km/h).
"""

import math
from pathlib import Path

import numpy as np
import pytest

from bogie.weighings.formats import LAYOUTS
from bogie.weighings.readers import read_weighings

DATA = Path(__file__).parent / "data" / "weighings"
LOADS = {
    "A": [6500, 9000, 7400, 8000, 8600],
    "B": [6000, 9500, 8500],
    "C": [7000, 9000, 9000, 9000, 7000, 8000],
    "D": [5000, 6000, 2000, 2100, 1900],
    "E": [1200, 1100],
}
SPACINGS_MM = {"A": [3.6, 5.2, 1.31, 1.31], "B": [4.2, 1.35], "C": [3.8, 1.35, 6.0, 1.31, 1.31], "E": [2.6]}
SPACINGS_DM = {"A": [3.6, 5.2, 1.3, 1.3], "B": [4.2, 1.4], "C": [3.8, 1.4, 6.0, 1.3, 1.3], "E": [2.6]}
#: the four bad records of each file: line -> reason (what the hand-written line breaks)
BAD = {
    # A cut short by 3 characters; B with an X in its first spacing; E with 00 axles; B's middle axle at 30 000 kg
    "mon": {3: "wrong length", 5: "non-numeric field", 7: "no axles", 9: "implausible axle load"},
    # A cut short; B's second spacing 3 dm (0.3 m); C dated 30 February; B with an X in its third axle weight
    "castor": {3: "wrong length", 5: "implausible axle spacing", 7: "invalid date or time", 9: "non-numeric field"},
    # E with 00 axles; B's middle axle 30 000 kg; C's gross weight 54 000 kg against 49 000 summed; A cut short
    "bedit": {3: "no axles", 5: "implausible axle load", 7: "gross weight is not the sum", 9: "wrong length"},
    # B with an X; B's second spacing 300 mm; A 9.0 m long over an 11.42 m wheelbase; A cut short
    "ditis": {3: "non-numeric field", 5: "implausible axle spacing", 7: "length shorter than the wheelbase",
              9: "wrong length"},
    # 14 fields under a 16-column header; '95OO' with letters O; 0 axles; a 30 000 kg axle
    "csv": {4: "wrong length", 6: "non-numeric field", 8: "no axles", 10: "implausible axle load"},
}  # fmt: skip


@pytest.mark.parametrize("fmt", ["csv", "mon", "castor", "bedit", "ditis"])
def test_every_format_reads_the_five_vehicles_and_counts_the_four_bad_records(fmt):
    result = read_weighings(DATA / f"site.{fmt}", fmt)
    v = result.vehicles
    assert (result.n_read, result.n_skipped) == (5, 4)
    assert v["n_axles"].tolist() == [5, 3, 6, 5, 2]
    for row, name in zip(v.itertuples(), "ABCDE"):
        loads = [getattr(row, f"axle_load_{i}") for i in range(row.n_axles)]
        assert loads == pytest.approx(LOADS[name], abs=1e-9), name
    spacings = SPACINGS_DM if fmt in ("castor", "bedit") else SPACINGS_MM
    for j, name in zip((0, 1, 2, 4), "ABCE"):
        got = [v.loc[j, f"spacing_{i}"] for i in range(len(spacings[name]))]
        assert got == pytest.approx(spacings[name], abs=1e-9), name
    assert math.isnan(v.loc[4, "spacing_1"])  # past E's one spacing
    # speeds 82, 75, 88, 90, 100 km/h; dm/s formats round to 228, 208, 244, 250, 278 dm/s
    expected = [82, 75, 88, 90, 100] if fmt in ("csv", "castor", "ditis") else [82.08, 74.88, 87.84, 90.0, 100.08]
    assert (3.6 * v["speed"]).tolist() == pytest.approx(expected, abs=1e-9)
    assert v["lane"].tolist() == [1, 1, 2, 1, 2]
    assert v["timestamp"].dt.strftime("%Y-%m-%d %H:%M:%S").tolist() == [
        "2026-03-14 07:05:09", "2026-03-14 07:06:30", "2026-03-14 07:08:01", "2026-03-14 07:09:59",
        "2026-03-14 07:11:00",
    ]  # fmt: skip
    lines = {line: reason for reason, found in result.bad_lines.items() for line in found}
    assert sorted(lines) == sorted(BAD[fmt])
    for line, reason in BAD[fmt].items():
        assert lines[line].startswith(reason), (line, lines[line])
    assert v["line"].tolist() == ([2, 3, 5, 7, 9] if fmt == "csv" else [1, 2, 4, 6, 8])
    assert "4 skipped" in result.summary()


def test_fractions_of_a_second_heads_groups_and_the_fields_only_fixed_width_formats_have():
    mon = read_weighings(DATA / "site.mon", "mon").vehicles
    # MON gives milliseconds: A at 07:05:09.120; its head is 'WIMA', its own count of axle groups 3
    assert mon.loc[0, "timestamp"].microsecond == 120_000
    assert mon["head"].tolist() == ["WIMA", "WIMB", "WIMC", "WIMD", "WIME"]
    assert mon["n_groups"].tolist() == [3, 2, 3, 3, 2]
    assert mon["gross_weight"].tolist() == [39500, 24000, 49000, 17000, 2300]
    assert mon["length"].tolist() == pytest.approx([16.5, 9.0, 16.5, 16.5, 4.5])
    assert mon["direction"].tolist() == ["N", "N", "S", "N", "S"]
    castor = read_weighings(DATA / "site.castor", "castor").vehicles
    # CASTOR: hundredths (D at 07:09:59.99), a two-digit year, gross weight in 100 kg
    assert castor.loc[3, "timestamp"].microsecond == 990_000 and castor.loc[3, "timestamp"].year == 2026
    assert castor["gross_weight"].tolist() == [39500, 24000, 49000, 17000, 2300]
    assert read_weighings(DATA / "site.ditis", "ditis").vehicles.loc[0, "timestamp"].microsecond == 0
    csv = read_weighings(DATA / "site.csv", "csv").vehicles
    assert np.isnan(csv["gross_weight"]).all() and np.isnan(csv["n_groups"]).all()


def test_each_layout_adds_up_to_the_record_length_of_its_example_lines():
    # the first record (A, 5 axles) of each file: fixed part + 5 weights + 4 spacings
    widths = {"mon": 47 + 5 * 5 + 4 * 5, "castor": 34 + 5 * 3 + 4 * 3, "bedit": 43 + 5 * 5 + 4 * 4,
              "ditis": 36 + 5 * 3 + 4 * 5}  # fmt: skip
    for fmt, width in widths.items():
        first = (DATA / f"site.{fmt}").read_text().splitlines()[0]
        assert LAYOUTS[fmt].record_length(5) == width == len(first), fmt


def test_a_mostly_bad_file_is_refused_with_the_reasons():
    # 3 of 4 records cut short or too long: more than half bad
    with pytest.raises(ValueError, match=r"not read as MON records \(format mon\): 3 of 4 records bad \(wrong length"):
        read_weighings(DATA / "mostly_bad.mon", "mon")


@pytest.mark.parametrize(("name", "fmt"), [("empty.ditis", "ditis"), ("blank.bedit", "bedit")])
def test_an_empty_file_is_refused(name, fmt):
    with pytest.raises(ValueError, match=rf"no records: expected \w+ records \(format {fmt}\), found an empty file"):
        read_weighings(DATA / name, fmt)


@pytest.mark.parametrize(
    ("name", "fmt", "found"),
    [("site.mon", "castor", "mon"), ("site.castor", "ditis", "castor"), ("site.csv", "mon", "csv"),
     ("site.mon", "csv", "mon"), ("site.ditis", "bedit", "ditis")],
)  # fmt: skip
def test_a_file_in_another_format_is_refused_naming_the_expected_and_the_found_format(name, fmt, found):
    with pytest.raises(ValueError, match=rf"\(format {fmt}\).*parse as {found} records \(--format {found}\?\)"):
        read_weighings(DATA / name, fmt)


def test_an_unknown_format_is_refused():
    with pytest.raises(ValueError, match="format 'xls' unknown; allowed: csv, mon, castor, bedit, ditis"):
        read_weighings(DATA / "site.csv", "xls")


def test_a_single_bad_record_among_good_ones_is_skipped_and_named(tmp_path):
    good = (DATA / "site.mon").read_text().splitlines()
    # A with its front axle at 50 kg: below the 100 kg of any real axle
    light = good[0][:47] + "00050" + good[0][52:]
    (tmp_path / "x.mon").write_text("\n".join([good[0], light, good[1]]) + "\n")
    result = read_weighings(tmp_path / "x.mon", "mon")
    assert (result.n_read, result.n_skipped) == (2, 1)
    assert result.bad_lines == {"implausible axle load (allowed 100-22680 kg)": [2]}


CSV_HEADER = "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,spacing_1\n"
CSV_GOOD = "2026-01-01T00:00:00,80,1,2,5000,6000,1.3\n"


def test_csv_with_a_spreadsheets_byte_order_mark_and_a_weighbridge_record_without_speed_or_lane(tmp_path):
    path = tmp_path / "bridge.csv"
    path.write_text("\ufeff" + CSV_HEADER + CSV_GOOD + "2026-01-01T00:05:00,,,2,5000,6000,1.3\n", encoding="utf-8")
    v = read_weighings(path, "csv").vehicles
    assert v["speed"].tolist()[0] == pytest.approx(80 / 3.6) and math.isnan(v["speed"].tolist()[1])
    assert v["lane"].tolist() == [1, -1]


@pytest.mark.parametrize(
    ("row", "reason"),
    [(",80,1,2,5000,6000,1.3", "invalid date or time"), ("2026-01-01,80,1,2.5,5000,6000,1.3", "non-numeric field"),
     ("2026-01-01,-5,1,2,5000,6000,1.3", "implausible speed"), ("2026-01-01,80,1,2,nan,6000,1.3", "non-numeric"),
     ("2026-01-01,80,1,3,5000,6000,1.3", "more axles than the file has columns for"),
     ("2026-01-01,80,1,2,5000,6000,0.4", "implausible axle spacing")],
)  # fmt: skip
def test_each_bad_csv_row_is_skipped_under_its_reason(tmp_path, row, reason):
    path = tmp_path / "one.csv"
    path.write_text(CSV_HEADER + row + "\n" + CSV_GOOD + CSV_GOOD)
    result = read_weighings(path, "csv")
    assert (result.n_read, result.n_skipped) == (2, 1)
    ((found, lines),) = result.bad_lines.items()
    assert found.startswith(reason) and lines == [2]


def test_a_csv_file_with_only_its_header_is_refused(tmp_path):
    (tmp_path / "h.csv").write_text(CSV_HEADER)
    with pytest.raises(ValueError, match=r"no records: expected CSV layout \(format csv\), found a header and no"):
        read_weighings(tmp_path / "h.csv", "csv")
