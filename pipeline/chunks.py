"""The runs dataset's chunks: what determines a part file's content, the plan of files, and their resumption.

:func:`plan_chunks` splits each study into chunks and hashes each (:func:`chunk_hash`: the sample rows, the protocols
and the code, :func:`code_version`); :func:`reconcile` keeps the part files whose stored hash matches and that read back
whole (:func:`pipeline.schema.read_runs_content`: the file's SHA-256 and its pages' CRC32s), counting their failed runs,
deletes the rest and quarantines files that are not ours; :func:`runs_lock` keeps a second process off the dataset;
:func:`part_content` makes a part file's bytes (in the worker that weighed the chunk) and :func:`write_part` writes them
atomically. The work itself, weighing a chunk's samples, is :func:`pipeline.simulate.chunk_table`.
"""

from __future__ import annotations

import dataclasses
import fcntl
import functools
import hashlib
import json
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import scipy

from bogie.digest import numerics_digest
from bogie.numerics import compile_target
from pipeline.config import StaticProtocol, WimProtocol
from pipeline.deps import ROOT, project_files
from pipeline.sample import COLUMNS
from pipeline.schema import RunsFileError, failed_runs, read_runs_content, runs_file_content, write_file

Spec = StaticProtocol | WimProtocol
#: a study's protocols in run order: (name, settings) pairs
Protocols = tuple[tuple[str, Spec], ...]

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
    An edit elsewhere (the CLI, the plotting, the report) changes nothing here.
    """
    digest = hashlib.sha256()
    for path in project_files("pipeline.simulate"):
        name = path.relative_to(ROOT).as_posix()
        digest.update(name.encode() + b"\0" + path.read_bytes() + b"\0")
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
        The chunk's sample rows: each column of :data:`pipeline.sample.COLUMNS` as an array.
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
    return digest.hexdigest()


# ---- the plan: chunks, their files and hashes ------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Chunk:
    """One task and its part file (compared by identity: it holds the sample rows).

    ``rows`` holds the chunk's samples column by column, each column of :data:`pipeline.sample.COLUMNS` a list of
    Python values (what ``to_dict("records")`` gives): a task's argument that pickles in a tenth of the time a frame
    of the same rows takes, and that a worker reads without pandas.
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
    """Compare the plan with the files in ``out``; delete every part that does not belong to it.

    A part is kept only if its stored hash matches its chunk's and it reads back whole
    (:func:`pipeline.schema.read_runs_content`: the SHA-256 of every byte, page statistics and footer included, every
    page's CRC32 and the runs schema's fields); a part with a changed byte is recomputed, with a log line. Any other
    file in ``out`` (a user's ``notes.txt``, which would stop pandas from reading the dataset) is moved to ``<out
    parent>/.quarantine/<out name>/`` with a log line, never deleted.

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


def _sweep(out: Path, keep: set[Path], log: Log) -> list[Path]:
    """Delete the parts and temporaries in ``out`` not in ``keep``; quarantine every file that is not ours."""
    removed = []
    quarantine = out.parent / ".quarantine" / out.name
    for path in sorted(out.rglob("*")):
        if path.is_dir() or path in keep:
            continue
        relative = path.relative_to(out)
        ours = len(relative.parts) == 2 and relative.parts[0].startswith("study=")
        ours = ours and path.name.startswith(("part-", ".part-"))
        if ours:
            path.unlink()
            removed.append(path)
        else:
            target = quarantine / relative
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(path, target)
            log(f"simulate: warning: {path} is not a part file of the runs dataset; moved it to {target}")
    for directory in sorted((d for d in out.rglob("*") if d.is_dir()), reverse=True):
        if not any(directory.iterdir()):
            directory.rmdir()
    return removed


@contextmanager
def runs_lock(out: Path) -> Iterator[None]:
    """Hold an exclusive lock on the dataset ``out`` (file ``<out>.lock`` beside it) while the stage writes it.

    Raises
    ------
    RunsLockedError
        If another process holds it: two stages writing one dataset would delete each other's temporary files.
    """
    out.parent.mkdir(parents=True, exist_ok=True)
    lock_path = out.parent / f".{out.name}.lock"
    with open(lock_path, "a+", encoding="utf-8") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "unknown"
            raise RunsLockedError(
                f"{out} is being written by another simulate process (pid {holder}, lock {lock_path}): wait for it "
                "to finish or stop it, then run again"
            ) from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        try:
            yield
        finally:
            handle.seek(0)
            handle.truncate()
            fcntl.flock(handle, fcntl.LOCK_UN)


class RunsLockedError(RuntimeError):
    """Another process is writing the runs dataset."""


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
