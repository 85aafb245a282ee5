"""A file of weighings read in chunks (issue 41 Must 4): the bytes in blocks ending at a line end, gzip decompressed
as it goes, and what a whole-file read decides across records kept across the chunks.

- **Bytes.** :func:`blocks` yields the file's bytes (gunzipped, without a UTF-8 byte order mark) in blocks of about
  :data:`CHUNK_BYTES`, each ending at a line end, with the number of lines before it; a CSV file's header line is
  kept to put before every later block.
- **Repeats.** A record equal to an earlier good one (time, lane, direction, speed, axle loads and spacings) may be in
  an earlier chunk: each good record's key is hashed (:func:`key_hashes`, 64 bits, independent of the chunk's axle
  width) into a store by the day of the record's time stamp (:class:`SeenStore`: a repeat has its record's time, so
  its day; a file in time order keeps a day or two in memory, the days beyond wait on disk). Within a
  chunk, records are compared exactly, as a whole-file read does; across chunks, by their hashes: two different
  records share a 64-bit hash with probability about 2^-64 a pair, so that in 10^7 records the chance that any
  good record is taken for a repeat is about n^2 / 2^65 = 3e-6 (named as such in ``docs/weighings.md``).
"""

from __future__ import annotations

import shutil
import tempfile
import weakref
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from bogie.weighings._records import _BOM, _GZIP_MAGIC, _regular

__all__ = ["CHUNK_BYTES", "SeenStore", "blocks", "key_hashes"]

#: bytes of records parsed at a time [bytes]: 16 MiB, about 180,000 MON records; the parse's working memory is a
#: few times this, whatever the file's length
CHUNK_BYTES = 16 << 20
#: compressed bytes read from a gzip file at a time [bytes]
_READ_BYTES = 4 << 20


def _raw_blocks(path: Path, cap: int | None) -> Iterator[bytes]:
    """The file's bytes in pieces, gunzipped (every member; a bomb refused past ``cap`` bytes) if it starts with
    gzip's magic number."""
    with open(path, "rb") as fh:
        start = fh.read(2)
        if start != _GZIP_MAGIC:
            data = start + fh.read(CHUNK_BYTES)
            total = len(data)
            while data:
                if cap is not None and total > cap:
                    raise ValueError(f"{path}: more than {cap / 2**30:g} GiB (bogie.weighings._records.MAX_FILE_BYTES"
                                     "): split the survey into smaller files")  # fmt: skip
                yield data
                data = fh.read(CHUNK_BYTES)
                total += len(data)
            return
        pending = start + fh.read(_READ_BYTES)
        engine = zlib.decompressobj(wbits=31)
        total = 0
        while True:
            try:
                out = engine.decompress(pending, CHUNK_BYTES)
            except zlib.error as exc:
                raise ValueError(f"{path}: starts as a gzip file but does not decompress: {exc}") from None
            pending = engine.unconsumed_tail
            total += len(out)
            if cap is not None and total > cap:
                raise ValueError(f"{path}: decompresses to more than {cap / 2**30:g} GiB (bogie.weighings._records."
                                 "MAX_FILE_BYTES): split the survey into smaller files")  # fmt: skip
            if out:
                yield out
            if engine.eof:
                rest = engine.unused_data + pending + fh.read(_READ_BYTES)
                rest = rest.lstrip(b"\0")
                if rest[:2] != _GZIP_MAGIC:
                    return  # trailing bytes after the last member, as gzip itself ignores them
                engine, pending = zlib.decompressobj(wbits=31), rest
                continue
            if not pending:
                more = fh.read(_READ_BYTES)
                if not more:
                    if not out:
                        raise ValueError(f"{path}: starts as a gzip file but does not decompress: the compressed data "
                                         "end early")  # fmt: skip
                    continue
                pending = more


def blocks(path: str | Path, cap: int | None, chunk_bytes: int = CHUNK_BYTES) -> Iterator[tuple[bytes, int]]:
    """(block, lines before it): the file's bytes in blocks of about ``chunk_bytes`` ending at a line end (the last
    at the file's end), the byte order mark dropped; refused past ``cap`` bytes (compressed or not; None: any)."""
    path = Path(path)
    size = _regular(path).st_size
    if cap is not None and size > cap:
        raise ValueError(f"{path}: {size / 2**30:.2f} GiB is more than {cap / 2**30:g} GiB (bogie.weighings._records."
                         "MAX_FILE_BYTES): split the survey into smaller files")  # fmt: skip
    carry = b""
    lines_before = 0
    first = True
    for piece in _raw_blocks(path, cap):
        if first:
            piece = piece[3:] if piece[:3] == _BOM else piece  # a mark split across pieces is not expected: 3 bytes
            first = False
        carry += piece
        pos = 0
        while len(carry) - pos >= chunk_bytes:
            # the last line end within the next chunk_bytes, or the first after them (a longer line)
            cut = carry.rfind(b"\n", pos, pos + chunk_bytes)
            if cut < 0:
                cut = carry.find(b"\n", pos + chunk_bytes)
            if cut < 0:
                break
            block = carry[pos : cut + 1]
            yield block, lines_before
            lines_before += block.count(b"\n")
            pos = cut + 1
        carry = carry[pos:]
    if carry or first:
        yield carry, lines_before


# ---- repeats across chunks -----------------------------------------------------------------------------------------
def key_hashes(columns: list[np.ndarray], loads: np.ndarray, spacings: np.ndarray, n: np.ndarray) -> np.ndarray:
    """A 64-bit hash of each record's repeat key: the ``columns`` (time, lane, direction, speed, station), then its
    own ``n`` axle loads and ``n - 1`` spacings (slots past them not hashed, so that the hash does not depend on
    the widest vehicle of the chunk). Each value's 64 bits (a float's or an integer's; a string's pandas hash),
    folded FNV-1a-style and finished by a 64-bit mixer in one compiled pass; deterministic on every machine."""
    words = np.empty((len(n), len(columns)), np.uint64)
    for j, values in enumerate(columns):
        values = np.asarray(values)
        if values.dtype == object:
            words[:, j] = pd.util.hash_array(values)
        else:
            words[:, j] = values.astype(np.float64 if values.dtype.kind == "f" else np.int64).view(np.uint64)
    return _fold(words, np.ascontiguousarray(loads, np.float64).view(np.uint64),
                 np.ascontiguousarray(spacings, np.float64).view(np.uint64), np.asarray(n, np.int64))  # fmt: skip


@njit(cache=True, nogil=True)
def _fold(words, loads, spacings, n):  # pragma: no cover - compiled
    prime = np.uint64(0x100000001B3)
    out = np.empty(words.shape[0], np.uint64)
    for r in range(words.shape[0]):
        h = np.uint64(0xCBF29CE484222325)
        for j in range(words.shape[1]):
            h = (h ^ words[r, j]) * prime
        for i in range(min(n[r], loads.shape[1])):
            h = (h ^ loads[r, i]) * prime
        for i in range(min(n[r] - 1, spacings.shape[1])):
            h = (h ^ spacings[r, i]) * prime
        # splitmix64's finaliser: every input bit moves every output bit
        h = (h ^ (h >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        h = (h ^ (h >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        out[r] = h ^ (h >> np.uint64(31))
    return out


#: repeat hashes held in memory at most [-]: 2^22, 32 MiB; the days beyond wait on disk (:class:`SeenStore`)
SEEN_IN_MEMORY = 1 << 22


class SeenStore:
    """The hashes of the good records read so far, by the day of their time stamp: a repeat has its record's time,
    so it can only be in its own day's bucket. Each day is a sorted array of distinct hashes; when the days in
    memory hold more than ``in_memory`` hashes, those least recently used are written to a temporary directory and
    read back when a record of their day comes again. A file in time order (as WIM systems write them) keeps a day or
    two in memory whatever its length; a file in random order is as right but reads its days back often. Memory: at
    most ``in_memory`` hashes and the day in hand (8 bytes a hash); disk: 8 bytes a good record, removed by
    :meth:`close` (or when the store is collected)."""

    def __init__(self, in_memory: int = SEEN_IN_MEMORY) -> None:
        self.in_memory = in_memory
        self.days: dict[int, np.ndarray] = {}  # in the order of their last use, oldest first
        self.on_disk: set[int] = set()
        self.held = 0
        self.count = 0
        self._dir: Path | None = None
        self._cleanup: weakref.finalize | None = None

    def _path(self, day: int) -> Path:
        if self._dir is None:
            self._dir = Path(tempfile.mkdtemp(prefix="bogie-seen-"))
            self._cleanup = weakref.finalize(self, shutil.rmtree, self._dir, True)
        return self._dir / f"{day}.npy"

    def _day(self, day: int) -> np.ndarray:
        """The day's hashes, now the most recently used (read back from disk if they were written there)."""
        if day in self.days:
            hashes = self.days.pop(day)
        elif day in self.on_disk:
            path = self._path(day)
            hashes = np.load(path)
            path.unlink()
            self.on_disk.discard(day)
            self.held += len(hashes)
        else:
            hashes = np.zeros(0, np.uint64)
        self.days[day] = hashes
        return hashes

    def _evict(self, keep: int) -> None:
        """Write the least recently used days to disk until at most ``in_memory`` hashes are held (``keep`` stays)."""
        for day in list(self.days):
            if self.held <= self.in_memory:
                break
            if day == keep:
                continue
            hashes = self.days.pop(day)
            np.save(self._path(day), hashes)
            self.on_disk.add(day)
            self.held -= len(hashes)

    def _by_day(self, stamps: np.ndarray) -> Iterator[tuple[int, np.ndarray]]:
        days = np.asarray(stamps, "datetime64[D]").view(np.int64)
        if not len(days):
            return
        if days.min() == days.max():
            yield int(days[0]), np.arange(len(days))
            return
        order = np.argsort(days, kind="stable")
        bounds = np.flatnonzero(np.diff(days[order])) + 1
        for rows in np.split(order, bounds):
            yield int(days[rows[0]]), rows

    @staticmethod
    def _known(known: np.ndarray, hashes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whether each hash is in the sorted ``known``, and where it would go."""
        at = np.searchsorted(known, hashes)
        if not len(known):
            return np.zeros(len(hashes), bool), at
        return known[np.minimum(at, len(known) - 1)] == hashes, at

    def contains(self, stamps: np.ndarray, hashes: np.ndarray) -> np.ndarray:
        """Whether each hash (of a record of time stamp ``stamps``, numpy datetime64) is in the store."""
        found = np.zeros(len(hashes), bool)
        for day, rows in self._by_day(stamps):
            found[rows] = self._known(self._day(day), hashes[rows])[0]
            self._evict(day)
        return found

    def add(self, stamps: np.ndarray, hashes: np.ndarray) -> np.ndarray:
        """Add the hashes of records of time stamps ``stamps`` (datetime64; those already in stay once), and return
        whether each was in the store before this call (:meth:`contains`, in the same pass over the days)."""
        found = np.zeros(len(hashes), bool)
        for day, rows in self._by_day(stamps):
            known = self._day(day)
            found[rows] = self._known(known, hashes[rows])[0]
            new = np.unique(hashes[rows][~found[rows]])  # not yet in: put in place, a copy of the day, not a sort
            merged = np.insert(known, self._known(known, new)[1], new) if len(known) else new
            self.days[day] = merged
            self.held += len(merged) - len(known)
            self.count += len(merged) - len(known)
            self._evict(day)
        return found

    def close(self) -> None:
        """Remove the days written to disk."""
        if self._cleanup is not None:
            self._cleanup()
        self.days, self.on_disk, self.held = {}, set(), 0
