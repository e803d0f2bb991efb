"""The results store: one JSON file per finished run, tables rebuilt from them, aggregation.

Layout under ``results_dir``::

    .rows/<config_hash>.json   the truth: one finished run (row fields + small per-time curves)
    runs.parquet, runs.csv     one row per config_hash, rebuilt from .rows/
    curves.parquet             (config_hash, t, rel_error, energy_violation, z_true_i, z_pred_i)
    checkpoints.parquet        learning curves: (config_hash, step, fraction, train_seconds,
                               status, rollout_error, energy_violation, mse, ...) per checkpoint
    checkpoint_curves.parquet  (config_hash, step, t, rel_error, energy_violation) per checkpoint

A row file is written to a temporary name, fsynced and ``os.replace``d into place, and the
tables are rebuilt the same way, so a process killed at any moment (or a full disk) leaves
either the whole row or none, and a hash can never appear twice. Each row carries the sha256
of its own content (``_row_sha256``, checked on read and not a column). A row file that does
not read back (truncated, not JSON, wrong fields, checksum mismatch) is named in a
:class:`DamagedRowWarning` and moved aside to ``.rows/.damaged/`` (never deleted): its run then
counts as not done and the next sweep reruns it. ``.rows/`` is meant to be committed: results
reload from a fresh clone.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
import time
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

ROWS = ".rows"
DAMAGED = ".damaged"  # under .rows/: row files that did not read back, kept for inspection
CURVE_KEYS = ("t", "rel_error", "energy_violation", "z_true", "z_pred")
STATUSES = ("ok", "diverged", "failed")
CHECKSUM = "_row_sha256"
NESTED = ("curves", "checkpoints")  # row fields kept out of the runs table (tables of their own)


# The committed reference results, read-only: one folder per budget (results/README.md).
REFERENCE_ROOT = Path(__file__).resolve().parents[2] / "results" / "reference"
REFERENCE_DIRS = {
    "smoke": None,
    "quick": "quick",
    "paper-core": "paper",  # the CPU campaign of issue 24 (paper-profile runs)
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


class DamagedRowWarning(UserWarning):
    """A stored row file could not be read; it was moved aside and its run will be rerun."""


class ResultsDirError(ValueError):
    """A results folder that cannot be used (a file, under a file, not writable)."""


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


TMP_PREFIX = ".tmp-"


def _tmp_prefix() -> str:
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


def _atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write to a temporary file, fsync, rename: ``path`` holds all of ``data`` or its old
    content, never a prefix (a full disk leaves no partial file; the temporary is removed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=_tmp_prefix(), suffix=path.suffix)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as e:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(e, OSError) and not e.filename:  # name the file the disk refused
            raise OSError(e.errno, e.strerror, str(path)) from e
        raise
    _fsync_dir(path.parent)


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


def _jsonable(x):
    if isinstance(x, dict):
        return {str(a): _jsonable(b) for a, b in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        return _jsonable(x.item())
    if isinstance(x, float) and not math.isfinite(x):
        return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def _canonical(row: dict) -> str:
    return json.dumps(row, sort_keys=True, separators=(",", ":"))


def write_row(results_dir, row: dict) -> Path:
    """Atomically write one finished run as ``.rows/<config_hash>.json``, with its checksum."""
    path = Path(results_dir) / ROWS / f"{row['config_hash']}.json"
    payload = _jsonable({a: b for a, b in row.items() if a != CHECKSUM})
    payload[CHECKSUM] = hashlib.sha256(_canonical(payload).encode()).hexdigest()
    _atomic_write_bytes(path, _canonical(payload).encode())
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


def _flat(row: dict) -> dict:
    out = {}
    for a, b in row.items():
        if a in NESTED:
            continue
        if isinstance(b, list | tuple | dict):
            b = json.dumps(b)
        out[a] = b
    return out


def _numeric_or_null(v) -> bool:
    if v is None or isinstance(v, str) and v in ("inf", "-inf"):
        return True
    return isinstance(v, int | float) and not isinstance(v, bool)


def rows_frame(rows: Sequence[dict]) -> pd.DataFrame:
    """The runs table of some rows: one row per config_hash, lists as JSON strings."""
    df = pd.DataFrame([_flat(r) for r in rows])
    if len(df):
        by = [c for c in ("experiment", "system", "model", "seed", "config_hash") if c in df]
        df = df.drop_duplicates("config_hash", keep="first").sort_values(by, na_position="last")
        for col in df.columns:  # JSON null -> NaN, "inf" -> inf, where a column is numeric
            if df[col].dtype == object and df[col].map(_numeric_or_null).all():
                df[col] = pd.to_numeric(df[col], errors="coerce").astype(float)
    return df.reset_index(drop=True)


def curves_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Long table of per-time curves: config_hash, t, rel_error, energy_violation, z_*_i."""
    parts = []
    for r in rows:
        c = r.get("curves")
        if not c or not c.get("t"):
            continue
        d = {"config_hash": r["config_hash"], "t": np.asarray(c["t"], dtype=float)}
        for key in ("rel_error", "energy_violation"):
            v = c.get(key)
            d[key] = np.asarray(v if v is not None else [np.nan] * len(c["t"]), dtype=float)
        for key in ("z_true", "z_pred"):
            z = np.asarray(c.get(key) or [], dtype=float)
            if z.ndim == 2 and len(z) == len(c["t"]):
                for i in range(z.shape[1]):
                    d[f"{key}_{i}"] = z[:, i]
        parts.append(pd.DataFrame(d))
    if not parts:
        return pd.DataFrame(columns=["config_hash", "t", "rel_error", "energy_violation"])
    return pd.concat(parts, ignore_index=True)


CHECKPOINT_COLUMNS = ("step", "fraction", "train_seconds", "status")


def checkpoints_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Learning curves, one row per (run, checkpoint): config_hash, step, fraction,
    train_seconds, status and the checkpoint metrics (``bench.core._execute.CHECKPOINT_METRICS``);
    empty (with those first columns) when no row has checkpoints."""
    parts = []
    for r in rows:
        c = r.get("checkpoints")
        if not c or not c.get("step"):
            continue
        d = {"config_hash": r["config_hash"]}
        d.update({k: v for k, v in c.items() if not k.endswith("_t")})
        parts.append(pd.DataFrame(d))
    if not parts:
        return pd.DataFrame(columns=["config_hash", *CHECKPOINT_COLUMNS])
    out = pd.concat(parts, ignore_index=True)
    for col in out.columns:
        if col not in ("config_hash", "status"):
            out[col] = pd.to_numeric(out[col], errors="coerce").astype(float)
    out["step"] = out["step"].astype(int)
    return out


def checkpoint_curves_frame(rows: Iterable[dict]) -> pd.DataFrame:
    """Per-time curves at each checkpoint: config_hash, step, t, rel_error, energy_violation
    (the columns of :func:`curves_frame`, so a claim rule reads them as it reads the final ones)."""
    cols: dict[str, list] = {k: [] for k in ("config_hash", "step", "t", "rel_error")}
    cols["energy_violation"] = []
    for r in rows:
        c, t = r.get("checkpoints"), (r.get("curves") or {}).get("t")
        if not c or not c.get("step") or not t:
            continue
        n, steps = len(t), c["step"]
        for key in ("rel_error", "energy_violation"):
            v = [
                x if x is not None and len(x) == n else [np.nan] * n
                for x in c.get(f"{key}_t") or [None] * len(steps)
            ]
            cols[key].append(np.asarray(v, dtype=float).reshape(-1))
        cols["config_hash"].append(np.repeat(r["config_hash"], n * len(steps)))
        cols["step"].append(np.repeat(np.asarray(steps, dtype=int), n))
        cols["t"].append(np.tile(np.asarray(t, dtype=float), len(steps)))
    if not cols["t"]:
        return pd.DataFrame(columns=list(cols))
    return pd.DataFrame({k: np.concatenate(v) for k, v in cols.items()})


def rebuild_tables(results_dir) -> pd.DataFrame:
    """Rewrite runs.parquet, runs.csv, curves.parquet, checkpoints.parquet and
    checkpoint_curves.parquet from ``.rows/`` (atomically)."""
    results_dir = Path(results_dir)
    digest = rows_digest(results_dir)  # before reading: a row written meanwhile shows as stale
    rows = read_rows(results_dir)
    df = rows_frame(rows)
    results_dir.mkdir(parents=True, exist_ok=True)
    for name, writer in (
        ("runs.parquet", lambda p: df.to_parquet(p, index=False)),
        ("runs.csv", lambda p: df.to_csv(p, index=False)),
        ("curves.parquet", lambda p: curves_frame(rows).to_parquet(p, index=False)),
        ("checkpoints.parquet", lambda p: checkpoints_frame(rows).to_parquet(p, index=False)),
        (
            "checkpoint_curves.parquet",
            lambda p: checkpoint_curves_frame(rows).to_parquet(p, index=False),
        ),
    ):
        fd, tmp = tempfile.mkstemp(dir=results_dir, prefix=_tmp_prefix(), suffix=name)
        os.close(fd)
        try:
            writer(tmp)
            os.replace(tmp, results_dir / name)
        finally:
            Path(tmp).unlink(missing_ok=True)
    record_schema(results_dir, rows_digest=digest)
    return df


def rows_digest(results_dir) -> str:
    """sha256 over the row files' names and bytes: what the tables were built from. Recorded
    by :func:`rebuild_tables` in ``bench_meta.json``; :func:`stale_tables` compares it, so a row
    rewritten under the same hash (a rerun) marks the tables stale too."""
    h = hashlib.sha256()
    rows_dir = Path(results_dir) / ROWS
    for p in sorted(rows_dir.glob("*.json")) if rows_dir.is_dir() else ():
        if p.name.startswith("."):  # a temporary being written (see scan_rows)
            continue
        try:
            data = p.read_bytes()
        except OSError:
            continue
        h.update(p.name.encode() + b"\0" + hashlib.sha256(data).digest())
    return h.hexdigest()


META = "bench_meta.json"


def _read_meta(results_dir) -> dict:
    try:
        meta = json.loads((Path(results_dir) / META).read_text())
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def record_schema(results_dir, rows_digest: str | None = None) -> None:
    """Record the tables' schema version (:data:`bench.core._schema.SCHEMA_VERSION`) in
    ``bench_meta.json`` (other keys kept; ``python -m bench compare`` checks it), and the
    :func:`rows_digest` the tables were built from, where given."""
    from ._schema import SCHEMA_VERSION

    path = Path(results_dir) / META
    meta = _read_meta(results_dir)
    want = {"schema_version": SCHEMA_VERSION}
    if rows_digest is not None:
        want["rows_digest"] = rows_digest
    if all(meta.get(a) == b for a, b in want.items()):
        return
    meta.update(want)
    _atomic_write_bytes(path, json.dumps(meta, indent=1).encode())


TABLES = (
    "runs.parquet",
    "runs.csv",
    "curves.parquet",
    "checkpoints.parquet",
    "checkpoint_curves.parquet",
)


def stale_tables(results_dir) -> list[tuple[str, str]]:
    """The tables of ``results_dir`` that do not match ``.rows/`` (the truth), as
    ``(file name, why)``: missing, unreadable (truncated, not a table), for the runs tables
    holding other runs than the row files, or built from other row files than those stored now
    (the :func:`rows_digest` recorded at the last rebuild differs: a row rewritten under its
    hash; folders built before digests were recorded skip this check). Empty without
    ``.rows/`` (nothing to rebuild from)."""
    results_dir = Path(results_dir)
    if not (results_dir / ROWS).is_dir():
        return []
    rows = {p.stem for p in (results_dir / ROWS).glob("*.json") if not p.name.startswith(".")}
    out = []
    for name in TABLES:
        path = results_dir / name
        if not path.exists():
            if rows:
                out.append((name, "missing"))
            continue
        try:
            df = pd.read_csv(path) if name.endswith(".csv") else pd.read_parquet(path)
        except Exception as e:  # noqa: BLE001 - any reader error means a damaged table
            out.append((name, f"unreadable ({type(e).__name__})"))
            continue
        if name.startswith("runs.") and set(df.get("config_hash", pd.Series(dtype=str))) != rows:
            out.append((name, "other runs than the row files"))
    recorded = _read_meta(results_dir).get("rows_digest")
    if recorded is not None and recorded != rows_digest(results_dir):
        flagged = {name for name, _ in out}
        out += [
            (name, "built from other row files (rows added or rewritten since)")
            for name in TABLES
            if name not in flagged
        ]
    return out


def load_runs(results_dir="results") -> pd.DataFrame:
    """The runs table: from ``.rows/`` when present (the truth), else runs.parquet."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        return rows_frame(read_rows(results_dir))
    if (results_dir / "runs.parquet").exists():
        return pd.read_parquet(results_dir / "runs.parquet")
    return pd.DataFrame()


def load_curves(results_dir="results") -> pd.DataFrame:
    """The per-time curves table (see :func:`curves_frame`)."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        return curves_frame(read_rows(results_dir))
    if (results_dir / "curves.parquet").exists():
        return pd.read_parquet(results_dir / "curves.parquet")
    return curves_frame([])


def load_checkpoints(results_dir="results") -> tuple[pd.DataFrame, pd.DataFrame]:
    """(checkpoints, checkpoint curves) tables (see :func:`checkpoints_frame`)."""
    results_dir = Path(results_dir)
    if (results_dir / ROWS).is_dir():
        rows = read_rows(results_dir)
        return checkpoints_frame(rows), checkpoint_curves_frame(rows)
    out = []
    for name, empty in (
        ("checkpoints.parquet", checkpoints_frame),
        ("checkpoint_curves.parquet", checkpoint_curves_frame),
    ):
        path = results_dir / name
        out.append(pd.read_parquet(path) if path.exists() else empty([]))
    return out[0], out[1]


def runs_of(experiment, profile: str, results_dir="results") -> pd.DataFrame:
    """The stored rows of an experiment's runs under a profile (by config_hash, shared runs
    included whichever experiment produced them first)."""
    from ._experiments import expand

    hashes = [c.config_hash for c in expand(experiment, profile)]
    df = load_runs(results_dir)
    if df.empty:
        return df
    return df[df["config_hash"].isin(hashes)].reset_index(drop=True)
