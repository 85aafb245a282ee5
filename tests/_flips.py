"""One bit flipped in a part file of the runs dataset, at each kind of place (issue 28, item 4).

Each function flips one bit of the file ``path`` in place and returns the byte offset. The places are found from the
file's own footer (``pyarrow.parquet.read_metadata``), in the column ``max_deviation`` (a float with a statistic in
every page header and in the footer): a value in its dictionary page (what the survey averages), its data page's
header statistics, its column statistics in the footer, and a value of the footer's key-value metadata (the pandas
version in the ``pandas`` entry, which no reader needs: a flip there changes no number and only a checksum over the
footer sees it).
"""

from __future__ import annotations

import struct
from pathlib import Path

import pyarrow.parquet as pq

COLUMN = "max_deviation"
#: every place :func:`flip` knows
PLACES = ("data page", "page statistics", "footer statistics", "footer metadata")


def _footer_start(content: bytes) -> int:
    (length,) = struct.unpack("<I", content[-8:-4])
    return len(content) - 8 - length


def _chunk(path: Path):
    metadata = pq.read_metadata(path)
    names = [metadata.schema.column(i).name for i in range(metadata.num_columns)]
    return metadata.row_group(0).column(names.index(COLUMN))


def offset(path: str | Path, place: str) -> int:
    """The byte of ``path`` that :func:`flip` changes for ``place`` (one of :data:`PLACES`)."""
    path = Path(path)
    content = path.read_bytes()
    chunk = _chunk(path)
    largest = struct.pack("<d", chunk.statistics.max)
    if place == "data page":
        # the largest value in the dictionary page (the column's values; its indices follow in the data page)
        start = chunk.dictionary_page_offset
        at = content.find(largest, start, chunk.data_page_offset)
        return at + 6  # a bit of the mantissa's top byte: the value changes by a few per cent, no NaN, no error
    if place == "page statistics":
        at = content.find(largest, chunk.data_page_offset, chunk.data_page_offset + 64)  # in the page header
        assert at > 0, "no statistics in the data page header"
        return at + 6
    if place == "footer statistics":
        at = content.find(largest, _footer_start(content))
        assert at > 0
        return at + 6
    if place == "footer metadata":
        needle = b'"pandas_version": "'
        at = content.find(needle, _footer_start(content))
        assert at > 0
        return at + len(needle)  # the version's first digit
    raise ValueError(f"place must be one of {PLACES}, not {place!r}")


def flip(path: str | Path, place: str) -> int:
    """Flip the lowest bit of the byte :func:`offset` names; returns its offset."""
    path = Path(path)
    at = offset(path, place)
    content = bytearray(path.read_bytes())
    content[at] ^= 0x01
    path.write_bytes(bytes(content))
    return at
