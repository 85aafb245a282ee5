"""bogie.weighings.writers: write_weighings in every format, read back with read_weighings.

The round trips write a hand-built table of six vehicles (2, 3, 5, 6, 2 and 5 axles; both directions; lanes 1 and
2) whose times cross a year end (23:59:59.996 on 31 December), a month end (31 January 23:59:59.9996, 30 June
23:59:59.994) and Feb 29 of leap years (2024: a tie, 23:59:59.995; 2028), and whose loads, spacings, speeds and
positions fall between the formats' steps (half steps included), then compare every column read back with the
input rounded to the format's resolution: the expected values are rounded here with ``decimal`` (half away from
zero) and the expected times are written out by hand, not computed by the writer's code.

The exact-line tests compare one vehicle's line in each format with a line assembled by hand, field by field,
from the tables of the shared reference wim-record-formats.md.
"""

import gzip
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bogie.weighings.readers import read_weighings
from bogie.weighings.writers import write_weighings

NAN = float("nan")
T = pd.Timestamp

#: the six vehicles: loads [kg], spacings [m], the rest per vehicle
LOADS = [
    [1240, 1160],  # kg/100: 12.4 -> 12, 11.6 -> 12
    [6000, 9550, 8450],  # kg/100: 95.5 -> 96, 84.5 -> 85 (half away from zero)
    [6500, 9000, 7400, 8000, 8600],
    [7000, 9000, 9000, 9000, 7000, 8000],
    [1200, 1100],
    [6530, 9070, 7440, 8010, 8650],  # kg/100: 65, 91, 74, 80, 87
]
SPACINGS = [
    [2.63],  # dm 26.3 -> 26; mm 2630
    [4.2, 1.35],  # dm 13.5 -> 14
    [3.6, 5.2, 1.31, 1.31],
    [3.8, 1.35, 6.0, 1.31, 1.31],
    [2.65],  # dm 26.5 -> 27 (2.65 / 0.1 is 26.499999999999996 in binary: the writer's cleaning rounds it up)
    [3.6, 5.2, 1.3125, 1.3125],  # mm 1312.5 -> 1313
]
TIMES = [
    T("2025-12-31 23:59:59.996"),  # year end: 1/100 s -> 2026-01-01 00:00:00.00; ms -> unchanged
    T("2026-01-31 23:59:59.9996"),  # month end: both resolutions carry to 1 February
    T("2028-02-29 12:30:45.125"),  # leap day; 1/100 s: a tie, to the later time, .13
    T("2024-02-29 23:59:59.995"),  # leap day; 1/100 s: a tie, carried to 1 March
    T("2026-06-30 23:59:59.994"),  # month end, 1/100 s rounds down: .99
    T("2026-03-14 07:05:09.12"),
]
#: the times as read back, by resolution (written out by hand)
TIMES_100 = [
    T("2026-01-01 00:00:00.00"),
    T("2026-02-01 00:00:00.00"),
    T("2028-02-29 12:30:45.13"),
    T("2024-03-01 00:00:00.00"),
    T("2026-06-30 23:59:59.99"),
    T("2026-03-14 07:05:09.12"),
]
TIMES_MS = [
    T("2025-12-31 23:59:59.996"),
    T("2026-02-01 00:00:00.000"),
    T("2028-02-29 12:30:45.125"),
    T("2024-02-29 23:59:59.995"),
    T("2026-06-30 23:59:59.994"),
    T("2026-03-14 07:05:09.120"),
]
SPEEDS = [27.78, 20.85, 22.8, 24.45, 27.8, 22.8]  # m/s; dm/s 277.8 -> 278, 208.5 -> 209, 244.5 -> 245
GROSS = [NAN, 24000.0, 39500.0, 49000.0, 2300.0, NAN]  # NaN: the sum of the loads as written
LENGTHS = [4.52, 9.0, 16.5, 16.55, NAN, 16.5]  # NaN: written 0
TRANSVERSE = [1.55, 1.6, 1.8, 1.9, 1.5, NAN]  # NaN: written 0
LANES = [2, 1, 1, 2, 2, 1]
DIRECTIONS = [2, 1, 2, 1, 2, 1]
HEADS = [7, 12, 1, 4, 8, 3]
N_GROUPS = [NAN, NAN, 3.0, NAN, 1.0, NAN]  # MON: NaN counted from the spacings; given ones kept
#: DITIS axle widths [m]; NaN written 0 ("not given", our assumption)
WIDTHS = [[2.05, 1.8], [NAN, NAN, NAN], [2.0, 2.1, 2.1, 2.1, 2.1], [], [1.985, 1.8], [NAN] * 5]

#: the fixed-width formats' resolutions: load, spacing, speed, length, transverse, width [SI], time
STEPS = {
    "castor": dict(load="100", spacing="0.1", length="0.1", transverse="0.1", times=TIMES_100),
    "bedit": dict(load="100", spacing="0.1", length="0.1", transverse="0.1", times=TIMES_100),
    "ditis": dict(load="100", spacing="0.1", length="0.1", transverse="0.01", width="0.01", times=TIMES_100),
    "mon": dict(load="1", spacing="0.001", length="0.001", transverse="0.001", times=TIMES_MS),
}


def _table() -> pd.DataFrame:
    width = max(len(x) for x in LOADS)
    data = {
        "line": range(1, len(LOADS) + 1),
        "head": HEADS,
        "timestamp": TIMES,
        "speed": SPEEDS,
        "gross_weight": GROSS,
        "length": LENGTHS,
        "n_axles": [len(x) for x in LOADS],
        "n_groups": N_GROUPS,
        "lane": LANES,
        "direction": DIRECTIONS,
        "transverse_position": TRANSVERSE,
    }
    for i in range(width):
        data[f"axle_load_{i + 1}"] = [float(x[i]) if i < len(x) else NAN for x in LOADS]
    for i in range(width - 1):
        data[f"spacing_{i + 1}"] = [x[i] if i < len(x) else NAN for x in SPACINGS]
    for i in range(width):
        data[f"axle_width_{i + 1}"] = [x[i] if i < len(x) else NAN for x in WIDTHS]
    return pd.DataFrame(data)


def _round(x: float, step: str) -> float:
    """x rounded to a multiple of step, a half away from zero, in decimal (x as written in the table)."""
    units = (Decimal(repr(x)) / Decimal(step)).quantize(Decimal(1), rounding=ROUND_HALF_UP)
    return float(units * Decimal(step))


def _expected(fmt: str) -> dict[str, list]:
    s = STEPS[fmt]
    loads = [[_round(w, s["load"]) for w in x] for x in LOADS]
    spacings = [[_round(d, s["spacing"]) for d in x] for x in SPACINGS]
    if fmt == "mon":  # km/h
        speeds = [_round(v * 3.6, "1") / 3.6 for v in SPEEDS]
    else:  # dm/s
        speeds = [_round(v, "0.1") for v in SPEEDS]
    gross = [sum(w) if np.isnan(g) else _round(g, s["load"]) for g, w in zip(GROSS, loads)]
    out = {
        "timestamp": s["times"],
        "speed": speeds,
        "gross_weight": gross,
        "length": [0.0 if np.isnan(v) else _round(v, s["length"]) for v in LENGTHS],
        "transverse_position": [0.0 if np.isnan(v) else _round(v, s["transverse"]) for v in TRANSVERSE],
        "n_axles": [len(x) for x in LOADS],
        "lane": LANES,
        "direction": DIRECTIONS,
        "head": HEADS,
        "loads": loads,
        "spacings": spacings,
    }
    if fmt == "mon":  # counted: 1 + the spacings (as written) over 2.0 m
        out["n_groups"] = [2.0, 2.0, 3.0, 3.0, 1.0, 3.0]
    if fmt == "ditis":
        out["widths"] = [[0.0 if np.isnan(b) else _round(b, s["width"]) for b in x] for x in WIDTHS]
        out["widths"][3] = [0.0] * 6  # vehicle 3 has no widths (NaN): written 0
    return out


@pytest.mark.parametrize("fmt", ["castor", "bedit", "ditis", "mon"])
def test_round_trip_fixed_width(tmp_path, fmt):
    path = tmp_path / f"site.{fmt}"
    assert write_weighings(_table(), path, fmt) == 6
    result = read_weighings(path, fmt)
    assert result.n_skipped == 0, result.summary()
    got, want = result.vehicles, _expected(fmt)
    assert list(got["timestamp"]) == want["timestamp"]
    for name in ("speed", "gross_weight", "length", "transverse_position"):
        np.testing.assert_allclose(got[name].to_numpy(float), want[name], rtol=0, atol=1e-9, err_msg=name)
    for name in ("n_axles", "lane", "direction", "head"):
        assert [int(v) for v in got[name]] == want[name], name
    if fmt == "mon":
        assert list(got["n_groups"]) == want["n_groups"]
    else:
        assert got["n_groups"].isna().all()
    for j, n in enumerate(want["n_axles"]):
        loads = got.loc[j, [f"axle_load_{i + 1}" for i in range(n)]].to_numpy(float)
        spacings = got.loc[j, [f"spacing_{i + 1}" for i in range(n - 1)]].to_numpy(float)
        np.testing.assert_allclose(loads, want["loads"][j], rtol=0, atol=1e-9, err_msg=f"loads of {j}")
        np.testing.assert_allclose(spacings, want["spacings"][j], rtol=0, atol=1e-9, err_msg=f"spacings of {j}")
        if fmt == "ditis":
            widths = got.loc[j, [f"axle_width_{i + 1}" for i in range(n)]].to_numpy(float)
            np.testing.assert_allclose(widths, want["widths"][j], rtol=0, atol=1e-9, err_msg=f"widths of {j}")


def test_round_trip_csv(tmp_path):
    table = _table()
    table.loc[4, "lane"] = -1  # written blank, read -1
    table.loc[0, "axle_load_1"] = 1234.5678901234567  # any float: the CSV keeps it exactly
    table.loc[0, "spacing_1"] = 0.1 + 0.2 + 2.4
    path = tmp_path / "site.csv"
    assert write_weighings(table, path, "csv") == 6
    got = read_weighings(path, "csv").vehicles
    assert list(got["timestamp"]) == TIMES
    np.testing.assert_allclose(got["speed"], table["speed"], rtol=1e-12, atol=0)
    assert list(got["lane"]) == [2, 1, 1, 2, -1, 1]
    assert list(got["n_axles"]) == [len(x) for x in LOADS]
    for j, n in enumerate(got["n_axles"]):
        for name, count in (("axle_load", n), ("spacing", n - 1)):
            cols = [f"{name}_{i + 1}" for i in range(count)]
            assert got.loc[j, cols].tolist() == table.loc[j, cols].tolist()  # bitwise


def test_csv_text(tmp_path):
    table = _table().iloc[[1]]
    path = tmp_path / "b.csv"
    write_weighings(table, path, "csv")
    # header: N = 3 axles; 20.85 m/s * 3.6 = 75.06 km/h (repr of the float product); 1-based columns
    assert path.read_text() == (
        "timestamp,speed_kmh,lane,n_axles,axle_load_1,axle_load_2,axle_load_3,spacing_1,spacing_2\n"
        f"2026-01-31T23:59:59.999600,{20.85 * 3.6!r},1,3,6000.0,9550.0,8450.0,4.2,1.35\n"
    )


#: vehicle B of the readers' test files: 14 March 2026 07:06:30.45, head 12
B = pd.DataFrame(
    {
        "head": [12],
        "timestamp": [T("2026-03-14 07:06:30.45")],
        "speed": [20.8],  # 208 dm/s; 74.88 km/h
        "gross_weight": [24000.0],
        "length": [9.0],
        "n_axles": [3],
        "lane": [1],
        "direction": [1],
        "transverse_position": [1.6],
        "axle_load_1": [6000.0],
        "axle_load_2": [9500.0],
        "axle_load_3": [8500.0],
        "spacing_1": [4.2],
        "spacing_2": [1.35],
        "axle_width_1": [2.05],
        "axle_width_2": [2.1],
        "axle_width_3": [1.8],
    }
)
#: B's line by hand, field by field from wim-record-formats.md (zero-padded; the slot after the last axle 0)
LINES = {
    # head I4 | day month year(2) I2 | hour minute second second/100 I2 | speed dm/s I3 | gross kg/100 I4 |
    # length dm I3 | n I1 | direction (1|2) I1 | lane I1 | transverse dm I3 | per axle: weight kg/100 I3,
    # spacing dm I2 (13.5 dm -> 14)
    "castor": "0012" + "14" "03" "26" + "07" "06" "30" "45" + "208" + "0240" + "090" + "3" + "1" + "1" + "016"
    + "060" "42" + "095" "14" + "085" "00",
    # as CASTOR but n I2, direction zero-based (0|1), spacing dm I3
    "bedit": "0012" + "14" "03" "26" + "07" "06" "30" "45" + "208" + "0240" + "090" + "03" + "0" + "1" + "016"
    + "060" "042" + "095" "014" + "085" "000",
    # year I4 at 8; transverse cm I3; per axle: weight kg/100 I3, width cm I3, spacing dm I3
    "ditis": "0012" + "14" "03" "2026" + "07" "06" "30" "45" + "208" + "0240" + "090" + "03" + "1" + "1" + "160"
    + "060" "205" "042" + "095" "210" "014" + "085" "180" "000",
    # head I9 | day month I2 year I4 | hour minute I2 | ms of the minute I5 | n I2 | groups I2 (4.2 m > 2 m: 2) |
    # gross kg I6 | speed km/h I3 (74.88 -> 75) | length mm I5 | lane I1 | direction (0|1) I1 | transverse mm I4 |
    # per axle: weight kg I5, spacing mm I5
    "mon": "000000012" + "14" "03" "2026" + "07" "06" + "30450" + "03" + "02" + "024000" + "075" + "09000" + "1"
    + "0" + "1600" + "06000" "04200" + "09500" "01350" + "08500" "00000",
}  # fmt: skip


@pytest.mark.parametrize("fmt", ["castor", "bedit", "ditis", "mon"])
def test_exact_line(tmp_path, fmt):
    path = tmp_path / f"b.{fmt}"
    assert write_weighings(B, path, fmt) == 1
    assert path.read_bytes() == (LINES[fmt] + "\n").encode("ascii")
    assert len(LINES[fmt]) == {"castor": 34 + 3 * 5, "bedit": 35 + 3 * 6, "ditis": 37 + 3 * 9, "mon": 50 + 3 * 10}[fmt]


@pytest.mark.parametrize("fmt", ["csv", "castor", "bedit", "ditis", "mon"])
def test_same_bytes_every_time(tmp_path, fmt):
    write_weighings(_table(), tmp_path / "a", fmt)
    write_weighings(_table(), tmp_path / "b", fmt)
    assert (tmp_path / "a").read_bytes() == (tmp_path / "b").read_bytes()


@pytest.mark.parametrize("fmt", ["csv", "castor", "mon"])
def test_gzip_reproducible(tmp_path, fmt):
    a, b, plain = tmp_path / f"a.{fmt}.gz", tmp_path / f"sub.{fmt}.gz", tmp_path / f"plain.{fmt}"
    write_weighings(_table(), a, fmt)
    write_weighings(_table(), b, fmt)  # another name: no file name in the gzip header
    write_weighings(_table(), plain, fmt)
    assert a.read_bytes()[:2] == b"\x1f\x8b"
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes()[4:8] == b"\0\0\0\0"  # mtime 0
    assert gzip.decompress(a.read_bytes()) == plain.read_bytes()


@pytest.mark.parametrize("fmt", ["csv", "castor", "mon"])
def test_gzip_round_trip(tmp_path, fmt):
    path = tmp_path / f"site.{fmt}.gz"
    write_weighings(_table(), path, fmt)
    got = read_weighings(path, fmt).vehicles
    assert list(got["n_axles"]) == [len(x) for x in LOADS]


def _one(**changes) -> pd.DataFrame:
    table = B.copy()
    for name, value in changes.items():
        table[name] = [value]
    return table


def _ten_axles() -> pd.DataFrame:
    table = B.copy()
    table["n_axles"] = 10
    for i in range(10):
        table[f"axle_load_{i + 1}"] = 5000.0
    for i in range(9):
        table[f"spacing_{i + 1}"] = 1.3
    return table


ERRORS = [
    # (format, table, the message's pieces: column, value, row, range, unit)
    ("castor", _one(axle_load_2=100_000.0), ["axle_load_2 = 100000 kg", "row 0", "0-99 900 kg in kg/100", "3 digits"]),
    ("castor", _ten_axles(), ["n_axles = 10", "row 0", "2-9 axles"]),
    ("mon", _one(direction=-1), ["direction = -1", "in 1 row (first: 0)", "1 or 2"]),
    ("bedit", _one(spacing_1=-4.2), ["spacing_1 = -4.2 m", "row 0", "negative", "0-99.9 m in dm", "3 digits"]),
    ("castor", _one(timestamp=T("2070-05-01 12:00")), ["timestamp = 2070-05-01T12:00:00", "row 0", "1969-2068"]),
    ("ditis", _one(axle_load_3=NAN), ["axle_load_3 = nan kg", "row 0", "NaN", "0-99 900 kg in kg/100", "3 digits"]),
    ("mon", _one(lane=-1), ["lane = -1", "(first: 0)", "1-9"]),
    ("csv", _one(axle_load_1=NAN), ["axle_load_1 = nan kg", "row 0", "NaN"]),
]


@pytest.mark.parametrize(("fmt", "table", "pieces"), ERRORS)
def test_errors_leave_no_file(tmp_path, fmt, table, pieces):
    path = tmp_path / f"out.{fmt}"
    with pytest.raises(ValueError) as info:
        write_weighings(table, path, fmt)
    message = str(info.value)
    assert message.startswith(f"{fmt}: ")
    for piece in pieces:
        assert piece in message, message
    assert list(tmp_path.iterdir()) == []  # neither the file nor a temporary one


def test_error_message_names_rows(tmp_path):
    table = pd.concat([B] * 6, ignore_index=True)
    table.loc[[2, 4, 5], "direction"] = -1
    with pytest.raises(ValueError, match=r"direction = -1 or NaN \(not given\) in 3 rows \(first: 2, 4, 5\)"):
        write_weighings(table, tmp_path / "x.castor", "castor")
    table = pd.concat([B] * 3, ignore_index=True)
    table.loc[1, "axle_load_2"] = 104_500.0
    with pytest.raises(ValueError) as info:
        write_weighings(table, tmp_path / "x.castor", "castor")
    assert (
        str(info.value)
        == "castor: axle_load_2 = 104500 kg in row 1 does not fit its field (0-99 900 kg in kg/100, 3 digits)"
    )


def test_error_keeps_an_existing_file(tmp_path):
    path = tmp_path / "site.castor"
    path.write_text("old\n")
    with pytest.raises(ValueError):
        write_weighings(_one(axle_load_1=NAN), path, "castor")
    assert path.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["site.castor"]


def test_unknown_format_and_heads(tmp_path):
    with pytest.raises(ValueError, match="allowed: csv, mon, castor, bedit, ditis"):
        write_weighings(B, tmp_path / "x", "btls")
    with pytest.raises(ValueError, match=r"head = 'A1' in row 0 is not an integer"):
        write_weighings(_one(head="A1"), tmp_path / "x", "mon")
    with pytest.raises(ValueError, match=r"head = 12345 in row 0 does not fit its field \(0-9 999, 4 digits\)"):
        write_weighings(_one(head=12345), tmp_path / "x", "castor")
    write_weighings(_one(head=""), tmp_path / "x.castor", "castor")  # the CSV reader's head: written 0
    assert Path(tmp_path / "x.castor").read_text().startswith("0000")


def test_year_pivot_bounds(tmp_path):
    # 1969 and 2068 are the two-digit year's ends; 23:59:59.996 on 31 December 2068 rounds into 2069: refused
    write_weighings(_one(timestamp=T("1969-01-01 00:00")), tmp_path / "a.bedit", "bedit")
    write_weighings(_one(timestamp=T("2068-12-31 23:59:59.99")), tmp_path / "b.bedit", "bedit")
    assert (tmp_path / "a.bedit").read_text()[4:10] == "010169"
    assert (tmp_path / "b.bedit").read_text()[4:18] == "31126823595999"
    with pytest.raises(ValueError, match="1969-2068"):
        write_weighings(_one(timestamp=T("2068-12-31 23:59:59.996")), tmp_path / "c.bedit", "bedit")
