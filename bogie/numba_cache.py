"""numba's on-disk cache of bogie's kernels: one directory per version of the sources, and no more than a few.

numba invalidates a cached function only when its own file changes, not when a compiled function it calls (in
another module) does, so ``import bogie`` points ``NUMBA_CACHE_DIR`` at a directory of its own per version of the
sources (:func:`source_digest`: every module below ``bogie/``, subpackages included): ``<root>/<digest>/``, the root
``$XDG_CACHE_HOME/bogie-numba`` (``~/.cache`` without it, :func:`cache_root`). numba keys what it caches there by
the path of each source file too (one subdirectory per clone), so two clones of one version would share the
directory but not the files and each would compile again: :mod:`bogie._numba_locator` files them by their place in
the package instead, stamped by content, so every clone and ``dvc exp run --temp`` copy of one version shares them.

Every edit of a source is a new version, and nothing removed the old ones: the root grew by a directory per version
and clone (75 MB after a day's work). So each process that sets the directory claims it (:func:`claim`: a shared
lock on ``<digest>/.in-use`` held until the process ends, and the directory's modification time set to now, the
time of its last use) and prunes the root (:func:`prune`): it keeps the :data:`KEEP` most recently used directories,
its own among them, and removes the others, except one in use by a running process (its lock is held: another clone
compiling now keeps its cache to the end) or used within :data:`GRACE`. Removal takes the directory's lock
exclusively, renames it out of the way and then deletes it, so a process that starts on it meanwhile finds the lock
file gone, starts afresh on a new directory and recompiles; two processes pruning at once remove each directory
once. Nothing here may stop ``import bogie``: a root that cannot be written or locked is left as it is.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import time
from collections.abc import Iterable
from pathlib import Path

try:
    import fcntl
except ImportError:  # no flock (Windows): claim nothing, prune nothing
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "GRACE",
    "KEEP",
    "cache_root",
    "claim",
    "hash_sources",
    "is_cached",
    "keyed_by_code",
    "prune",
    "source_digest",
    "subpath",
]

#: the cache directories kept, the most recently used first, this process's own among them: the versions a day's
#: switching between branches and clones comes back to (each is 0.5-25 MB; one not kept costs a recompilation,
#: about a minute)
KEEP = 4
#: a directory used within this time is never removed, whatever :data:`KEEP` says [s]: a process of an older bogie,
#: which takes no lock, may still be running on it
GRACE = 3600.0
#: the lock file in each cache directory: held shared by every process using the directory
LOCK_NAME = ".in-use"
#: name prefix of a directory being removed (renamed into the root first); leftovers of an interrupted removal too
_REMOVING = ".removing-"


def is_cached(module_file: str | Path, cache_dir: str | Path | None = None, function: str = "*") -> bool:
    """Whether numba's cache holds compiled ``function`` (default: any) of the source ``module_file``: an index
    (``<module>.<function>-<line>.py<version>.nbi``) in the subdirectory the locator gives that file under
    ``cache_dir`` (None: the ``NUMBA_CACHE_DIR`` ``import bogie`` set): in the directory keyed by the package's
    sources, its place in the package (:func:`subpath`, the same in every clone); elsewhere
    numba's own, ``<parent name>_<sha1 of the parent's absolute path>``. A prediction for a progress message, not a
    guarantee: an index without the signature asked for still compiles."""
    directory = cache_dir or os.environ.get("NUMBA_CACHE_DIR")
    if not directory:
        return False
    parent = Path(module_file).resolve().parent
    place = subpath(module_file) if keyed_by_code(directory) else None
    sub = Path(directory) / (place or f"{parent.name}_{hashlib.sha1(str(parent).encode()).hexdigest()}")
    return any(sub.glob(f"{Path(module_file).stem}.{function}-*.nbi"))


#: the package whose modules :class:`bogie._numba_locator.PackageLocator` files by their place in it
PACKAGE = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=1)
def _own_digest() -> str:
    return source_digest(PACKAGE)


def subpath(py_file: str | Path) -> str | None:
    """The subdirectory of the cache directory where the kernels of ``py_file`` lie: its directory's dotted place in
    the package (``bogie``, ``bogie.steel.phases``), the same in every clone; None for a file outside the package."""
    path = Path(py_file).resolve()
    try:
        relative = path.parent.relative_to(PACKAGE.parent)
    except ValueError:
        return None
    return ".".join(relative.parts) if relative.parts and relative.parts[0] == PACKAGE.name else None


def keyed_by_code(cache_dir: str | Path | None) -> bool:
    """Whether ``cache_dir`` is the directory ``import bogie`` keys by the package's sources (:func:`source_digest`)."""
    return bool(cache_dir) and Path(cache_dir).name == _own_digest()


def cache_root() -> Path:
    """The directory of bogie's numba caches: ``$XDG_CACHE_HOME/bogie-numba``, or ``~/.cache/bogie-numba``."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "bogie-numba"


def hash_sources(digest: hashlib._Hash, paths: Iterable[Path], root: Path) -> None:
    """Feed each source file to ``digest``: its path relative to ``root`` (POSIX), a NUL, its bytes, a NUL.

    The one way bogie's sources are hashed: for numba's cache directory (:func:`source_digest`) and for the
    simulate stage's code version (:func:`pipeline.chunks.code_version`). The name counts, so a module moved or
    renamed is another version; the caller gives the order.
    """
    for path in paths:
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")


def source_digest(package: Path) -> str:
    """A 16-hex-digit hash of every module of the package, its subpackages' included: a cache directory's name.

    Every ``.py`` file below ``package`` (recursively), in the order of their relative paths, each with its relative
    path (:func:`hash_sources`): a kernel inlines compiled functions from other modules, a subpackage's too, and
    numba does not see their changes.
    """
    digest = hashlib.sha256()
    paths = sorted(package.rglob("*.py"), key=lambda path: path.relative_to(package).as_posix())
    hash_sources(digest, paths, package)
    return digest.hexdigest()[:16]


def claim(directory: Path, attempts: int = 5) -> int | None:
    """Mark the cache directory ``directory`` as in use by this process until it ends; create it if need be.

    A shared lock on ``directory/.in-use`` (the returned descriptor holds it: keep it open) and the directory's
    modification time set to now. If a pruner renamed the directory away between the open and the lock, the lock
    file is no longer at its path: the claim starts again on a fresh directory.

    Returns
    -------
    int or None
        The lock file's descriptor, or None if no lock could be taken (no flock, an unwritable root).
    """
    if fcntl is None:
        return None
    for _ in range(attempts):
        try:
            directory.mkdir(parents=True, exist_ok=True)
            fd = os.open(directory / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            return None
        try:
            fcntl.flock(fd, fcntl.LOCK_SH)
            if os.fstat(fd).st_ino == os.stat(directory / LOCK_NAME).st_ino:
                os.utime(directory)
                return fd
        except OSError:
            pass  # the lock file vanished with a pruner's rename: again
        os.close(fd)
    return None


def prune(root: Path, keep: int = KEEP, grace: float = GRACE, now: float | None = None) -> list[Path]:
    """Remove the cache directories of ``root`` beyond the ``keep`` most recently used (by modification time).

    A directory is removed only if it was not used within ``grace`` seconds of ``now`` and no running process holds
    its lock (:func:`claim`); a directory that vanishes or is taken meanwhile is skipped. Leftovers of an interrupted
    removal older than ``grace`` are removed too. Errors are ignored: pruning must never stop an import.

    Returns
    -------
    list of Path
        The directories removed.
    """
    if fcntl is None:
        return []
    now = time.time() if now is None else now
    # a directory another pruner renames away between the listing and its stat is no candidate, and holds no place
    # among the kept: ranked as used now (or never), it would push a kept one out (issue 28's CI failure)
    used = {entry: mtime for entry in _entries(root) if (mtime := _mtime(entry)) != float("inf")}
    ranked = sorted(used, key=lambda entry: (used[entry], entry.name), reverse=True)
    removed = [entry for entry in ranked[keep:] if now - used[entry] >= grace and _remove(entry, root)]
    for leftover in root.glob(f"{_REMOVING}*"):
        if now - _mtime(leftover) >= grace:
            shutil.rmtree(leftover, ignore_errors=True)
    return removed


def _entries(root: Path) -> list[Path]:
    """The cache directories in ``root`` (leftovers and lock files excluded); none if it cannot be read."""
    try:
        return [p for p in root.iterdir() if not p.name.startswith(".") and p.is_dir()]
    except OSError:
        return []


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:
        return float("inf")  # gone or unreadable: never a candidate


def _remove(entry: Path, root: Path) -> bool:
    """Remove ``entry`` unless a process holds its lock; True if this call removed it."""
    trash = root / f"{_REMOVING}{entry.name}-{os.getpid()}"
    try:
        # not O_CREAT: creating the lock file would set the directory's modification time to now, and a pruner
        # listing at that moment would rank it as just used and remove an older, kept one instead (a test saw 11
        # removals of 10 under load). A directory without a lock file was never claimed by a running process
        fd = os.open(entry / LOCK_NAME, os.O_RDWR)
    except FileNotFoundError:
        try:
            os.rename(entry, trash)  # removed by another process first, or gone: an error, not ours
        except OSError:
            return False
        shutil.rmtree(trash, ignore_errors=True)
        return True
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        # the lock file still at its path: not renamed away by another pruner between our open and our lock
        if os.fstat(fd).st_ino != os.stat(entry / LOCK_NAME).st_ino:
            return False
        os.rename(entry, trash)
    except OSError:
        return False  # in use, or removed by another process first
    finally:
        os.close(fd)
    shutil.rmtree(trash, ignore_errors=True)
    return True
