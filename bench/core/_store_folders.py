"""Results folders: the committed reference folders (one per budget), the user's own folder,
and the check that a folder can hold results (a folder, writable) before a sweep starts."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from ._store_rows import ROWS

# The committed reference results, read-only: one folder per budget (results/README.md).
REFERENCE_ROOT = Path(__file__).resolve().parents[2] / "results" / "reference"
REFERENCE_DIRS = {
    "smoke": None,
    "quick": "quick",
    "paper-core": "paper",  # the CPU campaign of paper-profile runs
    "paper": "paper",
}
# The user's own results (git-ignored): where make bench and every verb write by default.
OWN_DIR = Path("results") / "own"


def reference_dir(profile: str) -> Path | None:
    """The committed reference folder of ``profile`` (None where there is none)."""
    name = REFERENCE_DIRS.get(profile)
    return None if name is None else REFERENCE_ROOT / name


def holds_runs(d: Path) -> bool:
    """``d`` is a folder with stored runs (a runs table or row files)."""
    d = Path(d)
    return d.is_dir() and any((d / f).exists() for f in ("runs.parquet", "runs.csv", ROWS))


def compare_folders(results_dir: Path, reference_root: Path | None = None) -> list[Path]:
    """The folders whose verdicts a report sets beside its own: the committed reference
    folders (``results/reference/*``, the paper-core campaign first) other than
    ``results_dir`` itself, then the subfolders of ``results_dir`` holding stored runs."""
    root = REFERENCE_ROOT if reference_root is None else Path(reference_root)
    here = Path(results_dir).resolve()
    refs = sorted(root.iterdir()) if root.is_dir() else []
    subs = sorted(Path(results_dir).iterdir()) if Path(results_dir).is_dir() else []
    found, seen = [], set()
    for d in [*sorted(refs, key=lambda d: (d.name != "paper", d.name)), *subs]:
        if holds_runs(d) and d.resolve() != here and d.resolve() not in seen:
            seen.add(d.resolve())
            found.append(d)
    return found


class ResultsDirError(ValueError):
    """A results folder that cannot be used (a file, under a file, not writable)."""


def check_results_dir(results_dir, *, create: bool = True, what: str = "results folder") -> Path:
    """The results folder, usable: created if missing (``create``) and writable.

    Raises :class:`ResultsDirError` (a ValueError) with one line naming the path and the
    problem: a file, a folder under a file, a folder that cannot be created or written.
    ``what`` names the folder in the message (the runner checks its cache folder this way).
    """
    path = Path(results_dir)
    for p in (path, *path.parents):
        if p.exists() and not p.is_dir():
            where = "is a file" if p == path else f"is under {p}, which is a file"
            raise ResultsDirError(f"{what} {path} {where}, not a folder")
    rows = path / ROWS
    if rows.exists() and not rows.is_dir():
        raise ResultsDirError(f"{what} {path}: {rows} is a file, not a folder")
    if not path.exists():
        if not create:
            return path
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ResultsDirError(f"{what} {path} cannot be created: {e.strerror or e}") from None
    try:  # os.access says yes to root everywhere: write a probe file instead
        fd, probe = tempfile.mkstemp(dir=path, prefix=".tmp-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise ResultsDirError(f"{what} {path} is not writable: {e.strerror or e}") from None
    return path
