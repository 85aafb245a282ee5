"""bogie.weighings.readers: every format read from small hand-written files, bad records skipped and counted.

Every site.<format> file in tests/data/weighings/ holds the same five vehicles and four bad records, interleaved
(lines 3, 5, 7, 9; in site.csv lines 4, 6, 8, 10, under the header). The fixed-width files are written character by
character from the layouts of the shared reference wim-record-formats.md (docs/weighings.md): every field at its
offset, right-aligned, with space- and zero-padded fields, padding past the stated axles (MON A with zero fields
to 9 axle slots, MON D with space-padded zero fields, CASTOR C to 9 slots), a trailing spacing slot in some lines
and none in others (the line ending at the last weight, DITIS at the last axle width).

    A  5 axles  6500 | 9000 | 7400 8000 8600 kg, spacings 3.6 5.2 1.31 1.31 m, 82 km/h, gross 39 500 kg, 16.5 m
    B  3 axles  6000 | 9500 8500 kg, spacings 4.2 1.35 m, 75 km/h, gross 24 000 kg, 9.0 m
    C  6 axles  7000 | 9000 9000 | 9000 7000 8000 kg, spacings 3.8 1.35 6.0 1.31 1.31 m, 88 km/h, 49 000 kg
    D  5 axles  5000 | 6000 | 2000 2100 1900 kg (unladen), as A's spacings, 90 km/h, 17 000 kg
    E  2 axles  1200 | 1100 kg, spacing 2.6 m, 100 km/h, 2 300 kg, 4.5 m

Lanes 1, 1, 2, 1, 2; directions (normalised to 1 or 2) 1, 1, 2, 1, 2, written 0/1 in MON and BeDIT, 1/2 in
CASTOR and DITIS; transverse positions 1.8, 1.6, 1.9, 1.7, 1.5 m (MON mm, DITIS cm, CASTOR and BeDIT dm).
CASTOR, BeDIT and DITIS write spacings in dm: 1.31 m as 13 dm (1.3 m), 1.35 m as 14 dm (1.4 m); MON in mm. Their
speeds are in dm/s: 82 km/h as 228 dm/s (82.08 km/h); MON's in km/h. Weights: MON in kg, the others in kg/100
(every load here is a multiple of 100 kg).
"""

import math
from pathlib import Path

import numpy as np
import pandas as pd
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
TOO_SHORT = "record too short for its stated axles"
#: the four bad records of each file: line -> reason (what the hand-written line breaks)
BAD = {
    # A (5 axles) stopping after axle 4's spacing, 90 of 95 characters; B with an X in its first spacing
    # (offset 56); E with direction 2 (MON's are 0 or 1); B's middle axle at 30 000 kg
    "mon": {3: TOO_SHORT, 5: "non-numeric field", 7: "direction not 0 or 1", 9: "implausible axle load"},
    # A stopping after axle 4's weight, 52 of 57 characters; B's second spacing 03 dm (0.3 m); C dated 30 February
    # (300226); B with an X in its second axle weight (offset 39)
    "castor": {3: TOO_SHORT, 5: "implausible axle spacing", 7: "invalid date or time", 9: "non-numeric field"},
    # E with 00 axles; B with direction 2 (BeDIT's are 0 or 1); C's gross weight 0540 (54 000 kg) against 49 000
    # summed; A's last weight cut to 2 characters, 61 of 62
    "bedit": {3: "no axles", 5: "direction not 0 or 1", 7: "gross weight is not the sum", 9: TOO_SHORT},
    # B with an X in its second spacing (offset 52); B's second spacing 003 dm; A 090 dm (9.0 m) long over an
    # 11.4 m wheelbase; A without its last axle width, 76 of 79 characters
    "ditis": {3: "non-numeric field", 5: "implausible axle spacing", 7: "length shorter than the wheelbase",
              9: TOO_SHORT},
    # 14 fields under a 16-column header; '95OO' with letters O; 0 axles; a 30 000 kg axle
    "csv": {4: "wrong length", 6: "non-numeric field", 8: "no axles", 10: "implausible axle load"},
}  # fmt: skip


def at_minute(line: str, minute: int) -> str:
    """A MON record at another minute (offset 19, I2): another vehicle, not a repeat."""
    return line[:19] + f"{minute:02d}" + line[21:]


@pytest.mark.parametrize("fmt", ["csv", "mon", "castor", "bedit", "ditis"])
def test_every_format_reads_the_five_vehicles_and_counts_the_four_bad_records(fmt):
    result = read_weighings(DATA / f"site.{fmt}", fmt)
    v = result.vehicles
    assert (result.n_read, result.n_skipped) == (5, 4)
    assert v["n_axles"].tolist() == [5, 3, 6, 5, 2]
    for row, name in zip(v.itertuples(), "ABCDE"):
        loads = [getattr(row, f"axle_load_{i + 1}") for i in range(row.n_axles)]
        assert loads == pytest.approx(LOADS[name], abs=1e-9), name
    spacings = SPACINGS_DM if fmt in ("castor", "bedit", "ditis") else SPACINGS_MM
    for j, name in zip((0, 1, 2, 4), "ABCE"):
        got = [v.loc[j, f"spacing_{i + 1}"] for i in range(len(spacings[name]))]
        assert got == pytest.approx(spacings[name], abs=1e-9), name
    assert math.isnan(v.loc[4, "spacing_2"])  # past E's one spacing
    # speeds 82, 75, 88, 90, 100 km/h; dm/s formats round to 228, 208, 244, 250, 278 dm/s
    expected = [82, 75, 88, 90, 100] if fmt in ("csv", "mon") else [82.08, 74.88, 87.84, 90.0, 100.08]
    assert (3.6 * v["speed"]).tolist() == pytest.approx(expected, abs=1e-9)
    assert v["lane"].tolist() == [1, 1, 2, 1, 2]
    assert v["timestamp"].dt.strftime("%Y-%m-%d %H:%M:%S.%f").tolist() == [
        "2026-03-14 07:05:09.120000", "2026-03-14 07:06:30.450000", "2026-03-14 07:08:01.000000",
        "2026-03-14 07:09:59.990000", "2026-03-14 07:11:00.500000",
    ]  # fmt: skip
    lines = {line: reason for reason, found in result.bad_lines.items() for line in found}
    assert sorted(lines) == sorted(BAD[fmt])
    for line, reason in BAD[fmt].items():
        assert lines[line].startswith(reason), (line, lines[line])
    assert v["line"].tolist() == ([2, 3, 5, 7, 9] if fmt == "csv" else [1, 2, 4, 6, 8])
    assert "4 skipped" in result.summary()
    if fmt == "csv":
        assert np.isnan(v["gross_weight"]).all() and np.isnan(v["n_groups"]).all()
        assert v["direction"].tolist() == [-1] * 5 and np.isnan(v["transverse_position"]).all()
    else:
        assert v["gross_weight"].tolist() == pytest.approx([39500, 24000, 49000, 17000, 2300], abs=1e-9)
        assert v["length"].tolist() == pytest.approx([16.5, 9.0, 16.5, 16.5, 4.5], abs=1e-9)
        assert v["direction"].tolist() == [1, 1, 2, 1, 2]
        assert v["transverse_position"].tolist() == pytest.approx([1.8, 1.6, 1.9, 1.7, 1.5], abs=1e-9)


def test_heads_groups_axle_widths_and_the_fields_only_some_formats_have():
    heads = {"mon": [100001, 100002, 100004, 100006, 100008], "castor": [1, 2, 4, 6, 8],
             "bedit": [11, 12, 14, 16, 18], "ditis": [21, 22, 24, 26, 28]}  # fmt: skip
    for fmt, expected in heads.items():
        v = read_weighings(DATA / f"site.{fmt}", fmt).vehicles
        assert v["head"].tolist() == expected, fmt
        assert (fmt == "ditis") == ("axle_width_1" in v), fmt
        assert (fmt == "mon") == v["n_groups"].notna().all(), fmt
    # MON's own count of axle groups (offset 28, I2)
    assert read_weighings(DATA / "site.mon", "mon").vehicles["n_groups"].tolist() == [3, 2, 3, 3, 2]
    # DITIS: an axle width (track) per axle, in cm: 205 for the steer axle, 180 or 185 for the others
    ditis = read_weighings(DATA / "site.ditis", "ditis").vehicles
    assert [ditis.loc[0, f"axle_width_{i + 1}"] for i in range(5)] == pytest.approx([2.05, 1.8, 1.85, 1.85, 1.85])
    assert [ditis.loc[4, f"axle_width_{i + 1}"] for i in range(2)] == pytest.approx([2.05, 1.8])
    assert math.isnan(ditis.loc[4, "axle_width_3"])


def test_each_layout_has_the_references_header_and_axle_stride_and_its_lines_their_lengths():
    # reference: header 50 / 34 / 35 / 37 characters, 10 / 5 / 6 / 9 per axle; the shortest 5-axle record ends at
    # the last axle's weight (DITIS: its width)
    expected = {"mon": (50, 10, 95), "castor": (34, 5, 57), "bedit": (35, 6, 62), "ditis": (37, 9, 79)}
    for fmt, (header, stride, five) in expected.items():
        layout = LAYOUTS[fmt]
        assert (layout.fixed_width, layout.axles.stride, layout.min_record_length(5)) == (header, stride, five), fmt
    # line lengths of the files (vehicle A, line 1): MON padded to 9 axle slots, CASTOR and DITIS end at the last
    # axle, BeDIT has the trailing spacing slot; MON's line 3 (A cut) is 5 short
    lengths = {"mon": (140, 90), "castor": (57, 52), "bedit": (65, 47), "ditis": (79, 64)}
    for fmt, (first, third) in lengths.items():
        lines = (DATA / f"site.{fmt}").read_text().splitlines()
        assert (len(lines[0]), len(lines[2])) == (first, third), fmt
    # each format's own axle limit: CASTOR's I1 count, BeDIT's and DITIS's stated 20, MON's 2 digits
    assert [LAYOUTS[f].max_axles for f in ("castor", "bedit", "ditis", "mon")] == [9, 20, 20, 99]


def test_a_line_longer_than_its_axles_need_is_read_and_one_character_short_of_the_last_weight_is_bad(tmp_path):
    b = (DATA / "site.mon").read_text().splitlines()[1]  # B: 3 axles, 80 characters with the trailing spacing
    # ends right after axle 3's weight (75), padded with zero fields to 20 slots (250), one short (74); each at its
    # own minute (offset 19, I2), since the same record twice is a repeat
    b = [at_minute(b, minute) for minute in (10, 11, 12, 13)]
    (tmp_path / "x.mon").write_text("\n".join([b[0][:75], b[1][:75] + "0" * 175, b[2][:74], b[3]]) + "\n")
    result = read_weighings(tmp_path / "x.mon", "mon")
    assert result.vehicles["line"].tolist() == [1, 2, 4]
    assert result.bad_lines == {TOO_SHORT: [3]}
    assert result.vehicles["axle_load_3"].tolist() == [8500, 8500, 8500]


@pytest.mark.parametrize("text", ["085 0", "0850 ", "-8500", "     ", "\uff18\uff15\uff10\uff10\uff10"])
def test_a_field_with_an_inner_or_trailing_space_a_sign_blanks_or_non_ascii_digits_is_non_numeric(tmp_path, text):
    b = [at_minute((DATA / "site.mon").read_text().splitlines()[1], minute) for minute in (10, 11, 12)]
    (tmp_path / "x.mon").write_text("\n".join([b[0], b[1], b[2][:70] + text + b[2][75:]]) + "\n")
    assert read_weighings(tmp_path / "x.mon", "mon").bad_lines == {"non-numeric field": [3]}


def test_the_two_digit_year_hundredths_and_the_milliseconds_of_the_minute():
    # CASTOR and BeDIT: year 26 -> 2026 (century ASSUMED), D at 07:09:59.99; MON: ' 9120' ms of the minute (space-
    # padded) -> 09.120 s; DITIS: a 4-digit year and hundredths
    for fmt in ("castor", "bedit", "ditis", "mon"):
        stamps = read_weighings(DATA / f"site.{fmt}", fmt).vehicles["timestamp"]
        assert (stamps[0].year, stamps[0].second, stamps[0].microsecond) == (2026, 9, 120_000), fmt
        assert (stamps[3].second, stamps[3].microsecond) == (59, 990_000), fmt


def test_a_mostly_bad_file_is_refused_with_the_reasons():
    # 3 of 4 records bad: cut inside the header (40 characters), cut inside axle 2 (70 of 75), direction 3
    with pytest.raises(ValueError, match=r"not read as MON records \(format mon\): 3 of 4 records bad \(") as exc:
        read_weighings(DATA / "mostly_bad.mon", "mon")
    for reason in ("record shorter than the header: 1, line 2", f"{TOO_SHORT}: 1, line 3",
                   "direction not 0 or 1: 1, line 4"):  # fmt: skip
        assert reason in str(exc.value)


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
    with pytest.raises(ValueError, match="format 'xls' unknown; allowed: auto, csv, mon, castor, bedit, ditis"):
        read_weighings(DATA / "site.csv", "xls")


def test_a_single_bad_record_among_good_ones_is_skipped_and_named(tmp_path):
    good = (DATA / "site.mon").read_text().splitlines()
    # A with its front axle (offset 50, I5 kg) at 50 kg: below the 100 kg of any real axle
    light = good[0][:50] + "00050" + good[0][55:]
    (tmp_path / "x.mon").write_text("\n".join([good[0], light, good[1]]) + "\n")
    result = read_weighings(tmp_path / "x.mon", "mon")
    assert (result.n_read, result.n_skipped) == (2, 1)
    assert result.bad_lines == {"implausible axle load (allowed 100-22680 kg)": [2]}


CSV_HEADER = "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,spacing_1\n"
CSV_GOOD = "2026-01-01T00:00:00,80,1,2,5000,6000,1.3\n"
#: another vehicle a minute later (the same record twice is a repeat, a bad record)
CSV_LATER = "2026-01-01T00:01:00,80,1,2,5000,6000,1.3\n"


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
    path.write_text(CSV_HEADER + row + "\n" + CSV_GOOD + CSV_LATER)
    result = read_weighings(path, "csv")
    assert (result.n_read, result.n_skipped) == (2, 1)
    ((found, lines),) = result.bad_lines.items()
    assert found.startswith(reason) and lines == [2]


def test_a_csv_file_with_only_its_header_is_refused(tmp_path):
    (tmp_path / "h.csv").write_text(CSV_HEADER)
    with pytest.raises(ValueError, match=r"no records: expected CSV layout \(format csv\), found a header and no"):
        read_weighings(tmp_path / "h.csv", "csv")


@pytest.mark.parametrize("fmt", ["csv", "mon", "castor", "bedit", "ditis"])
def test_format_auto_finds_each_files_layout_and_says_which(fmt):
    result = read_weighings(DATA / f"site.{fmt}")  # auto is the default
    assert result.format == fmt and (result.n_read, result.n_skipped) == (5, 4)


def test_format_auto_refuses_when_no_layout_or_two_fit_naming_the_candidates(tmp_path):
    (tmp_path / "junk.txt").write_text("hello world\nnot a record\n")
    with pytest.raises(ValueError, match=r"format auto: no known format fits .*mon: 0 of 2 good.*--format"):
        read_weighings(tmp_path / "junk.txt", "auto")
    # two MON and two CASTOR records: neither layout fits more than half the lines
    mon = (DATA / "site.mon").read_text().splitlines()[:2]
    castor = (DATA / "site.castor").read_text().splitlines()[:2]
    (tmp_path / "mixed.txt").write_text("\n".join(mon + castor) + "\n")
    with pytest.raises(ValueError, match=r"no known format fits .*mon: 2 of 4 good.*castor: 2 of 4 good"):
        read_weighings(tmp_path / "mixed.txt")
    with pytest.raises(ValueError, match=r"no records: format auto found an empty file"):
        read_weighings(DATA / "empty.ditis")


# ---- every good record read: comparisons in the file's units (issue 41 Must 1) ------------------------------------
def _float_breaking_pair(unit: float) -> tuple[int, int]:
    """Two plausible spacings (1.2 to 9.9 m) in a format's units whose sum in metres, summed as floats, exceeds their
    sum's length in metres."""
    lo, hi = round(1.2 / unit), round(9.9 / unit)
    for a in range(lo, hi):
        for b in range(lo, min(hi, lo + 50)):
            if np.nansum([a * unit, b * unit]) > (a + b) * unit:
                return a, b
    raise AssertionError("no pair found")


@pytest.mark.parametrize("fmt", ["mon", "castor", "bedit", "ditis"])
def test_a_length_equal_to_the_wheelbase_is_read_and_one_unit_shorter_is_not(tmp_path, fmt):
    # 146 of a real MON file's 5,000 records were lost: their stated length equals the sum of the spacings to the
    # unit, and the check summed the spacings in metres in floating point (2.95 + 1.35 = 4.300000000000001 > 4.3)
    from bogie.weighings.formats import LAYOUTS
    from bogie.weighings.writers import write_weighings

    unit = LAYOUTS[fmt].axle_field("spacing").scale
    a, b = _float_breaking_pair(unit)
    base = read_weighings(DATA / "site.mon", "mon").vehicles
    row = base[base["n_axles"] == 3].iloc[:1].copy()
    row["head"] = 1
    row["spacing_1"], row["spacing_2"] = a * unit, b * unit
    equal, shorter = row.copy(), row.copy()
    equal["length"] = (a + b) * unit
    shorter["length"] = (a + b - 1) * unit
    frame = pd.concat([equal, shorter, equal], ignore_index=True)
    frame["timestamp"] = frame["timestamp"].iloc[0] + pd.to_timedelta([0, 1, 2], unit="s")
    path = tmp_path / f"x.{fmt}"
    write_weighings(frame, path, fmt)
    result = read_weighings(path, fmt)
    assert result.vehicles["line"].tolist() == [1, 3], result.reasons()
    assert result.skipped == {"length shorter than the wheelbase": 1}
    assert np.nansum([a * unit, b * unit]) > result.vehicles["length"].iloc[0]  # the float sum would have lost it


def test_values_at_a_ranges_ends_are_in():
    from bogie.weighings._checks import _outside

    lo, hi = 0.6, 18.75
    assert not _outside(np.array([60 * 0.01, 1875 * 0.01, 6 * 0.1]), lo, hi).any()
    assert _outside(np.array([59 * 0.01, 1876 * 0.01]), lo, hi).all()
