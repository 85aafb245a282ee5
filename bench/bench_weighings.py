"""The whole ``bogie weighings --json`` on a year of a WIM site and on a network's year (issue 41 Must 4).

Issue 41's targets: the whole command on 10^6 records at most 15 times ``pandas.read_csv`` of the same records as
CSV, measured in the same run; 10^7 records in time linear in the records; at most 1.5 GiB of memory for any file.

The files are :mod:`bench.bench_readers`' synthetic MON records (its fleet, seeded; a 10^7 file is ten 10^6 files
of other seeds one after the other), written to a temporary directory removed at the end, with the 10^6 records
also in the CSV layout for the peer. Each command runs in a fresh process (``python -m bogie.cli weighings FILE
--json``, output discarded) after one warm-up run on a small file, so that numba's cache is filled and the figures
are those of a user's second run; the first run of a fresh checkout compiles the kernels as well (a few seconds).
The process reports its own peak resident memory (``ru_maxrss``) and the wall time is measured around it. The peer,
``pandas.read_csv`` of the CSV file, is timed in this process (median of 3). The load average is printed at the
start and the end. Nothing here passes or fails.

Run alone: ``python -m bench.bench_weighings [--records 1000000 10000000]``.

**A network's year** (issue 46 Musts 3 and 5): ``python -m bench.bench_weighings --network 10000000 --stations 20``
writes the records as 20 station files (seeds 141, 142, ...) in a folder and reads the folder as one survey, each
file a site (:func:`bogie.weighings.survey.observed_survey` of the folder, groups spilled, the pipeline's observed
stage's way), in a fresh process; then the same bytes as one file, the peer, measured in the same run. It prints
both times and peak memories, and their ratio (issue 46: bounded memory, at most 2 GiB, and time linear in the
records).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from bench.bench_readers import _commit, _load, csv_bytes, fleet, mon_bytes

ROOT = Path(__file__).resolve().parent.parent
#: the sizes timed [-]: a busy site's year and a network's
SIZES = (1_000_000, 10_000_000)
#: records generated at a time (the generator's memory) [-]
PIECE = 1_000_000
#: the issue's targets: the command over read_csv at 10^6 records, and peak memory [MiB]
TARGET_RATIO = 15.0
TARGET_MIB = 1536

CHILD = r"""
import contextlib, io, json, resource, sys, time
start = time.perf_counter()
from bogie.cli import main
with contextlib.redirect_stdout(io.StringIO()) as out:
    code = main(["weighings", sys.argv[1], "--json"])
seconds = time.perf_counter() - start
result = json.loads(out.getvalue())
print(json.dumps({"code": code, "seconds": seconds, "peak_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
                  "read": result["records"]["read"], "skipped": result["records"]["skipped"]}))
"""


NETWORK_CHILD = r"""
import json, resource, sys, time
start = time.perf_counter()
from bogie.weighings.survey import observed_survey
survey = observed_survey(sys.argv[1], "mon", min_group_load_kg=15000.0, position="trailer", keep_groups=False)
seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "peak_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
                  "read": survey.read.n_read, "skipped": survey.read.n_skipped, "sites": len(survey.stations),
                  "groups": survey.n_kept}))
"""


def write_mon(path: Path, n: int) -> None:
    """``n`` synthetic MON records (``bench_readers.fleet``, seeds 41, 42, ... a million at a time)."""
    with open(path, "wb") as fh:
        for k, start in enumerate(range(0, n, PIECE)):
            fh.write(mon_bytes(fleet(min(PIECE, n - start), seed=41 + k)))


def run_command(path: Path, child: str = CHILD) -> dict:
    """``bogie weighings PATH --json`` (or another ``child``) in a fresh process: its report and the wall time around
    it."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", child, str(path)], cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1:], "wall": wall}
    return {**json.loads(done.stdout.strip().splitlines()[-1]), "wall": wall}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_weighings", description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, nargs="+", default=list(SIZES), help="sizes (default 10^6 10^7)")
    parser.add_argument("--network", type=int, default=None, help="records of a network's year (e.g. 10000000)")
    parser.add_argument("--stations", type=int, default=20, help="its station files (default 20)")
    args = parser.parse_args(argv)
    print(f"commit {_commit(ROOT)}; load average at start {_load()}")
    if args.network is not None:
        network(args.network, args.stations)
        print(f"load average at end {_load()}")
        return
    with tempfile.TemporaryDirectory(prefix="bench-weighings-") as tmp:
        tmp = Path(tmp)
        small = tmp / "small.mon"
        write_mon(small, 2_000)
        run_command(small)  # the warm-up: numba's cache, the imports' bytecode
        rows = []
        peer = None
        for n in args.records:
            mon = tmp / f"site-{n}.mon"
            write_mon(mon, n)
            if peer is None and n <= PIECE:  # the same records (the same seed) as CSV
                csv = tmp / f"site-{n}.csv"
                csv.write_bytes(csv_bytes(fleet(n, seed=41)))
                times = []
                for _ in range(3):
                    start = time.perf_counter()
                    pd.read_csv(csv)
                    times.append(time.perf_counter() - start)
                peer = (n, statistics.median(times))
                csv.unlink()
            report = run_command(mon)
            rows.append((n, mon.stat().st_size, report))
            mon.unlink()
    print()
    print(f"{'records':>11} {'file':>9} {'command':>9} {'per 10^6':>9} {'peak':>9}  read / skipped")
    for n, size, r in rows:
        if "error" in r:
            print(f"{n:>11,} {size / 1e6:>7,.0f} MB  failed: {r['error']}")
            continue
        print(f"{n:>11,} {size / 1e6:>7,.0f} MB {r['wall']:>7.1f} s {r['wall'] / n * 1e6:>7.2f} s "
              f"{r['peak_kib'] / 1024:>6,.0f} MiB  {r['read']:,} / {r['skipped']:,}")  # fmt: skip
    if peer is not None:
        n, seconds = peer
        command = next((r["wall"] for m, _, r in rows if m == n and "wall" in r), None)
        print(f"\npandas.read_csv of the same {n:,} records as CSV: {seconds:.2f} s (median of 3); the command takes "
              f"{command / seconds:.1f} times as long (target at most {TARGET_RATIO:g})")  # fmt: skip
    if len(rows) > 1 and all("wall" in r for _, _, r in rows):
        (n0, _, r0), (n1, _, r1) = rows[0], rows[-1]
        print(f"{n1:,} records over {n0:,}: {r1['wall'] / r0['wall']:.1f} times the time for {n1 / n0:.0f} times the "
              f"records; peak memory at most {max(r['peak_kib'] for _, _, r in rows) / 1024:,.0f} MiB (target "
              f"{TARGET_MIB:,})")  # fmt: skip
    print(f"load average at end {_load()}")


def network(n: int, stations: int) -> None:
    """A network's ``n`` records over ``stations`` files read as one survey, against the same bytes as one file."""
    with tempfile.TemporaryDirectory(prefix="bench-network-") as tmp:
        tmp = Path(tmp)
        small = tmp / "small.mon"
        write_mon(small, 2_000)
        run_command(small, NETWORK_CHILD)  # the warm-up
        folder = tmp / "network"
        folder.mkdir()
        per = n // stations
        for k in range(stations):
            with open(folder / f"station-{k:03d}.mon", "wb") as fh:
                for start in range(0, per, PIECE):
                    fh.write(mon_bytes(fleet(min(PIECE, per - start), seed=141 + k * 100 + start // PIECE)))
        whole = tmp / "whole.mon"
        with open(whole, "wb") as out:
            for path in sorted(folder.iterdir()):
                out.write(path.read_bytes())
        size = whole.stat().st_size
        rows = [("folder", run_command(folder, NETWORK_CHILD)), ("one file", run_command(whole, NETWORK_CHILD))]
    print(
        f"\n{stations * per:,} records over {stations} station files ({size / 1e6:,.0f} MB), read as one survey "
        "(groups spilled, laden trailer groups kept):"
    )
    print(f"{'read as':>9} {'time':>8} {'per 10^6':>9} {'peak':>9} {'sites':>6} {'groups':>10}  read / skipped")
    for name, r in rows:
        if "error" in r:
            print(f"{name:>9}  failed: {r['error']}")
            continue
        print(
            f"{name:>9} {r['wall']:>6.1f} s {r['wall'] / (stations * per) * 1e6:>7.2f} s "
            f"{r['peak_kib'] / 1024:>6,.0f} MiB {r['sites']:>6} {r['groups']:>10,}  {r['read']:,} / {r['skipped']:,}"
        )
    if all("wall" in r for _, r in rows):
        (_, a), (_, b) = rows
        same = (a["read"], a["skipped"], a["groups"]) == (b["read"], b["skipped"], b["groups"])
        print(
            f"the folder takes {a['wall'] / b['wall']:.2f} times the one file's time; the same records and groups: "
            f"{same}; peak memory {max(a['peak_kib'], b['peak_kib']) / 1024:,.0f} MiB (issue 46: at most 2,048)"
        )


if __name__ == "__main__":
    main()
