"""The runs dataset's chunks: what determines a part file's content, the plan of files, and their resumption.

:func:`plan_chunks` splits each study into chunks and hashes each (:func:`chunk_hash`: the sample rows, the
protocols and the code, :func:`code_version`); :func:`check_runs_dir` refuses a folder that is not the stage's runs
dataset (marker :data:`MARKER`) and :func:`claim_runs_dir` marks a new one; :func:`reconcile` keeps the part files
whose stored hash matches and that read back whole (:func:`pipeline.schema.read_runs_content`: the file's SHA-256 and
its pages' CRC32s), counting their failed runs, deletes the rest of the stage's own files and quarantines the files
that are not ours; :func:`runs_lock` keeps a second process off the dataset; :func:`part_content` makes a part file's
bytes (in the worker that weighed the chunk) and :func:`write_part` writes them atomically. The work itself, weighing
a chunk's samples, is :func:`pipeline.simulate.chunk_table`.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
import re
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import scipy

from bogie.bogie_file import base_fields
from bogie.digest import numerics_digest
from bogie.fleet.sampling.sample import COLUMNS
from bogie.fleet.weighing.weigher import Protocols
from bogie.numba_cache import hash_sources
from bogie.numerics import compile_target
from bogie.presets import PRESETS
from pipeline.atomic import LockedError, atomic_file, output_lock, temporary_name
from pipeline.deps import ROOT, project_files
from pipeline.schema import RunsFileError, failed_runs, read_runs_content, runs_file_content, write_file

#: Parquet metadata key of a part file's content hash
HASH_KEY = b"bogie.simulate.hash"
#: Parquet metadata key of what computed a part file (:func:`process_numerics` of the process that weighed it)
NUMERICS_KEY = b"bogie.simulate.numerics"

#: a summary or progress line goes here; tests pass their own
Log = Callable[[str], None]


def _print(line: str) -> None:
    print(line, flush=True)


# ---- what determines a chunk's content -------------------------------------------------------------------------
def code_version() -> str:
    """A hash of the code and libraries that turn a sample row into a run row.

    The sources of every project module the simulate stage imports (:func:`pipeline.deps.project_files`, the same
    list as the stage's code dependencies in ``dvc.yaml``), plus the versions of numpy, scipy, numba, pandas and
    pyarrow, and the numerics digest of this process (:func:`bogie.digest.numerics_digest`: a machine that computes
    other last bits has another, and recomputes every part; :func:`process_numerics`). Any edit to those files
    invalidates every part file: a cosmetic edit costs a rerun, a missed physics change would cost a wrong dataset.
    An edit elsewhere (the CLI, the plotting, the report) changes nothing here. Each file is hashed with its path as
    numba's cache directory hashes bogie's (:func:`bogie.numba_cache.hash_sources`); the import graph follows
    subpackages, so a module of one that the stage imports is covered.
    """
    digest = hashlib.sha256()
    hash_sources(digest, project_files("pipeline.simulate"), ROOT)
    for module in (np, scipy, numba, pd, pa):
        digest.update(f"{module.__name__}={module.__version__}\0".encode())
    digest.update(f"numerics={process_numerics()}\0".encode())
    return digest.hexdigest()


@functools.lru_cache(maxsize=1)
def process_numerics() -> str:
    """What this process computes the runs with: its numerics digest (:func:`bogie.digest.numerics_digest`) and the
    CPU numba compiles for, as ``"<digest> <target>"``. A part file records the one of the process that computed it
    (:data:`NUMERICS_KEY`); the same on every x86-64 machine with AVX2 and FMA, so it keeps the files the same bytes.
    """
    return f"{numerics_digest()} {compile_target()}"


def _rows_digest(columns: Mapping[str, np.ndarray]) -> bytes:
    """The exact content of sample rows (every bit of every float), column by column from their arrays (a frame's
    ``to_numpy``, or a slice of a whole study's: the same values)."""
    digest = hashlib.sha256()
    for name in COLUMNS:
        values = columns[name]
        digest.update(f"{name}:{COLUMNS[name]}:{len(values)}\0".encode())
        if COLUMNS[name] == "str":
            digest.update("\x1f".join(map(str, values)).encode())
        else:
            digest.update(np.ascontiguousarray(values, dtype=COLUMNS[name]).tobytes())
    return digest.digest()


def chunk_hash(study: str, rows: Mapping[str, np.ndarray], protocols: Protocols, code: str) -> str:
    """The content hash of one part file: study, sample rows, protocols with their settings, code version.

    Parameters
    ----------
    study
        Study name.
    rows
        The chunk's sample rows: each column of :data:`bogie.fleet.sampling.sample.COLUMNS` as an array.
    protocols
        The study's protocols in run order, each with its settings (SI).
    code
        :func:`code_version`.

    Returns
    -------
    str
        A hex SHA-256 digest.
    """
    # json writes floats with repr, which round-trips every bit
    specs = json.dumps([[name, dataclasses.asdict(spec)] for name, spec in protocols], sort_keys=True)
    digest = hashlib.sha256(f"{study}\0{specs}\0{code}\0".encode())
    digest.update(_rows_digest(rows))
    # a row names a bogie file by its path: its bogie is part of the content (none for a study on presets alone)
    for label in sorted({str(v) for v in rows["preset"]} - set(PRESETS)):
        fields = json.dumps(base_fields(label), sort_keys=True)
        digest.update(f"{label}\0{fields}\0".encode())
    return digest.hexdigest()


# ---- the plan: chunks, their files and hashes ------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Chunk:
    """One task and its part file (compared by identity: it holds the sample rows).

    ``rows`` holds the chunk's samples column by column, each column of :data:`bogie.fleet.sampling.sample.COLUMNS` a
    list of Python values (what ``to_dict("records")`` gives): a task's argument that pickles in a tenth of the time a
    frame of the same rows takes, and that a worker reads without pandas.
    """

    study: str
    index: int
    rows: dict[str, list]
    protocols: Protocols
    hash: str
    path: Path

    @property
    def n_runs(self) -> int:
        """Rows of its part file: samples times protocols [-]."""
        return len(self.rows["sample_id"]) * len(self.protocols)


def part_name(index: int) -> str:
    """File name of chunk ``index``: ``part-00003.parquet``."""
    return f"part-{index:05d}.parquet"


def plan_chunks(
    samples: Mapping[str, pd.DataFrame], protocols: Mapping[str, Protocols], chunk_size: int, out: Path
) -> list[Chunk]:
    """Split each study into chunks of ``chunk_size`` consecutive samples (by ``sample_id``) and hash each."""
    code = code_version()
    chunks = []
    for study, frame in samples.items():
        frame = frame.sort_values("sample_id", kind="stable").reset_index(drop=True)
        # the study's columns once: a chunk's rows and hash are slices of them (a frame's columns cost 20 us each to
        # get, a frame's slice 0.1-0.3 ms)
        columns = {name: frame[name].to_numpy() for name in COLUMNS}
        for index, start in enumerate(range(0, len(frame), chunk_size)):
            sliced = {name: values[start : start + chunk_size] for name, values in columns.items()}
            rows = {name: values.tolist() for name, values in sliced.items()}
            h = chunk_hash(study, sliced, protocols[study], code)
            chunks.append(Chunk(study, index, rows, protocols[study], h, out / f"study={study}" / part_name(index)))
    return chunks


def reconcile(
    chunks: Sequence[Chunk], out: Path, log: Log = _print
) -> tuple[list[Chunk], list[Chunk], list[Path], int]:
    """Compare the plan with the files in the marked dataset ``out``; delete every part of the stage's that does not
    belong to it.

    A part is kept only if its stored hash matches its chunk's and it reads back whole
    (:func:`pipeline.schema.read_runs_content`: the SHA-256 of every byte, page statistics and footer included, every
    page's CRC32 and the runs schema's fields); a part with a changed byte is recomputed, with a log line. Only the
    stage's own files are deleted: a part's name in a ``study=*`` folder and a content hash in its metadata
    (:func:`is_own_part`), or the exact name of the stage's temporary. Any other file (a user's ``notes.txt`` or
    ``part-notes.txt``, which would stop pandas from reading the dataset, or a part's name on a file without the
    stage's metadata) is moved to ``<out parent>/.quarantine/<out name>/`` under a name no earlier quarantined file
    has, with a log line naming it, never deleted.

    Returns
    -------
    pending, done, removed, failed
        Chunks to compute, chunks whose file is up to date, the files deleted (parts of chunks that no longer
        exist or whose hash differs, damaged parts, temporary files of interrupted writes, and the parts of
        studies that are no longer simulated), and the failed runs in the files kept.
    """
    pending, done, failed = [], [], 0
    for chunk in chunks:
        kept = _kept_failures(chunk, log)
        if kept is None:
            pending.append(chunk)
        else:
            done.append(chunk)
            failed += kept
    keep = {c.path for c in done}
    removed = _sweep(out, keep, log) if out.is_dir() else []
    return pending, done, removed, failed


def _kept_failures(chunk: Chunk, log: Log) -> int | None:
    """The failed runs in ``chunk``'s part file if the file is up to date (see :func:`reconcile`), else None.

    One read of the file's bytes gives its hash, its verification (:func:`pipeline.schema.read_runs_content`: its
    SHA-256 over every byte, statistics and footer included, its pages' CRC32s, its fields) and its failures.
    """
    try:
        content = chunk.path.read_bytes()
        stored = (pq.read_metadata(pa.BufferReader(content)).metadata or {}).get(HASH_KEY)
    except (OSError, pa.ArrowException):
        return None  # no readable footer: another chunk's leftover or garbage, recomputed without a word
    if stored != chunk.hash.encode():
        return None
    try:
        table = read_runs_content(content, str(chunk.path))
    except RunsFileError as exc:
        log(f"simulate: {chunk.path} is damaged ({exc}); recomputing it")
        return None
    return failed_runs(table)


# ---- what the stage owns in its folder -------------------------------------------------------------------------
#: the file that makes a folder a runs dataset this stage made: the stage writes and sweeps no other folder
MARKER = ".bogie-runs"
#: the marker's format: the names, places and metadata of the parts (this module's)
MARKER_FORMAT = 1
_PART = re.compile(r"part-\d{5}\.parquet")
#: the temporary names of :func:`write_part` (:func:`pipeline.atomic.temporary_name` of a part)
_PART_TMP = re.compile(r"\.part-\d{5}\.parquet\.[a-z0-9_]{8}\.tmp")


class NotRunsDatasetError(RuntimeError):
    """The output folder is not a runs dataset the stage made: the stage touches nothing in it."""


def is_own_part(path: Path) -> bool:
    """Whether ``path`` is a part file the stage wrote: a Parquet footer whose metadata holds a content hash
    (:data:`HASH_KEY`, :func:`part_content`)."""
    try:
        return HASH_KEY in (pq.read_schema(path).metadata or {})
    except (OSError, pa.ArrowException):
        return False


def _kind(relative: Path) -> str | None:
    """What the stage's file at ``relative`` (to the dataset) is by its name and place: ``"marker"``,
    ``"temporary"`` (of a part or of the marker), ``"part"`` (if its content says so too: :func:`is_own_part`), or
    None: not a name the stage writes."""
    parts = relative.parts
    if parts == (MARKER,):
        return "marker"
    if len(parts) == 1 and temporary_name(MARKER).fullmatch(parts[0]):
        return "temporary"
    if len(parts) != 2 or not parts[0].startswith("study="):
        return None
    if _PART_TMP.fullmatch(parts[1]):
        return "temporary"
    return "part" if _PART.fullmatch(parts[1]) else None


def _files(out: Path) -> list[Path]:
    """Every entry of ``out`` but its directories (symbolic links are entries, never followed), relative, sorted."""
    found = []
    for root, dirs, files in os.walk(out):
        base = Path(root).relative_to(out)
        links = [d for d in dirs if os.path.islink(os.path.join(root, d))]
        dirs[:] = [d for d in dirs if d not in links]
        found += [base / name for name in (*files, *links)]
    return sorted(found)


def _marker_format(out: Path) -> object:
    try:
        return json.loads((out / MARKER).read_text(encoding="utf-8")).get("format")
    except (OSError, ValueError, AttributeError):
        return None


def _not_ours(out: Path) -> list[Path]:
    """The files of an unmarked ``out`` that are not the stage's (anything but parts, :func:`is_own_part`, and part
    temporaries in ``study=*`` folders), and its empty folders other than ``study=*``."""
    # an empty folder of someone else's counts too: out would not be empty without it
    foreign = [
        p
        for p in out.iterdir()
        if p.is_dir() and not p.is_symlink() and not p.name.startswith("study=") and not any(p.iterdir())
    ]
    for relative in _files(out):
        kind = _kind(relative)
        if kind != "temporary" and not (kind == "part" and is_own_part(out / relative)):
            foreign.append(out / relative)
    return sorted(set(foreign))


def check_runs_dir(out: Path) -> bool:
    """Refuse ``out`` unless the stage may write and sweep it; returns whether it carries the marker.

    The stage's folder is absent, empty, marked (:data:`MARKER`, written by :func:`claim_runs_dir`), or, written by
    the stage before the marker existed, holds nothing but the stage's parts. It reads, never writes.

    Raises
    ------
    NotRunsDatasetError
        Naming the folder and why (the first files the stage did not write), in one line.
    """
    if not os.path.lexists(out):
        return False
    if not out.is_dir():
        raise NotRunsDatasetError(f"{out} is not a folder: the runs dataset must be one")
    if os.path.lexists(out / MARKER):
        found = _marker_format(out)
        if found != MARKER_FORMAT:
            raise NotRunsDatasetError(
                f"{out} has a runs dataset marker {MARKER} of format {found!r}, and this stage writes format "
                f"{MARKER_FORMAT}: it touched nothing there; choose another folder for the runs"
            )
        return True
    foreign = _not_ours(out)
    if foreign:
        # the entries of out that hold them: .git rather than its 160 files
        tops = sorted({p.relative_to(out).parts[0] for p in foreign})
        names = ", ".join(tops[:3]) + (f" and {len(tops) - 3} more" if len(tops) > 3 else "")
        raise NotRunsDatasetError(
            f"{out} is not a runs dataset of this stage (it has no {MARKER}) and holds {len(foreign)} files the stage "
            f"did not write (in {names}): it touched nothing there; choose a new or empty folder for the runs, or "
            "move those files out"
        )
    return False


def claim_runs_dir(out: Path, log: Log) -> None:
    """Make ``out`` the stage's runs dataset: check it again (:func:`check_runs_dir`) and write the marker if it
    has none. Call it holding :func:`runs_lock`."""
    if check_runs_dir(out):
        return
    adopted = out.is_dir() and any(out.iterdir())
    out.mkdir(parents=True, exist_ok=True)
    with atomic_file(out / MARKER) as tmp:
        tmp.write_text(json.dumps({"format": MARKER_FORMAT, "written_by": "pipeline.simulate"}) + "\n")
    if adopted:
        log(f"simulate: {out} holds only part files of this stage: marked it as its runs dataset ({MARKER})")


def quarantine_dir(out: Path) -> Path:
    """Where the files of ``out`` the stage did not write go: ``<out's parent>/.quarantine/<out's name>``."""
    out = Path(os.path.abspath(out))  # "." has no name of its own
    return out.parent / ".quarantine" / out.name


def quarantine(path: Path, target: Path) -> Path:
    """Move ``path`` to ``target``, or to ``target.1``, ``target.2``, ... if that name is taken; returns where."""
    target.parent.mkdir(parents=True, exist_ok=True)
    candidate, n = target, 0
    while os.path.lexists(candidate):
        n += 1
        candidate = target.with_name(f"{target.name}.{n}")
    os.replace(path, candidate)
    return candidate


def _sweep(out: Path, keep: set[Path], log: Log) -> list[Path]:
    """Delete the stage's parts and temporaries in ``out`` not in ``keep``; quarantine every file the stage did not
    write (:func:`quarantine`), naming each. Call it holding :func:`runs_lock` on a marked ``out``: the lock proves
    that no writer of a temporary is alive."""
    removed = []
    for relative in _files(out):
        path = out / relative
        kind = _kind(relative)
        if path in keep or kind == "marker":
            continue
        if kind == "temporary" or (kind == "part" and is_own_part(path)):
            path.unlink()
            removed.append(path)
        else:
            target = quarantine(path, quarantine_dir(out) / relative)
            log(f"simulate: warning: {path} is not a file the stage wrote; moved it to {target}")
    for root, _, _ in os.walk(out, topdown=False):
        if Path(root) != out and not any(Path(root).iterdir()):
            Path(root).rmdir()
    return removed


def runs_lock(out: Path) -> AbstractContextManager[None]:
    """Hold an exclusive lock on the dataset ``out`` while the stage writes it (:func:`pipeline.atomic.output_lock`).

    Raises
    ------
    RunsLockedError
        If another process holds it: two stages writing one dataset would delete each other's temporary files.
    """
    return output_lock(out, "simulate")


#: another process is writing the runs dataset (:class:`pipeline.atomic.LockedError`, the one lock of every stage)
RunsLockedError = LockedError


def part_content(table: pa.Table, chunk_hash_: str, numerics: str) -> bytes:
    """A part file's bytes: the chunk's runs (:func:`pipeline.simulate.chunk_table`) with its hash and what computed
    it (``numerics``, :func:`process_numerics` of the weighing process) in the Parquet metadata
    (:func:`pipeline.schema.runs_file_content`)."""
    return runs_file_content(table, {HASH_KEY: chunk_hash_.encode(), NUMERICS_KEY: numerics.encode()})


def write_part(content: bytes, path: Path) -> None:
    """Write a part file (:func:`part_content`) atomically: temporary dot-name, then rename. Readers (pyarrow
    datasets) skip dot-files, and a rerun deletes a leftover temporary file.
    """
    write_file(content, path)
