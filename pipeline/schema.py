"""The one schema of the runs dataset (``data/runs``): every column's type and unit, used to write and to read.

One row per sampled bogie and protocol: the sample's columns (:data:`bogie.fleet.sampling.sample.COLUMNS`, ``study``
being the partition directory), then the weighing's result. A failed weighing (``status = "failed"``, the reason in
``message``) has every result column null (NaN in pandas floats, ``<NA>`` in the booleans): never a made-up number,
so an unfiltered mean is NaN rather than silently wrong. A successful row has no null. Each field's unit is in its
Parquet field metadata (key ``unit``); the text columns are dictionary-encoded, so pandas reads them back as
categoricals.
"""

from __future__ import annotations

import functools
import hashlib
import os
import struct
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from bogie.fleet.weighing.runs import (
    CATEGORICAL,
    CATEGORIES,
    RESULT_COLUMNS,
    RUN_COLUMNS,
    SAMPLE_COLUMNS,
    UNITS,
    SchemaError,
    check_runs,
    conform,
    preset_categories,
    runs_frame,
)
from pipeline.atomic import atomic_file

__all__ = [
    "CATEGORICAL",
    "ChecksummedWriter",
    "CATEGORIES",
    "RESULT_COLUMNS",
    "RUNS_SCHEMA",
    "RUN_COLUMNS",
    "SAMPLE_COLUMNS",
    "UNITS",
    "CHECKSUM_KEY",
    "RunsFileError",
    "SchemaError",
    "check_file_schema",
    "checksummed_content",
    "check_runs",
    "check_table",
    "conform",
    "failed_runs",
    "read_runs_content",
    "read_runs_file",
    "read_runs_frame",
    "runs_frame",
    "runs_file_content",
    "runs_table",
    "table_from_rows",
    "write_file",
    "write_runs_file",
    "sealed",
]


def _arrow_type(dtype: str) -> pa.DataType:
    return {
        "int64": pa.int64(),
        "float64": pa.float64(),
        "str": pa.string(),
        "boolean": pa.bool_(),
        "category": pa.dictionary(pa.int32(), pa.string()),
    }[dtype]


#: the Arrow schema every part file is written with, each field's unit in its metadata
RUNS_SCHEMA: pa.Schema = pa.schema(
    [
        pa.field(name, _arrow_type(dtype), nullable=name in RESULT_COLUMNS, metadata={"unit": UNITS[name]})
        for name, dtype in RUN_COLUMNS.items()
    ]
)


class RunsFileError(SchemaError):
    """A part file of the runs dataset that does not read back as written: a changed byte, no checksum, no footer."""


def runs_table(frame: pd.DataFrame) -> pa.Table:
    """``frame`` as an Arrow table of :data:`RUNS_SCHEMA`, conformed and checked (:func:`check_runs`) first."""
    frame = conform(frame)
    check_runs(frame)
    return pa.Table.from_pandas(frame, schema=RUNS_SCHEMA, preserve_index=False)


#: each categorical column's dictionary (its categories in :data:`CATEGORIES`' order) and each label's index in it
_DICTIONARIES: dict[str, pa.Array] = {c: pa.array(labels, pa.string()) for c, labels in CATEGORIES.items()}
_CODES: dict[str, dict[str, int]] = {c: {v: i for i, v in enumerate(labels)} for c, labels in CATEGORIES.items()}


@functools.cache
def _pandas_metadata() -> bytes:
    """The ``pandas`` schema metadata that :func:`runs_table` gets from ``Table.from_pandas``.

    It describes the conformed frame's dtypes only, never its values, so an empty frame gives it; a table built
    without pandas carries it too, and its file is byte for byte the one the same rows give through pandas.
    """
    empty = conform(pd.DataFrame({c: pd.Series([], dtype=object) for c in RUN_COLUMNS}))
    return pa.Table.from_pandas(empty, schema=RUNS_SCHEMA, preserve_index=False).schema.metadata[b"pandas"]


def table_from_rows(rows: Sequence[Mapping[str, object]]) -> pa.Table:
    """Run rows as an Arrow table of :data:`RUNS_SCHEMA`: ``runs_table(runs_frame(rows))`` without pandas.

    The same table, metadata included, at a tenth of the cost (a chunk's frame took longer to build and convert
    than its rows take to weigh): each column straight from the rows' Python values, a missing key, None or NaN
    being a null as pandas makes it, each label coded by its index in its column's categories.

    Raises
    ------
    SchemaError
        If a label is not one of its column's categories. The nulls are :func:`check_table`'s to check.
    """
    arrays, unknown = [], {}
    for field in RUNS_SCHEMA:
        values = [row.get(field.name) for row in rows]
        if field.name not in _CODES:
            # from_pandas: NaN is a null, as in pandas
            arrays.append(pa.array(values, field.type, from_pandas=True))
            continue
        codes = _CODES[field.name]
        dictionary = _DICTIONARIES[field.name]
        if field.name == "preset" and not all(v in codes for v in values):
            # bogie files' paths after the presets' names (bogie.fleet.weighing.runs.preset_categories)
            labels = preset_categories([v for v in values if v is not None and v == v])
            codes, dictionary = {v: i for i, v in enumerate(labels)}, pa.array(labels, pa.string())
        # a null label (None or NaN) stays null; an unknown one is collected for the error
        indices = [None if v is None or v != v else codes.get(v, -1) for v in values]
        if -1 in indices:
            unknown[field.name] = sorted({str(v) for v, i in zip(values, indices) if i == -1})
        arrays.append(pa.DictionaryArray.from_arrays(pa.array(indices, pa.int32()), dictionary))
    if unknown:
        raise SchemaError(f"run rows with labels outside the schema's categories: {unknown}")
    return pa.Table.from_arrays(arrays, schema=RUNS_SCHEMA.with_metadata({b"pandas": _pandas_metadata()}))


def check_table(table: pa.Table, where: str = "the runs") -> None:
    """:func:`check_runs` for an Arrow table of :data:`RUNS_SCHEMA`: the schema's fields and types, and its nulls.

    Raises
    ------
    SchemaError
        Naming the fields of another type, or the columns and the number of rows that break the null rule.
    """
    if not table.schema.equals(RUNS_SCHEMA):
        check_file_schema(table.schema, where)  # names the fields missing, extra or of another type
        raise SchemaError(f"{where} do not have the runs schema's column order or nullability")
    problems = [f"{c} null in {n} rows" for c in RUN_COLUMNS if c not in RESULT_COLUMNS
                if (n := table.column(c).null_count)]  # fmt: skip
    ok = np.asarray(table.column("status").to_numpy(zero_copy_only=False) == "ok", dtype=bool)
    n_failed = len(ok) - int(ok.sum())
    nulls, filled = {}, {}
    for c in RESULT_COLUMNS:
        column = table.column(c)
        if column.null_count == n_failed == 0:
            continue  # the usual chunk: no failed run and no null, nothing to locate
        valid = np.asarray(column.is_valid().to_numpy(zero_copy_only=False), dtype=bool)
        nulls[c], filled[c] = int((ok & ~valid).sum()), int((~ok & valid).sum())
    problems += [f"{c} null in {n} successful rows" for c, n in nulls.items() if n]
    problems += [f"{c} set in {n} failed rows (must be null)" for c, n in filled.items() if n]
    if problems:
        raise SchemaError(f"{where} break the runs schema: {'; '.join(problems)}")


#: Parquet metadata key of a part file's checksum: the SHA-256 of every byte of the file, this value read as
#: :data:`_UNSEALED` (:func:`runs_file_content`, :func:`read_runs_content`)
CHECKSUM_KEY = b"bogie.runs.sha256"
#: the checksum's value while the file is hashed: 64 characters, as long as a hex SHA-256 digest
_UNSEALED = b"0" * 64
#: the Thrift compact encoding between a key and its 64-byte value in the footer: a binary field 2 (0x18) of length
#: 64 (varint 0x40)
_VALUE_HEADER = b"\x18\x40"


def runs_file_content(table: pa.Table, metadata: Mapping[bytes, bytes] | None = None) -> bytes:
    """The Parquet file of an Arrow table of run rows (:func:`runs_table`, :func:`table_from_rows`), checked
    (:func:`check_table`), with extra schema metadata: what :func:`write_runs_file` writes, as bytes a process can
    pass to the one that writes the file.

    The file carries two checksums. Every page's CRC32 (Parquet's page checksum) covers the pages' data; the file's
    SHA-256 under :data:`CHECKSUM_KEY` covers every byte, page headers (their statistics), the footer (the column
    statistics, the schema, every metadata value) and the data alike: the file is written with a placeholder of the
    digest's length, hashed, and the placeholder replaced by the digest. Every stage that reads runs verifies both
    (:func:`read_runs_content`).
    """
    check_table(table)
    if metadata:
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), **metadata})
    return checksummed_content(table)


def checksummed_content(table: pa.Table) -> bytes:
    """The Parquet file of any Arrow table with the checksums of a part file (:func:`runs_file_content`, which checks
    the table first): a test's way to a file that verifies but holds other columns or nulls."""
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), CHECKSUM_KEY: _UNSEALED})
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink, write_page_checksum=True)
    return sealed(sink.getvalue().to_pybytes())


class ChecksummedWriter:
    """A Parquet file written to ``path`` a table at a time (one row group each), with the checksums of a part file
    (:func:`checksummed_content`, the same bytes) once :meth:`close` seals it in place: a stage's output that a
    streamed input fills, never held in memory whole."""

    def __init__(self, schema: pa.Schema, path: str | Path) -> None:
        self.path = Path(path)
        schema = schema.with_metadata({**(schema.metadata or {}), CHECKSUM_KEY: _UNSEALED})
        self.schema = schema
        self.writer = pq.ParquetWriter(str(self.path), schema, write_page_checksum=True)
        self.rows = 0

    def write(self, table: pa.Table) -> None:
        self.writer.write_table(table.replace_schema_metadata(self.schema.metadata))
        self.rows += table.num_rows

    def close(self) -> Path:
        """Close the file and seal it: its digest (the file hashed with the placeholder, as it is) written over the
        placeholder. Returns its path."""
        self.writer.close()
        with open(self.path, "r+b") as fh:
            size = fh.seek(0, os.SEEK_END)
            fh.seek(size - 8)
            (length,) = struct.unpack("<I", fh.read(4))
            start = size - 8 - length
            fh.seek(start)
            at = _checksum_offset(fh.read(length + 8), _UNSEALED)
            if at is None:  # a pyarrow that encodes the footer otherwise: no file without its checksum
                raise RuntimeError(
                    f"pyarrow {pa.__version__} did not write {CHECKSUM_KEY.decode()} where it is looked for"
                )
            fh.seek(0)
            digest = hashlib.sha256()
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
            fh.seek(start + at)
            fh.write(digest.hexdigest().encode())
        return self.path


def sealed(content: bytes) -> bytes:
    """``content``, a Parquet file written with the checksum's placeholder in its metadata, with the checksum."""
    at = _checksum_offset(content, _UNSEALED)
    if at is None:  # a pyarrow that encodes the footer otherwise: no file without its checksum
        raise RuntimeError(f"pyarrow {pa.__version__} did not write {CHECKSUM_KEY.decode()} where it is looked for")
    return content[:at] + _file_digest(content, at) + content[at + len(_UNSEALED) :]


def _file_digest(content: bytes, at: int) -> bytes:
    """The hex SHA-256 of ``content`` with the checksum's value at ``at`` read as :data:`_UNSEALED`."""
    view = memoryview(content)
    digest = hashlib.sha256(view[:at])
    digest.update(_UNSEALED)
    digest.update(view[at + len(_UNSEALED) :])
    return digest.hexdigest().encode()


def _checksum_offset(content: bytes, value: bytes) -> int | None:
    """Where the checksum's ``value`` lies in the footer of the Parquet file ``content``, if once there."""
    (length,) = struct.unpack("<I", content[-8:-4])
    start = len(content) - 8 - length
    needle = CHECKSUM_KEY + _VALUE_HEADER + value
    at = content.find(needle, start)
    if at < 0 or content.find(needle, at + 1) >= 0:
        return None
    return at + len(CHECKSUM_KEY) + len(_VALUE_HEADER)


def verified_table(content: bytes, where: str, rerun: str) -> pa.Table:
    """The Arrow table of the Parquet file ``content`` (named ``where`` in errors) written by
    :func:`checksummed_content`, verified: its SHA-256 (:data:`CHECKSUM_KEY`) must match its bytes and every page's
    CRC32 its data. ``rerun`` says what to do about a damaged file (``delete it and rerun the sample stage``).

    Raises
    ------
    RunsFileError
        Naming ``where`` and what failed.
    """
    if len(content) < 12 or content[:4] != b"PAR1" or content[-4:] != b"PAR1":
        raise RunsFileError(f"{where} is not a whole Parquet file (no PAR1 marks at both ends): {rerun}")
    try:
        stored = (pq.read_metadata(pa.BufferReader(content)).metadata or {}).get(CHECKSUM_KEY)
    except (OSError, pa.ArrowException) as exc:
        raise RunsFileError(f"{where} is damaged: its footer does not read ({exc}); {rerun}") from None
    if stored is None:
        raise RunsFileError(
            f"{where} carries no checksum (metadata key {CHECKSUM_KEY.decode()}): not written by this version of the "
            f"pipeline; {rerun}"
        )
    at = _checksum_offset(content, stored)
    if at is None or _file_digest(content, at) != stored:
        raise RunsFileError(
            f"{where} is damaged: its SHA-256 does not match the checksum it carries (a changed byte in a data page, "
            f"a page's statistics or the footer); {rerun}"
        )
    try:
        return pq.ParquetFile(pa.BufferReader(content), page_checksum_verification=True).read()
    except (OSError, pa.ArrowException) as exc:
        raise RunsFileError(f"{where} is damaged: {exc}; {rerun}") from None


def read_checksummed(path: str | Path, rerun: str) -> pa.Table:
    """:func:`verified_table` of the file ``path``: every Parquet file a stage writes for another to read (samples,
    observed groups, survey tables) carries the checksums of a part file and is read through this.

    Raises
    ------
    RunsFileError
        Naming the file, what failed and ``rerun``.
    OSError
        If the file cannot be read.
    """
    return verified_table(Path(path).read_bytes(), str(path), rerun)


def write_checksummed(frame: pd.DataFrame | pa.Table, path: str | Path) -> None:
    """Write a frame or an Arrow table to the Parquet file ``path`` with a part file's checksums
    (:func:`checksummed_content`), atomically; read it back with :func:`read_checksummed`."""
    table = frame if isinstance(frame, pa.Table) else pa.Table.from_pandas(frame, preserve_index=False)
    write_file(checksummed_content(table), path)


def read_runs_content(content: bytes, where: str) -> pa.Table:
    """The runs table of the part file ``content`` (named ``where`` in errors), verified.

    The file's SHA-256 (:data:`CHECKSUM_KEY`) must match its bytes, every page's CRC32 its data
    (:func:`verified_table`), and its fields the runs schema's (:func:`check_file_schema`). A changed bit anywhere, in
    a data page, a page's statistics or the footer, is an error, not a silently different number.

    Raises
    ------
    RunsFileError
        Naming ``where`` and what failed.
    """
    table = verified_table(content, where, "delete it and rerun the simulate stage (make repro) to recompute it")
    check_file_schema(table.schema, where)
    return table


def read_runs_file(path: str | Path) -> pa.Table:
    """The runs table of the part file ``path``, verified (:func:`read_runs_content`).

    Raises
    ------
    RunsFileError
        Naming the file and what failed.
    OSError
        If the file cannot be read.
    """
    return read_runs_content(Path(path).read_bytes(), str(path))


def read_runs_frame(
    runs_dir: str | Path, study: str | None = None, columns: Sequence[str] | None = None
) -> pd.DataFrame:
    """The runs of one study (None: of every study) of the dataset ``runs_dir``, every part file verified
    (:func:`read_runs_file`; a file in a study's directory that is not a part fails too): what
    ``pd.read_parquet(runs_dir, filters=[("study", "==", study)])`` gives (the ``study`` column last, as text),
    ``columns`` and ``study`` alone if ``columns`` is given.

    Raises
    ------
    RunsFileError
        Naming the first part file that fails verification and what failed, or if there is none.
    OSError
        If a file cannot be read.
    """
    runs_dir = Path(runs_dir)
    # every file pyarrow's dataset reads (it skips names starting with a dot or an underscore): a stray file fails
    paths = sorted(p for p in runs_dir.glob(f"study={study if study is not None else '*'}/*")
                   if not p.name.startswith((".", "_")) and not p.is_dir())  # fmt: skip
    frames = []
    for path in paths:
        table = read_runs_file(path)
        table = table.select(list(columns)) if columns is not None else table
        frame = table.to_pandas()
        frame["study"] = path.parent.name.removeprefix("study=")
        frames.append(frame)
    if not frames:
        what = f"study {study!r}" if study is not None else "any study"
        raise RunsFileError(f"{runs_dir}/ holds no part file of {what}; run the simulate stage first")
    runs = pd.concat(frames, ignore_index=True)
    if "preset" in runs and not isinstance(runs["preset"].dtype, pd.CategoricalDtype):
        # parts that name other bogie files (or none) have other dictionaries, which concat turns into text
        runs["preset"] = runs["preset"].astype(pd.CategoricalDtype(preset_categories(runs["preset"])))
    return runs


def write_file(content: bytes, path: str | Path) -> None:
    """Write ``content`` to ``path`` atomically (:func:`pipeline.atomic.atomic_file`)."""
    with atomic_file(path) as tmp:
        tmp.write_bytes(content)


def write_runs_file(frame: pd.DataFrame, path: str | Path, metadata: Mapping[bytes, bytes] | None = None) -> None:
    """Write run rows to the Parquet file ``path`` in the runs schema, atomically, with extra schema metadata."""
    write_file(runs_file_content(runs_table(frame), metadata), path)


def failed_runs(table: pa.Table) -> int:
    """The rows of a runs table whose status is not ``ok``."""
    return int((table.column("status").to_numpy(zero_copy_only=False) != "ok").sum())


def check_file_schema(schema: pa.Schema, where: str) -> None:
    """Check that a part file's Arrow schema has the runs schema's fields and types (``study`` aside).

    Raises
    ------
    SchemaError
        Naming the fields that are missing, extra or of another type.
    """
    theirs = {f.name: f.type for f in schema if f.name != "study"}
    ours = {f.name: f.type for f in RUNS_SCHEMA}
    problems = [f"{n} missing" for n in ours if n not in theirs]
    problems += [f"{n} not in the schema" for n in theirs if n not in ours]
    problems += [f"{n} is {theirs[n]}, not {t}" for n, t in ours.items() if n in theirs and theirs[n] != t]
    if problems:
        raise SchemaError(f"{where} is not a runs file of this version: {'; '.join(problems)}; rerun simulate")
