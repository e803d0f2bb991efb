"""Row files, the truth of a results folder: ``.rows/<config_hash>.json``, one per finished
run, written atomically with the sha256 of its own content (``_row_sha256``, checked on read,
not a column). A file that does not read back is named in a :class:`DamagedRowWarning` and
moved aside to ``.rows/.damaged/`` (never deleted); its run then counts as not done."""

from __future__ import annotations

import hashlib
import json
import os
import time
import warnings
from pathlib import Path

from ._atomic import atomic_write_bytes, jsonable

ROWS = ".rows"
DAMAGED = ".damaged"  # under .rows/: row files that did not read back, kept for inspection
CURVE_KEYS = ("t", "rel_error", "energy_violation", "z_true", "z_pred")
STATUSES = ("ok", "diverged", "failed")
CHECKSUM = "_row_sha256"
NESTED = ("curves", "checkpoints")  # row fields kept out of the runs table (tables of their own)


class DamagedRowWarning(UserWarning):
    """A stored row file could not be read; it was moved aside and its run will be rerun."""


def _canonical(row: dict) -> str:
    return json.dumps(row, sort_keys=True, separators=(",", ":"))


def write_row(results_dir, row: dict) -> Path:
    """Atomically write one finished run as ``.rows/<config_hash>.json``, with its checksum."""
    path = Path(results_dir) / ROWS / f"{row['config_hash']}.json"
    payload = jsonable({a: b for a, b in row.items() if a != CHECKSUM})
    payload[CHECKSUM] = hashlib.sha256(_canonical(payload).encode()).hexdigest()
    atomic_write_bytes(path, _canonical(payload).encode())
    return path


def _parse_row(path: Path) -> tuple[dict | None, str | None]:
    """(row, None) for a good row file, (None, what is wrong) otherwise."""
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        return None, "not text"
    if not text.strip():
        return None, "empty"
    try:
        row = json.loads(text)
    except ValueError as e:
        return None, f"not JSON ({e}; {len(text)} characters: truncated?)"
    if not isinstance(row, dict):
        return None, f"not a row (a JSON {type(row).__name__})"
    stored = row.pop(CHECKSUM, None)  # rows written before checksums have none
    if stored is not None and hashlib.sha256(_canonical(row).encode()).hexdigest() != stored:
        return None, "checksum mismatch (content changed after writing)"
    if row.get("config_hash") != path.stem:
        return None, f"config_hash {row.get('config_hash')!r} is not the file name's"
    if row.get("status") not in STATUSES:
        return None, f"status {row.get('status')!r} is not one of {', '.join(STATUSES)}"
    for key, kind in (("system", str), ("model", str), ("seed", int)):
        if not isinstance(row.get(key), kind) or isinstance(row.get(key), bool):
            return None, f"field {key!r} missing or not a {kind.__name__}"
    for key in NESTED:
        if row.get(key) is not None and not isinstance(row.get(key), dict):
            return None, f"field {key!r} is not an object"
    return row, None


def _set_aside(path: Path) -> Path:
    dest_dir = path.parent / DAMAGED
    dest_dir.mkdir(exist_ok=True)
    dest = dest_dir / path.name
    if dest.exists():  # an earlier damaged copy of the same run: keep both
        dest = dest_dir / f"{path.stem}.{time.strftime('%Y%m%dT%H%M%S')}-{os.getpid()}.json"
    os.replace(path, dest)
    return dest


def scan_rows(results_dir, *, set_aside: bool = True) -> tuple[list[dict], list[tuple[Path, str]]]:
    """(good rows, [(damaged file, what is wrong)]) of ``.rows/``.

    Each damaged file is named in a :class:`DamagedRowWarning` and, with ``set_aside``, moved to
    ``.rows/.damaged/`` so that its run counts as not done (the path in the list is then the
    new one). A file that cannot be moved (read-only results) is left in place and skipped.
    """
    rows, damaged = [], []
    rows_dir = Path(results_dir) / ROWS
    for path in sorted(rows_dir.glob("*.json")):
        if path.name.startswith("."):  # a temporary being written (or left by a kill)
            continue
        try:
            row, problem = _parse_row(path)
        except FileNotFoundError:  # removed meanwhile (e.g. another process set it aside)
            continue
        except OSError as e:
            row, problem = None, f"unreadable ({e.strerror or e})"
        if row is not None:
            rows.append(row)
            continue
        where = path
        note = "left in place"
        if set_aside:
            try:
                where = _set_aside(path)
                note = f"moved to {where}"
            except OSError as e:
                note = f"could not be moved aside ({e.strerror or e})"
        warnings.warn(
            f"damaged row file {path}: {problem}; {note}; its run counts as not done "
            "and the next sweep reruns it",
            DamagedRowWarning,
            stacklevel=2,
        )
        damaged.append((where, problem))
    return rows, damaged


def read_rows(results_dir) -> list[dict]:
    """Every stored row that reads back (damaged files are set aside, see :func:`scan_rows`)."""
    return scan_rows(results_dir)[0]


def done_hashes(results_dir) -> set[str]:
    """config_hash of every finished run (whatever its status) whose row file reads back."""
    return {r["config_hash"] for r in read_rows(results_dir)}


def unread_rows(results_dir) -> list[Path]:
    """Damaged row files in ``.rows/.damaged/`` (or left in ``.rows/``) whose run has no good
    row yet: the runs the tables are missing until the next sweep reruns them."""
    rows_dir = Path(results_dir) / ROWS
    if not rows_dir.is_dir():
        return []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DamagedRowWarning)
        rows, damaged = scan_rows(results_dir, set_aside=False)
    done = {r["config_hash"] for r in rows}
    out = [p for p, _ in damaged]
    for p in sorted((rows_dir / DAMAGED).glob("*.json")):
        if p.name.split(".")[0] not in done:
            out.append(p)
    return out
