"""The files of a survey and their site names (issue 46 Must 1): one file, a list, or a folder's files, each a site.

Light to import (no reader, no compiled code): the pipeline's configuration checks a folder with it before any stage
reads a record.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

__all__ = ["survey_files"]


def survey_files(path: str | Path | Sequence[str | Path]) -> list[tuple[Path, str | None]]:
    """The files of a survey and their site names: ``[(file, None)]`` for one file (or a list of one), as before
    issue 46; each file of a folder (even of one file) or a list of two or more, named by its file name (by its path
    as given where two names are alike).

    Raises
    ------
    ValueError
        A folder with no file, an empty list, a file given twice.
    """
    if isinstance(path, (str, Path)):
        path = Path(path)
        if not path.is_dir():
            return [(path, None)]
        files = sorted((p for p in path.iterdir() if p.is_file() and not _left_out(p.name)), key=lambda p: p.name)
        if not files:
            raise ValueError(
                f"path: the folder {path} holds no file of records (names beginning with '.' or ending '.dvc', and "
                "folders, are left out)"
            )
        return [(p, p.name) for p in files]
    given = [str(p) for p in path]
    if not given:
        raise ValueError("path: an empty list of files; give one file, a folder, or a list of files")
    twice = sorted({p for p in given if given.count(p) > 1})
    if twice:
        raise ValueError(f"path: a file given twice ({', '.join(twice)}); each file is one site")
    if len(given) == 1:
        return [(Path(given[0]), None)]
    names = [Path(p).name for p in given]
    return [(Path(p), n if names.count(n) == 1 else p) for p, n in zip(given, names)]


def _left_out(name: str) -> bool:
    """A name in a folder of survey files that is no site: hidden (``.gitignore``) or a DVC pointer (``a.mon.dvc``,
    beside the file ``dvc add`` tracks)."""
    return name.startswith(".") or name.endswith(".dvc")
