"""The suite's one atomic write: every file it stores (datasets, task files, rows, tables,
cached parameters, checkpoints) is written to a temporary beside it, fsynced and renamed into
place, so that a process killed at any moment, or a full disk, leaves the whole file or its
old content, never a prefix. It sits in the lowest package so that every layer writes through
it."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

TMP_PREFIX = ".tmp-"


def tmp_prefix() -> str:
    """Temporaries are named ``.tmp-<pid>-*``: a later run can tell a dead writer's."""
    return f"{TMP_PREFIX}{os.getpid()}-"


def fsync_path(path, flags=os.O_RDONLY) -> None:
    """fsync a file or a folder by path; a platform that cannot is left as it is."""
    try:
        fd = os.open(path, flags)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write(path, write: Callable[[Path], object]) -> Path:
    """``write(tmp)`` writes the file at the temporary path ``tmp`` (same folder and suffix as
    ``path``); it is then fsynced and renamed to ``path``. On any error the temporary is
    removed, and an OSError without a file name names ``path`` (the file the disk refused)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=tmp_prefix(), suffix=path.suffix)
    os.close(fd)
    try:
        write(Path(tmp))
        fsync_path(tmp)
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and not e.filename:
            raise OSError(e.errno, e.strerror, str(path)) from e
        raise
    fsync_path(path.parent)
    return path
