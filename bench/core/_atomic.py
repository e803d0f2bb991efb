"""Atomic files: every file the suite stores (rows, tables, cached parameters, artifacts) is
written to a temporary beside it, fsynced and renamed into place, so that a process killed at
any moment, or a full disk, leaves the whole file or its old content, never a prefix."""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

TMP_PREFIX = ".tmp-"


def tmp_prefix() -> str:
    """Temporaries are named ``.tmp-<pid>-*``: :func:`clear_orphans` can tell a dead writer's."""
    return f"{TMP_PREFIX}{os.getpid()}-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):  # another user's process, or no way to ask: keep
        return True
    return True


def clear_orphans(directory) -> list[Path]:
    """Remove the temporaries in ``directory`` whose writer no longer runs (a kill mid-write
    leaves its ``.tmp-<pid>-*`` behind; a killed sweep's next run calls this). A live
    process's temporaries, and names without a pid, stay. Returns the removed paths."""
    removed = []
    for p in Path(directory).glob(f"{TMP_PREFIX}*"):
        pid = p.name[len(TMP_PREFIX) :].split("-", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            p.unlink(missing_ok=True)
            removed.append(p)
    return removed


def _fsync(path, flags=os.O_RDONLY) -> None:
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
        _fsync(tmp)
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and not e.filename:
            raise OSError(e.errno, e.strerror, str(path)) from e
        raise
    _fsync(path.parent)
    return path


def atomic_write_bytes(path, data: bytes) -> Path:
    """:func:`atomic_write` of ``data``."""
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def jsonable(x):
    """``x`` with arrays as lists, numpy scalars as Python ones, NaN as null and infinities as
    the strings ``"inf"``/``"-inf"`` (strict JSON)."""
    if isinstance(x, dict):
        return {str(a): jsonable(b) for a, b in x.items()}
    if isinstance(x, list | tuple):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        return jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def write_json(path, obj) -> Path:
    """Atomically write ``obj`` (:func:`jsonable`) as indented JSON."""
    return atomic_write_bytes(path, json.dumps(jsonable(obj), indent=1).encode())
