"""One-line error messages for tables and the CLI, and the errors that stop a sweep."""

from __future__ import annotations

import errno
import os
import re

# Write failures that will repeat for every run (full disk, quota, file-size limit, read-only
# or forbidden folder, a folder under a file): they stop a sweep instead of being recorded as
# a failed run.
STORAGE_ERRNOS = frozenset(
    {errno.ENOSPC, errno.EFBIG, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.ENOTDIR}
)
_ERRNO_TEXT = re.compile(r"\[Errno (\d+)\]")


class StorageError(RuntimeError):
    """A write to the results or the cache failed (e.g. a full disk): the sweep stopped.

    Every row stored before it is whole (rows are written atomically); running the sweep
    again resumes with the runs not stored.
    """


class WorkerDied(RuntimeError):
    """A worker process of a sweep's pool died (killed by the OS, out of memory, a crash in
    native code): the sweep stopped. Every row stored before it is whole; running it again
    resumes with the runs not stored (the run in flight is lost)."""


def storage_error(err: BaseException) -> OSError | None:
    """The storage OSError (errno in :data:`STORAGE_ERRNOS`) behind ``err``, if any.

    Follows ``__cause__``/``__context__``; an error re-raised from another process (a Ray task)
    is recognised by the ``[Errno N]`` of its message.
    """
    seen = set()
    e: BaseException | None = err
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        if isinstance(e, OSError) and e.errno in STORAGE_ERRNOS:
            return e
        m = _ERRNO_TEXT.search(str(e)) if not isinstance(e, OSError) else None
        if m and int(m.group(1)) in STORAGE_ERRNOS:
            code = int(m.group(1))
            return OSError(code, os.strerror(code))
        e = e.__cause__ or e.__context__
    return None


def one_line(err: BaseException, limit: int = 300) -> str:
    """The error's own message on one line.

    Equinox's runtime errors (a failed ``eqx.error_if`` or a diffrax solve inside jit) wrap
    their message in a stack dump whose first line says nothing; the line that names the
    error is the one to keep.
    """
    text = str(err)
    for line in text.splitlines():
        if "EquinoxRuntimeError:" in line or "XlaRuntimeError:" in line:
            return line.strip()[:limit]
    return f"{type(err).__name__}: {text}".replace("\n", " ").strip()[:limit]
