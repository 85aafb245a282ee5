"""A survey of several files (issue 46 Must 1): each file a site, read one after another into one tally.

- **The files** (:func:`bogie.weighings.files.survey_files`): a list of files, or a folder (its files, in name
  order, but for hidden ones and DVC pointers; not its subfolders). Each is a site named by its file name, or by its
  path as given if two files share a name; a file of a station column (a state-wide TMG file) is a site per
  station, ``name:station``.
- **One read** (:func:`pooled_read`): the files' records, skips and dummy records summed; the first line numbers of
  each skip reason named by their file (``a.mon:12``). The files must be of one format and one weight resolution:
  a survey's statistics, and the simulated readings held against them, are at one resolution; the message says
  which file differs and how to give them (``resolution_kg``, or separate surveys). The pooled resolution's
  evidence (loads on, below and above a step) is the files' summed; its chance bound the product of the files'
  (their log10s summed: the files are independent draws).
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bogie.weighings._records import EXAMPLES
from bogie.weighings.readers import ReadResult

__all__ = ["check_alike", "file_entry", "pooled_read"]


def pooled_read(reads: Sequence[ReadResult], sites: Sequence[str]) -> ReadResult:
    """One :class:`ReadResult` of the files' ``reads`` (in their order; ``sites`` their names), each already held to
    the first by :func:`check_alike` as it was read: the module's "One read"."""
    first = reads[0]
    skipped: Counter = Counter()
    bad_lines: dict[str, list[Any]] = {}
    counted: Counter = Counter()
    for read, site in zip(reads, sites):
        skipped.update(read.skipped)
        counted.update(read.counted)
        for reason, lines in read.bad_lines.items():
            bad_lines[reason] = (bad_lines.get(reason, []) + [f"{site}:{line}" for line in lines])[:EXAMPLES]
    resolution = first.resolution
    if resolution is not None and all(r.resolution is not None for r in reads):
        resolution = dataclasses.replace(
            resolution, **{key: sum(getattr(r.resolution, key) for r in reads)
                           for key in ("n_loads", "on", "below", "above", "chance_log10")},
        )  # fmt: skip
    n = sum(r.n_read for r in reads)
    return ReadResult(first.vehicles.iloc[:0], first.format, skipped, bad_lines, resolution, dict(counted), n)


def check_alike(first: ReadResult, name: str, read: ReadResult, site: str) -> None:
    """Raise a ValueError if the file just read (``read``, named ``site``) differs in format or weight step from the
    survey's first (``first``, named ``name``)."""
    if read.format != first.format:
        raise ValueError(
            f"path: the files of one survey must be of one format: {name} is {first.format}, {site} is "
            f"{read.format}; survey them apart (bogie weighings with several files compares their sites)"
        )
    if read.weight_step_kg != first.weight_step_kg:
        raise ValueError(
            f"path: the files of one survey must be read at one weight resolution: {name} at "
            f"{_step(first.weight_step_kg)}, {site} at {_step(read.weight_step_kg)}; set resolution_kg to the "
            "coarser for all of them, or survey them apart"
        )


def _step(step_kg: float | None) -> str:
    return "none (loads not whole kilograms)" if step_kg is None else f"{step_kg:g} kg"


def file_entry(path: Path, site: str, read: ReadResult) -> dict[str, Any]:
    """What :attr:`bogie.weighings.survey.ObservedSurvey.files` says of one file: its path and site, the format read,
    its records read and skipped (by reason), its weight resolution [kg]."""
    return {
        "path": str(path), "site": site, "format": read.format,
        "records": {"read": read.n_read, "skipped": read.n_skipped, "weight_step_kg": read.weight_step_kg,
                    "skipped_by_reason": dict(sorted(read.skipped.items()))},
    }  # fmt: skip
