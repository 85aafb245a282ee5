"""All-or-nothing writes of a stage's outputs: every stage writes through :func:`atomic_outputs`.

Each output (a file or a directory) is first written under a temporary dot-name beside its final path, then all of
them replace their targets by renames once every one is complete. A reader sees the old outputs or the new ones,
never half a file; an exception while writing removes the temporaries and leaves the old outputs in place. Readers
that list a directory (pyarrow datasets) skip dot-names. Files and directories get the permissions of the user's umask
(``tempfile`` would make them private).

A stage owns its outputs while it runs through :func:`stage_outputs`: :func:`output_lock` on each (a second process
of the stage is refused in one line), then :func:`remove_leftovers` deletes what a killed run's
:func:`atomic_outputs` left beside them (``data/.design.k2x9a_7q.tmp``): every writer of those names holds the lock,
so a temporary found while holding it belongs to no live process.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

import yaml

__all__ = [
    "INPUT_ERRORS", "OUTPUT_MARKER", "LockedError", "OutputError", "StageError", "atomic_outputs", "atomic_file",
    "guard_outputs", "io_error", "output_lock", "refuse_outputs", "remove_leftovers", "replace_dir", "run_stage",
    "stage_inputs", "stage_outputs",
]  # fmt: skip

try:  # POSIX: flock; Windows has no fcntl, and locks a byte of the file with msvcrt instead
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]
    import msvcrt


def _try_lock(handle: Any) -> bool:
    """Take the exclusive lock of an open lock file without waiting; False if another process holds it."""
    if fcntl is not None:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
    try:  # pragma: no cover - Windows
        handle.seek(0)
        msvcrt.locking(handle.fileno(), msvcrt.LK_NBLCK, 1)
    except OSError:  # pragma: no cover - Windows
        return False
    return True  # pragma: no cover - Windows


def _unlock(handle: Any) -> None:
    if fcntl is not None:
        fcntl.flock(handle, fcntl.LOCK_UN)
        return
    handle.seek(0)  # pragma: no cover - Windows
    msvcrt.locking(handle.fileno(), msvcrt.LK_UNLCK, 1)  # pragma: no cover - Windows


#: the random part of a ``tempfile`` name: 8 characters of its alphabet (``tempfile._RandomNameSequence``)
_RANDOM = "[a-z0-9_]{8}"


def io_error(stage: str, exc: OSError) -> str:
    """One line for a failed read or write: the stage, the path and the cause (``survey: cannot write
    data/survey: [Errno 28] No space left on device``), with no traceback."""
    path = exc.filename if exc.filename is not None else "?"
    cause = f"[Errno {exc.errno}] {exc.strerror}" if exc.strerror else str(exc)
    return f"{stage}: cannot write {path}: {cause}"


#: the file every output directory of a stage holds, with the stage's name: what proves the directory is the stage's
OUTPUT_MARKER = ".bogie-output"


class OutputError(ValueError):
    """An output option names a place a stage must not replace (the project, a parent of it, home, another's files)."""


def _protected() -> dict[Path, str]:
    """The folders no output may be: the file system's root, home, the working directory and the project root, and
    every parent of the last three, with what each is."""
    from pipeline.deps import ROOT

    out: dict[Path, str] = {Path("/").resolve(): "the file system's root"}
    for place, what in ((Path.home(), "your home folder"), (Path.cwd(), "the working directory"),
                        (ROOT, "the project root")):  # fmt: skip
        place = place.resolve()
        for parent in reversed(place.parents):
            out.setdefault(parent, f"a parent of {what} ({place})")
        out[place] = what
    return out


def guard_outputs(
    stage: str, files: Sequence[str | Path] = (), dirs: Sequence[str | Path] = (), own: Sequence[str | Path] = ()
) -> None:
    """Refuse outputs that replacing would destroy what the stage did not write, before anything is touched.

    A directory output may not be the file system's root, home, the working directory, the project root or any
    parent of these (symlinks resolved), nor an existing file; an existing directory that is not empty must be the
    stage's own: it holds :data:`OUTPUT_MARKER` naming the stage (every directory :func:`atomic_outputs` writes for a
    stage does), or it is one of ``own`` (the stage's default outputs, written before the marker existed). A file
    output may not be an existing directory nor one of the protected folders. Nothing is moved or deleted here.

    Raises
    ------
    OutputError
        Naming the output, what it is and what to do.
    """
    protected = _protected()
    own_paths = {Path(p).resolve() for p in own}
    for raw in dirs:
        path = Path(raw)
        real = path.resolve()
        if real in protected:
            raise OutputError(
                f"{stage}: the output folder {raw} is {protected[real]}: a stage replaces its output folder whole, so "
                "it must be a folder of its own, e.g. the default under data/"
            )
        if os.path.lexists(path) and not path.is_dir():
            raise OutputError(f"{stage}: the output folder {raw} is an existing file, not a folder: name a folder")
        if not path.is_dir() or real in own_paths:
            continue
        marker = path / OUTPUT_MARKER
        try:
            writer = marker.read_text(encoding="utf-8").strip() if marker.is_file() else None
        except OSError:
            writer = None
        if writer == stage:
            continue
        try:
            entries = [entry.name for entry in os.scandir(path)]
        except OSError as exc:
            raise OutputError(f"{stage}: the output folder {raw} cannot be listed: {exc}") from None
        if not entries:
            continue
        whose = f"the {writer} stage's output" if writer else "files the stage did not write"
        shown = ", ".join(sorted(entries)[:3]) + (", ..." if len(entries) > 3 else "")
        raise OutputError(
            f"{stage}: the output folder {raw} holds {whose} ({shown}): the stage replaces its output folder whole "
            "and would delete them; name a new or empty folder, or move them away first"
        )
    for raw in files:
        path = Path(raw)
        real = path.resolve()
        if real in protected or path.is_dir():
            what = protected.get(real, "an existing folder")
            raise OutputError(f"{stage}: the output file {raw} is {what}: name a file")


def refuse_outputs(
    stage: str, parser: Any, args: Any, files: Sequence[str] = (), dirs: Sequence[str] = ()
) -> tuple[str | None, list[Path]]:
    """:func:`guard_outputs` on a stage's output options (``args``' attributes ``files`` and ``dirs``), the parser's
    defaults being the stage's own folders: ``(the error line or None, those defaults)``. A stage calls it right
    after parsing its arguments, so that a refused output costs no work."""
    own = [Path(parser.get_default(name)) for name in dirs]
    try:
        guard_outputs(stage, [getattr(args, n) for n in files], [getattr(args, n) for n in dirs], own)
    except OutputError as exc:
        return str(exc), own
    return None, own


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _exchange():
    """Linux's renameat2 with RENAME_EXCHANGE (two paths swapped in one step), or None where there is none."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        rename2 = libc.renameat2
    except (OSError, AttributeError):
        return None
    rename2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    rename2.restype = ctypes.c_int
    at_fdcwd, rename_exchange = -100, 2

    def exchange(a: Path, b: Path) -> bool:
        if rename2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
            return True
        errno = ctypes.get_errno()
        if errno in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: the file system or kernel cannot; rename instead
            return False
        raise OSError(errno, os.strerror(errno), str(b))

    return exchange


_EXCHANGE = _exchange()


def replace_dir(tmp: Path, final: Path) -> None:
    """Replace directory ``final`` (if any) by ``tmp``; the old directory is removed after.

    Where the system can (Linux's ``renameat2``), the two are swapped in one step, so ``final`` is never missing, not
    even if the process is killed here: the old content is then left under ``tmp``'s temporary name, which the next
    run removes (:func:`remove_leftovers`). Elsewhere ``final`` is first renamed to ``.<name>.old``, which the next
    run puts back if it was killed between the two renames."""
    if final.is_dir() and not final.is_symlink() and _EXCHANGE is not None and _EXCHANGE(tmp, final):
        shutil.rmtree(tmp, ignore_errors=True)
        return
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
def atomic_outputs(
    files: Sequence[str | Path] = (), dirs: Sequence[str | Path] = (), stage: str | None = None,
    own: Sequence[str | Path] = (),
) -> Iterator[tuple[list[Path], list[Path]]]:  # fmt: skip
    """Yield temporary paths ``(file_tmps, dir_tmps)`` for ``files`` and ``dirs``; on success move them into place.

    With ``stage``, the outputs are first checked by :func:`guard_outputs` (``own``: the stage's default outputs),
    before anything is created, and each directory gets :data:`OUTPUT_MARKER` naming the stage. Each temporary file
    exists (empty) and each temporary directory exists (empty) when the block starts; parent directories are
    created. Directories are put in place first, files last, in the order given.
    """
    if stage is not None:
        guard_outputs(stage, files, dirs, own)
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
            if stage is not None:
                (tmp / OUTPUT_MARKER).write_text(f"{stage}\n", encoding="utf-8")
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


def temporary_name(path: str | Path) -> re.Pattern[str]:
    """The exact names of :func:`atomic_outputs`'s temporaries for ``path``: ``.<name>.<8 random characters>.tmp``."""
    return re.compile(rf"\.{re.escape(Path(path).name)}\.{_RANDOM}\.tmp")


def remove_leftovers(path: str | Path) -> list[Path]:
    """Delete what a killed :func:`atomic_outputs` left for the output ``path``; returns what was deleted.

    Only names the writer makes are touched: its temporaries (:func:`temporary_name`, files or directories) and
    :func:`replace_dir`'s ``.<name>.old``. An ``.old`` directory with no ``path`` beside it is the previous output of
    a run killed between its two renames: it is put back, not deleted. Call it only while holding
    :func:`output_lock` on ``path``: that proves no writer of these names is alive.
    """
    path = Path(path)
    if not path.parent.is_dir():
        return []
    removed = []
    pattern = temporary_name(path)
    for entry in sorted(path.parent.iterdir()):
        if not pattern.fullmatch(entry.name):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()
        removed.append(entry)
    old = path.with_name(f".{path.name}.old")
    if old.is_dir() and not old.is_symlink():
        if os.path.lexists(path):
            shutil.rmtree(old)
            removed.append(old)
        else:
            os.replace(old, path)
    return removed


class LockedError(RuntimeError):
    """Another process is writing a stage's output."""


def _new_dirs(directory: Path) -> list[Path]:
    """The directories ``mkdir(parents=True)`` of ``directory`` would create, deepest first."""
    missing = []
    while not directory.exists() and directory != directory.parent:
        missing.append(directory)
        directory = directory.parent
    return missing


@contextmanager
def output_lock(path: str | Path, stage: str) -> Iterator[None]:
    """Hold an exclusive lock on the output ``path`` (file ``.<name>.lock`` beside it) while ``stage`` writes it.

    The lock file holds the holder's pid and is removed when the lock is released (while still held: a process that
    locked it in between sees that the file at the path is no longer the one it locked and takes the new one), and
    so are the directories made for it that are still empty: a refused or failed run leaves nothing behind.

    Raises
    ------
    LockedError
        If another process holds it, naming the output, the holder's pid and the lock file.
    """
    shown = Path(path)
    path = Path(os.path.abspath(path))  # "." and ".." have no name of their own
    lock_path = path.parent / f".{path.name}.lock"
    created = _new_dirs(path.parent)
    try:
        while True:
            path.parent.mkdir(parents=True, exist_ok=True)
            try:
                handle = open(lock_path, "a+", encoding="utf-8")
            except FileNotFoundError:  # a finishing holder removed the directory it had made
                continue
            if not _try_lock(handle):
                handle.seek(0)
                try:
                    holder = handle.read().strip() or "unknown"
                except OSError:  # Windows: the holder's locked byte cannot be read
                    holder = "unknown"
                handle.close()
                raise LockedError(
                    f"{shown} is being written by another {stage} process (pid {holder}, lock {lock_path}): wait "
                    "for it to finish or stop it, then run again"
                ) from None
            try:
                same = os.path.samestat(os.stat(lock_path), os.fstat(handle.fileno()))
            except FileNotFoundError:
                same = False
            if same:
                break
            handle.close()
        handle.seek(0)
        handle.truncate()
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        try:
            yield
        finally:
            try:
                lock_path.unlink(missing_ok=True)
            except PermissionError:  # Windows: an open file cannot be removed; it is left, unlocked
                pass
            _unlock(handle)
            handle.close()
    finally:
        for directory in created:
            try:
                directory.rmdir()
            except OSError:
                break


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


@contextmanager
def stage_outputs(
    stage: str, files: Sequence[str | Path] = (), dirs: Sequence[str | Path] = (), log: Callable[[str], None] = _stderr
) -> Iterator[None]:
    """Own a stage's outputs while it runs: lock each (:func:`output_lock`), then delete the leftovers of a killed
    run of the stage beside them (:func:`remove_leftovers`), one log line for each.

    Raises
    ------
    LockedError
        If another process of the stage holds one of them; nothing is deleted then.
    """
    with ExitStack() as stack:
        outputs = [Path(p) for p in (*files, *dirs)]
        for path in outputs:
            stack.enter_context(output_lock(path, stage))
        for path in outputs:
            for leftover in remove_leftovers(path):
                log(f"{stage}: removed {leftover}, left by an interrupted run of the stage")
        yield


class StageError(Exception):
    """What stops a stage that is the user's to mend: :func:`run_stage` prints its one line (``<stage>: <what is
    wrong>``) on stderr and exits 2, with no traceback."""


#: the errors of a stage's inputs (params.yaml, the runs, a survey file, the other stages' outputs) that are the
#: user's to mend, each with a message naming what is wrong: the configuration's and the library's own errors
#: (ConfigError, RunsError, CalibrationError, DesignError, FleetError...) are ValueErrors, by the project's rule that
#: bad input raises a ValueError naming the parameter, value, range and unit; a file that cannot be read an OSError;
#: a params.yaml that is not YAML a YAMLError. A KeyError, TypeError, IndexError... is a bug: a traceback (a stage
#: whose inputs are other stages' files, where a missing key is a damaged input, adds KeyError by ``more``)
INPUT_ERRORS: tuple[type[BaseException], ...] = (ValueError, OSError, yaml.YAMLError)


@contextmanager
def stage_inputs(stage: str, *more: type[BaseException], prefix: str = "") -> Iterator[None]:
    """Around the reading of a stage's inputs: an error of :data:`INPUT_ERRORS` (or of ``more``) becomes a
    :class:`StageError`, ``<stage>: <prefix><the error's message>``."""
    try:
        yield
    except (*INPUT_ERRORS, *more) as exc:
        raise StageError(f"{stage}: {prefix}{exc}") from exc


def run_stage(
    stage: str, parser: Any, args: Any, work: Callable[[list[Path]], int], files: Sequence[str] = (),
    dirs: Sequence[str] = (),
) -> int:  # fmt: skip
    """A stage's command around its ``work``: refuse output options that would destroy what the stage did not write
    (:func:`refuse_outputs`, before any work), own the outputs while it runs (:func:`stage_outputs`: a second process
    refused, a killed run's leftovers removed), then ``work(own)`` (``own``: the stage's default output folders) and
    its exit code. A refused output, a locked one, an error of the file system (:func:`io_error`) or a
    :class:`StageError` (:func:`stage_inputs`) is one line on stderr and exit 2: the one place a stage's errors become
    its exit code. A stage with no outputs of its own to guard passes none.

    ``files`` and ``dirs`` name the options (``args``' attributes) of the stage's output files and folders.
    """
    refused, own = refuse_outputs(stage, parser, args, files=files, dirs=dirs)
    if refused:
        print(refused, file=sys.stderr)
        return 2
    try:
        with stage_outputs(stage, files=[getattr(args, n) for n in files], dirs=[getattr(args, n) for n in dirs]):
            return work(own)
    except StageError as exc:
        print(exc, file=sys.stderr)
        return 2
    except LockedError as exc:
        print(f"{stage}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(io_error(stage, exc), file=sys.stderr)
        return 2
