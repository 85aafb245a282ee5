"""Readers of observed weighings: the documented CSV layout and the fixed-width WIM formats (``formats.py``).

:func:`read_weighings` returns one row per vehicle in SI units (kg, m, m/s) and the count of every record it
skipped, by reason, with the first few line numbers, and the file's weight resolution. A bad record (shorter than
its stated axles need, a character that is not a digit or a space, no axles, a direction code the format does not
have, a date that does not exist or an implausible year, an implausible weight, spacing, speed or lane, a gross
weight that is not the sum of the axles, a length shorter than the wheelbase, a repeat of an earlier record; a
longer line, padded past its stated axles, is normal) is skipped and counted, never silently; a file that is empty,
mostly bad (more than half its records) or in another format is refused with a :class:`ValueError` that names the
format expected and what was found. Layouts and bounds: ``docs/weighings.md``.

The bytes are parsed in bulk (issue 27 Must 5): the file is one numpy byte array, its records are located by their
line ends, and every field of every record is read with one gather per field (per axle slot for the axle fields),
never line by line in Python. Records end at ``\\n`` only (a trailing ``\\r`` is dropped): a form feed, a vertical tab
or a Unicode line separator inside a record is a bad character of that record, not a line end, so that line numbers
are those of any editor that counts ``\\n``. A file whose first two bytes are gzip's magic number is decompressed first.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings import _records
from bogie.weighings._checks import _alike, _check_vehicles, _flag_repeats
from bogie.weighings._csv import _parse_csv
from bogie.weighings._fixed import _parse_fixed
from bogie.weighings._records import (
    AXLE_LOAD_RANGE,
    CSV_LANE_RANGE,
    CSV_MAX_AXLES,
    EXAMPLES,
    MAX_AXLES,
    MAX_BAD_FRACTION,
    MAX_FILE_BYTES,
    MEMORY_PER_BYTE,
    SNIFF_LINES,
    SPACING_RANGE,
    SPEED_RANGE,
    SURVEY_BASE_MEMORY,
    YEAR_RANGE,
    _head,
    _Reasons,
    _shown,
    _split,
    _timestamps,
    survey_memory,
    uncompressed_size,
)
from bogie.weighings._stream import CHUNK_BYTES, SeenStore, blocks
from bogie.weighings._tmg import ALIKE, TMG_LAYOUTS, parse_tmg, split_dummies
from bogie.weighings.formats import FORMATS, LAYOUTS
from bogie.weighings.resolution import (
    WEIGHT_STEPS_KG,
    ResidueCounts,
    Resolution,
    check_resolution_kg,
    detect_resolution,
)

__all__ = [
    "AXLE_LOAD_RANGE", "CSV_LANE_RANGE", "CSV_MAX_AXLES", "MAX_AXLES", "MAX_BAD_FRACTION", "SNIFF_LINES",
    "SPACING_RANGE", "SPEED_RANGE", "WEIGHT_STEPS_KG", "YEAR_RANGE", "ReadResult", "detect_format", "read_weighings",
    "stream_weighings", "MAX_FILE_BYTES", "MEMORY_PER_BYTE", "SURVEY_BASE_MEMORY", "survey_memory",
    "uncompressed_size",
]  # fmt: skip


@dataclass
class ReadResult:
    """What :func:`read_weighings` read.

    Attributes
    ----------
    vehicles
        One row per good record: ``line`` (1-based line of the file), ``head`` (an integer; '' in CSV),
        ``timestamp``, ``speed`` [m/s], ``gross_weight`` [kg], ``length`` [m] (NaN where the format has none),
        ``n_axles``, ``n_groups`` (MON's own count; NaN otherwise), ``lane`` (1-based; -1 not given),
        ``direction`` (1 or 2 in every format: a zero-based code, BeDIT's and MON's 0 or 1, plus 1; -1 not
        given), ``transverse_position`` [m] (NaN where not given), ``axle_load_1..`` [kg] (front first) and
        ``spacing_1..`` [m] (``spacing_i`` between axles i and i + 1), NaN past the vehicle's axles; DITIS also
        ``axle_width_1..`` [m].
    format
        The format read (``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``).
    skipped
        Bad records per reason.
    bad_lines
        The first :data:`EXAMPLES` line numbers of each reason.
    resolution
        The file's weight resolution (:class:`bogie.weighings.resolution.Resolution`): detected from the axle loads
        of the records that passed the checks before the gross weight's, tolerant of a one-unit offset (loads
        ending in 00 or 99 are a 100 kg file), or set by the caller; its evidence and its source.
    weight_step_kg
        The resolution in use [kg] (``resolution.step_kg``); None when the loads are not whole kilograms (a CSV
        file of other data) or no record has loads.
    format_step_kg
        The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None for
        CSV (decimal numbers).
    """

    vehicles: pd.DataFrame
    format: str
    skipped: Counter = field(default_factory=Counter)
    bad_lines: dict[str, list[int]] = field(default_factory=dict)
    resolution: Resolution | None = None
    counted: dict[str, int] = field(default_factory=dict)
    n_vehicles: int | None = None

    @property
    def weight_step_kg(self) -> float | None:
        """The weight resolution in use [kg] (None: none)."""
        return None if self.resolution is None else self.resolution.step_kg

    @property
    def format_step_kg(self) -> float | None:
        """The step of the format's weight field [kg]: 1 for MON, 100 for CASTOR, BeDIT and DITIS (kg/100), None
        for CSV (decimal numbers)."""
        return _unit_kg(self.format)

    @property
    def n_read(self) -> int:
        """Good records [-] (``n_vehicles`` when the vehicles were streamed, not kept)."""
        return len(self.vehicles) if self.n_vehicles is None else self.n_vehicles

    @property
    def n_skipped(self) -> int:
        """Bad records, skipped [-]."""
        return sum(self.skipped.values())

    def reasons(self) -> str:
        """Each reason a record was skipped, its count and first line numbers; '' if none was."""
        return "; ".join(
            f"{reason}: {n}, line{'s' if n > 1 else ''} {', '.join(map(str, self.bad_lines[reason]))}"
            + (", ..." if n > len(self.bad_lines[reason]) else "")
            for reason, n in self.skipped.most_common()
        )

    def describe_resolution(self) -> str:
        """The weight resolution in words: the step, where it came from and how sure its detection is."""
        if self.resolution is None:
            return "weight resolution: none detected (no axle loads)"
        return self.resolution.describe()

    def summary(self) -> str:
        """One line: records read and skipped, each reason with its first line numbers; what else was counted."""
        text = f"{self.n_read} records read, {self.n_skipped} skipped"
        text += f" ({self.reasons()})" if self.skipped else ""
        return text + "".join(f"; {n} {what}" for what, n in self.counted.items())


# ---- the file ------------------------------------------------------------------------------------------------------
def _utf8(data: bytes) -> bytes:
    """``data`` if it is UTF-8; else decoded with U+FFFD for every undecodable byte and encoded again."""
    if data.isascii():
        return data
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("utf-8", errors="replace").encode("utf-8")
    return data


def _parse(data: bytes, fmt: str, path: str, gross_kg: float | None = None, seen: SeenStore | None = None) -> dict:
    """Parse every record of ``data`` in ``fmt`` and check it; a ValueError for a CSV header not the layout's.
    ``gross_kg``: the weight step the gross-weight check allows for (None: the one these records support);
    ``seen``: the hashes of the good records of earlier chunks (None: no earlier chunk)."""
    if fmt == "csv":
        data = _utf8(data)
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_csv(data, lines, path)
        stamps = parsed["stamps"]
    elif fmt in TMG_LAYOUTS:
        lines = _split(data)
        if not len(lines):
            return {}
        keep, dummies = split_dummies(lines, TMG_LAYOUTS[fmt])
        lines = lines.take(keep)
        parsed = parse_tmg(lines, TMG_LAYOUTS[fmt])
        parsed["line"] = lines.line
        parsed["counted"] = dummies
        stamps = None
    else:
        lines = _split(data)
        if not len(lines):
            return {}
        parsed = _parse_fixed(lines, LAYOUTS[fmt])
        parsed["line"] = lines.line
        stamps = None
    parsed["counts"], parsed["gross_kg"] = _check_vehicles(parsed, gross_kg)
    if stamps is None:
        stamps = _timestamps(parsed["reasons"].ok, *parsed["stamp"])
    if fmt in TMG_LAYOUTS:  # time stamps to the hour: alike trucks of one hour are vehicles, counted, not dropped
        alike = _alike(parsed, stamps, seen)
        if alike:
            parsed["counted"][ALIKE] = alike
    else:
        _flag_repeats(parsed, stamps, seen)
    parsed["stamps"] = stamps
    return parsed


def _frame(parsed: dict) -> pd.DataFrame:
    ok = parsed["reasons"].ok
    n = parsed["columns"]["n_axles"][ok]
    width = int(n.max()) if len(n) else 2
    col = parsed["columns"]
    base = {
        "line": parsed["line"][ok], "head": col["head"][ok], "timestamp": parsed["stamps"][ok],
        **{k: col[k][ok] for k in ("speed", "gross_weight", "length", "n_axles", "n_groups", "lane", "direction",
                                   "transverse_position")},
    }  # fmt: skip
    pad = max(0, width - parsed["loads"].shape[1])
    loads = np.pad(parsed["loads"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
    spacings = np.pad(parsed["spacings"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, : width - 1]
    extra = {f"axle_load_{i + 1}": loads[:, i] for i in range(width)}
    extra.update({f"spacing_{i + 1}": spacings[:, i] for i in range(width - 1)})
    for name, values in parsed.get("extra", {}).items():  # TMG: station, vehicle_class
        extra[name] = values[ok]
    if parsed["widths"] is not None:
        widths = np.pad(parsed["widths"][ok], ((0, 0), (0, pad)), constant_values=np.nan)[:, :width]
        extra.update({f"axle_width_{i + 1}": widths[:, i] for i in range(width)})
    # copy=False: the columns are fresh arrays; pandas would otherwise copy them into blocks (0.7 s a million rows)
    frame = pd.DataFrame({**base, **extra}, copy=False)
    frame["timestamp"] = frame["timestamp"].astype("datetime64[us]")
    frame["n_axles"] = frame["n_axles"].astype(np.int64)
    frame["line"] = frame["line"].astype(np.int64)
    frame["lane"] = frame["lane"].astype(np.int64)  # -1: not given (CSV)
    frame["direction"] = frame["direction"].astype(np.int64)  # 1 or 2; -1: not given (CSV)
    return frame


def _fits(head: bytes, fmt: str, path: str) -> tuple[int, int]:
    """(good, all) records of ``head`` in ``fmt``; a ValueError for a CSV header not the layout's."""
    parsed = _parse(head, fmt, path)
    if not parsed:
        return 0, 0
    ok = parsed["reasons"].ok
    # a TMG file's dummy hour records fit their edition: they are its records too, though not vehicles
    dummies = sum(n for what, n in parsed.get("counted", {}).items() if what.startswith("dummy"))
    return int(ok.sum()) + dummies, len(ok) + dummies


def _sniff(data: bytes, expected: str) -> str:
    """Which other known format the first lines parse as, for the refusal message ('' if none)."""
    head = _head(data, 20)
    for fmt in FORMATS:
        if fmt == expected:
            continue
        try:
            good, total = _fits(head, fmt, "")
        except ValueError:
            continue
        if total and good > total / 2:
            return f"; its first lines parse as {fmt} records (--format {fmt}?)"
    return ""


def _detect(head: bytes, path: str) -> str:
    fits, tried = [], []
    n_lines = 0
    for fmt in FORMATS:
        try:
            good, total = _fits(head, fmt, path)
        except ValueError:
            tried.append(f"{fmt}: not its header")
            continue
        n_lines = max(n_lines, total)
        tried.append(f"{fmt}: {good} of {total} good")
        if total and good > total / 2:
            fits.append(fmt)
    if len(fits) == 1:
        return fits[0]
    what = "no known format fits" if not fits else f"more than one format fits ({', '.join(fits)})"
    shown = len([line for line in head.split(b"\n") if line.strip()])
    raise ValueError(
        f"{path}: format auto: {what} the first {shown} non-blank lines ({'; '.join(tried)}); "
        f"name one with --format ({', '.join(FORMATS)})"
    )


def detect_format(lines: list[str], path: str = "") -> str:
    """The one known format in which more than half of the first :data:`SNIFF_LINES` non-blank lines are good
    records; a :class:`ValueError` naming the candidates when none or more than one fits."""
    data = "\n".join(lines).encode("utf-8", errors="replace")
    return _detect(_head(data, SNIFF_LINES), path)


def _unit_kg(fmt: str) -> float | None:
    """The weight unit of format ``fmt`` [kg]: its axle load field's scale; None for CSV (decimal numbers)."""
    if fmt in TMG_LAYOUTS:
        return TMG_LAYOUTS[fmt].weight_unit_kg
    return None if fmt == "csv" else LAYOUTS[fmt].axle_field("axle_load").scale


def _format_name(fmt: str) -> str:
    """How a message names the format's records: 'CSV layout', 'MON records', 'TMG 2001 records'."""
    if fmt == "csv":
        return "CSV layout"
    return f"{(TMG_LAYOUTS[fmt] if fmt in TMG_LAYOUTS else LAYOUTS[fmt]).name} records"


def read_weighings(
    path: str | Path, fmt: str = "auto", resolution_kg: float | None = None, chunk_bytes: int = CHUNK_BYTES
) -> ReadResult:
    """Read a file of weighings (one vehicle a record) in format ``fmt``.

    Parameters
    ----------
    path
        The file (text; fixed-width records one a line, or CSV with a header line); gzip-compressed or not (told by
        its first bytes, not its name).
    fmt
        ``csv``, ``mon``, ``castor``, ``bedit`` or ``ditis`` (layouts in ``docs/weighings.md``), or ``auto``
        (default): the one layout in which most of the first :data:`SNIFF_LINES` non-blank lines parse
        (:func:`detect_format`); ``ReadResult.format`` says which.
    resolution_kg
        The file's weight resolution [kg], in (0, 1000] and a whole multiple of the format's weight unit; None
        (default): detected from the loads (:mod:`bogie.weighings.resolution`), and reported either way.
    chunk_bytes
        Bytes of records parsed at a time (:func:`stream_weighings`); the result does not depend on it.

    Returns
    -------
    ReadResult
        The good records as a vehicle table (SI), the bad ones counted by reason, the weight resolution.

    Raises
    ------
    ValueError
        For an unknown format, an empty file, a file whose records are more than half bad or that is in another
        format (the message names the format expected and what was found), a gzip file that does not decompress.
    OSError
        If the file cannot be read.
    """
    frames: list[pd.DataFrame] = []

    def start() -> None:
        frames.clear()

    # the whole table is held: a file past MAX_FILE_BYTES is refused (stream it with stream_weighings)
    result = stream_weighings(path, fmt, resolution_kg, start, frames.append, chunk_bytes, _records.MAX_FILE_BYTES)
    result.vehicles = _concat(frames)
    return result


def _concat(frames: list[pd.DataFrame]) -> pd.DataFrame:
    """The chunks' vehicle tables as one, the axle columns of the widest (NaN where a chunk had fewer)."""
    if len(frames) == 1:
        return frames[0]
    frame = pd.concat(frames, ignore_index=True)
    axles = sorted((c for c in frame.columns if c.startswith(("axle_load_", "spacing_", "axle_width_"))),
                   key=lambda c: (c.rsplit("_", 1)[0], int(c.rsplit("_", 1)[1])))  # fmt: skip
    order = [c for c in frame.columns if not c.startswith(("axle_load_", "spacing_", "axle_width_"))]
    tail = [c for c in order if c in ("station", "vehicle_class")]
    head = [c for c in order if c not in tail]
    width = [c for c in axles if c.startswith("axle_load_")] + [c for c in axles if c.startswith("spacing_")]
    width += [c for c in axles if c.startswith("axle_width_")]
    return frame[head + width + tail]


def stream_weighings(
    path: str | Path,
    fmt: str,
    resolution_kg: float | None,
    start: Callable[[], None],
    consume: Callable[[pd.DataFrame], None],
    chunk_bytes: int = CHUNK_BYTES,
    max_bytes: int | None = None,
) -> ReadResult:
    """Read a file of weighings chunk by chunk (:mod:`bogie.weighings._stream`): ``consume`` gets each chunk's
    vehicle table (the good records, as :func:`read_weighings`' rows, in file order), and the result is
    :func:`read_weighings`' without its vehicles (``n_vehicles`` counts them).

    ``consume`` runs on a second thread while the next chunk is parsed: one call at a time, in file order, the next
    only once the last returned, and an error it raises stops the read and is raised here as it was; a consumer
    tied to its thread (a ``threading.local``, a sqlite3 connection made with ``check_same_thread``) must not be
    used. ``start`` runs on the calling thread, with no call of ``consume`` in flight.

    The gross-weight check allows for the file's weight resolution, which is known only at the end: the first
    chunk's is used, and if the whole file's differs, the file is read again with it (``start`` is called before
    every pass, so that the consumer begins afresh). The records are then those of a whole-file read, and so are
    the repeats (of an earlier chunk, by a 64-bit hash of their key). Memory: a few times ``chunk_bytes`` and at most
    :data:`bogie.weighings._stream.SEEN_IN_MEMORY` hashes of the good records (the rest on disk), whatever the file's
    length; ``max_bytes``: refuse a file of more bytes (None: any length; :func:`read_weighings`, which holds the
    whole table, refuses one past :data:`bogie.weighings._records.MAX_FILE_BYTES`).
    """
    if fmt != "auto" and fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} unknown; allowed: auto, {', '.join(FORMATS)}")
    check_resolution_kg(resolution_kg, None)  # its type and range before the file is read; its unit once known
    path = Path(path)
    first_block = next(blocks(path, max_bytes, chunk_bytes))[0]
    if fmt == "auto":
        fmt = _auto_format(path, first_block)
    name = _format_name(fmt)
    resolution_kg = check_resolution_kg(resolution_kg, _unit_kg(fmt))
    gross_kg = resolution_kg
    while True:
        start()
        tally = _pass(path, fmt, gross_kg, consume, chunk_bytes, first_block, max_bytes)
        if tally["records"] == 0:
            found = "a header and no record" if tally["header"] or _head(first_block, 1).strip() else "an empty file"
            if tally["counted"]:
                found = "dummy hour records only (" + "; ".join(f"{n} {w}" for w, n in tally["counted"].items()) + ")"
            raise ValueError(f"{path}: no records: expected {name} (format {fmt}), found {found}")
        resolution = detect_resolution(tally["counts"], resolution_kg)
        if resolution_kg is not None or resolution.step_kg == tally["gross_kg"]:
            break
        gross_kg = resolution.step_kg  # the first chunk's step was not the file's: read again with the file's
    result = ReadResult(pd.DataFrame(), fmt, tally["skipped"], tally["bad_lines"], resolution, tally["counted"],
                        tally["good"])  # fmt: skip
    total = result.n_read + result.n_skipped
    if result.n_skipped > MAX_BAD_FRACTION * total:
        first = _head(first_block, 1).decode("utf-8", errors="replace").rstrip()
        raise ValueError(
            f"{path}: not read as {name} (format {fmt}): {result.n_skipped} of {total} records bad "
            f"({result.reasons()}); first line {_shown(first)}" + _sniff(first_block, fmt)
        )
    return result


def _auto_format(path: Path, first_block: bytes) -> str:
    """The format of the file at ``path`` read with format ``auto``, from its first block (a ValueError for an
    empty file)."""
    head = _head(first_block, SNIFF_LINES)
    if not head.strip():
        raise ValueError(f"{path}: no records: format auto found an empty file")
    return _detect(head, str(path))


def _pass(
    path: Path, fmt: str, gross_kg: float | None, consume, chunk_bytes: int, first_block: bytes, max_bytes: int | None
) -> dict:
    """One pass over the file's chunks: each parsed and checked, and its vehicles consumed on a second thread while
    the next chunk is parsed (one chunk at a time, in file order: the consumer sees what a single thread would give
    it); the tallies of the pass."""
    seen = SeenStore()
    tally = {"records": 0, "good": 0, "header": False, "skipped": Counter(), "bad_lines": {}, "counted": Counter(),
             "counts": None}  # fmt: skip
    header = b""
    behind = None  # the chunk being consumed
    with ThreadPoolExecutor(1) as pool:
        for k, (block, lines_before) in enumerate(blocks(path, max_bytes, chunk_bytes)):
            data, offset = block, lines_before
            if fmt == "csv":
                if k == 0:
                    end = block.find(b"\n")
                    header = block[: end + 1] if end >= 0 else block + b"\n"
                else:
                    data, offset = header + block, lines_before - 1  # the header is line 1 of the chunk
            try:
                parsed = _parse(data, fmt, str(path), gross_kg, seen)
            except ValueError as exc:  # a CSV header that is not the layout's
                raise ValueError(f"{exc}{_sniff(first_block, fmt)}") from None
            if not parsed:
                continue
            if gross_kg is None:
                gross_kg = parsed["gross_kg"]  # the first chunk's resolution, for the chunks after it
            tally["gross_kg"] = gross_kg if k else parsed["gross_kg"]
            parsed["line"] = parsed["line"] + offset
            if _count(tally, parsed):
                if behind is not None:
                    behind.result()
                behind = pool.submit(consume, _frame(parsed))
        if behind is not None:
            behind.result()
    seen.close()  # on an exception, when the store is collected
    tally.update(counted=dict(tally["counted"]), counts=tally["counts"] or ResidueCounts(None))
    tally.setdefault("gross_kg", gross_kg)
    return tally


def _count(tally: dict, parsed: dict) -> bool:
    """Add a parsed chunk's records, skips (with their first lines), dummy records and weight residues to the pass's
    ``tally``; whether the chunk has a good record."""
    tally["header"] = True
    reasons: _Reasons = parsed["reasons"]
    tally["records"] += len(reasons.code)
    tally["good"] += int(reasons.ok.sum())
    chunk_skipped, chunk_lines = reasons.counted(parsed["line"])
    tally["skipped"].update(chunk_skipped)
    for reason, lines in chunk_lines.items():
        tally["bad_lines"][reason] = (tally["bad_lines"].get(reason, []) + lines)[:EXAMPLES]
    tally["counted"].update(parsed.get("counted", {}))
    if tally["counts"] is None:
        tally["counts"] = parsed["counts"]
    else:
        tally["counts"].merge(parsed["counts"])
    return bool(reasons.ok.any())
