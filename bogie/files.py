"""What a reader of a user's file checks before it opens it: that it is a regular file (symlinks followed).

A FIFO waits for a writer for ever, a device (``/dev/zero``) never ends and a folder cannot be read: each is refused
with one line naming what it is. The survey readers (``bogie.weighings``) and the YAML reader of params.yaml and bogie
files (``bogie.guarded_yaml``) both call :func:`regular_file`.
"""

from __future__ import annotations

import os
import stat

__all__ = ["regular_file"]


def regular_file(path: str | os.PathLike[str], hint: str = "") -> os.stat_result:
    """``path``'s status if it is a regular file (symlinks followed).

    Raises
    ------
    ValueError
        ``<path>: is a FIFO (named pipe), not a regular file`` (a folder, a device, ...), then ``: <hint>`` if given.
    FileNotFoundError
        If there is no such file, as ``open`` gives it.
    """
    status = os.stat(path)
    mode = status.st_mode
    if not stat.S_ISREG(mode):
        kind = (
            "a folder" if stat.S_ISDIR(mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
            else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "not a file"
        )  # fmt: skip
        raise ValueError(f"{path}: is {kind}, not a regular file" + (f": {hint}" if hint else ""))
    return status
