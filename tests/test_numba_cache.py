"""numba's on-disk cache stays bounded (bogie.numba_cache; issue 28, item 8).

Every test works in a cache root of its own (``XDG_CACHE_HOME`` or a ``root`` argument), never in ``~/.cache``.
"""

import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from bogie.numba_cache import GRACE, KEEP, LOCK_NAME, claim, prune

ROOT = Path(__file__).resolve().parents[1]
DAY = 86400.0


def fake_entries(root, n, age_days=3.0):
    """``n`` cache directories of other versions, each with a kernel file, used ``age_days`` ago and before."""
    entries = []
    for i in range(n):
        entry = root / f"{i:016x}"
        (entry / "bogie_0123").mkdir(parents=True)
        (entry / "bogie_0123" / "kernel.nbi").write_bytes(b"x" * 1000)
        used = time.time() - (age_days + i / 24.0) * DAY
        os.utime(entry, (used, used))
        entries.append(entry)
    return entries


def directories(root):
    return sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))


def test_one_start_prunes_thirty_old_directories_to_the_bound_and_keeps_a_fresh_one(tmp_path):
    root = tmp_path / "bogie-numba"
    old = fake_entries(root, 30)
    fresh = root / ("f" * 16)
    (fresh / "bogie_4567").mkdir(parents=True)  # another version compiled a minute ago, by a process now ended
    os.utime(fresh, (time.time() - 60.0, time.time() - 60.0))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    script = "import os, bogie; print(os.environ['NUMBA_CACHE_DIR'])"
    result = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, env=env,
                            timeout=300)  # fmt: skip
    assert result.returncode == 0, result.stderr
    own = Path(result.stdout.strip())
    left = directories(root)
    assert len(left) <= KEEP and own in left and fresh in left, left
    assert old[0] in left and old[-1] not in left  # the most recently used of the old ones stay
    assert not [p for p in root.iterdir() if p.name.startswith(".")]  # no half-removed leftover


def test_a_directory_in_use_or_used_within_the_grace_time_is_never_removed(tmp_path):
    root = tmp_path / "bogie-numba"
    entries = fake_entries(root, 6)
    busy, recent = entries[-1], entries[-2]  # the least recently used two
    fd = claim(busy)  # a running process holds it (another open of the lock file conflicts with this one's lock)
    assert fd is not None
    try:
        os.utime(busy, (time.time() - 9 * DAY, time.time() - 9 * DAY))
        now = time.time() + 1.0
        os.utime(recent, (now - GRACE / 2, now - GRACE / 2))
        removed = prune(root, keep=0, now=now)  # nothing kept for being recent in rank: only the lock and the time
        assert sorted(removed) == sorted(set(entries) - {busy, recent})
        assert directories(root) == sorted([busy, recent])
    finally:
        os.close(fd)
    # the process has ended and the grace time passed: both go
    assert sorted(prune(root, keep=0, now=now + 2 * GRACE)) == sorted([busy, recent])
    assert directories(root) == []


def test_two_pruners_at_once_remove_each_directory_once_and_a_claim_survives_a_removal(tmp_path):
    root = tmp_path / "bogie-numba"
    fake_entries(root, 12)
    script = textwrap.dedent(f"""
        from pathlib import Path
        from bogie.numba_cache import prune
        print(len(prune(Path({str(root)!r}), keep=2)))
    """)
    runs = [subprocess.Popen([sys.executable, "-c", script], cwd=ROOT, stdout=subprocess.PIPE, text=True)
            for _ in range(2)]  # fmt: skip
    counts = [int(p.communicate(timeout=300)[0]) for p in runs]
    assert sum(counts) == 10 and len(directories(root)) == 2
    # a process that claims a directory a pruner has just removed gets a fresh one, lock file included
    entry = directories(root)[0]
    shutil.rmtree(entry)
    fd = claim(entry)
    try:
        assert fd is not None and os.fstat(fd).st_ino == (entry / LOCK_NAME).stat().st_ino
    finally:
        os.close(fd)


def test_the_cache_key_covers_every_module_below_bogie_subpackages_included(tmp_path):
    """A kernel may inline a compiled function from a subpackage: an edit there is a new cache directory (issue 29)."""
    from bogie.numba_cache import source_digest

    package = tmp_path / "bogie"
    shutil.copytree(ROOT / "bogie", package, ignore=shutil.ignore_patterns("__pycache__"))
    assert source_digest(package) == source_digest(ROOT / "bogie")  # the key depends on the files, not where they lie
    before = source_digest(package)

    nested = package / "weighings" / "stats.py"
    nested.write_text(nested.read_text() + "\n# an edit in a subpackage\n")
    edited = source_digest(package)
    assert edited != before

    (package / "physics" / "steel").mkdir(parents=True)
    (package / "physics" / "steel" / "kernel.py").write_text("X = 1\n")
    deeper = source_digest(package)
    assert deeper != edited
    (package / "physics" / "steel" / "kernel.py").write_text("X = 2\n")
    assert source_digest(package) != deeper

    moved = package / "physics" / "kernel.py"  # the same bytes under another name: another version
    (package / "physics" / "steel" / "kernel.py").rename(moved)
    assert source_digest(package) not in (deeper, edited, before)


def test_the_simulate_code_version_hashes_its_sources_as_the_cache_key_does():
    """pipeline.chunks.code_version and the cache key hash source files one way (bogie.numba_cache.hash_sources)."""
    import hashlib

    from bogie.numba_cache import hash_sources
    from pipeline.deps import project_files

    paths = project_files("pipeline.simulate")
    assert ROOT / "bogie" / "numba_cache.py" in paths
    digest = hashlib.sha256()
    hash_sources(digest, paths, ROOT)
    expected = hashlib.sha256()
    for path in paths:  # the format code_version has always hashed: a part file's hash does not move with this change
        expected.update(path.relative_to(ROOT).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    assert digest.hexdigest() == expected.hexdigest()


def test_a_directory_gone_between_the_listing_and_its_stat_takes_no_place_among_the_kept(tmp_path, monkeypatch):
    """Another pruner renamed it away after this one listed it: it must not push a kept directory out.

    The race of CI's run of the two-pruner test (11 removed of 12 with ``keep=2``), made deterministic: the listing
    holds a directory that no longer exists.
    """
    import bogie.numba_cache as numba_cache

    root = tmp_path / "bogie-numba"
    entries = fake_entries(root, 5)  # entries[0] and entries[1] the most recently used
    listed = numba_cache._entries(root)
    ghost = root / ("e" * 16)  # listed, then renamed away by another pruner
    monkeypatch.setattr(numba_cache, "_entries", lambda _root: [ghost, *listed])
    removed = prune(root, keep=2)
    assert sorted(removed) == sorted(entries[2:])
    assert directories(root) == sorted(entries[:2])


#: a process that uses every family of compiled functions: bogie.numerics's ufuncs, products, solves and Cholesky
#: factor, the static and linear models, and weighings of each kind (static and WIM, tandem and tri-axle, steel and
#: air) through the simulate stage's own code; prints each function numba compiled (not loaded from the cache)
EVERY_KERNEL = textwrap.dedent(
    """
    import math, sys
    from numba.core import event

    compiled = []

    class Listener(event.Listener):
        def on_start(self, ev):
            compiled.append(ev.data["dispatcher"].py_func.__qualname__)

        def on_end(self, ev):
            pass

    event.register("numba:compile", Listener())

    import numpy as np
    import pipeline
    from bogie import numerics
    from bogie.steel import cases
    from bogie.steel.static import wheel_loads
    from bogie.params import triaxle_stage1
    from pipeline.config import load_config
    from pipeline.sample import sample_studies
    from pipeline.simulate import chunk_table, study_protocols

    x = np.linspace(0.1, 2.0, 5)
    for f in (numerics.exp, numerics.log, numerics.log1p, numerics.expm1, numerics.sin, numerics.cos):
        f(x)
    numerics.power(x, 2.5), numerics.arctan2(x, x), numerics.sinc(x), numerics.geomspace(1.0, 2.0, 3)
    a = np.array([[4.0, 1.0], [1.0, 3.0]])
    numerics.solve(a, x[:2]), numerics.matmul(a, a), numerics.cholesky(a), numerics.inv(a), numerics.cov(a)
    wheel_loads(triaxle_stage1(), 0.057, math.radians(1.0))
    cases.run("L01")
    config = load_config(sys.argv[1])
    for study, frame in sample_studies(config).items():
        if study != "fleet":
            continue
        for suspension in ("steel", "air"):
            for group in ("tandem", "triaxle"):
                pick = frame[(frame["suspension"] == suspension) & (frame["group"] == group)].iloc[:1]
                rows = {c: pick[c].tolist() for c in pick.columns if c != "study"}
                chunk_table(rows, study_protocols(config, study))
    import bogie
    print(bogie.__file__)
    print(" ".join(sorted(set(compiled))) or "nothing")
    """
)


def _cache_files(root: Path) -> dict[str, tuple[int, int]]:
    return {p.relative_to(root).as_posix(): (p.stat().st_size, p.stat().st_mtime_ns) for p in root.rglob("*")
            if p.is_file() and p.suffix in (".nbi", ".nbc")}  # fmt: skip


def test_a_fresh_process_compiles_nothing_and_writes_nothing_once_the_cache_is_warm(tmp_path):
    # issue 39 Must 6: a function made anew in each process (a closure) missed the cache and compiled every time;
    # issue 45 Must 6: another clone of the same code (or dvc exp run --temp's copy) compiled everything again
    import yaml

    raw = yaml.safe_load((ROOT / "params.yaml").read_text(encoding="utf-8"))
    raw["fleet"]["n_bogies"] = 24
    raw["fleet"]["suspension_mix"] = {"tandem": {"steel": 0.5, "air": 0.5}, "triaxle": {"steel": 0.5, "air": 0.5}}
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump(raw), encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")  # an empty cache: the first process compiles everything

    def run(where: Path) -> str:
        out = subprocess.run([sys.executable, "-c", EVERY_KERNEL, str(params)], cwd=where, env=env,
                             capture_output=True, text=True, timeout=1200)  # fmt: skip
        assert out.returncode == 0, out.stderr[-3000:]
        imported, compiled = out.stdout.strip().splitlines()[-2:]
        assert Path(imported).resolve().is_relative_to(where.resolve()), imported  # this copy's bogie, not another
        return compiled

    first = run(ROOT)
    assert first != "nothing" and "matmul" in first.split()  # the listener does see compilations
    before = _cache_files(tmp_path / "cache")
    assert before
    second = run(ROOT)
    assert second == "nothing", f"compiled again in a new process: {second}"
    after = _cache_files(tmp_path / "cache")
    assert after == before, f"cache entries written again: {sorted(set(after.items()) - set(before.items()))[:5]}"
    clone = tmp_path / "elsewhere" / "another-clone"  # the same code at another path, its files just written
    for package in ("bogie", "pipeline"):
        shutil.copytree(ROOT / package, clone / package, ignore=shutil.ignore_patterns("__pycache__"))
    third = run(clone)
    assert third == "nothing", f"another clone of the same code compiled again: {third}"
    assert _cache_files(tmp_path / "cache") == before, "another clone of the same code wrote cache entries again"


def test_a_pruner_does_not_mark_a_directory_used_before_it_removes_it(tmp_path, monkeypatch):
    """Creating the lock file of an unclaimed directory set its modification time to now: a second pruner listing
    at that moment ranked it as just used and removed an older, kept directory instead (11 removals of 10 in
    test_two_pruners_at_once... under CI's load). Each directory must be renamed away with its time untouched."""
    from bogie import numba_cache

    root = tmp_path / "bogie-numba"
    entries = fake_entries(root, 4)
    before = {entry: entry.stat().st_mtime_ns for entry in entries}
    seen = []
    rename = os.rename

    def spy(src, dst):
        seen.append((Path(src), Path(src).stat().st_mtime_ns))
        return rename(src, dst)

    monkeypatch.setattr(numba_cache.os, "rename", spy)
    removed = numba_cache.prune(root, keep=1)
    assert len(removed) == 3 and len(seen) == 3
    assert all(mtime == before[path] for path, mtime in seen), seen
