"""Atomic files: every file the suite stores (rows, tables, cached parameters, artifacts) goes
through the one atomic write (``systems.atomic_write``: a temporary beside it, fsynced and
renamed into place); here, the clearing of a killed writer's temporaries and JSON."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from systems import TMP_PREFIX, atomic_write, tmp_prefix

__all__ = [
    "TMP_PREFIX",
    "atomic_write",
    "atomic_write_bytes",
    "clear_orphans",
    "jsonable",
    "tmp_prefix",
    "write_json",
]


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
