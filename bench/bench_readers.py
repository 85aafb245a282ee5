"""The WIM record readers on a million vehicles: time and peak memory of ``read_weighings`` (issue 27).

Issue 27's target for the fixed-width readers: 1,000,000 records in at most 10 s and at most 1 GiB of peak memory
on one core, gzip files read directly. This bench generates, from a fixed seed and without a Python loop over the
records, a plausible MON file of N heavy vehicles (:func:`fleet`, :func:`mon_bytes`: the layout of the shared
reference ``wim-record-formats.md``, section MON), the same records in the project's CSV layout
(:func:`csv_bytes`) and the MON file gzipped (``.mon.gz``, gzip mtime 0), in a temporary directory removed at the
end. A small file of the same kind is first read in this process and every record must be good and equal to what
was written (:func:`check`).

Each file is then read by ``read_weighings(path, fmt)`` in its own fresh process (:data:`CHILD`), pinned to one
CPU (the first this process may use) with ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and ``NUMBA_NUM_THREADS``
set to 1: it imports the reader, notes its resident memory, times the one call with ``time.perf_counter`` and
reports the records read and skipped, the sum of the axle loads read (checked against the sum written) and its
peak resident memory (``ru_maxrss``), both as it is and less the memory after the import. A reader that cannot read
a file (today's, a gzip file) is reported as "not supported"; nothing here passes or fails. The peer is the CSV
reader on the same records in the same run: the table's ratio is the MON reading's time over the CSV reading's.
The load average is printed at the start and the end.

Run alone: ``python -m bench.bench_readers [--records N] [--repeat R] [--castor] [--reader-root DIR] [--previous DIR]``.
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
#: records in each file [-] (issue 27's million)
N_RECORDS = 1_000_000
#: the generator's seed
SEED = 27
#: issue 27's targets on one core: seconds and peak memory [KiB] for a million records
TARGET_SECONDS = 10.0
TARGET_KIB = 1024 * 1024
#: records in the file :func:`check` reads in this process [-]
CHECK_RECORDS = 2000
#: gzip's compression level for the ``.mon.gz`` file (gzip's own default, 6: level 9 is slower to write and
#: hardly smaller on these records)
GZIP_LEVEL = 6
#: most axles of a generated vehicle [-]
MAX_AXLES = 6
#: the first timestamp: the year 2026 from its first millisecond
YEAR_START = np.datetime64("2026-01-01T00:00:00.000", "ms")
YEAR_MS = 365 * 86_400_000

# ---- the fleet -----------------------------------------------------------------------------------------------------
#: heavy vehicles only (cars excluded): name, axle groups front to back, share of the flow. The shares are rounded
#: from the class mix of European motorway WIM sites (the 5-axle artic with a tri-axle trailer bogie dominant).
CLASSES: tuple[tuple[str, tuple[int, ...], float], ...] = (
    ("2-axle rigid", (1, 1), 0.25),
    ("3-axle rigid", (1, 2), 0.10),
    ("4-axle rigid, twin steer", (2, 2), 0.05),
    ("4-axle artic, tandem trailer", (1, 1, 2), 0.05),
    ("5-axle artic, tri-axle trailer", (1, 1, 3), 0.42),
    ("5-axle artic, tandem drive and trailer", (1, 2, 2), 0.05),
    ("6-axle artic, tandem drive, tri-axle trailer", (1, 2, 3), 0.08),
)
#: spacing within an axle group [mm]: a tandem's or tri-axle's (a twin steer's is wider, TWIN_STEER), all < 2.0 m
BOGIE_SPACING_MM = (1300, 1400)
TWIN_STEER_MM = (1700, 1950)
#: spacing between groups [mm], each > 2.0 m: the first gap (steer to drive), the second (a tractor's drive group
#: to its trailer's group, the kingpin's reach)
FIRST_GAP_MM = {"rigid": (3200, 5800), "artic": (3000, 3900)}
SECOND_GAP_MM = (5000, 7500)
#: axle load empty and full [kg] by the axle's group: steer, a single drive or trailer axle, an axle of a tandem,
#: an axle of a tri-axle group
LOAD_KG = {"steer": (3800, 7200), "single": (3000, 10500), "tandem": (2500, 9200), "tri": (1800, 8000)}
#: overhangs [mm]: front, rear
FRONT_OVERHANG_MM = (1200, 1600)
REAR_OVERHANG_MM = (800, 3200)
#: the EU's longest vehicle [mm] (Directive 96/53/EC)
MAX_LENGTH_MM = 18750


def fleet(n: int, seed: int = SEED) -> dict[str, np.ndarray]:
    """N heavy vehicles in integer units as MON writes them (kg, mm, km/h, ms), timestamps increasing through 2026.

    Axle loads 1-11 t rounded to 10 kg (a common MON resolution), gross weight their sum, spacings in mm with a new
    axle group at every spacing over 2.0 m and ``n_groups`` counted so, length longer than the wheelbase by the
    overhangs, speed 40-100 km/h, lane 1 or 2, direction 0 or 1, transverse position in mm. Arrays of n records;
    ``loads`` (n, :data:`MAX_AXLES`) and ``spacings`` (n, :data:`MAX_AXLES` - 1) are 0 past the vehicle's axles.
    """
    rng = np.random.default_rng(seed)
    # per class: axle count, load kind per axle, gap kind per gap (0 none, 1 in a group, 2 twin steer, 3 first
    # gap of a rigid, 4 first gap of an artic, 5 second gap)
    n_classes = len(CLASSES)
    axles = np.zeros(n_classes, dtype=np.int64)
    kinds = np.zeros((n_classes, MAX_AXLES), dtype=np.int64)  # index into LOAD_KG's order
    gaps = np.zeros((n_classes, MAX_AXLES - 1), dtype=np.int64)
    order = list(LOAD_KG)
    for c, (name, groups, _) in enumerate(CLASSES):
        axles[c] = sum(groups)
        artic = "artic" in name
        a = 0
        for g, size in enumerate(groups):
            kind = "steer" if g == 0 else {1: "single", 2: "tandem", 3: "tri"}[size]
            for k in range(size):
                kinds[c, a] = order.index(kind)
                if k > 0:
                    gaps[c, a - 1] = 2 if g == 0 else 1
                a += 1
            if g + 1 < len(groups):
                gaps[c, a - 1] = (4 if artic else 3) if g == 0 else 5
    share = np.array([s for *_, s in CLASSES])
    cls = rng.choice(n_classes, size=n, p=share / share.sum())
    n_axles = axles[cls]
    # loads: one fill per vehicle (a third near empty, the rest part or fully laden), a little scatter per axle
    laden = rng.random(n) < 2 / 3
    fill = np.where(laden, rng.beta(5.0, 2.0, n), rng.beta(1.5, 8.0, n))
    lo = np.array([LOAD_KG[k][0] for k in order])[kinds[cls]]
    hi = np.array([LOAD_KG[k][1] for k in order])[kinds[cls]]
    loads = (lo + fill[:, None] * (hi - lo)) * rng.normal(1.0, 0.04, (n, MAX_AXLES))
    loads = np.round(np.clip(loads, 1000.0, 11000.0) / 10.0).astype(np.int64) * 10
    loads[np.arange(MAX_AXLES)[None, :] >= n_axles[:, None]] = 0
    # spacings: the same bogie spacing for every group of a vehicle
    kind = gaps[cls]
    ranges = np.array([(0, 0), BOGIE_SPACING_MM, TWIN_STEER_MM, FIRST_GAP_MM["rigid"], FIRST_GAP_MM["artic"],
                       SECOND_GAP_MM])  # fmt: skip
    u = np.where(kind == 1, rng.random((n, 1)), rng.random((n, MAX_AXLES - 1)))  # one bogie spacing per vehicle
    spacings = np.round(ranges[kind, 0] + u * (ranges[kind, 1] - ranges[kind, 0])).astype(np.int64)
    wheelbase = spacings.sum(axis=1)
    length = (wheelbase + rng.integers(*FRONT_OVERHANG_MM, n, endpoint=True)
              + rng.integers(*REAR_OVERHANG_MM, n, endpoint=True))  # fmt: skip
    length = np.minimum(length, np.maximum(MAX_LENGTH_MM, wheelbase + 1000))  # the EU's longest, if it can be
    # timestamps: gaps of at least 1 ms, exponential, scaled to fill the year
    steps = np.cumsum(1.0 + rng.exponential(1.0, n))
    stamps = YEAR_START + np.floor(steps * ((YEAR_MS - 1) / steps[-1])).astype("timedelta64[ms]")
    return {
        "head": np.arange(1, n + 1, dtype=np.int64),
        "stamp": stamps,
        "n_axles": n_axles,
        "n_groups": 1 + (spacings > 2000).sum(axis=1),
        "gross": loads.sum(axis=1),
        "speed": np.clip(np.round(rng.normal(82.0, 8.0, n)), 40, 100).astype(np.int64),
        "length": length,
        "lane": np.where(rng.random(n) < 0.8, 1, 2),
        "direction": rng.integers(0, 2, n),
        "transverse": np.clip(np.round(rng.normal(800.0, 200.0, n)), 0, 1999).astype(np.int64),
        "loads": loads,
        "spacings": spacings,
        "class": cls,
    }


def calendar(stamps: np.ndarray) -> dict[str, np.ndarray]:
    """Year, month, day, hour, minute, second and millisecond of the minute of datetime64[ms] stamps, as int64."""
    year = stamps.astype("datetime64[Y]")
    month = stamps.astype("datetime64[M]")
    day = stamps.astype("datetime64[D]")
    in_day = (stamps - day).astype(np.int64)  # ms
    return {
        "year": year.astype(np.int64) + 1970,
        "month": (month - year.astype("datetime64[M]")).astype(np.int64) + 1,
        "day": (day - month.astype("datetime64[D]")).astype(np.int64) + 1,
        "hour": in_day // 3_600_000,
        "minute": in_day // 60_000 % 60,
        "ms_of_minute": in_day % 60_000,
    }


# ---- fixed-width text, built as a byte array ------------------------------------------------------------------------
def digits(values: np.ndarray, width: int, zero_pad: bool = False) -> np.ndarray:
    """(n, width) ASCII bytes of non-negative integers right-aligned in ``width`` characters, padded with spaces
    (Fortran ``I<width>``) or zeros."""
    values = np.asarray(values, dtype=np.int64)
    if values.size and (values.min() < 0 or values.max() >= 10**width):
        raise ValueError(f"a value outside 0-{10**width - 1} for a field of {width} characters")
    powers = 10 ** np.arange(width - 1, -1, -1, dtype=np.int64)
    out = (values[:, None] // powers % 10 + ord("0")).astype(np.uint8)
    if not zero_pad:
        lead = values[:, None] < powers
        lead[:, -1] = False  # 0 is written "0"
        out[lead] = ord(" ")
    return out


def _lines(grid: np.ndarray, ends: np.ndarray) -> bytes:
    """The rows of a byte grid, each cut at its own end (exclusive), each followed by a newline, as one string."""
    n, width = grid.shape
    grid[np.arange(n), ends] = ord("\n")
    return grid[np.arange(width)[None, :] <= ends[:, None]].tobytes()


#: the MON header of the reference: field, offset, width (50 characters), then per axle i (from 0) the load I5
#: at 50 + 10 i and the spacing to the next axle I5 at 55 + 10 i
MON_HEADER = (
    ("head", 0, 9), ("day", 9, 2), ("month", 11, 2), ("year", 13, 4), ("hour", 17, 2), ("minute", 19, 2),
    ("ms_of_minute", 21, 5), ("n_axles", 26, 2), ("n_groups", 28, 2), ("gross", 30, 6), ("speed", 36, 3),
    ("length", 39, 5), ("lane", 44, 1), ("direction", 45, 1), ("transverse", 46, 4),
)  # fmt: skip


def mon_bytes(v: dict[str, np.ndarray]) -> bytes:
    """The vehicles as MON records, one a line: the 50-character header, then 10 characters per axle (load, then
    the spacing to the next axle; the slot after the last axle 0). Lines end at their last axle's spacing slot."""
    n = len(v["head"])
    fields = {**v, **calendar(v["stamp"])}
    grid = np.full((n, 50 + 10 * MAX_AXLES + 1), ord(" "), dtype=np.uint8)
    for name, start, width in MON_HEADER:
        grid[:, start : start + width] = digits(fields[name], width)
    spacings = np.concatenate([v["spacings"], np.zeros((n, 1), dtype=np.int64)], axis=1)  # the slot after the last
    for i in range(MAX_AXLES):
        grid[:, 50 + 10 * i : 55 + 10 * i] = digits(v["loads"][:, i], 5)
        grid[:, 55 + 10 * i : 60 + 10 * i] = digits(spacings[:, i], 5)
    return _lines(grid, 50 + 10 * v["n_axles"])


#: CASTOR (reference, section CASTOR): field, offset, width (34 characters), then per axle i the load I3 (kg/100)
#: at 34 + 5 i and the spacing I2 (dm) at 37 + 5 i
CASTOR_HEADER = (
    ("head", 0, 4), ("day", 4, 2), ("month", 6, 2), ("year2", 8, 2), ("hour", 10, 2), ("minute", 12, 2),
    ("second", 14, 2), ("second_100", 16, 2), ("speed_dms", 18, 3), ("gross_100", 21, 4), ("length_dm", 25, 3),
    ("n_axles", 28, 1), ("direction_12", 29, 1), ("lane", 30, 1), ("transverse_dm", 31, 3),
)  # fmt: skip


def castor_bytes(v: dict[str, np.ndarray]) -> bytes:
    """The vehicles as CASTOR records (100 kg and dm steps: loads and spacings rounded, gross the sum of the
    rounded loads, head the record number modulo 10,000)."""
    n = len(v["head"])
    cal = calendar(v["stamp"])
    loads = np.round(v["loads"] / 100.0).astype(np.int64)
    spacings = np.concatenate([np.round(v["spacings"] / 100.0).astype(np.int64), np.zeros((n, 1), np.int64)], axis=1)
    fields = {
        "head": v["head"] % 10_000, "day": cal["day"], "month": cal["month"], "year2": cal["year"] % 100,
        "hour": cal["hour"], "minute": cal["minute"], "second": cal["ms_of_minute"] // 1000,
        "second_100": cal["ms_of_minute"] % 1000 // 10, "speed_dms": np.round(v["speed"] / 0.36).astype(np.int64),
        "gross_100": loads.sum(axis=1), "length_dm": np.ceil(v["length"] / 100.0).astype(np.int64),
        "n_axles": v["n_axles"], "direction_12": v["direction"] + 1, "lane": v["lane"],
        "transverse_dm": np.round(v["transverse"] / 100.0).astype(np.int64),
    }  # fmt: skip
    grid = np.full((n, 34 + 5 * MAX_AXLES + 1), ord(" "), dtype=np.uint8)
    for name, start, width in CASTOR_HEADER:
        grid[:, start : start + width] = digits(fields[name], width)
    for i in range(MAX_AXLES):
        grid[:, 34 + 5 * i : 37 + 5 * i] = digits(loads[:, i], 3)
        grid[:, 37 + 5 * i : 39 + 5 * i] = digits(spacings[:, i], 2)
    return _lines(grid, 34 + 5 * v["n_axles"])


def csv_bytes(v: dict[str, np.ndarray]) -> bytes:
    """The vehicles in the CSV layout (``docs/weighings.md``): timestamp (ISO 8601, ms), speed_kmh, lane, n_axles,
    axle_load_1..6 [kg], spacing_1..5 [m, three decimals], cells past a vehicle's axles empty."""
    n = len(v["head"])
    cal = calendar(v["stamp"])
    header = ",".join(
        ["timestamp", "speed_kmh", "lane", "n_axles"]
        + [f"axle_load_{i}" for i in range(1, MAX_AXLES + 1)]
        + [f"spacing_{i}" for i in range(1, MAX_AXLES)]
    )
    second = cal["ms_of_minute"] // 1000
    parts: list[np.ndarray | bytes] = [
        digits(cal["year"], 4, True), b"-", digits(cal["month"], 2, True), b"-", digits(cal["day"], 2, True), b"T",
        digits(cal["hour"], 2, True), b":", digits(cal["minute"], 2, True), b":", digits(second, 2, True), b".",
        digits(cal["ms_of_minute"] % 1000, 3, True), b",", digits(v["speed"], 3), b",", digits(v["lane"], 1), b",",
        digits(v["n_axles"], 1),
    ]  # fmt: skip
    present = np.arange(MAX_AXLES)[None, :] < v["n_axles"][:, None]
    for i in range(MAX_AXLES):
        cell = digits(v["loads"][:, i], 5)
        cell[~present[:, i]] = ord(" ")
        parts += [b",", cell]
    for i in range(MAX_AXLES - 1):
        metres = v["spacings"][:, i]
        cell = np.concatenate([digits(metres // 1000, 2), np.full((n, 1), ord("."), np.uint8),
                               digits(metres % 1000, 3, True)], axis=1)  # fmt: skip
        cell[~present[:, i + 1]] = ord(" ")
        parts += [b",", cell]
    columns = [np.full((n, 1), p[0], np.uint8) if isinstance(p, bytes) else p for p in parts]
    grid = np.concatenate([*columns, np.zeros((n, 1), np.uint8)], axis=1)
    grid[:, -1] = ord("\n")
    flat = grid.ravel()
    return header.encode() + b"\n" + flat[flat != ord(" ")].tobytes()


def write_files(directory: Path, n: int, castor: bool = False) -> dict[str, tuple[Path, str, float]]:
    """Write the files of n vehicles: {row: (path, format, the sum of the axle loads written [kg])}."""
    v = fleet(n)
    load_sum = float(v["loads"].sum())
    files = {}
    mon = directory / "vehicles.mon"
    data = mon_bytes(v)
    mon.write_bytes(data)
    files["MON"] = (mon, "mon", load_sum)
    gz = directory / "vehicles.mon.gz"
    with gz.open("wb") as raw, gzip.GzipFile(mon.name, "wb", GZIP_LEVEL, raw, mtime=0) as out:
        out.write(data)
    files["MON, gzipped"] = (gz, "mon", load_sum)
    del data
    path = directory / "vehicles.csv"
    path.write_bytes(csv_bytes(v))
    files["CSV (the peer)"] = (path, "csv", load_sum)
    if castor:
        path = directory / "vehicles.castor"
        path.write_bytes(castor_bytes(v))
        files["CASTOR"] = (path, "castor", 100.0 * float(np.round(v["loads"] / 100.0).sum()))
    return files


def check(directory: Path, reader_root: Path, n: int = CHECK_RECORDS) -> None:
    """Read a small generated file of each kind in a process of ``reader_root``'s reader: every record good and as
    written (the loads, spacings, counts and timestamps of MON and CSV), else SystemExit."""
    v = fleet(n, SEED + 1)
    for name, data in (("mon", mon_bytes(v)), ("csv", csv_bytes(v)), ("castor", castor_bytes(v))):
        (directory / f"check.{name}").write_bytes(data)
    np.savez(directory / "check.npz", **{k: v[k] for k in ("loads", "spacings", "n_groups", "gross", "length")},
             stamp=v["stamp"].astype(np.int64))  # fmt: skip
    result = subprocess.run([sys.executable, "-c", CHECK, str(directory)], cwd=reader_root, env=child_env(reader_root),
                            capture_output=True, text=True)  # fmt: skip
    if result.returncode != 0:
        raise SystemExit(f"the generated records do not read back as written:\n{result.stdout}{result.stderr}")
    print(result.stdout.strip())


#: run in a fresh process by :func:`check`
CHECK = r"""
import sys
from pathlib import Path
import numpy as np
from bogie.weighings.readers import read_weighings
d = Path(sys.argv[1])
want = np.load(d / "check.npz")
n = len(want["gross"])
loads, spacings = want["loads"].astype(float), want["spacings"] / 1000.0
loads[loads == 0] = np.nan
spacings[spacings == 0] = np.nan
for fmt in ("mon", "csv", "castor"):
    r = read_weighings(d / f"check.{fmt}", fmt)
    assert (r.n_read, r.n_skipped) == (n, 0), (fmt, r.summary())
    f = r.vehicles
    got_loads = f[[f"axle_load_{i + 1}" for i in range(loads.shape[1])]].to_numpy()
    got_spacings = f[[f"spacing_{i + 1}" for i in range(spacings.shape[1])]].to_numpy()
    step = 100.0 if fmt == "castor" else 0.0
    assert np.allclose(got_loads, loads, atol=step / 2 + 1e-9, rtol=0, equal_nan=True), fmt
    assert np.allclose(got_spacings, spacings, atol=step / 2000 + 1e-9, rtol=0, equal_nan=True), fmt
    stamps = f["timestamp"].to_numpy().astype("datetime64[ms]").astype(np.int64)
    assert np.array_equal(stamps // 10 * 10 if fmt == "castor" else stamps,
                          want["stamp"] // 10 * 10 if fmt == "castor" else want["stamp"]), fmt
    if fmt == "mon":
        assert np.array_equal(f["n_groups"].to_numpy(), want["n_groups"]), fmt
        assert np.array_equal(f["gross_weight"].to_numpy(), want["gross"]), fmt
        assert np.allclose(f["length"].to_numpy(), want["length"] / 1000.0), fmt
print(f"check: {n} generated records each of MON, CSV and CASTOR read back as written, none skipped")
"""

# ---- one reading in a fresh process ---------------------------------------------------------------------------------
#: run in a fresh process: pin to one CPU, import the reader, note the memory, time one read_weighings call
CHILD = r"""
import json, os, resource, sys, time
os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
def rss_kib():
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS:"))
start = time.perf_counter()
from bogie.weighings.readers import read_weighings
import bogie.weighings.readers as readers
out = {"import_s": time.perf_counter() - start, "rss_import_kib": rss_kib(), "reader": readers.__file__,
       "cpus": sorted(os.sched_getaffinity(0))}
start = time.perf_counter()
try:
    result = read_weighings(sys.argv[1], sys.argv[2])
except Exception as exc:
    out["seconds"] = time.perf_counter() - start
    out["error"] = f"{type(exc).__name__}: {exc}"
else:
    out["seconds"] = time.perf_counter() - start
    out["peak_kib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    frame = result.vehicles
    out.update(n_read=result.n_read, n_skipped=result.n_skipped, reasons=result.reasons(),
               load_sum=float(frame[[c for c in frame.columns if c.startswith("axle_load_")]].sum().sum()))
out.setdefault("peak_kib", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
print(json.dumps(out))
"""


def child_env(reader_root: Path) -> dict[str, str]:
    """The environment of a reading: one thread everywhere, ``bogie`` from ``reader_root``."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", NUMBA_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join([str(reader_root), *filter(None, [os.environ.get("PYTHONPATH")])])
    return env


def read_in_child(path: Path, fmt: str, reader_root: Path) -> dict:
    """One reading in a fresh process (:data:`CHILD`): its report, plus the process's own wall time."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, str(path), fmt], cwd=reader_root, env=child_env(reader_root),
                          capture_output=True, text=True)  # fmt: skip
    wall = time.perf_counter() - start
    if done.returncode != 0:
        return {"error": f"process failed ({done.returncode}): {done.stderr.strip().splitlines()[-1:]}", "wall": wall}
    report = json.loads(done.stdout.strip().splitlines()[-1])
    if "error" in report:  # the file's name, not the temporary directory's
        report["error"] = report["error"].replace(f"{path.parent}{os.sep}", "")
    return {**report, "wall": wall}


# ---- the table -----------------------------------------------------------------------------------------------------
def _mib(kib: float) -> str:
    return f"{kib / 1024:,.0f} MiB"


def _size(path: Path) -> str:
    return f"{path.stat().st_size / 1e6:,.1f} MB"


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def _commit(root: Path) -> str:
    try:
        sha = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             check=True).stdout.strip()  # fmt: skip
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    except (OSError, subprocess.CalledProcessError):
        return "not a git checkout"
    return sha + (" with uncommitted changes" if dirty else "")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_readers", description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=N_RECORDS, help=f"records per file (default {N_RECORDS:,})")
    parser.add_argument("--repeat", type=int, default=1, help="readings of each file, interleaved (default 1)")
    parser.add_argument("--castor", action="store_true", help="a CASTOR file of the same vehicles too")
    parser.add_argument("--reader-root", type=Path, default=ROOT,
                        help="the checkout whose bogie.weighings.readers is timed (default: this one)")  # fmt: skip
    parser.add_argument("--previous", type=Path, default=None,
                        help="a checkout of the previous reader: its MON and CSV readings as rows of the same run "
                        "(e.g. `git worktree add /tmp/previous 46608fd`, the line-by-line reader)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.records < 1 or args.repeat < 1:
        parser.error("--records and --repeat must be at least 1")
    root = args.reader_root.resolve()
    print(f"load average (1, 5, 15 min) at the start: {_load()} on {os.cpu_count()} CPUs", flush=True)
    print(f"reader: {root} ({_commit(root)}); {args.records:,} records per file, {args.repeat} reading(s) each")
    runs: dict[str, list[dict]] = {}
    with tempfile.TemporaryDirectory(prefix="bench_readers-") as tmp:
        check(Path(tmp), root)
        start = time.perf_counter()
        files = write_files(Path(tmp), args.records, args.castor)
        print(f"generated in {time.perf_counter() - start:.1f} s (not timed below): "
              + ", ".join(f"{path.name} {_size(path)}" for path, *_ in files.values()), flush=True)  # fmt: skip
        roots = dict.fromkeys(files, root)
        if args.previous is not None:
            previous = args.previous.resolve()
            print(f"previous reader: {previous} ({_commit(previous)})")
            for row in ("MON", "CSV (the peer)"):
                name = f"{row.split(' ')[0]}, previous reader"
                files[name], roots[name] = files[row], previous
        sizes = {row: _size(path) for row, (path, *_) in files.items()}
        for r in range(args.repeat):
            for row, (path, fmt, _) in files.items():
                report = read_in_child(path, fmt, roots[row])
                runs.setdefault(row, []).append(report)
                what = report.get("error") or f"{report['n_read']:,} read in {report['seconds']:.2f} s"
                print(f"  reading {r + 1} {row:15s}: {what[:160]}", flush=True)
    print(f"load average (1, 5, 15 min) at the end: {_load()}")
    done = [rep for reports in runs.values() for rep in reports if "reader" in rep]
    if done:
        print(f"reader imported from {done[0]['reader']} in {done[0]['import_s']:.2f} s, pinned to CPU "
              f"{done[0]['cpus']}")  # fmt: skip
    good = {row: [rep for rep in reports if "error" not in rep] for row, reports in runs.items()}
    medians = {row: statistics.median(rep["seconds"] for rep in reps) for row, reps in good.items() if reps}
    csv_time = medians.get("CSV (the peer)")
    print()
    print("| file | size | records read | skipped | time | records/s | / CSV time | peak RSS | peak - after import |"
          " after import |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    for row, reports in runs.items():
        if not good[row]:
            note = "not supported" if "gzip" in row else "failed"
            first = reports[0]
            after = f"refused after {first['seconds']:.2f} s: " if "seconds" in first else ""
            print(f"| {row} | {sizes[row]} | {note} ({after}{first['error'][:80]}) | | | | | | | |")
            continue
        t = medians[row]
        rep = min(good[row], key=lambda rep: abs(rep["seconds"] - t))  # the median reading (the lower of two)
        peak = max(r["peak_kib"] for r in good[row])
        best = "" if len(good[row]) == 1 else f" (best {min(r['seconds'] for r in good[row]):.2f})"
        want = files[row][2]
        sums = "" if abs(rep["load_sum"] - want) <= 1e-9 * want else " (axle loads differ from those written)"
        ratio = f"{t / csv_time:.2f}" if csv_time else ""
        print(
            f"| {row} | {sizes[row]} | {rep['n_read']:,}{sums} | {rep['n_skipped']:,} | {t:.2f} s{best} | "
            f"{rep['n_read'] / t:,.0f} | {ratio} | {_mib(peak)} | {_mib(peak - rep['rss_import_kib'])} | "
            f"{_mib(rep['rss_import_kib'])} |"
        )
    scale = N_RECORDS / args.records
    print(
        f"\nIssue 27's target for {N_RECORDS:,} records on one core: at most {TARGET_SECONDS:g} s and "
        f"{_mib(TARGET_KIB)} peak."
        + ("" if args.records == N_RECORDS else f" These files hold {args.records:,}: scale the times by {scale:g}.")
    )


if __name__ == "__main__":
    main()
