"""A file of weighings read in chunks (issue 41 Must 4): the bytes in blocks ending at a line end, gzip decompressed
as it goes, and what a whole-file read decides across records kept across the chunks.

- **Bytes.** :func:`blocks` yields the file's bytes (gunzipped, without a UTF-8 byte order mark) in blocks of about
  :data:`CHUNK_BYTES`, each ending at a line end, with the number of lines before it; a CSV file's header line is
  kept to put before every later block.
- **Repeats.** A record equal to an earlier good one (time, lane, direction, speed, axle loads and spacings) may be in
  an earlier chunk: each good record's key is hashed (:func:`key_hashes`, 64 bits, independent of the chunk's axle
  width) into a compiled open-addressing set (:class:`SeenSet`, 11-23 bytes a record, at most 70 % full). Within a
  chunk, records are compared exactly, as a whole-file read does; across chunks, by their hashes: two different
  records share a 64-bit hash with probability about 2^-64 a pair, so that in 10^7 records the chance that any
  good record is taken for a repeat is about n^2 / 2^65 = 3e-6 (named as such in ``docs/weighings.md``).
"""

from __future__ import annotations

import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
from numba import njit

from bogie.weighings._records import _BOM, _GZIP_MAGIC, _regular

__all__ = ["CHUNK_BYTES", "SeenSet", "blocks", "key_hashes"]

#: bytes of records parsed at a time [bytes]: 16 MiB, about 180,000 MON records; the parse's working memory is a
#: few times this, whatever the file's length
CHUNK_BYTES = 16 << 20
#: compressed bytes read from a gzip file at a time [bytes]
_READ_BYTES = 4 << 20


def _raw_blocks(path: Path, cap: int) -> Iterator[bytes]:
    """The file's bytes in pieces, gunzipped (every member; a bomb refused past ``cap`` bytes) if it starts with
    gzip's magic number."""
    with open(path, "rb") as fh:
        start = fh.read(2)
        if start != _GZIP_MAGIC:
            data = start + fh.read(CHUNK_BYTES)
            total = len(data)
            while data:
                if total > cap:
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
            if total > cap:
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


def blocks(path: str | Path, cap: int, chunk_bytes: int = CHUNK_BYTES) -> Iterator[tuple[bytes, int]]:
    """(block, lines before it): the file's bytes in blocks of about ``chunk_bytes`` ending at a line end (the last
    at the file's end), the byte order mark dropped; refused past ``cap`` bytes (compressed or not)."""
    path = Path(path)
    size = _regular(path).st_size
    if size > cap:
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


@njit(cache=True)
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


@njit(cache=True)
def _probe(table, hashes, insert, found):  # pragma: no cover - compiled
    """Look each hash up in the open-addressing ``table`` (0: empty; a hash of 0 stored as 1) and, where ``insert``,
    add it; ``found[i]``: the hash was there before. Returns the number added."""
    mask = np.uint64(table.shape[0] - 1)
    one = np.uint64(1)
    added = 0
    for i in range(hashes.shape[0]):
        h = hashes[i]
        if h == 0:
            h = one
        j = (h ^ (h >> np.uint64(29))) & mask
        while True:
            t = table[np.int64(j)]
            if t == 0:
                if insert[i]:
                    table[np.int64(j)] = h
                    added += 1
                break
            if t == h:
                found[i] = True
                break
            j = (j + one) & mask
    return added


class SeenSet:
    """The hashes of the good records read so far: at most 70 % full (linear probing's few probes a lookup),
    doubled and rehashed when it would be more: 11-23 bytes a record."""

    def __init__(self) -> None:
        self.table = np.zeros(1 << 16, np.uint64)
        self.count = 0

    def contains(self, hashes: np.ndarray) -> np.ndarray:
        """Whether each hash is in the set."""
        found = np.zeros(len(hashes), bool)
        _probe(self.table, hashes, np.zeros(len(hashes), bool), found)
        return found

    def add(self, hashes: np.ndarray) -> None:
        """Add the hashes (those already in stay once)."""
        while 10 * (self.count + len(hashes)) > 7 * len(self.table):
            old = self.table[self.table != 0]
            self.table = np.zeros(2 * len(self.table), np.uint64)
            _probe(self.table, old, np.ones(len(old), bool), np.zeros(len(old), bool))
        self.count += _probe(self.table, hashes, np.ones(len(hashes), bool), np.zeros(len(hashes), bool))

    @property
    def nbytes(self) -> int:
        return int(self.table.nbytes)
