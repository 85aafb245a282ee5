"""All-or-nothing writes of a stage's outputs: every stage writes through :func:`atomic_outputs`.

Each output (a file or a directory) is first written under a temporary dot-name beside its final path, then all of
them replace their targets by renames once every one is complete. A reader sees the old outputs or the new ones,
never half a file; an exception while writing removes the temporaries and leaves the old outputs in place. Readers
that list a directory (pyarrow datasets) skip dot-names, and the stages delete leftover temporaries of a killed run.
Files and directories get the permissions of the user's umask (``tempfile`` would make them private).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_outputs", "atomic_file", "io_error", "replace_dir"]


def io_error(stage: str, exc: OSError) -> str:
    """One line for a failed read or write: the stage, the path and the cause (``survey: cannot write
    data/survey: [Errno 28] No space left on device``), with no traceback."""
    path = exc.filename if exc.filename is not None else "?"
    cause = f"[Errno {exc.errno}] {exc.strerror}" if exc.strerror else str(exc)
    return f"{stage}: cannot write {path}: {cause}"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def replace_dir(tmp: Path, final: Path) -> None:
    """Replace directory ``final`` (if any) by ``tmp`` with renames; the old directory is removed after."""
    old = final.with_name(f".{final.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    if final.exists():
        os.replace(final, old)
    try:
        os.replace(tmp, final)
    except BaseException:
        if old.exists() and not final.exists():
            os.replace(old, final)
        raise
    shutil.rmtree(old, ignore_errors=True)


@contextmanager
def atomic_outputs(files: Sequence[str | Path] = (), dirs: Sequence[str | Path] = ()) -> Iterator[
    tuple[list[Path], list[Path]]
]:
    """Yield temporary paths ``(file_tmps, dir_tmps)`` for ``files`` and ``dirs``; on success move them into place.

    Each temporary file exists (empty) and each temporary directory exists (empty) when the block starts; parent
    directories are created. Directories are put in place first, files last, in the order given.
    """
    files, dirs = [Path(f) for f in files], [Path(d) for d in dirs]
    for path in (*files, *dirs):
        path.parent.mkdir(parents=True, exist_ok=True)
    file_tmps: list[Path] = []
    dir_tmps: list[Path] = []
    try:
        for path in files:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            os.close(fd)
            file_tmps.append(Path(tmp))
        for path in dirs:
            dir_tmps.append(Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)))
        yield file_tmps, dir_tmps
        mask = _umask()
        for tmp, final in zip(dir_tmps, dirs):
            os.chmod(tmp, 0o777 & ~mask)  # its files were created with the umask already
            replace_dir(tmp, final)
        for tmp, final in zip(file_tmps, files):
            os.chmod(tmp, 0o666 & ~mask)
            os.replace(tmp, final)
    finally:
        for tmp in file_tmps:
            tmp.unlink(missing_ok=True)
        for tmp in dir_tmps:
            shutil.rmtree(tmp, ignore_errors=True)


@contextmanager
def atomic_file(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write ``path``'s new content to; it replaces ``path`` when the block succeeds."""
    with atomic_outputs(files=[path]) as (tmps, _):
        yield tmps[0]
